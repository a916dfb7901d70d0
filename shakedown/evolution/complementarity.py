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
bytes) and an assignment within ``max_update_rank`` changed nodes of the last factorized one is
solved by a Sherman-Morrison-Woodbury update of it, so a step in which few nodes change state
costs a few triangular solves instead of a factorization.  Every answer is verified (natural
complementarity residuals, scaled per node) and the outcome is a status: below the critical
friction (``system.critical_friction()``) the solution is ``"unique"``; above it, for
``N <= enumerate_max_nodes`` every state assignment is enumerated and the step is classified
``"unique"``, ``"multiple_solutions"`` or ``"no_solution"``; otherwise it is ``"solved"``
(uniqueness not guaranteed) or ``"failed"``.

The same machinery solves the *rate* problems of the event-driven evolution (some nodes are
held in one state, some may take a subset of the states): :meth:`StepSolver.solve_mixed`.
"""

from __future__ import annotations

import itertools
import warnings
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg as sla
from scipy.linalg.lapack import dgecon

from ..model.errors import InputError, ShapeError
from ..model.system import DiscreteSystem
from ..model.validation import check_node_vector
from .lemke import lemke

STICK, FORWARD, BACKWARD, SEPARATED = 0, 1, 2, 3
#: Names of the node states, indexed by their codes (also the ``state`` column of tables).
STATE_NAMES = ("stick", "forward", "backward", "separation")

#: Default relative feasibility tolerance: a force is "zero" below ``FEAS_TOL * force_scale``,
#: a slip or gap of node ``j`` below ``FEAS_TOL * force_scale / K_jj``.  LU solves of the
#: systems met here are accurate to ~1e-13 relative; 1e-9 leaves room for ill-conditioning
#: (stiffness ratios 1e8) without accepting visible sign violations.
FEAS_TOL = 1e-9

ALL_ALLOWED = np.ones(4, bool)


@dataclass(frozen=True, eq=False)
class StepResult:
    """One implicit step (see module docstring).

    Attributes
    ----------
    slip, gap : ndarray, shape (N,)
        ``v = v_prev + dv`` and ``w`` at the end of the step [length].
    slip_increment : ndarray, shape (N,)
        ``dv``.
    q, p : ndarray, shape (N,)
        Tangential and normal reactions at the end of the step [force] (compression ``p > 0``).
    states : ndarray of int8, shape (N,)
        Kinematic node states (codes of :data:`STATE_NAMES`): separated if ``w_j`` exceeds its
        tolerance, else forward/backward if ``|dv_j|`` does, else stick.
    active_set : ndarray of int8, shape (N,)
        The state assignment whose linear system produced the answer (a node at the friction
        limit with ``dv = 0`` may be "forward" here and "stick" in ``states``); pass it as
        ``guess`` to the next step.
    success : bool
        A solution was found and verified.
    status : str
        ``"unique"`` (guaranteed by friction below critical, or by enumeration),
        ``"solved"`` (found; uniqueness not guaranteed: friction above the sufficient bound of a
        large system), ``"multiple_solutions"`` (enumeration found several; ``slip`` is the one
        the active-set path reached, the others are in ``alternative_slips``),
        ``"no_solution"`` (enumeration proves none exists), ``"failed"`` (none found, existence
        undecided).
    message : str
    residual : float
        ``max(complementarity_residual, equilibrium_residual)``.
    complementarity_residual : float
        Largest natural residual ``|min(x, y)|`` over the pairs ``(w, p)``, ``(dv+, f p + q)``,
        ``(dv-, f p - q)``, forces scaled by ``force_scale``, slips and gaps of node ``j`` by
        ``force_scale / K_jj`` (dimensionless).
    equilibrium_residual : float
        ``max |(q, p) - (q_w, p_w) - K (v, w)| / force_scale``, recomputed independently.
    force_scale : float
        ``max |(q_w, p_w, q_w + A v_prev, p_w + B^T v_prev)|``.
    method : {"active_set", "lemke", "enumeration", "none"}
    iterations, lemke_pivots, factorizations, updates, cache_hits : int
        Active-set iterations, Lemke pivots, fresh LU factorizations, low-rank (Woodbury)
        solves and LU-cache hits spent on this step.
    n_solutions : int
        Distinct solutions found by enumeration, ``-1`` when not enumerated.
    alternative_slips : tuple of ndarray
        The other solutions' slips when several exist.
    """

    slip: np.ndarray
    gap: np.ndarray
    slip_increment: np.ndarray
    q: np.ndarray
    p: np.ndarray
    states: np.ndarray
    active_set: np.ndarray
    success: bool
    status: str
    message: str
    residual: float
    complementarity_residual: float
    equilibrium_residual: float
    force_scale: float
    method: str
    iterations: int = 0
    lemke_pivots: int = 0
    factorizations: int = 0
    updates: int = 0
    cache_hits: int = 0
    n_solutions: int = -1
    alternative_slips: tuple = field(default=(), repr=False)

    @property
    def state_names(self) -> np.ndarray:
        """``states`` as strings (:data:`STATE_NAMES`)."""
        return np.asarray(STATE_NAMES)[self.states]


@dataclass
class _Factor:
    key: bytes
    s: np.ndarray  # assignment
    free: np.ndarray  # indices into z = (dv, w) of the unknowns (= indices of the K-rows)
    coef: np.ndarray  # per free a-row: 0 (separated) or +-f (slip)
    jv: np.ndarray  # nodes with a slip unknown
    jw: np.ndarray  # nodes with a gap unknown
    lu: tuple
    nbytes: int


@dataclass
class MixedSolution:
    """Raw answer of :meth:`StepSolver.solve_mixed` (internal; fields as in StepResult)."""

    s: np.ndarray
    z: np.ndarray
    q: np.ndarray
    p: np.ndarray
    success: bool
    method: str
    iterations: int
    lemke_pivots: int
    counters: dict


class StepSolver:
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
        Largest number of changed nodes solved by a Woodbury update instead of a new LU.
    update_min_size : int
        Woodbury updates are used only when the factorized system has at least this many
        unknowns; below it a fresh LU (cached for the next visit) is cheaper than the update's
        Python overhead (measured: an LU of order 200 costs ~0.3 ms, an update ~1 ms).
    enumerate_max_nodes : int
        Above the critical friction, steps of systems with at most this many nodes are checked
        by enumerating all ``4^N`` state assignments.
    check_uniqueness : bool
        Compute ``system.critical_friction()`` (once) to certify uniqueness.
    """

    def __init__(self, system: DiscreteSystem, *, feas_tol: float = FEAS_TOL,
                 max_iter: int | None = None, cache_bytes: float = 256e6,
                 max_update_rank: int = 6, update_min_size: int = 256,
                 enumerate_max_nodes: int = 4, check_uniqueness: bool = True):
        if not isinstance(system, DiscreteSystem):
            raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
        if not (np.isfinite(feas_tol) and 0 < feas_tol < 1):
            raise InputError(f"feas_tol must be in (0, 1); got {feas_tol}")
        self.system = system
        n = self.n = system.n_nodes
        self.A, self.B, self.C = system.A, system.B, system.C
        self.Bt = np.ascontiguousarray(system.B.T)
        self.f = np.asarray(system.friction, float)
        self.diag = np.concatenate([np.diag(self.A), np.diag(self.C)])
        self.feas_tol = float(feas_tol)
        self.max_iter = 2 * n + 20 if max_iter is None else int(max_iter)
        self.cache_bytes = float(cache_bytes)
        self.max_update_rank = int(max_update_rank)
        self.update_min_size = int(update_min_size)
        self.enumerate_max_nodes = int(enumerate_max_nodes)
        self.check_uniqueness = bool(check_uniqueness)
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

    @property
    def well_posed(self) -> bool | None:
        """``True`` when the friction is below critical; ``None`` if not checked."""
        return bool(self.critical.well_posed) if self.check_uniqueness else None

    # ------------------------------------------------------------------ K blocks
    def _Kq(self, rows, cols):
        """Rows ``rows`` of ``dq/dz`` (``z = (dv, w)``), columns ``cols`` (indices into z)."""
        n = self.n
        out = np.empty((len(rows), len(cols)))
        mv = cols < n
        out[:, mv] = self.A[np.ix_(rows, cols[mv])]
        out[:, ~mv] = self.B[np.ix_(rows, cols[~mv] - n)]
        return out

    def _Kp(self, rows, cols):
        n = self.n
        out = np.empty((len(rows), len(cols)))
        mv = cols < n
        out[:, mv] = self.Bt[np.ix_(rows, cols[mv])]
        out[:, ~mv] = self.C[np.ix_(rows, cols[~mv] - n)]
        return out

    def _layout(self, s):
        """Free unknowns (indices into z) and the row coefficients of assignment ``s``."""
        n = self.n
        jv = np.flatnonzero(s != STICK)
        jw = np.flatnonzero(s == SEPARATED)
        sv = s[jv]
        coef = np.where(sv == FORWARD, self.f[jv], np.where(sv == BACKWARD, -self.f[jv], 0.0))
        return np.concatenate([jv, n + jw]), coef, jv, jw

    def _G_rows(self, s, free, coef, jv, jw, cols):
        """Rows of the assignment's equations (a-rows ``q + c p``, b-rows ``p``) at ``cols``."""
        top = self._Kq(jv, cols) + coef[:, None] * self._Kp(jv, cols)
        return np.vstack([top, self._Kp(jw, cols)])

    def _rhs(self, coef, jv, jw, q0, p0):
        return -np.concatenate([q0[jv] + coef * p0[jv], p0[jw]])

    # ------------------------------------------------------------------ factorizations
    def _factor(self, s, key):
        free, coef, jv, jw = self._layout(s)
        Ms = self._G_rows(s, free, coef, jv, jw, free)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lu = sla.lu_factor(Ms, check_finite=False)
            anorm = np.abs(Ms).sum(axis=0).max()
            rcond = dgecon(lu[0], anorm, norm="1")[0]
        self.totals["factorizations"] += 1
        self._counters["factorizations"] += 1
        if not np.isfinite(rcond) or rcond < 1e-14:
            return None
        F = _Factor(key, s.copy(), free, coef, jv, jw, lu, Ms.nbytes)
        self._cache[key] = F
        self._cache_used += F.nbytes
        while self._cache_used > self.cache_bytes and len(self._cache) > 1:
            _, old = self._cache.popitem(last=False)
            self._cache_used -= old.nbytes
        self._base = F
        return F

    def _full_solve(self, F: _Factor, rhs):
        """Solve ``G_s z = rhs`` (full 2N system of assignment ``F.s``); rhs shape (2N, k)."""
        n2 = 2 * self.n
        Z = np.zeros((n2, rhs.shape[1]))
        fixed = np.ones(n2, bool)
        fixed[F.free] = False
        Z[fixed] = rhs[fixed]
        red = rhs[F.free].copy()
        nzc = np.flatnonzero(fixed & np.any(rhs != 0, axis=1))
        if nzc.size and F.free.size:
            red -= self._G_rows(F.s, F.free, F.coef, F.jv, F.jw, nzc) @ Z[nzc]
        if F.free.size:
            Z[F.free] = sla.lu_solve(F.lu, red, check_finite=False)
        return Z

    def _full_rhs(self, s, q0, p0):
        n = self.n
        h = np.zeros(2 * n)
        c = np.where(s == FORWARD, self.f, np.where(s == BACKWARD, -self.f, 0.0))
        a = s != STICK
        h[:n][a] = -(q0[a] + c[a] * p0[a])
        b = s == SEPARATED
        h[n:][b] = -p0[b]
        return h

    def _rows_full(self, s, rows):
        """Full rows (length 2N) ``rows`` of the assignment's system ``G_s``."""
        n = self.n
        G = np.zeros((len(rows), 2 * n))
        for i, r in enumerate(rows):
            j = int(r) % n
            if r < n and s[j] != STICK:
                c = self.f[j] if s[j] == FORWARD else (-self.f[j] if s[j] == BACKWARD else 0.0)
                G[i, :n] = self.A[j] + c * self.Bt[j]
                G[i, n:] = self.B[j] + c * self.C[j]
            elif r >= n and s[j] == SEPARATED:
                G[i, :n] = self.Bt[j]
                G[i, n:] = self.C[j]
            else:
                G[i, r] = 1.0
        return G

    def _woodbury(self, F: _Factor, s, q0, p0):
        """Solve assignment ``s`` from the factors of ``F.s`` by a low-rank correction.

        ``G_s = G_F + E D^T`` differs in the rows of the changed nodes; Sherman-Morrison-Woodbury
        ``z = x0 - Y (I + D^T Y)^-1 D^T x0`` with ``x0 = G_F^-1 h_s``, ``Y = G_F^-1 E``.
        """
        n = self.n
        changed = np.flatnonzero(s != F.s)
        rows = np.concatenate([changed, n + changed])
        DT = self._rows_full(s, rows) - self._rows_full(F.s, rows)
        keep = np.any(DT != 0, axis=1)
        rows, DT = rows[keep], DT[keep]
        E = np.zeros((2 * n, rows.size + 1))
        E[rows, np.arange(rows.size)] = 1.0
        E[:, -1] = self._full_rhs(s, q0, p0)
        Y = self._full_solve(F, E)
        Y, x0 = Y[:, :-1], Y[:, -1]
        cap = np.eye(rows.size) + DT @ Y
        if np.linalg.cond(cap) > 1e10:
            return None
        z = x0 - Y @ np.linalg.solve(cap, DT @ x0)
        z[:n][s == STICK] = 0.0
        z[n:][s != SEPARATED] = 0.0
        self.totals["updates"] += 1
        self._counters["updates"] += 1
        return z

    def _solve_set(self, s, q0, p0, scale):
        """``z = (dv, w)`` of assignment ``s``; ``None`` if its matrix is singular."""
        n = self.n
        if not np.any(s != STICK):
            return np.zeros(2 * n)
        key = s.tobytes()
        F = self._cache.get(key)
        if F is not None:
            self._cache.move_to_end(key)
            self.totals["cache_hits"] += 1
            self._counters["cache_hits"] += 1
            self._base = F
            z = np.zeros(2 * n)
            z[F.free] = sla.lu_solve(F.lu, self._rhs(F.coef, F.jv, F.jw, q0, p0),
                                     check_finite=False)
            return z
        B0 = self._base
        if (B0 is not None and B0.free.size >= self.update_min_size
                and np.count_nonzero(s != B0.s) <= self.max_update_rank):
            z = self._woodbury(B0, s, q0, p0)
            if z is not None and self._equations_ok(s, z, q0, p0, scale):
                return z
        F = self._factor(s, key)
        if F is None:
            return None
        z = np.zeros(2 * n)
        z[F.free] = sla.lu_solve(F.lu, self._rhs(F.coef, F.jv, F.jw, q0, p0),
                                 check_finite=False)
        return z

    def _remember(self, s, key):
        """Factorize (and cache) an accepted assignment the second time it is accepted.

        Assignments solved by a Woodbury update are not cached; one that recurs (the same set
        over consecutive steps, or the same step of the next period on the way to a steady
        cycle) is worth one LU so that later visits are plain cache hits.
        """
        if key in self._cache or not np.any(s != STICK):
            return
        count = self._accepted.get(key, 0) + 1
        if len(self._accepted) > 100000:
            self._accepted.clear()
        self._accepted[key] = count
        m = np.count_nonzero(s != STICK) + np.count_nonzero(s == SEPARATED)
        if count >= 2 and self._cache_used + 8.0 * m * m <= self.cache_bytes:  # no thrashing
            base = self._base
            self._factor(s, key)
            self._base = base if base is not None else self._base

    def _equations_ok(self, s, z, q0, p0, scale):
        q, p = self._reactions(z, q0, p0)
        c = np.where(s == FORWARD, self.f, np.where(s == BACKWARD, -self.f, 0.0))
        a = s != STICK
        b = s == SEPARATED
        err = max(np.abs(q[a] + c[a] * p[a]).max(initial=0.0), np.abs(p[b]).max(initial=0.0))
        return err <= 1e-3 * self.feas_tol * scale

    def _reactions(self, z, q0, p0):
        n = self.n
        iv = np.flatnonzero(z[:n])
        iw = np.flatnonzero(z[n:])
        if iv.size + iw.size > n // 4:  # dense products beat column gathers
            zv, zw = z[:n], z[n:]
            return q0 + self.A @ zv + self.B @ zw, p0 + self.Bt @ zv + self.C @ zw
        q = q0 + self.A[:, iv] @ z[iv] + self.B[:, iw] @ z[n + iw]
        p = p0 + self.Bt[:, iv] @ z[iv] + self.C[:, iw] @ z[n + iw]
        return q, p

    # ------------------------------------------------------------------ sign checks
    def _violations(self, s, z, q, p, allowed, forced, ft, dtol):
        """Normalised violation (> 1: violated) and target state per node."""
        n = self.n
        dv, w = z[:n], z[n:]
        f = self.f
        sp, sm = f * p + q, f * p - q
        cand = np.full((n, 4), -np.inf)  # magnitude of the violation that points to state k
        dvt, dwt = dtol[:n], dtol[n:]
        isS, isF, isB, isO = (s == STICK), (s == FORWARD), (s == BACKWARD), (s == SEPARATED)
        cand[:, SEPARATED] = np.where(~isO & allowed[:, SEPARATED], -p / ft, -np.inf)
        cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sp / ft, -np.inf)
        cand[:, BACKWARD] = np.where(isS & allowed[:, BACKWARD], -sm / ft, -np.inf)
        back = np.where(isF, -dv / dvt, np.where(isB, dv / dvt, np.where(isO, -w / dwt, -np.inf)))
        cand[:, STICK] = np.where(allowed[:, STICK], back, -np.inf)
        cand[forced] = -np.inf
        target = np.argmax(cand, axis=1).astype(np.int8)
        mag = cand[np.arange(n), target]
        return mag, target

    def residuals(self, z, q, p, allowed, forced, scale):
        """Natural complementarity residual of an answer (dimensionless; see StepResult).

        ``allowed=None`` / ``forced=None``: the step problem (every state allowed).
        """
        n = self.n
        dv, w = z[:n], z[n:]
        f = self.f
        ds = scale / self.diag
        xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(-dv, 0) / ds[:n])
        fp = f * p
        ys = (p / scale, (fp + q) / scale, (fp - q) / scale)
        if allowed is None:
            return float(np.abs(np.minimum(np.concatenate(xs), np.concatenate(ys))).max())
        res = 0.0
        free_nodes = ~forced
        for k, (x, y) in enumerate(zip(xs, ys, strict=True)):
            state = (SEPARATED, FORWARD, BACKWARD)[k]
            m = free_nodes & allowed[:, state]
            if np.any(m):
                res = max(res, float(np.abs(np.minimum(x[m], y[m])).max()))
            m2 = free_nodes & ~allowed[:, state]  # variable absent: must be zero
            if np.any(m2):
                res = max(res, float(np.abs(x[m2]).max()))
        fo = forced & allowed[:, SEPARATED]
        if np.any(fo):
            res = max(res, float(np.abs(np.concatenate([q[fo], p[fo]])).max() / scale))
        return res

    # ------------------------------------------------------------------ the mixed problem
    def solve_mixed(self, q0, p0, allowed=None, guess=None, scale=None) -> MixedSolution:
        """Solve the step (or rate) problem with base reactions ``(q0, p0)`` at ``z = 0``.

        ``allowed`` (N, 4) bool: the states each node may take (rows with a single ``True`` are
        held in that state with no sign check: the interior nodes of a rate problem).
        """
        n = self.n
        allowed = np.ones((n, 4), bool) if allowed is None else np.asarray(allowed, bool)
        forced = allowed.sum(axis=1) == 1
        if scale is None:
            scale = float(max(np.abs(q0).max(initial=0), np.abs(p0).max(initial=0)))
        scale = scale if scale > 0 else 1.0
        ft = self.feas_tol * scale
        dtol = ft / self.diag
        s = np.zeros(n, np.int8) if guess is None else np.array(guess, np.int8)
        bad = ~allowed[np.arange(n), s]
        s[bad] = np.argmax(allowed[bad], axis=1)
        self._counters = dict(factorizations=0, updates=0, cache_hits=0)
        visited = set()
        single = False
        it = 0
        while it < self.max_iter:
            it += 1
            key = s.tobytes()
            if key in visited:
                if single:
                    break
                single, visited = True, set()
            visited.add(key)
            z = self._solve_set(s, q0, p0, scale)
            if z is None:
                break
            q, p = self._reactions(z, q0, p0)
            mag, target = self._violations(s, z, q, p, allowed, forced, ft, dtol)
            if mag.max(initial=-np.inf) <= 1.0:
                self._remember(s, key)
                self.totals["iterations"] += it
                return MixedSolution(s, z, q, p, True, "active_set", it, 0, self._counters)
            idx = np.flatnonzero(mag > 1.0) if not single else [int(np.argmax(mag))]
            s = s.copy()
            s[idx] = target[idx]
        self.totals["iterations"] += it
        if not np.any(forced) and np.all(allowed):
            sol = self._lemke_flexibility(q0, p0, scale)
        else:
            free = np.flatnonzero(~forced)
            n_assign = float(np.prod(allowed[free].sum(axis=1).astype(float)))
            sol = (self._enumerate_mixed(q0, p0, allowed, forced, scale) if n_assign <= 4096
                   else self._lemke(q0, p0, allowed, forced, scale))
        sol.iterations = it
        return sol

    @cached_property
    def flexibility(self) -> np.ndarray:
        """``G = K^-1`` (computed once, only when the Lemke fallback is needed)."""
        K = np.block([[self.A, self.B], [self.Bt, self.C]])
        return sla.cho_solve(sla.cho_factor(K), np.eye(2 * self.n))

    def _lemke_flexibility(self, q0, p0, scale) -> MixedSolution:
        """Lemke on the reaction-based LCP of the step, which is copositive for any friction.

        Unknowns ``x = (p, b+, b-, lam) >= 0`` with ``q = b+ - b-`` and ``(dv, w) = G (r - r0)``,
        ``G = K^-1``; complementary slacks ``w``, ``lam + dv``, ``lam - dv``, ``f p - b+ - b-``
        (the quasi-static analogue of the Stewart-Trinkle formulation).  ``x^T M x = r^T G r +
        lam^T F p >= 0`` for ``x >= 0``, and a secondary ray would need ``q^T x < 0`` on a
        direction with ``r = 0``, which the constant terms exclude; so lexicographic Lemke ends
        with a solution (Cottle, Pang & Stone 1992, Thm 4.4.13 argument as in Anitescu & Potra
        1997).
        """
        n = self.n
        self.totals["lemke_calls"] += 1
        G = self.flexibility
        c = -G @ np.concatenate([q0, p0])
        Gvq, Gvp, Gwq, Gwp = G[:n, :n], G[:n, n:], G[n:, :n], G[n:, n:]
        I, Z = np.eye(n), np.zeros((n, n))
        M = np.block([
            [Gwp, Gwq, -Gwq, Z],
            [Gvp, Gvq, -Gvq, I],
            [-Gvp, -Gvq, Gvq, I],
            [np.diag(self.f), -I, -I, Z],
        ])
        qv = np.concatenate([c[n:], c[:n], -c[:n], np.zeros(n)])
        # scale rows (displacements by K_jj) so that Lemke's tolerances are relative
        rs = np.concatenate([self.diag[n:], self.diag[:n], self.diag[:n], np.ones(n)])
        res = lemke(rs[:, None] * M, rs * qv)
        self.totals["lemke_pivots"] += res.pivots
        x = res.z
        p = x[:n]
        q = x[n:2 * n] - x[2 * n:3 * n]
        z = G @ (np.concatenate([q, p]) - np.concatenate([q0, p0]))
        allowed = np.ones((n, 4), bool)
        forced = np.zeros(n, bool)
        dtol = self.feas_tol * scale / self.diag
        s = kinematic_states(z[:n], z[n:], dtol)
        # re-solve with the assignment (clean answer, cached factors) when it verifies
        z2 = self._solve_set(s, q0, p0, scale)
        if z2 is not None:
            q2, p2 = self._reactions(z2, q0, p0)
            if self.residuals(z2, q2, p2, allowed, forced, scale) <= self.feas_tol:
                z = z2
        q, p = self._reactions(z, q0, p0)
        ok = res.success and self.residuals(z, q, p, allowed, forced, scale) <= 10 * self.feas_tol
        return MixedSolution(s, z, q, p, bool(ok), "lemke", 0, res.pivots, self._counters)

    def _enumerate_mixed(self, q0, p0, allowed, forced, scale) -> MixedSolution:
        """Try every assignment of the non-held nodes (rate problems: few boundary nodes)."""
        n = self.n
        free = np.flatnonzero(~forced)
        base = np.argmax(allowed, axis=1).astype(np.int8)
        choices = [np.flatnonzero(allowed[j]) for j in free]
        best = None
        for combo in itertools.product(*choices):
            s = base.copy()
            s[free] = combo
            z = self._solve_set(s, q0, p0, scale)
            if z is None:
                continue
            q, p = self._reactions(z, q0, p0)
            r = self.residuals(z, q, p, allowed, forced, scale)
            if best is None or r < best[0]:
                best = (r, s, z, q, p)
            if r <= self.feas_tol:
                break
        if best is None:
            z = np.zeros(2 * n)
            q, p = self._reactions(z, q0, p0)
            return MixedSolution(base, z, q, p, False, "enumeration", 0, 0, self._counters)
        r, s, z, q, p = best
        return MixedSolution(s, z, q, p, bool(r <= self.feas_tol), "enumeration", 0, 0,
                             self._counters)

    def _lemke(self, q0, p0, allowed, forced, scale) -> MixedSolution:
        """Lexicographic Lemke on the LCP in (w, dv+, dv-) after condensing held-open nodes."""
        n = self.n
        self.totals["lemke_calls"] += 1
        held_open = forced & allowed[:, SEPARATED]
        act = np.flatnonzero(~forced)
        o = np.flatnonzero(held_open)
        ocols = np.concatenate([o, n + o])
        acols = np.concatenate([act, n + act])
        r0 = np.concatenate([q0, p0])
        Kaa = np.vstack([self._Kq(act, acols), self._Kp(act, acols)])
        ra = r0[acols]
        if o.size:
            Kao = np.vstack([self._Kq(act, ocols), self._Kp(act, ocols)])
            Koo = np.vstack([self._Kq(o, ocols), self._Kp(o, ocols)])
            Koa = np.vstack([self._Kq(o, acols), self._Kp(o, acols)])
            X = np.linalg.solve(Koo, np.column_stack([Koa, r0[ocols]]))
            Kaa = Kaa - Kao @ X[:, :-1]
            ra = ra - Kao @ X[:, -1]
        m = act.size
        fa = self.f[act]
        Qv, Qw, Pv, Pw = Kaa[:m, :m], Kaa[:m, m:], Kaa[m:, :m], Kaa[m:, m:]
        qa, pa = ra[:m], ra[m:]
        # rows: p, f p + q, f p - q ; columns: g (gap), a (dv+), b (dv-)
        Rv = [Pv, fa[:, None] * Pv + Qv, fa[:, None] * Pv - Qv]
        Rw = [Pw, fa[:, None] * Pw + Qw, fa[:, None] * Pw - Qw]
        Mfull = np.block([[Rw[i], Rv[i], -Rv[i]] for i in range(3)])
        qfull = np.concatenate([pa, fa * pa + qa, fa * pa - qa])
        use = np.concatenate([allowed[act, SEPARATED], allowed[act, FORWARD],
                              allowed[act, BACKWARD]])
        idx = np.flatnonzero(use)
        res = lemke(Mfull[np.ix_(idx, idx)], qfull[idx])
        self.totals["lemke_pivots"] += res.pivots
        x = np.zeros(3 * m)
        x[idx] = res.z
        basic = np.zeros(3 * m, bool)
        nb = res.basis[(res.basis >= idx.size) & (res.basis < 2 * idx.size)] - idx.size
        basic[idx[nb]] = True
        s = np.zeros(n, np.int8)
        s[held_open] = SEPARATED
        sa = np.where(basic[:m] | (x[:m] > 0), SEPARATED,
                      np.where(basic[m:2 * m], FORWARD, np.where(basic[2 * m:], BACKWARD, STICK)))
        s[act] = sa
        z = np.zeros(2 * n)
        za = np.concatenate([x[m:2 * m] - x[2 * m:], x[:m]])
        z[acols] = za
        if o.size:
            z[ocols] = -(X[:, -1] + X[:, :-1] @ za)
        ok = res.success
        if ok:  # re-solve with the assignment read off the basis (clean answer, cached factors)
            z2 = self._solve_set(s, q0, p0, scale)
            if z2 is not None:
                q2, p2 = self._reactions(z2, q0, p0)
                if self.residuals(z2, q2, p2, allowed, forced, scale) <= self.feas_tol:
                    z = z2
        q, p = self._reactions(z, q0, p0)
        ok = ok and self.residuals(z, q, p, allowed, forced, scale) <= 10 * self.feas_tol
        return MixedSolution(s, z, q, p, bool(ok), "lemke", 0, res.pivots, self._counters)

    def enumerate_solutions(self, q0, p0, scale):
        """Every solution of the step problem, by trying all ``4^N`` assignments."""
        n = self.n
        self.totals["enumerations"] += 1
        allowed = np.ones((n, 4), bool)
        forced = np.zeros(n, bool)
        sols = []
        ds = scale / self.diag
        for combo in itertools.product(range(4), repeat=n):
            s = np.array(combo, np.int8)
            free, coef, jv, jw = self._layout(s)
            z = np.zeros(2 * n)
            if free.size:
                Ms = self._G_rows(s, free, coef, jv, jw, free)
                try:
                    z[free] = np.linalg.solve(Ms, self._rhs(coef, jv, jw, q0, p0))
                except np.linalg.LinAlgError:
                    continue
            q, p = self._reactions(z, q0, p0)
            if self.residuals(z, q, p, allowed, forced, scale) <= self.feas_tol:
                if not any(np.all(np.abs(z - z2) <= 1e3 * self.feas_tol * ds) for z2, *_ in sols):
                    sols.append((z, q, p, s))
        return sols

    # ------------------------------------------------------------------ the step
    def solve(self, v_prev, q_w, p_w, guess=None) -> StepResult:
        """One implicit step (arguments validated by :func:`solve_step`)."""
        n = self.n
        self.totals["steps"] += 1
        q0 = q_w + self.A @ v_prev
        p0 = p_w + self.Bt @ v_prev
        scale = float(max(np.abs(q_w).max(), np.abs(p_w).max(), np.abs(q0).max(),
                          np.abs(p0).max()))
        scale = scale if scale > 0 else 1.0
        sol = self.solve_mixed(q0, p0, None, guess, scale)
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
                            allowed, forced, n_sol, alts)

    def _result(self, v_prev, q_w, p_w, z, q, p, s, ok, status, msg, method, sol, scale,
                allowed, forced, n_sol, alts):
        n = self.n
        dv, w = z[:n].copy(), z[n:].copy()
        v = v_prev + dv
        comp = self.residuals(z, q, p, allowed, forced, scale)
        qe = q_w + self.A @ v + self.B @ w
        pe = p_w + self.Bt @ v + self.C @ w
        eq = float(max(np.abs(qe - q).max(), np.abs(pe - p).max()) / scale)
        states = kinematic_states(dv, w, self.feas_tol * scale / self.diag)
        c = sol.counters
        return StepResult(
            slip=v, gap=w, slip_increment=dv, q=q, p=p, states=states,
            active_set=np.asarray(s, np.int8).copy(), success=bool(ok), status=status,
            message=msg, residual=max(comp, eq), complementarity_residual=comp,
            equilibrium_residual=eq, force_scale=scale, method=method,
            iterations=sol.iterations, lemke_pivots=sol.lemke_pivots,
            factorizations=c["factorizations"], updates=c["updates"],
            cache_hits=c["cache_hits"], n_solutions=n_sol, alternative_slips=alts,
        )


def kinematic_states(dv, w, dtol):
    """State codes from increments: separated if ``w > dtol_w``, else by the sign of ``dv``.

    ``dtol`` has shape (2N,) (slip tolerances, then gap tolerances).
    """
    n = dv.shape[-1]
    st = np.where(dv > dtol[:n], FORWARD, np.where(dv < -dtol[:n], BACKWARD, STICK))
    return np.where(w > dtol[n:], SEPARATED, st).astype(np.int8)


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
    return solver.solve(v_prev, q_w, p_w, g)
