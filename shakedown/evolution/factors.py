"""LU factor cache and low-rank updates of the step's linear systems (MODEL.md s.4).

A node-state assignment ``s`` fixes two of ``(dv_j, w_j, q_j + s f_j p_j, p_j)`` per node and
leaves a square system ``M_s x = h`` in the slips of the non-stick nodes and the gaps of the
separated ones.  :class:`FactorCache` (a mixin of :class:`~.complementarity.StepSolver`) keeps
LU factors per assignment (LRU, bounded in bytes) and solves an assignment within
``max(max_update_rank, update_fraction * m)`` changed nodes of the last factorized one by a
Sherman-Morrison-Woodbury update of it (refactorized when the update would cost more).

With the compiled kernel available (``StepSolver(kernel=True)``, the default), every
assignment system is solved by the kernel's inverse cache and block updates instead
(:meth:`FactorCache._kernel_solve`, :mod:`.kernel`): the Python step, the steps the period loop
hands back, and the rate problems of the event-driven path then share the kernel's
factorizations; the LU cache here serves ``kernel=False``.

A sparse system (``system.is_sparse``) takes the same path with sparse matrices: an
assignment's system is gathered from the rows of the CSR ``K`` and factorized by SuperLU
(COLAMD ordering, partial pivoting) and the factor cached like a dense LU; no Woodbury updates
(a fresh sparse factor is cheaper: 0.6-1.5 ms against ~10 ms at N = 2000, see
``benchmarks/RESULTS_sparse.md``), and the reactions are one sparse product ``K z``.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg.lapack import dgecon

from . import kernel as _kernel
from . import schur_step
from .step_types import BACKWARD, FORWARD, SEPARATED, STICK, _Factor

#: ``_last_factor`` of an answer solved by the compiled kernel (its reactions are kept).
_KERNEL = object()
#: ``_last_factor`` of an answer solved with the interior DOFs (its reactions are kept).
_SCHUR = object()


class FactorCache:
    """Mixin: the assignment systems, their LU cache and Woodbury updates (see module doc)."""

    # ------------------------------------------------------------------ K blocks
    def _Kq(self, rows, cols):
        """Rows ``rows`` of ``dq/dz`` (``z = (dv, w)``), columns ``cols`` (indices into z);
        dense (the pivoting fallbacks' use)."""
        return self._dense(self.K[np.ix_(rows, cols)])

    def _Kp(self, rows, cols):
        """Rows ``rows`` of ``dp/dz``, columns ``cols`` (dense)."""
        return self._dense(self.K[np.ix_(self.n + np.asarray(rows, int), cols)])

    @staticmethod
    def _dense(M):
        return M.toarray() if sp.issparse(M) else M

    def _layout(self, s):
        """Free unknowns (indices into z) and the row coefficients of assignment ``s``."""
        n = self.n
        jv = np.flatnonzero(s != STICK)
        jw = np.flatnonzero(s == SEPARATED)
        sv = s[jv]
        coef = np.where(sv == FORWARD, self.f[jv], np.where(sv == BACKWARD, -self.f[jv], 0.0))
        return np.concatenate([jv, n + jw]), coef, jv, jw

    def _G_rows(self, s, free, coef, jv, jw, cols):
        """Rows of the assignment's equations (a-rows ``q + c p``, b-rows ``p``) at ``cols``
        (a CSR matrix for a sparse system)."""
        n = self.n
        cols = np.asarray(cols, int)
        if self.sparse and not self.schur:
            return schur_step.assignment_rows(self.K, n, coef, jv, jw, cols)
        rows = np.concatenate([jv, n + jw])
        if isinstance(self.K, np.ndarray):  # two takes: the same gather, cheaper than np.ix_
            out = self.K.take(rows, axis=0).take(cols, axis=1)
            if jv.size:
                out[:jv.size] += coef[:, None] * self.K.take(n + jv, axis=0).take(cols, axis=1)
            return out
        out = self.K[np.ix_(rows, cols)]  # cost ~ the output's size
        if jv.size:
            out[:jv.size] += coef[:, None] * self.K[np.ix_(n + jv, cols)]
        return out

    def _rhs(self, coef, jv, jw, q0, p0):
        return -np.concatenate([q0[jv] + coef * p0[jv], p0[jw]])

    # ------------------------------------------------------------------ factorizations
    def _factor(self, s, key):
        free, coef, jv, jw = self._layout(s)
        if self.schur:
            return self._factor_schur(s, key, free, coef, jv, jw)
        Ms = self._G_rows(s, free, coef, jv, jw, free)
        if self.sparse:
            return self._factor_sparse(s, key, free, coef, jv, jw, Ms)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            anorm = np.abs(Ms).sum(axis=0).max()
            # LAPACK getrf as scipy's lu_factor calls it (without its per-call wrapper)
            lu_, piv, info = self._getrf(Ms, overwrite_a=False)
            if info < 0:
                raise ValueError(f"getrf: illegal value in argument {-info}")
            lu = (lu_, piv)
            rcond = dgecon(lu_, anorm, norm="1")[0]
        self.totals["factorizations"] += 1
        self._counters["factorizations"] += 1
        if not np.isfinite(rcond) or rcond < 1e-14:
            return None
        return self._store(_Factor(key, s.copy(), free, coef, jv, jw, lu, Ms.nbytes))

    def _factor_sparse(self, s, key, free, coef, jv, jw, Ms):
        """SuperLU factor of a sparse assignment system; ``None`` if (nearly) singular.

        The singularity test is SuperLU's exact zero pivot or a pivot below ``1e-14`` of the
        largest (a cheap proxy for a reciprocal condition number; every answer is verified
        afterwards like the dense LU's).
        """
        lu = schur_step.pivoted_lu(Ms)
        self.totals["factorizations"] += 1
        self._counters["factorizations"] += 1
        if lu is None:
            return None
        nbytes = 12 * (lu.L.nnz + lu.U.nnz) + 8 * Ms.shape[0]
        return self._store(_Factor(key, s.copy(), free, coef, jv, jw, lu, nbytes))

    def _factor_schur(self, s, key, free, coef, jv, jw):
        """Sparse LU of the assignment's system with the interior DOFs of an uncondensed ``K``
        (:mod:`.schur_step`); ``None`` if (nearly) singular."""
        lu = schur_step.factor(self.K, free, coef, jv, jw)
        self.totals["factorizations"] += 1
        self._counters["factorizations"] += 1
        if lu is None:
            return None
        return self._store(_Factor(key, s.copy(), free, coef, jv, jw, lu, lu.nbytes))

    def _store(self, F):
        """Cache ``F`` (LRU within ``cache_bytes``) and make it the base of updates."""
        self._cache[F.key] = F
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
        """Full rows (length 2N) ``rows`` of the assignment's system ``G_s`` (the a-row of a
        non-stick node is ``q_j + c p_j``: rows ``j`` and ``n + j`` of ``K``; the b-row of a
        separated node is ``p_j``; every other row is the unit row of a fixed unknown)."""
        n = self.n
        rows = np.asarray(rows, int)
        j = rows % n
        a = (rows < n) & (s[j] != STICK)
        b = (rows >= n) & (s[j] == SEPARATED)
        c = np.where(s[j] == FORWARD, self.f[j], np.where(s[j] == BACKWARD, -self.f[j], 0.0))
        G = np.zeros((rows.size, 2 * n))
        if np.any(a | b):
            G[a | b] = self._dense(self.K[n + j[a | b]])  # p_j rows, gathered at once
            ia = np.flatnonzero(a)
            if ia.size:
                G[ia] *= c[ia, None]
                G[ia] += self._dense(self.K[j[ia]])
        unit = np.flatnonzero(~(a | b))
        G[unit, rows[unit]] = 1.0
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
        self._last_factor = None
        if self.kernel and _kernel.HAVE_KERNEL:
            return self._kernel_solve(s, q0, p0, scale)
        if not s.any():  # all stick (STICK = 0)
            return np.zeros(2 * n)
        key = s.tobytes()
        F = self._cache.get(key)
        if F is not None:
            self._cache.move_to_end(key)
            self.totals["cache_hits"] += 1
            self._counters["cache_hits"] += 1
            self._base = F
            self._keep_rows(F)
            return self._lu_solve(F, q0, p0)
        B0 = self._base
        # sparse: a fresh SuperLU factor (~1 ms at N = 2000) beats a dense Woodbury update
        if (not self.sparse and B0 is not None and B0.free.size >= self.update_min_size
                and np.count_nonzero(s != B0.s) <= max(
                    self.max_update_rank, self.update_fraction * B0.free.size)):
            z = self._woodbury(B0, s, q0, p0)
            if z is not None and self._equations_ok(s, z, q0, p0, scale):
                return z
        F = self._factor(s, key)
        if F is None:
            return None
        return self._lu_solve(F, q0, p0)

    def _lu_solve(self, F, q0, p0):
        """``z`` of the cached assignment ``F`` by one pair of triangular solves (LAPACK getrs
        called directly: the factors and right-hand side are finite by construction, checked
        once when ``F`` was factorized, so scipy's per-call checks are skipped)."""
        z = np.zeros(2 * self.n)
        rhs = self._rhs(F.coef, F.jv, F.jw, q0, p0)
        if self.schur:  # the reactions come with the solve (no second solve with K_ii)
            x, r = F.lu.solve_with_reactions(rhs)
            z[F.free] = x
            self._last_factor = _SCHUR
            self._kernel_answer = (z, q0 + r[:self.n], p0 + r[self.n:])
            return z
        if self.sparse:
            x = F.lu.solve(rhs)
        else:
            x, info = self._getrs(F.lu[0], F.lu[1], rhs, overwrite_b=True)
        z[F.free] = x
        self._last_factor = F
        return z

    def _kernel_solve(self, s, q0, p0, scale):
        """``z`` of assignment ``s`` by the compiled kernel's inverse cache (cache hit, block
        update or fresh inverse, see :mod:`.kernel`); its reactions are kept for
        :meth:`_reactions`.  ``None`` when the matrix is singular or the answer inaccurate."""
        from .kernel_warm import readonly as _readonly
        from .kernel_warm import writable

        n = self.n
        kc = self.kernel_cache
        z, q, p = np.empty(2 * n), np.empty(n), np.empty(n)
        c0 = kc.counters.copy()
        ok = _kernel._solve_set(
            np.array(s, np.int8), _readonly(self.K), _readonly(self.f),
            writable(q0), writable(p0), n,
            self.feas_tol * scale, kc.mult, kc.keys, kc.hashes, kc.offs, kc.sizes, kc.pool,
            kc.ipool, kc.fpool, kc.meta, kc.counters, z, q, p)
        d = kc.counters - c0
        for name, k in (("cache_hits", _kernel.C_HITS), ("factorizations", _kernel.C_FACT),
                        ("updates", _kernel.C_UPD)):
            self.totals[name] += int(d[k])
            self._counters[name] += int(d[k])
        if not ok:
            return None
        self._last_factor = _KERNEL
        self._kernel_answer = (z, q, p)
        return z

    def _remember(self, s, key):
        """Factorize (and cache) an accepted assignment the second time it is accepted.

        Assignments solved by a Woodbury update are not cached; one that recurs (the same set
        over consecutive steps, or the same step of the next period on the way to a steady
        cycle) is worth one LU so that later visits are plain cache hits.
        """
        if key in self._cache or not s.any() or self._last_factor in (_KERNEL,
                                                                                 _SCHUR):
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

    def _reactions(self, z, q0, p0, F=None):
        """``(q, p) = (q0, p0) + K z``.

        ``F``: the cached factor that produced ``z`` (its support is ``F.free``); its rows
        ``K[F.free]`` are kept with the factor (counted in the cache budget) so that a warm step
        costs one matrix-vector product with them and no gather.  Otherwise the rows of the
        non-zero entries are gathered (``K`` is symmetric: rows instead of strided columns).
        """
        n = self.n
        if F is _KERNEL or F is _SCHUR:
            kz, kq, kp = self._kernel_answer
            if kz is z:
                return kq, kp
            F = None
        if self.sparse:
            r = self.K @ z  # K is symmetric: reactions of z by one sparse product
        elif F is not None and F.krows is not None:
            r = z[F.free] @ F.krows
        else:
            idx = np.flatnonzero(z)
            if not idx.size:
                return q0.copy(), p0.copy()
            # a gather copies |idx| rows: cheaper than reading all of K below N / 2 of them
            r = z[idx] @ self.K[idx] if 2 * idx.size < n else self.K @ z
        return q0 + r[:n], p0 + r[n:]

    def _keep_rows(self, F):
        """Keep ``K[F.free]`` with a factor met again (a cache hit), within the cache budget."""
        if self.sparse:  # reactions are one sparse product: nothing to keep
            return
        if F.krows is None and self._cache_used + 16.0 * F.free.size * self.n <= self.cache_bytes:
            F.krows = self.K[F.free]
            F.nbytes += F.krows.nbytes
            self._cache_used += F.krows.nbytes
