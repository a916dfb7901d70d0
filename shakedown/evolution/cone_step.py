"""The 3-D implicit step: a second-order-cone complementarity problem (MODEL.md s.8.4).

:class:`ConeStepSolver` solves the step from ``v_k`` to ``t_{k+1}`` of a ``dim = 3`` system:
per node stick (``dv_i = 0``, ``|F_i^-1 q_i| <= p_i``), slip (``q_i = -p_i F_i^2 dv_i /
|F_i dv_i|``: for isotropic friction ``q_i = -f_i p_i dv_i / |dv_i|``) or separation
(``w_i > 0``, ``q_i = 0``, ``p_i = 0``), with ``q = q_w + A v + B w``, ``p = p_w + B^T v + C w``.
The solver is the compiled semismooth Newton method of :mod:`.cone_kernel` (Alart-Curnier
formulation, reduced Newton systems, backtracking line search), warm-started from a guess (the
previous step's increment and gaps); when it fails it is restarted cold and then replaced by the
projected block Gauss-Seidel method of the same module.  Every answer is verified by
:func:`verify_step` against its own conditions, independently of the formulation.

Scales: the step's *force scale* ``F = max |(q_w, p_w, q_w + A v_k, p_w + B^T v_k)|`` (1 if
zero); a slip or gap of node ``i`` is measured by the reaction its own stiffness gives it
(``k_i |dv_i|``, ``C_ii w_i``), an energy ``q . dv`` by ``F^2 / k_i``.  Uniqueness: the status is
``"unique"`` when the friction is below the sufficient bound of
:func:`shakedown.model.critical3d.critical_friction_3d`, else ``"solved"``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import InputError, ShapeError
from . import cone_kernel as ck
from .step_types import FEAS_TOL, StepResult

#: A node whose trial traction leaves the cone by at most ``STICK_SLACK * feas_tol * F`` is
#: solved as stuck (the 2-D active set accepts up to ``feas_tol * F``): slips far below the
#: verification tolerance do not linger, and an embedded 2-D system takes the 2-D path.
STICK_SLACK = 0.5

#: State names of 3-D steps, indexed by the codes of :mod:`.cone_kernel` (2 is unused).
STATE_NAMES_3D = ("stick", "slip", "unused", "separation")


@dataclass(frozen=True, eq=False, repr=False)  # StepResult's short repr
class ConeStepResult(StepResult):
    """One 3-D implicit step: :class:`~.step_types.StepResult` with 3-D shapes.

    ``slip``, ``slip_increment``, ``q`` have shape (N, 2); ``gap``, ``p`` (N,); ``states`` and
    ``active_set`` use the codes stick 0, slip 1, separation 3 (:data:`STATE_NAMES_3D`).
    ``complementarity_residual`` is the largest of the three residuals below; ``method`` is
    ``"newton"``, ``"newton_cold"``, ``"gauss_seidel"`` or ``"none"``.

    Attributes
    ----------
    cone_residual : float
        ``max_i max(0, |F_i^-1 q_i| - p_i) min(f_x,i, f_y,i) / F`` (cone feasibility in force
        units relative to ``F``: ``(|q_i| - f_i p_i) / F`` for isotropic friction, as in 2-D).
    direction_residual : float
        ``max_i k_i (q_i . dv_i + p_i |F_i dv_i|) / F^2``: zero iff each slipping node's reaction
        lies on the cone opposite to its slip (cone complementarity), dimensionless.
    normal_residual : float
        ``max_i |min(C_ii w_i, p_i)| / F`` (gap-pressure complementarity and signs).
    """

    cone_residual: float = 0.0
    direction_residual: float = 0.0
    normal_residual: float = 0.0

    @property
    def state_names(self) -> np.ndarray:
        """``states`` as strings (:data:`STATE_NAMES_3D`)."""
        return np.asarray(STATE_NAMES_3D)[self.states]


def node_order(n: int) -> np.ndarray:
    """Permutation from the system's unknowns ``(v_1x, v_1y, ..., v_Nx, v_Ny, w_1, ..., w_N)``
    to node order ``(v_1x, v_1y, w_1, v_2x, ...)``, shape (3N,)."""
    perm = np.empty(3 * n, int)
    perm[0::3] = 2 * np.arange(n)
    perm[1::3] = 2 * np.arange(n) + 1
    perm[2::3] = 2 * n + np.arange(n)
    return perm


@dataclass(frozen=True)
class ConeData:
    """The step's constant data in node order (see :mod:`.cone_kernel`)."""

    Kn: np.ndarray  # (3N, 3N)
    sx: np.ndarray  # (N,) cone scaling (f_x, or 1 for a frictionless node)
    sy: np.ndarray
    g: np.ndarray   # (N,) 1 frictional, 0 frictionless
    kT: np.ndarray  # (N,) tangential stiffness of the node (mean of its two diagonal entries)
    kN: np.ndarray  # (N,) C_ii
    coupled: bool

    @classmethod
    def from_matrices(cls, A, B, C, friction_xy):
        """From dense ``A`` (2N, 2N), ``B`` (2N, N), ``C`` (N, N) and ``friction_xy`` (N, 2)."""
        A, B, C = (np.asarray(M.toarray() if hasattr(M, "toarray") else M, float)
                   for M in (A, B, C))
        fxy = np.asarray(friction_xy, float)
        n = C.shape[0]
        if A.shape != (2 * n, 2 * n) or B.shape != (2 * n, n) or fxy.shape != (n, 2):
            raise ShapeError(f"3-D step needs A (2N, 2N), B (2N, N), C (N, N), friction (N, 2) "
                             f"with N = {n}; got {A.shape}, {B.shape}, {fxy.shape}")
        one_zero = (fxy == 0).sum(axis=1) == 1
        if np.any(one_zero):
            j = int(np.flatnonzero(one_zero)[0])
            raise InputError(f"friction of node {j} is {fxy[j].tolist()}: an elliptic cone needs "
                             "both f_x and f_y > 0 (or both 0 for a frictionless node)")
        K = np.block([[A, B], [B.T, C]])
        perm = node_order(n)
        Kn = np.ascontiguousarray(K[np.ix_(perm, perm)])
        fr = fxy[:, 0] > 0
        sx = np.where(fr, fxy[:, 0], 1.0)
        sy = np.where(fr, fxy[:, 1], 1.0)
        dA = np.diag(A)
        kT = 0.5 * (dA[0::2] + dA[1::2])
        return cls(Kn, sx, sy, fr.astype(float), kT, np.diag(C).copy(),
                   bool(np.any(B != 0)))

    @property
    def n(self) -> int:
        return self.g.size

    def rho(self):
        """AC parameters ``rho_T = k_T / s^2`` (s: the mean cone scaling), ``rho_N = C_ii``."""
        return self.kT / (self.sx * self.sy), self.kN.copy()


@dataclass(frozen=True)
class ConeResiduals:
    """The verification of one answer (all dimensionless, see :class:`ConeStepResult`)."""

    cone: float
    direction: float
    normal: float
    equilibrium: float

    @property
    def worst(self) -> float:
        return max(self.cone, self.direction, self.normal, self.equilibrium)


def verify_step(data: ConeData, rb, u, r, force_scale, equilibrium: bool = True) -> ConeResiduals:
    """Check an answer ``(u, r)`` (node order, shapes (N, 3)) of the step with base reactions
    ``rb`` (N, 3) by its own conditions: cone feasibility, cone complementarity (slip opposite
    to the traction, on the cone), gap-pressure complementarity, and equilibrium ``r = rb +
    K u`` recomputed with ``K`` (``equilibrium=False``: skipped and reported as 0, for callers
    that check a whole period by one matrix product).  Independent of how the answer was
    found."""
    F = float(force_scale)
    u = np.asarray(u, float).reshape(-1, 3)
    r = np.asarray(r, float).reshape(-1, 3)
    rb = np.asarray(rb, float).reshape(-1, 3)
    eq = (np.abs(rb.ravel() + data.Kn @ u.ravel() - r.ravel()).max(initial=0.0) / F
          if equilibrium else 0.0)
    q, p = r[:, :2], r[:, 2]
    dv, w = u[:, :2], u[:, 2]
    S = np.column_stack([data.sx, data.sy])
    cone = np.max(np.maximum(np.hypot(*(q / S).T) - data.g * p, 0.0) * S.min(axis=1),
                  initial=0.0) / F
    diss = np.einsum("ij,ij->i", q, dv) + data.g * p * np.hypot(*(S * dv).T)
    direction = np.max(np.abs(diss) * data.kT, initial=0.0) / F**2
    normal = np.max(np.abs(np.minimum(data.kN * w, p)), initial=0.0) / F
    return ConeResiduals(float(cone), float(direction), float(normal), float(eq))


class ConeStepSolver:
    """Solver of the 3-D step (see module docstring).

    Parameters
    ----------
    system : DiscreteSystem
        ``dim = 3``.
    feas_tol : float
        Relative tolerance of the verification (:data:`~.step_types.FEAS_TOL`).
    max_iter : int
        Newton iterations per attempt.
    dense_max : int
        Largest reduced Newton system solved by LU directly; larger ones are solved by
        block-Jacobi preconditioned GMRES first (:func:`.cone_linear._krylov`).
    """

    def __init__(self, system, feas_tol: float = FEAS_TOL, max_iter: int = 60,
                 dense_max: int = ck.DENSE_MAX):
        self.system = system
        sysd = system.to_dense() if getattr(system, "is_sparse", False) else system
        self.data = ConeData.from_matrices(sysd.A, sysd.B, sysd.C, system.friction_xy)
        self.n = self.data.n
        self.feas_tol = float(feas_tol)
        self.max_iter = int(max_iter)
        self.dense_max = int(dense_max)
        self.rhoT, self.rhoN = self.data.rho()
        self.A = np.asarray(sysd.A, float)
        self.Bt = np.asarray(sysd.B, float).T.copy()
        try:
            crit = system.critical_friction()
            self.well_posed = bool(crit.well_posed)
        except NotImplementedError:  # before the 3-D bound is wired into the system
            self.well_posed = not self.data.coupled
        # the Newton method's buffers (unknowns, reduced matrix), reused by every step
        self._buffers = ck.new_buffers(self.n)
        self.totals = dict(steps=0, iterations=0, cold_restarts=0, gauss_seidel=0, failed=0)

    # ------------------------------------------------------------------ base reactions
    def base(self, v_prev, q_w, p_w):
        """``rb`` (N, 3): ``(q_w + A v_prev, p_w + B^T v_prev)`` in node order."""
        v = np.asarray(v_prev, float).reshape(-1)
        rb = np.empty((self.n, 3))
        rb[:, :2] = np.asarray(q_w, float).reshape(self.n, 2) + (self.A @ v).reshape(self.n, 2)
        rb[:, 2] = np.asarray(p_w, float) + self.Bt @ v
        return rb

    def solve_raw(self, rb, u0=None, equilibrium: bool = True, ku0=None):
        """Solve from base reactions ``rb`` (N, 3) and guess ``u0`` (N, 3) [warm start];
        ``equilibrium``: passed to :func:`verify_step`; ``ku0`` (N, 3): ``K u0`` in node order
        when the caller knows it (from earlier products with ``K``: the warm start then skips
        its own; the answer's equilibrium must then be checked, ``equilibrium=True`` or by the
        caller).  An answer reached by a full Newton step has the reactions ``rb + K u``
        computed from scratch at it: its equilibrium holds by construction and is reported as 0
        (:func:`.cone_kernel.attempt`).

        Returns ``(u, r, states, method, iterations, residuals, scale)``; ``u, r`` (N, 3)."""
        n = self.n
        d = self.data
        rbf = np.ascontiguousarray(rb, dtype=float).reshape(-1)
        tries = [("newton", u0), ("newton_cold", None)] if u0 is not None else [
            ("newton_cold", None)]
        best = None
        iters = 0
        F = 1.0
        for name, guess in tries:
            u = np.zeros(3 * n) if guess is None else np.array(guess, dtype=float).reshape(-1)
            given = guess is not None and ku0 is not None
            r = rbf + np.asarray(ku0, dtype=float).reshape(-1) if given else np.empty(3 * n)
            st = np.empty(n, np.int8)
            code, it, F, *checks = ck.attempt(
                d.Kn, rbf, d.sx, d.sy, d.g, self.rhoT, self.rhoN, d.kT, d.kN, u, r, st,
                self.feas_tol, self.max_iter, self.dense_max, STICK_SLACK, given, self._buffers,
                bool(equilibrium))
            iters += it
            res = ConeResiduals(*checks)
            if best is None or res.worst < best[3].worst:
                best = (u, r, st, res, name)
            if res.worst <= self.feas_tol:
                break
            if name == "newton":
                self.totals["cold_restarts"] += 1
        if best[3].worst > self.feas_tol:  # fallback: projected block Gauss-Seidel
            self.totals["gauss_seidel"] += 1
            u, r, st = best[0].copy(), np.empty(3 * n), np.empty(n, np.int8)
            tol = 1e-3 * self.feas_tol * F
            slack = STICK_SLACK * self.feas_tol * F
            code, it, _ = ck.gauss_seidel(d.Kn, rbf, d.sx, d.sy, d.g, self.rhoT, self.rhoN, u,
                                          r, st, tol, 2000, 50, slack)
            iters += it
            res = self._verify(rbf, u, r, F, equilibrium)
            if res.worst < best[3].worst:
                best = (u, r, st, res, "gauss_seidel")
        u, r, st, res, name = best
        self.totals["steps"] += 1
        self.totals["iterations"] += iters
        return u.reshape(n, 3), r.reshape(n, 3), st, name, iters, res, F

    def _verify(self, rb, u, r, F, equilibrium):
        """:func:`verify_step` by its compiled twin :func:`.cone_kernel.residuals`."""
        d = self.data
        return ConeResiduals(*ck.residuals(d.Kn, rb, d.sx, d.sy, d.g, d.kT, d.kN, u, r,
                                           float(F), bool(equilibrium)))

    # ------------------------------------------------------------------ public step
    def solve(self, v_prev, q_w, p_w, guess=None) -> ConeStepResult:
        """The implicit step from slips ``v_prev`` (N, 2) under welded reactions ``q_w`` (N, 2),
        ``p_w`` (N,) at the end of the step; ``guess``: a previous :class:`ConeStepResult` (its
        increment and gaps warm-start the Newton method) or an array (N, 3) of
        ``(dv_x, dv_y, w)``."""
        n = self.n
        v_prev = _arr("v_prev", v_prev, (n, 2))
        q_w = _arr("q_w", q_w, (n, 2))
        p_w = _arr("p_w", p_w, (n,))
        u0 = None
        if isinstance(guess, StepResult):
            u0 = np.column_stack([guess.slip_increment, guess.gap])
        elif guess is not None:
            u0 = _arr("guess", guess, (n, 3))
        rb = self.base(v_prev, q_w, p_w)
        u, r, st, name, iters, res, F = self.solve_raw(rb, u0)
        return self.result(v_prev, u, r, st, name, iters, res, F)

    def result(self, v_prev, u, r, st, name, iters, res, F) -> ConeStepResult:
        """Assemble a :class:`ConeStepResult` (statuses as in 2-D)."""
        ok = res.worst <= self.feas_tol
        states = self.kinematic_states(u, F)
        if ok:
            status = "unique" if self.well_posed else "solved"
            msg = ("solved; unique (friction below the sufficient bound)" if self.well_posed
                   else "solved; uniqueness not guaranteed (friction above the sufficient bound)")
        else:
            status = "failed"
            self.totals["failed"] += 1
            msg = (f"no verified solution: residuals cone {res.cone:.3g}, direction "
                   f"{res.direction:.3g}, normal {res.normal:.3g}, equilibrium "
                   f"{res.equilibrium:.3g} > feas_tol {self.feas_tol:g}")
        comp = max(res.cone, res.direction, res.normal)
        return ConeStepResult(
            slip=v_prev + u[:, :2], gap=u[:, 2].copy(), slip_increment=u[:, :2].copy(),
            q=r[:, :2].copy(), p=r[:, 2].copy(), states=states, active_set=st.copy(),
            success=bool(ok), status=status, message=msg, residual=float(res.worst),
            complementarity_residual=float(comp), equilibrium_residual=float(res.equilibrium),
            force_scale=float(F), method=name if ok or name else "none", iterations=int(iters),
            cone_residual=res.cone, direction_residual=res.direction, normal_residual=res.normal)

    def kinematic_states(self, u, F):
        """Codes from the answer: separated when ``C_ii w_i > feas_tol F``, else slip when
        ``k_i |dv_i| > feas_tol F``, else stick; shape (..., N)."""
        u = np.asarray(u)
        tol = self.feas_tol * np.asarray(F, float)[..., None] if np.ndim(F) else self.feas_tol * F
        st = np.where(self.data.kT * np.hypot(u[..., 0], u[..., 1]) > tol, ck.SLIP, ck.STICK)
        st = np.where(self.data.kN * u[..., 2] > tol, ck.SEPARATED, st)
        return st.astype(np.int8)


def _arr(name, value, shape):
    try:
        x = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a real array of shape {shape}; got {value!r}") from exc
    if x.shape != shape:
        raise ShapeError(f"{name} must have shape {shape}; got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be finite")
    return x


__all__ = ["ConeStepSolver", "ConeStepResult", "ConeData", "ConeResiduals", "verify_step",
           "node_order", "STATE_NAMES_3D"]
