"""Half-space contact (sphere on flat) under force control as a 3-D :class:`shakedown.DiscreteSystem`.

Two elastic bodies, each approximated as a half-space near the contact (MODEL.md s.8.5), are
pressed together by ``P(t)`` and sheared by ``(Q_x(t), Q_y(t))``.  The window
``[-L/2, L/2]^2`` is cut into ``n x n`` square cells of side ``h = L / n``, numbered ``i n + j``
with centre ``(x_i, y_j)``; the cell compliance ``F`` of :mod:`.influence` gives the mean slips
and gaps::

    u = (v, w) = g~ + E z + F r,    E^T r = R = (Q_x, Q_y, P)                      (1)

with ``r`` the cell forces (reactions on body 1, in MODEL.md s.8 order), ``g~`` the cell means of
the initial gap, ``z`` the rigid shift ``(s_x, s_y)`` and approach ``d`` of body 1, ``E`` the
three rigid translations.  The rigid *rotations* are held (the indenter is guided, as in
Hertz-Mindlin theory: the resultants pass through the origin and no tilt or twist is allowed).

Exact condensation of the rigid-body modes (as in :mod:`shakedown.models.half_plane.model`):
one *reference cell* ``m`` (the minimum of ``g`` nearest the window's centre) measures every
displacement, ``u'_j = u_j - u_m`` (``T^T u``); ``r_m = R - sum_{j != m} r_j`` (``r = T r' + e_m R``)::

    u' = T^T g~ + T^T F e_m R + F' r',    F' = T^T F T   (symmetric positive definite)   (2)
    r' = r_w + K u',  K = F'^-1,  r_w = -K T^T (g~ + F e_m R(t))                       (3)

exact with no spring *provided the reference cell sticks and stays closed* along the run
(:meth:`HalfSpaceModel.check_reference` verifies it from the resultants).  For similar materials
and ``|Q| < f P`` the Cattaneo-Mindlin stick zone is central, so the centre cell never slips.

Dense ``K`` (the :attr:`~HalfSpaceModel.system`) is built up to :data:`DENSE_MAX_CELLS` cells; the
matrix-free FFT operators (:mod:`.operators`) serve every size.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ...model import DiscreteSystem, InputError, LoadCycle
from ..half_plane.model import _positive
from .influence import dense_compliance, material_constants, offset_kernels
from .operators import CellCompliance, ReducedCompliance, ReducedStiffness

PROFILES = ("sphere", "ellipsoid", "flat_rounded", "height_map")
#: Largest number of cells for which :attr:`HalfSpaceModel.system` builds the dense ``K``
#: (``50 x 50`` cells: ``K`` of 7497^2 doubles, 450 MB).
DENSE_MAX_CELLS = 2500
_GX, _GW = np.polynomial.legendre.leggauss(4)


def gap_function(profile: str, *, radius=None, radii=None, flat_radius=None):
    """The initial gap ``g(x, y)`` [length] of a built-in profile, vectorised and validated.

    ``"sphere"``: ``(x^2 + y^2) / (2 R)``; ``"ellipsoid"``: ``x^2/(2 R_x) + y^2/(2 R_y)``
    (``radii = (R_x, R_y)``); ``"flat_rounded"``: a flat circular punch of radius ``b``
    (``flat_radius``) with edges rounded to radius ``R``: ``max(rho - b, 0)^2 / (2 R)``,
    ``rho = sqrt(x^2 + y^2)``.  (``"height_map"`` gives the cell values directly.)
    """
    if profile == "sphere":
        R = _positive("radius", radius)
        return lambda x, y: (x * x + y * y) / (2 * R)
    if profile == "ellipsoid":
        try:
            Rx, Ry = radii
        except (TypeError, ValueError):
            raise InputError(f"radii must be (R_x, R_y) for profile 'ellipsoid', got {radii!r}") from None
        Rx, Ry = _positive("radii[0]", Rx), _positive("radii[1]", Ry)
        return lambda x, y: x * x / (2 * Rx) + y * y / (2 * Ry)
    if profile == "flat_rounded":
        R, b = _positive("radius", radius), _positive("flat_radius", flat_radius)
        return lambda x, y: np.maximum(np.hypot(x, y) - b, 0.0) ** 2 / (2 * R)
    raise InputError(f"profile must be one of {PROFILES}, got {profile!r}")


@dataclass(frozen=True, eq=False)
class HalfSpaceModel:
    """A discretised half-space contact; build with :func:`half_space_model`.

    Attributes
    ----------
    n : int
        Cells per side; ``n_cells = n^2``.
    h : float
        Cell side [length].
    xy_cells : ndarray, shape (n^2, 2)
        Centres of all cells [length]; ``reference`` indexes the reference cell in it.
    e_star, beta : float
        Contact modulus ``E*`` [force/length^2] and Dundurs' ``beta``.
    gap : ndarray, shape (n^2,)
        Cell means of the initial gap [length].
    friction : float
    materials : ((E1, nu1), (E2, nu2))
    kernels : dict
        Offset kernels of :func:`.influence.offset_kernels` [length/force].
    """

    n: int
    h: float
    xy_cells: np.ndarray
    reference: int
    e_star: float
    beta: float
    gap: np.ndarray
    friction: float
    profile: str
    radius: float | None
    materials: tuple = ((1.0, 0.3), (1.0, 0.3))
    kernels: dict = field(default=None, repr=False)

    # -- geometry -----------------------------------------------------------------------------
    @property
    def n_cells(self) -> int:
        return self.n * self.n

    @property
    def keep(self) -> np.ndarray:
        """Cell indices of the system's nodes (all cells but the reference), shape (n^2 - 1,)."""
        return np.delete(np.arange(self.n_cells), self.reference)

    @property
    def xy(self) -> np.ndarray:
        """Centres of the system's nodes [length], shape (n^2 - 1, 2)."""
        return self.xy_cells[self.keep]

    # -- operators ----------------------------------------------------------------------------
    @cached_property
    def compliance_operator(self) -> CellCompliance:
        """``F`` over all cells, applied by FFT, shape (3 n^2, 3 n^2) [length/force]."""
        return CellCompliance(self.kernels, self.n)

    @cached_property
    def reduced_compliance_operator(self) -> ReducedCompliance:
        """``F' = T^T F T`` by FFT, shape (3 (n^2 - 1),) * 2: the inverse of ``system.K``."""
        return ReducedCompliance(self.compliance_operator, self.reference)

    def stiffness_operator(self, rtol: float = 1e-10) -> ReducedStiffness:
        """``K = F'^-1`` matrix-free (CG with FFT products): products equal ``system.K @ x``."""
        return ReducedStiffness(self.reduced_compliance_operator, rtol=rtol)

    def dense_compliance(self) -> np.ndarray:
        """Dense ``F`` over all cells, shape (3 n^2, 3 n^2) [length/force]."""
        return dense_compliance(self.kernels, self.n)

    @cached_property
    def stiffness(self) -> np.ndarray:
        """Dense ``K = F'^-1``, shape (3 (n^2 - 1),) * 2 [force/length] (eq. (3))."""
        from scipy.linalg import lapack

        if self.n_cells > DENSE_MAX_CELLS:
            raise InputError(
                f"n_cells = {self.n}^2 = {self.n_cells} is above DENSE_MAX_CELLS = {DENSE_MAX_CELLS} "
                "for a dense stiffness; use model.stiffness_operator() (matrix-free FFT) instead")
        F = self.dense_compliance()
        red = self.reduced_compliance_operator
        full, ref = red.full, red.ref
        Fp = F[np.ix_(full, full)]
        Fp -= F[np.ix_(full, ref)]
        Fp -= F[np.ix_(ref, full)]
        Fp += F[np.ix_(ref, ref)]
        del F
        c, info = lapack.dpotrf(Fp, lower=0, overwrite_a=1)
        if info != 0:
            raise InputError(f"the reduced compliance is not positive definite (dpotrf info {info})")
        K, info = lapack.dpotri(c, lower=0, overwrite_c=1)
        K = np.triu(K) + np.triu(K, 1).T
        return K

    @cached_property
    def system(self) -> DiscreteSystem:
        """The 3-D :class:`~shakedown.DiscreteSystem` of the ``n^2 - 1`` non-reference cells."""
        K = self.stiffness
        t = 2 * (self.n_cells - 1)
        return DiscreteSystem(K[:t, :t], K[:t, t:], K[t:, t:], self.friction, dim=3)

    # -- loads --------------------------------------------------------------------------------
    @cached_property
    def _welded_basis(self):
        """``(r_gap, r_unit)``: welded reactions of ``g~`` (3(N-1),) and per unit ``(Q_x, Q_y, P)``."""
        red = self.reduced_compliance_operator
        N = self.n_cells
        m = self.reference
        em = np.zeros((3 * N, 3))
        em[2 * m, 0] = em[2 * m + 1, 1] = em[2 * N + m, 2] = 1.0
        g = np.zeros((3 * N, 1))
        g[2 * N:, 0] = self.gap
        rhs = np.column_stack([red.restrict(g), red.restrict(self.compliance_operator @ em)])
        if self.n_cells <= DENSE_MAX_CELLS:
            out = -(self.stiffness @ rhs)
        else:
            out = -(self.stiffness_operator(rtol=1e-12) @ rhs)
        return out[:, 0], out[:, 1:]

    def welded(self, Qx, Qy, P):
        """Welded reactions for resultants ``Q_x, Q_y, P`` (scalars or shape (T,)).

        Returns ``q_w`` of shape (..., N - 1, 2) and ``p_w`` of shape (..., N - 1) [force].
        """
        r_gap, r_unit = self._welded_basis
        R = np.stack(np.broadcast_arrays(*(np.asarray(a, float) for a in (Qx, Qy, P))), axis=-1)
        r = r_gap + R @ r_unit.T
        t = 2 * (self.n_cells - 1)
        return r[..., :t].reshape(r.shape[:-1] + (-1, 2)), r[..., t:]

    def _unit(self, k):
        R = np.zeros(3)
        R[k] = 1.0
        q, p = self.welded(*R)
        q0, p0 = self.welded(0.0, 0.0, 0.0)
        return q - q0, p - p0

    def load_cycle(self, P0, P1=0.0, Qx=0.0, Qy=0.0, phase=0.0) -> LoadCycle:
        """``P = P0 + lam P1 cos(2 pi t + phase)``, ``Q_x = lam Qx cos 2 pi t``, ``Q_y = lam Qy sin 2 pi t``.

        Parameters
        ----------
        P0 : float
            Mean normal load ``> 0`` [force].
        P1, Qx, Qy : float
            Amplitudes [force]: ``Qy = 0`` an oscillating, ``Qy = Qx`` a rotating, other values
            an elliptical tangential load.
        phase : float
            Phase of ``P`` ahead of ``Q_x`` [rad].
        """
        P0 = _positive("P0", P0)
        vals = {}
        for name, v in (("P1", P1), ("Qx", Qx), ("Qy", Qy), ("phase", phase)):
            try:
                vals[name] = float(v)
            except (TypeError, ValueError):
                raise InputError(f"{name} must be a number, got {v!r}") from None
            if not np.isfinite(vals[name]):
                raise InputError(f"{name} must be finite, got {v!r}")
        q0, p0 = self.welded(0.0, 0.0, P0)
        (ux, px), (uy, py), (uP, pP) = (self._unit(k) for k in range(3))
        c, s = vals["P1"] * np.cos(vals["phase"]), vals["P1"] * np.sin(vals["phase"])
        return LoadCycle.from_harmonics(
            q0, p0, q_cos=vals["Qx"] * ux + c * uP, q_sin=vals["Qy"] * uy - s * uP,
            p_cos=vals["Qx"] * px + c * pP, p_sin=vals["Qy"] * py - s * pP)

    def load_from_samples(self, P0, P1_samples, Qx_samples, Qy_samples=None) -> LoadCycle:
        """``P = P0 + lam P1(t)``, ``Q = lam (Q_x(t), Q_y(t))`` from samples at ``t = k / S``."""
        P0 = _positive("P0", P0)
        P1 = np.asarray(P1_samples, float)
        Qx = np.asarray(Qx_samples, float)
        Qy = np.zeros_like(Qx) if Qy_samples is None else np.asarray(Qy_samples, float)
        if P1.ndim != 1 or P1.shape != Qx.shape or Qy.shape != Qx.shape or P1.size < 2:
            raise InputError("P1_samples, Qx_samples and Qy_samples must be 1-D, same length >= 2, "
                             f"got shapes {P1.shape}, {Qx.shape}, {Qy.shape}")
        q0, p0 = self.welded(0.0, 0.0, P0)
        qa, pa = self.welded(Qx, Qy, P1)
        qz, pz = self.welded(0.0, 0.0, 0.0)
        return LoadCycle.from_samples(q0, p0, qa - qz, pa - pz)

    # -- the reference cell -------------------------------------------------------------------
    def reference_reactions(self, q, p, Qx, Qy, P):
        """Reactions of the reference cell ``(R - sum r')``: ``q`` (..., N-1, 2), ``p`` (..., N-1)
        -> ``q_m`` (..., 2), ``p_m`` (...)."""
        qm = np.stack([np.asarray(Qx, float), np.asarray(Qy, float)], axis=-1) - np.sum(q, axis=-2)
        return qm, np.asarray(P, float) - np.sum(p, axis=-1)

    def full(self, values, ref_value=0.0):
        """Insert ``ref_value`` at the reference cell: (..., N-1[, 2]) -> (..., N[, 2])."""
        values = np.asarray(values, float)
        axis = -2 if values.ndim >= 2 and values.shape[-1] == 2 and values.shape[-2] == self.n_cells - 1 \
            else -1
        return np.insert(values, self.reference, ref_value, axis=axis)

    def check_reference(self, q, p, Qx, Qy, P, rtol: float = 1e-9):
        """Is the reference cell stuck-admissible and closed at every instant (eq. (3) exact)?

        ``q`` (T, N-1, 2) and ``p`` (T, N-1) are the reactions of a run at ``T`` instants with
        resultants ``Qx, Qy, P`` (T,).  Returns ``(ok, worst)``,
        ``worst = max_t (|q_m| - f p_m) / max|P|``.
        """
        qm, pm = self.reference_reactions(q, p, Qx, Qy, P)
        scale = max(float(np.max(np.abs(P))), np.finfo(float).tiny)
        worst = float(np.max((np.linalg.norm(qm, axis=-1) - self.friction * pm) / scale))
        return bool(worst <= rtol and np.all(pm > -rtol * scale)), worst


def half_space_model(profile: str = "sphere", *, radius=None, radii=None, flat_radius=None,
                     heights=None, n_cells: int = 21, width=None, friction=0.5,
                     materials=((1.0, 0.3), (1.0, 0.3)), reference_xy=None) -> HalfSpaceModel:
    """Discretise a 3-D half-space contact (sphere on flat and kin) into square cells.

    Parameters
    ----------
    profile : {"sphere", "ellipsoid", "flat_rounded", "height_map"}
        Initial gap, see :func:`gap_function`; ``"height_map"`` takes ``heights``.
    radius : float
        Relative radius ``R`` [length] (sphere; edge radius of ``"flat_rounded"``).
    radii : (float, float)
        ``(R_x, R_y)`` of ``"ellipsoid"`` [length].
    flat_radius : float
        Radius of the flat of ``"flat_rounded"`` [length].
    heights : array_like, shape (n, n)
        ``"height_map"``: the initial gap of cell ``(i, j)`` (centre ``(x_i, y_j)``) [length].
    n_cells : int
        Cells per side ``n >= 2``; the system has ``n^2 - 1`` nodes (one is the reference).
    width : float
        Side ``L`` of the window ``[-L/2, L/2]^2`` [length]; must contain the largest contact.
    friction : float
        Coulomb coefficient ``f >= 0``.
    materials : ((E1, nu1), (E2, nu2))
        Young's moduli [force/length^2] (``inf``: rigid) and Poisson ratios.
    reference_xy : (float, float), optional
        Put the reference cell at the cell nearest this point [length].

    Examples
    --------
    >>> import shakedown as sd
    >>> m = sd.half_space_model(radius=1.0, n_cells=5, width=0.1, friction=0.5)
    >>> m.xy.shape, m.reference
    ((24, 2), 12)
    """
    if isinstance(n_cells, bool) or not isinstance(n_cells, (int, np.integer)) or n_cells < 2:
        raise InputError(f"n_cells must be an integer >= 2 (cells per side), got {n_cells!r}")
    n = int(n_cells)
    L = _positive("width", width)
    try:
        f = float(friction)
    except (TypeError, ValueError):
        raise InputError(f"friction must be a number >= 0, got {friction!r}") from None
    if not np.isfinite(f) or f < 0:
        raise InputError(f"friction must be >= 0, got {friction!r}")
    e_star, beta, b = material_constants(materials)
    h = L / n
    xc = -L / 2 + h * (np.arange(n) + 0.5)
    X, Y = np.meshgrid(xc, xc, indexing="ij")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    if profile == "height_map":
        g = np.asarray(heights, float) if heights is not None else None
        if g is None or g.shape != (n, n) or not np.all(np.isfinite(g)):
            raise InputError(f"heights must be a finite ({n}, {n}) array for profile 'height_map', "
                             f"got {None if g is None else g.shape}")
        gap = g.ravel().copy()
    else:
        gfun = gap_function(profile, radius=radius, radii=radii, flat_radius=flat_radius)
        u = 0.5 * h * _GX
        gx = xy[:, 0, None, None] + u[None, :, None]
        gy = xy[:, 1, None, None] + u[None, None, :]
        gap = 0.25 * np.einsum("kab,a,b->k", gfun(gx, gy), _GW, _GW)  # exact for degree <= 7
    if reference_xy is None:
        low = np.flatnonzero(gap <= gap.min() + 1e-12 * max(np.abs(gap).max(), 1e-300))
        m = int(low[np.argmin(np.hypot(xy[low, 0], xy[low, 1]))])
    else:
        try:
            px, py = (float(v) for v in reference_xy)
        except (TypeError, ValueError):
            raise InputError(f"reference_xy must be (x, y), got {reference_xy!r}") from None
        m = int(np.argmin(np.hypot(xy[:, 0] - px, xy[:, 1] - py)))
    kernels = offset_kernels(n, h, e_star, beta, b)
    return HalfSpaceModel(n=n, h=h, xy_cells=xy, reference=m, e_star=e_star, beta=beta, gap=gap,
                          friction=f, profile=profile,
                          radius=None if radius is None else float(radius),
                          materials=tuple((float(E), float(nu)) for E, nu in materials),
                          kernels=kernels)
