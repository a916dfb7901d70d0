"""The implicit quasi-static step as a linear complementarity problem (MODEL.md s.4).

From the slips ``v_prev`` the step to welded reactions ``(q_w, p_w)`` finds gaps ``w >= 0`` and
slip increments ``dv = dv+ - dv-`` with

    0 <= w    perp  p        >= 0
    0 <= dv+  perp  f p + q  >= 0
    0 <= dv-  perp  f p - q  >= 0,      q = q_w + A v + B w,  p = p_w + B^T v + C w.

**Algorithm.**  An active-set method on node states (stick / forward / backward / separated):
each state assignment fixes two of the four quantities ``(dv_j, w_j, q_j + s f_j p_j, p_j)`` per
node, which leaves a square linear system ``M_s x = h`` in the slips of the non-stick nodes and
the gaps of the separated ones.  The guess is the previous step's assignment; after each solve
the nodes whose signs are violated switch state (all at once; on a repeated assignment one at a
time, the most violated first; on a second repetition, a singular matrix or an exhausted
iteration budget, the LCP in ``(w, dv+, dv-)`` is solved by lexicographic Lemke, which always
terminates).  Factorizations are reused: LU factors are cached per assignment (LRU, bounded in
bytes) and an assignment within ``max(max_update_rank, update_fraction * m)`` changed nodes of
the last factorized one is solved by a Sherman-Morrison-Woodbury update of it, so a step in
which few nodes change state costs a few triangular solves instead of a factorization.  A warm
step (the guess is the answer, its factor cached) is one pair of triangular solves (LAPACK
``getrs`` called directly), one product with the rows of ``K`` kept with the factor, and
``O(N)`` vectorised sign checks; the cycle loop passes the step's base reactions
(:meth:`StepSolver.next_base`) so that no product with all of ``K`` is needed per step.
Modules: :mod:`.step_types` (codes, :class:`StepResult`), :mod:`.factors` (the LU cache and
updates), :mod:`.active_set` (the iteration and its sign checks), :mod:`.fallbacks` (Lemke,
enumeration); this module assembles them.  Every answer is verified (natural
complementarity residuals, scaled per node) and the outcome is a status: below the critical
friction (``system.critical_friction()``) the solution is ``"unique"``; above it, for
``N <= enumerate_max_nodes`` every state assignment is enumerated and the step is classified
``"unique"``, ``"multiple_solutions"`` or ``"no_solution"``; otherwise it is ``"solved"``
(uniqueness not guaranteed) or ``"failed"``.

The same machinery solves the *rate* problems of the event-driven evolution (some nodes are
held in one state, some may take a subset of the states): :meth:`StepSolver.solve_mixed`.
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from functools import cached_property

import numpy as np
from scipy.linalg import get_lapack_funcs

from ..model.errors import InputError, ShapeError
from ..model.schur import SchurStiffness
from ..model.system import DiscreteSystem
from ..model.threads import single_blas_thread
from ..model.validation import check_node_vector, require_two_dimensional
from .active_set import ActiveSet
from .factors import FactorCache
from .fallbacks import Fallbacks
from .kernel_warm import kernel_enabled
from .step_types import (
    ALL_ALLOWED,
    BACKWARD,
    FEAS_TOL,
    FORWARD,
    SEPARATED,
    STATE_NAMES,
    STICK,
    MixedSolution,
    StepResult,
    _Factor,
    kinematic_states,
)

__all__ = ["StepSolver", "StepResult", "solve_step", "get_solver", "parse_states",
           "kinematic_states", "STATE_NAMES", "FEAS_TOL", "STICK", "FORWARD", "BACKWARD",
           "SEPARATED", "ALL_ALLOWED", "MixedSolution", "_Factor"]


class StepSolver(FactorCache, ActiveSet, Fallbacks):
    """Reusable solver of the incremental step for one :class:`DiscreteSystem`.

    Holds the LU cache; :func:`solve_step` keeps one per system.  Parameters are described in
    the module docstring.

    Parameters
    ----------
    system : DiscreteSystem
    feas_tol : float
        Relative feasibility tolerance (see :data:`FEAS_TOL`).
    max_iter : int, optional
        Active-set iteration budget per step before Lemke (default ``2 N + 20``).
    cache_bytes : float
        Memory budget of the LU cache [bytes].
    max_update_rank : int
        Largest number of changed nodes solved by a Woodbury update instead of a new LU, at
        least; see ``update_fraction``.
    update_fraction : float
        Above ``max_update_rank``, an update of rank ``r`` is still used while
        ``r <= update_fraction * m`` (``m`` unknowns of the factorized system): its cost
        ``~ 2 r m^2`` plus ``O(r N)`` gathers stays below a fresh LU's ``2/3 m^3`` (default 1/8:
        about a third of it).  0 disables the proportional rule.
    update_min_size : int
        Woodbury updates are used only when the factorized system has at least this many
        unknowns; below it a fresh LU (cached for the next visit) is cheaper than the update's
        Python overhead (measured: an LU of order 200 costs ~0.3 ms, an update ~1 ms).
    enumerate_max_nodes : int
        Above the critical friction, steps of systems with at most this many nodes are checked
        by enumerating all ``4^N`` state assignments.
    check_uniqueness : bool
        Compute ``system.critical_friction()`` (once) to certify uniqueness.
    kernel : bool
        Let :func:`~shakedown.solve_cycles` march whole periods in the compiled kernel of
        :mod:`.kernel` (numba), handing back to :meth:`solve` only the steps it cannot finish
        (``False``: every step by :meth:`solve`; same answers to the solver tolerance).
        Ignored for a sparse system (``system.is_sparse``): its steps factorize the
        assignment systems as sparse matrices (SuperLU, cached per assignment like the dense
        LU factors) and compute reactions by sparse products; ``K`` is never densified (only
        the Lemke fallback, for steps the active set cannot finish, works on a dense
        ``K^-1``).  Also off when ``SHAKEDOWN_KERNEL=background`` and numba's cache does not
        hold the compiled kernel yet (:mod:`.kernel_warm`: decided when the solver is made).
    """

    def __init__(self, system: DiscreteSystem, *, feas_tol: float = FEAS_TOL,
                 max_iter: int | None = None, cache_bytes: float = 256e6,
                 max_update_rank: int = 6, update_fraction: float = 0.125,
                 update_min_size: int = 256,
                 enumerate_max_nodes: int = 4, check_uniqueness: bool = True,
                 kernel: bool = True):
        if not isinstance(system, DiscreteSystem):
            raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
        require_two_dimensional(system, "the 2-D step solver (StepSolver)")
        if not (np.isfinite(feas_tol) and 0 < feas_tol < 1):
            raise InputError(f"feas_tol must be in (0, 1); got {feas_tol}")
        self.system = system
        n = self.n = system.n_nodes
        self.A, self.B, self.C = system.A, system.B, system.C
        self.sparse = system.is_sparse
        self.schur = isinstance(system.K, SchurStiffness)  # uncondensed: K never formed
        self.Bt = (system.B.T if self.schur else system.B.T.tocsr() if self.sparse
                   else np.ascontiguousarray(system.B.T))
        self.f = np.asarray(system.friction, float)
        self.K = system.K
        self.diag = system.diagonal()
        self._getrs, self._getrf = get_lapack_funcs(("getrs", "getrf"), (self.diag,))
        self._last_factor = None
        self._all_allowed = np.ones((n, 4), bool)
        self._none_forced = np.zeros(n, bool)
        self._node_range = np.arange(n)
        self._sign_layouts: dict[bytes, tuple] = {}
        self._counters = dict(factorizations=0, updates=0, cache_hits=0)
        self.feas_tol = float(feas_tol)
        self.max_iter = 2 * n + 20 if max_iter is None else int(max_iter)
        self.cache_bytes = float(cache_bytes)
        self.max_update_rank = int(max_update_rank)
        if not (np.isfinite(update_fraction) and 0 <= update_fraction < 1):
            raise InputError(f"update_fraction must be in [0, 1); got {update_fraction}")
        self.update_fraction = float(update_fraction)
        self.update_min_size = int(update_min_size)
        self.enumerate_max_nodes = int(enumerate_max_nodes)
        self.check_uniqueness = bool(check_uniqueness)
        # the kernel is dense; decided here, so that one solver never mixes the two paths
        # (a cold numba cache under SHAKEDOWN_KERNEL=background: Python, see kernel_warm)
        self.kernel = bool(kernel) and not self.sparse and kernel_enabled()
        self._cache: OrderedDict[bytes, _Factor] = OrderedDict()
        self._cache_used = 0
        self._base: _Factor | None = None
        self._accepted: dict[bytes, int] = {}
        self.totals = dict(factorizations=0, updates=0, cache_hits=0, iterations=0,
                           lemke_calls=0, lemke_pivots=0, enumerations=0, steps=0)

    # ------------------------------------------------------------------ uniqueness certificate
    @cached_property
    def critical(self):
        """``system.critical_friction()`` (computed once)."""
        return self.system.critical_friction()

    @cached_property
    def kernel_cache(self):
        """The compiled kernel's cache of assignment inverses (:mod:`.fast_period`)."""
        from .fast_period import KernelCache
        return KernelCache(self.n, self.cache_bytes, self.max_iter)

    @property
    def well_posed(self) -> bool | None:
        """``True`` when the friction is below critical; ``None`` if not checked."""
        return bool(self.critical.well_posed) if self.check_uniqueness else None

    # ------------------------------------------------------------------ the step
    def solve(self, v_prev, q_w, p_w, guess=None, *, base=None, verify=True,
              prediction=None) -> StepResult:
        """One implicit step (arguments validated by :func:`solve_step`).

        Parameters
        ----------
        v_prev, q_w, p_w, guess
            As in :func:`solve_step` (validated arrays).
        base : tuple of ndarray, optional
            ``(q_w + A v_prev, p_w + B^T v_prev)`` when the caller already has them (the
            cycle loop updates them from the previous step's reactions, see
            :meth:`next_base`); computed here otherwise.
        verify : bool
            Recompute the equilibrium residual ``(q, p) - (q_w, p_w) - K (v, w)``
            independently (a product with ``K``).  The cycle loop passes ``False`` and checks
            all steps of a period at once with one matrix-matrix product; the result then has
            ``equilibrium_residual = nan``.
        prediction : ndarray of int8, shape (N,), optional
            The same step's assignment in the previous period: tried first when its factor is
            cached, accepted only strictly inside its checks (:meth:`_probe`); used only where
            the step's answer is unique (friction below critical).
        """
        n = self.n
        self.totals["steps"] += 1
        if base is None and self.schur:  # (A v, B^T v) by one product with K
            r = self.K @ np.concatenate([v_prev, np.zeros(n)])
            q0, p0 = q_w + r[:n], p_w + r[n:]
        elif base is None:
            q0 = q_w + self.A @ v_prev
            p0 = p_w + self.Bt @ v_prev
        else:
            q0, p0 = base
        scale = float(np.abs(np.concatenate((q_w, p_w, q0, p0))).max())
        scale = scale if scale > 0 else 1.0
        if not verify and guess is not None and not self.kernel and not guess.any():
            kept = self._stick_step(v_prev, q0, p0, scale)
            if kept is not None:
                return kept
        if prediction is not None and (self.kernel or self.well_posed is not True):
            prediction = None
        sol = self.solve_mixed(q0, p0, None, guess, scale, prediction)
        allowed = forced = None
        z, q, p, s = sol.z, sol.q, sol.p, sol.s
        method = sol.method
        n_sol, alts = -1, ()
        wp = self.well_posed
        if sol.success and wp:
            status, msg = "unique", "solved; unique (friction below critical)"
        elif n <= self.enumerate_max_nodes and (wp is False or not sol.success):
            sols = self.enumerate_solutions(q0, p0, scale)
            n_sol = len(sols)
            if n_sol == 0:
                status, msg = "no_solution", "no state assignment satisfies the step (enumerated)"
            else:
                if not sol.success:
                    z, q, p, s = sols[0]
                    method = "enumeration"
                ds = 1e3 * self.feas_tol * scale / self.diag
                others = [zz for zz, *_ in sols if np.any(np.abs(zz - z) > ds)]
                alts = tuple(v_prev + zz[:n] for zz in others)
                if n_sol == 1:
                    status, msg = "unique", "solved; unique (all 4^N assignments enumerated)"
                else:
                    status = "multiple_solutions"
                    msg = (f"{n_sol} solutions (friction above critical, factor "
                           f"{self.critical.factor:.4g}); returning the one reached from the "
                           "guess")
        elif sol.success:
            status = "solved"
            msg = ("solved; uniqueness not guaranteed (friction above the critical bound "
                   f"{self.critical.factor:.4g}x)" if wp is False else
                   "solved; uniqueness not checked")
        else:
            status, msg = "failed", "no solution found (active set and Lemke both failed)"
        ok = status in ("unique", "solved", "multiple_solutions")
        return self._result(v_prev, q_w, p_w, z, q, p, s, ok, status, msg, method, sol, scale,
                            allowed, forced, n_sol, alts, verify)

    def _stick_step(self, v_prev, q0, p0, scale):
        """The step of an all-stick guess when it holds, without the active-set machinery.

        Every node stuck is the answer ``z = 0``, ``(q, p) = (q0, p0)`` when its signs hold
        (``p >= -ft``, ``|q| - f p <= ft``: the checks of :meth:`_violations_step` for this
        assignment); the same :class:`StepResult` the general path returns, built directly
        (the steps of a shaken-down period, about half of the default study's steps, issue 25).
        ``None`` when a sign is violated or uniqueness is not certified (the general path then
        decides and words the status)."""
        if self.well_posed is not True:
            return None
        ft = self.feas_tol * scale
        fp = self.f * p0
        slack = min(p0.min(), (fp + q0).min(), (fp - q0).min())
        if not slack >= -ft:  # (NaN included)
            return None
        n = self.n
        self._last_factor = None
        self.totals["iterations"] += 1
        comp = float(max(-slack, 0.0) / scale)
        zero = np.zeros(n)
        return StepResult(
            slip=v_prev + zero, gap=zero.copy(), slip_increment=zero, q=q0.copy(), p=p0.copy(),
            states=np.zeros(n, np.int8), active_set=np.zeros(n, np.int8), success=True,
            status="unique", message="solved; unique (friction below critical)", residual=comp,
            complementarity_residual=comp, equilibrium_residual=float("nan"),
            force_scale=scale, method="active_set", iterations=1, lemke_pivots=0,
            factorizations=0, updates=0, cache_hits=0, n_solutions=-1, alternative_slips=())

    def next_base(self, q, p, gap, dq_w, dp_w):
        """``(q_w' + A v, p_w' + B^T v)`` for the next step from this step's reactions.

        ``q = q_w + A v + B w`` at the end of a step, so the next step's base with welded
        reactions ``q_w' = q_w + dq_w`` is ``q + dq_w - B w`` (only the separated nodes' columns
        of ``B`` and ``C`` are read: ``O(N n_sep)`` instead of a product with ``K``).  Rounding
        accumulates over the steps of one period only: :func:`solve_cycles` recomputes the base
        from scratch at the start of every period, and checks every step's equilibrium.
        """
        n = self.n
        sep = np.flatnonzero(gap)
        q0, p0 = q + dq_w, p + dp_w
        if sep.size and self.schur:
            r = self.K @ np.concatenate([np.zeros(n), gap])
            q0 -= r[:n]
            p0 -= r[n:]
        elif sep.size:
            r = self.K[n + sep].T @ gap[sep] if self.sparse else gap[sep] @ self.K[n + sep]
            q0 -= r[:n]
            p0 -= r[n:]
        return q0, p0

    def _result(self, v_prev, q_w, p_w, z, q, p, s, ok, status, msg, method, sol, scale,
                allowed, forced, n_sol, alts, verify=True):
        n = self.n
        dv, w = z[:n].copy(), z[n:].copy()
        v = v_prev + dv
        comp = self.residuals(z, q, p, allowed, forced, scale)
        if verify:
            r = np.concatenate([q_w, p_w]) + self.K @ np.concatenate([v, w])
            eq = float(max(np.abs(r[:n] - q).max(), np.abs(r[n:] - p).max()) / scale)
        else:
            eq = float("nan")
        states = kinematic_states(dv, w, self.feas_tol * scale / self.diag)
        c = sol.counters
        return StepResult(
            slip=v, gap=w, slip_increment=dv, q=q, p=p, states=states,
            active_set=np.asarray(s, np.int8).copy(), success=bool(ok), status=status,
            message=msg, residual=comp if eq != eq else max(comp, eq),
            complementarity_residual=comp,
            equilibrium_residual=eq, force_scale=scale, method=method,
            iterations=sol.iterations, lemke_pivots=sol.lemke_pivots,
            factorizations=c["factorizations"], updates=c["updates"],
            cache_hits=c["cache_hits"], n_solutions=n_sol, alternative_slips=alts,
        )

_SOLVERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def get_solver(system: DiscreteSystem, **options) -> StepSolver:
    """The cached :class:`StepSolver` of ``system`` (a new one when options are given)."""
    if options:
        return StepSolver(system, **options)
    sol = _SOLVERS.get(system)
    if sol is None:
        sol = _SOLVERS[system] = StepSolver(system)
    return sol


def _vec(name, value, n, *, nonneg=False):
    return check_node_vector(name, value, n, nonneg=nonneg)


def parse_states(guess, n: int) -> np.ndarray:
    """State codes from codes or names (:data:`STATE_NAMES`), shape (N,)."""
    arr = np.asarray(guess)
    if arr.shape != (n,):
        raise ShapeError(f"guess must have shape ({n},); got {arr.shape}")
    if arr.dtype.kind in "US":
        lookup = {s: i for i, s in enumerate(STATE_NAMES)}
        try:
            return np.array([lookup[str(x)] for x in arr], np.int8)
        except KeyError as exc:
            raise InputError(f"guess states must be among {STATE_NAMES}; got {exc}") from None
    codes = np.asarray(arr, int)
    if np.any((codes < 0) | (codes > 3)):
        raise InputError(
            f"guess codes must be 0..3 ({STATE_NAMES}); got {codes.min()}..{codes.max()}"
        )
    return codes.astype(np.int8)


def solve_step(system: DiscreteSystem, v_prev, q_w, p_w, guess=None, *, solver=None,
               **options) -> StepResult:
    """The implicit quasi-static step of MODEL.md s.4 (see the module docstring).

    Parameters
    ----------
    system : DiscreteSystem
    v_prev : array_like, shape (N,)
        Slips at the start of the step [length].
    q_w, p_w : array_like, shape (N,)
        Welded reactions at the end of the step [force].
    guess : array_like, shape (N,), optional
        Initial state assignment (codes 0..3 or names of :data:`STATE_NAMES`), e.g. the
        previous step's ``active_set``; all stick by default.
    solver : StepSolver, optional
        Reuse this solver (and its factorizations); by default one cached per system.
    **options
        Passed to :class:`StepSolver` (a fresh solver is built).

    Returns
    -------
    StepResult

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> r = sd.solve_step(s, [0.0], [-2.0], [2.0])   # push F = 2 > f p = 1: forward slip
    >>> r.status, float(r.slip[0]), float(r.q[0])
    ('unique', 1.0, -1.0)
    """
    if not isinstance(system, DiscreteSystem):
        raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
    n = system.n_nodes
    v_prev = _vec("v_prev", v_prev, n)
    q_w = _vec("q_w", q_w, n)
    p_w = _vec("p_w", p_w, n)
    g = None if guess is None else parse_states(guess, n)
    if solver is None:
        solver = get_solver(system, **options)
    elif solver.system is not system:
        raise InputError("solver was built for another system; pass solver=None")
    with single_blas_thread():  # small solves: see shakedown/model/threads.py
        return solver.solve(v_prev, q_w, p_w, g)
