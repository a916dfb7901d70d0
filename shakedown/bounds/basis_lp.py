"""Exact ``lam_high_k`` by a dual simplex in the coordinates of the ``lam2`` basis (issue 14).

In the slack coordinates ``sigma`` of the ``lam2`` basis rows (:mod:`.barycentric_walk`:
``v = x* - E sigma``, ``lam = lam2 - y . sigma``) the LP "``max lam`` with row ``k`` tight" is

    min  y . sigma   s.t.  sigma >= 0,   W_J sigma <= s*_J,   W_k sigma = s*_k,

with ``W_J = K_J + m_J y^T`` (``K = -G_J E``) and ``s*_J >= 0`` the slacks of the other rows
at the ``lam2`` optimum.  ``sigma = 0`` (the ``lam2`` vertex) is dual feasible (``y >= 0``) and
violates only row ``k``: the dual simplex starts there with an empty working basis, the ``m x
m`` block ``W_{T,P}`` (rows ``T`` tight, coordinates ``P`` basic) kept as an explicit inverse
(:mod:`.inverse_updates`): a pivot costs ``O(N m + m^2)``, not the ``O(N^2)`` of the dual
simplex in ``v`` (:mod:`.dual_simplex`: 149 s for 8 capped LPs on a 2000-crack network).

Nothing is taken on trust: the optimum is mapped back to ``(v, lam)`` and its multipliers to
the rows of the LP in ``v`` (the multiplier of row ``a`` of the basis is the reduced cost of
``sigma_a``, that of a tight row its dual value), and the answer carries the scaled KKT
residuals of the LP in ``v`` (:func:`~.certificates.kkt_residuals`); the pruning accepts it only
through its own checks (the point from scratch, the residuals), else it solves the LP the old
way.  Multipliers of the ``lam2`` basis that are zero up to rounding (degenerate optima) are
clipped to zero for the costs; an optimum that then fails the dual-sign check is not accepted.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.errors import InputError
from . import basis_kernel as bk
from . import inverse_updates as iu
from .certificates import CERT_TOL, DenseAnswer, batch_residuals, kkt_residuals

#: Primal feasibility tolerance (relative to the largest ``s*``) and pivot tolerance.
FEAS_TOL = 1e-10
PIV_TOL = 1e-9
#: Pivots an LP of :meth:`BasisLP.race` goes on for before the dual bounds are compared again,
#: and the answers it certifies together.
RACE_CHUNK, VERIFY_BATCH = 100, 8
#: Smallest problem (nodes) whose pivots run compiled (:mod:`.basis_kernel`, numba); below,
#: in NumPy (a cold cache's compilation, ~s, would cost more than it saves).
KERNEL_MIN_N = 800


class BasisLP:
    """"``max lam`` with row ``k`` tight" for any row ``k`` outside the ``lam2`` basis.

    Parameters
    ----------
    frame : :class:`~.barycentric_walk.SimplexFrame`
        Unit-norm rows (the pruning's).
    tab : :class:`~.dual_simplex.Tableau`
        The LP in ``v`` (rows ``[G, -m]`` and ``-lam <= 0``, unit norm): the answers are
        stated and certified on it.
    extra : tuple, optional
        ``(G_x, c_x, m_x, rows)``: more constraint rows ``G_x v <= c_x + lam m_x`` (rows
        ``rows`` of ``tab``), which may be violated at the ``lam2`` vertex (the no-separation
        rows, :func:`separation_lp`).
    """

    def __init__(self, frame, tab, extra=None):
        self.f, self.tab = frame, tab
        self.dropped = 0  # pivots of the LPs a race dropped unfinished
        f = frame
        self.n = f.n
        rows, K, mr = f.J, f.K, f.m[f.J]
        star = np.maximum(f.r(f.lam2), 0.0)  # slacks at the lam2 vertex
        ours = np.hstack([f.G[f.J], -mr[:, None]])
        if extra is not None:  # more rows: (G_x, c_x, m_x, their rows in tab)
            Gx, cx, mx, idx = extra
            rows = np.r_[rows, np.asarray(idx, int)]
            K = np.vstack([K, -(Gx @ f.E)])
            mr = np.r_[mr, mx]
            star = np.r_[star, cx + f.lam2 * mx - Gx @ f.x2]  # may be violated
            ours = np.vstack([ours, np.hstack([Gx, -np.asarray(mx)[:, None]])])
        self.rows, self.K, self.mJ, self.star = rows, K, mr, star
        self.KF = f.KF if extra is None else np.asfortranarray(K)
        self.loc = np.full(tab.R, -1)  # tab row -> position in rows (or -1)
        self.loc[rows] = np.arange(len(rows))
        self.cost = np.maximum(f.y, 0.0)
        self.clipped = bool(np.any(f.y < 0.0))
        # each row of tab = (our row) * g: the multipliers scale by 1 / g
        norm = np.linalg.norm
        self.g = norm(tab.A[rows], axis=1) / np.maximum(norm(ours, axis=1), 1e-300)
        self.gB = norm(tab.A[f.B], axis=1) / norm(np.hstack([f.G[f.B], -f.m[f.B, None]]),
                                                  axis=1)
        cap = f.n + 2
        self.KP = np.empty((len(rows), cap), order="F")
        self.KT = np.empty((cap, f.n + 1))
        self.tol = FEAS_TOL * max(1.0, float(np.abs(star).max(initial=0.0)))

    def _M(self, P, T, KT=None):
        """The working basis; ``KT``: the LP's array holding ``K[T]`` in its first ``len(T)``
        rows (a gather from it is ~7x cheaper than from ``K``: issue 26, ``m = 300``)."""
        KTP = KT[: len(T)][:, P] if KT is not None else self.K[np.ix_(T, P)]
        return KTP + np.outer(self.mJ[T], self.f.y[P])

    def _inverse(self, P, T, KT=None):
        return iu.inverse(self._M(P, T, KT)) if len(P) else np.zeros((0, 0))

    def solve(self, k: int | None, max_pivots: int | None = None) -> DenseAnswer | None:
        """The answer for row ``k`` (``None`` for a row of the basis: ``lam_high = lam2``;
        ``k=None``: ``max lam`` with no row held tight, for the extra rows of ``extra``).
        Status ``"failed"`` on a pivot cap (then ``x[-1]`` is the dual bound ``lam2 - c .
        sigma``, an upper bound of ``lam_high_k`` when no multiplier of the ``lam2`` basis was
        clipped), a vanishing pivot or an infeasible LP (``x`` is ``None``)."""
        kl = -1 if k is None else int(self.loc[k])
        if kl < 0 and k is not None:
            return None
        return _drive(self._run(k, kl, max_pivots, self.KP, self.KT))

    def _run(self, k, kl, max_pivots, KP, KT, verify=True, chunk=None):
        """The dual simplex of row ``k`` as a generator (:meth:`_steps`): compiled
        (:func:`.basis_kernel.steps`) on problems of :data:`KERNEL_MIN_N` nodes or more."""
        if self.n >= KERNEL_MIN_N and bk.HAVE_KERNEL:
            return bk.steps(self, k, kl, max_pivots, KP, KT, PIV_TOL, verify, chunk)
        return self._steps(k, kl, max_pivots, KP, KT, verify)

    def race(self, rows, below: float | None = None, chunk: int | None = None):
        """The exact answers of several rows side by side: yields ``(k, answer)`` (as
        :meth:`solve`) in the order the LPs finish.

        The LPs advance in turns of ``chunk`` pivots (:data:`RACE_CHUNK`), the one with the
        fewest pivots next; one whose dual bound ``lam2 - c . sigma`` (an upper bound of its
        ``lam_high`` while the costs are not clipped) drops below ``below`` runs to its end
        first.  So a row with ``lam_high < below`` is seen after about ``len(rows)`` times the
        pivots its bound needs to cross ``below`` (issue 26, a 2000-crack network: the batch's
        row below the incumbent was the last of 8, 2.1e4 pivots later one after the other).
        A caller that has what it needs stops iterating; the LPs left are dropped.  Without a
        row below ``below`` every LP runs to its end, as one after the other.  The answers are
        those of :meth:`solve`, pivot for pivot (each LP has its own working arrays), certified
        :data:`VERIFY_BATCH` at a time (one pass over the LP's matrix for all: issue 26, 1324
        LPs of ~100 pivots on a dense system of 2000 nodes spent 9.9 s in their certificates),
        an answer below ``below`` at once after those finished before it.
        """
        chunk = RACE_CHUNK if chunk is None else chunk
        if not isinstance(chunk, (int, np.integer)) or chunk < 1:
            raise InputError(f"race: chunk = {chunk!r} pivots; give a positive integer")
        runs = []  # [dual bound, pivots, k, steps]
        for k in rows:
            k = int(k)
            kl = int(self.loc[k])
            if kl < 0:
                yield k, None
                continue
            KP = np.empty((len(self.rows), self.n + 2), order="F")  # its own (pages touched
            KT = np.empty((self.n + 2, self.n + 1))  # as the working basis grows)
            runs.append([self.f.lam2, 0, k, self._run(k, kl, None, KP, KT, False, chunk)])
        done = []  # finished, not yet certified
        try:
            while runs:
                hot = [i for i, r in enumerate(runs) if below is not None and r[0] < below]
                i = hot[0] if hot else min(range(len(runs)), key=lambda i: runs[i][1])
                run = runs[i]
                try:
                    goal = run[1] + chunk
                    while run[1] < goal:
                        run[0], run[1] = next(run[3])
                except StopIteration as end:
                    runs.pop(i)
                    done.append((run[2], end.value))
                    low = below is not None and end.value.x is not None and end.value.x[-1] < below
                    if low or len(done) >= VERIFY_BATCH or not runs:
                        yield from self._certify(done)
                        done = []
        finally:  # (the caller stopped iterating: the LPs left are dropped)
            self.dropped += sum(r[1] for r in runs)

    def _steps(self, k, kl, max_pivots, KP, KT, verify=True):
        """The dual simplex of :meth:`solve` as a generator: yields the dual bound ``lam2 - c .
        sigma`` and the pivots so far after each pivot, returns the answer
        (``StopIteration.value``).  ``KP``,
        ``KT``: its working arrays (``K`` at the basic coordinates, at the tight rows)."""
        f = self.f
        y, c, mJ, K = f.y, self.cost, self.mJ, self.K
        cap = max_pivots if max_pivots is not None else 4 * self.n + 100
        P, T = [], []
        W = np.zeros((0, 0))
        it = since = 0
        while True:
            m = len(P)
            if iu.refactor_due(since, m):
                W, since = self._inverse(P, T, KT), 0
                if W is None:
                    return self._failed(it)
            sP = W @ self.star[T] if m else np.zeros(0)
            if it:
                yield f.lam2 - (float(c[P] @ sP) if m else 0.0), it
            ys = float(y[P] @ sP) if m else 0.0
            sJ = self.star - (KP[:, :m] @ sP if m else 0.0) - mJ * ys
            sJ[T] = 0.0
            z = -(W.T @ c[P]) if m else np.zeros(0)
            d = c + (z @ KT[:m] if m else 0.0) + y * float(mJ[T] @ z if m else 0.0)
            d[P] = 0.0
            # leaving variable: row k first, then the most infeasible
            if kl >= 0 and kl not in T and abs(sJ[kl]) > self.tol:  # its slack must come to 0
                kind, q, sgn = "row", kl, (-1.0 if sJ[kl] > 0 else 1.0)
            else:
                i = int(np.argmin(sJ))
                r = int(np.argmin(sP)) if m else -1
                worst = min(sJ[i], sP[r] if m else np.inf)
                if worst >= -self.tol:  # optimal (for the clipped costs: finish on y)
                    if self.clipped:
                        W, it = self._primal_finish(kl, P, T, W, it, cap, KP, KT)
                        if W is None:
                            return self._failed(it)
                    return self._answer(k, P, T, W, it, verify)
                kind, q, sgn = ("row", i, 1.0) if sJ[i] <= worst else ("coord", r, 1.0)
            if it >= cap:  # stopped: the dual bound ranks the row (screening)
                lam_ub = f.lam2 - (float(c[P] @ sP) if m else 0.0)
                return DenseAnswer("failed", np.r_[np.full(self.n, np.nan), lam_ub], None,
                                   np.zeros(0, int), it, (np.inf,) * 4)
            # pivot row: effect of one unit of each nonbasic variable on the leaving one
            if kind == "row":
                rowq = K[q, P] + mJ[q] * y[P]
                rho = rowq @ W if m else np.zeros(0)
                dc = -(K[q] + mJ[q] * y)
                if m:
                    dc += rho @ KT[:m] + float(rho @ mJ[T]) * y
                ds = rho.copy()  # slack of tight row T[p]
            else:
                rho = W[q]
                dc = -(rho @ KT[:m] + float(rho @ mJ[T]) * y)
                ds = -W[q].copy()
            dc[P] = 0.0
            if kl in T:
                ds[T.index(kl)] = 0.0  # row k is an equality: its slack never enters
            sc = max(float(np.abs(dc).max(initial=0.0)), float(np.abs(ds).max(initial=0.0)))
            okc = sgn * dc > PIV_TOL * max(sc, 1e-300)
            oks = sgn * ds > PIV_TOL * max(sc, 1e-300)
            rc = np.where(okc, np.maximum(d, 0.0) / np.where(okc, sgn * dc, 1.0), np.inf)
            rs = np.where(oks, np.maximum(z, 0.0) / np.where(oks, sgn * ds, 1.0), np.inf)
            tmin = min(rc.min(initial=np.inf), rs.min(initial=np.inf))
            if not np.isfinite(tmin):
                return self._failed(it)  # no entering variable: infeasible
            near = tmin + 1e-12 * (1.0 + tmin)
            ec = np.where(rc <= near, np.abs(dc), -np.inf)
            es = np.where(rs <= near, np.abs(ds), -np.inf)
            ic = int(np.argmax(ec))
            is_ = int(np.argmax(es)) if m else -1
            enter = ("coord", ic) if m == 0 or ec[ic] >= es[is_] else ("slack", is_)
            W = self._update(W, P, T, kind, q, enter, rowq if kind == "row" else None, KP, KT)
            if W is None:
                return self._failed(it)
            it += 1
            since += 1

    def _update(self, W, P, T, kind, q, enter, rowq, KP, KT):
        K, mJ, y = self.K, self.mJ, self.f.y
        m = len(P)
        e = enter[1]
        if kind == "row" and enter[0] == "coord":  # row q tight, coordinate e basic: border
            col = KT[:m, e] + mJ[T] * y[e] if m else np.zeros(0)
            wb = W @ col if m else np.zeros(0)
            cw = rowq @ W if m else np.zeros(0)
            schur = K[q, e] + mJ[q] * y[e] - (rowq @ wb if m else 0.0)
            if not abs(schur) > 0.0:
                return None
            W = iu.border(W, wb, cw, schur) if m else np.array([[1.0 / schur]])
            P.append(e)
            T.append(q)
            KP[:, m] = self.KF[:, e]
            KT[m] = K[q]
        elif kind == "row":  # row q replaces tight row T[e]
            old = KT[e, P] + mJ[T[e]] * y[P]
            dw = (rowq - old) @ W
            W = iu.replace_row(W, e, dw, 1.0 + dw[e])
            T[e] = q
            KT[e] = K[q]
        elif enter[0] == "coord":  # coordinate e replaces basic coordinate P[q]
            col = KT[:m, e] + mJ[T] * y[e]
            W = iu.replace_column(W, q, W @ col)
            P[q] = e
            KP[:, q] = self.KF[:, e]
        else:  # coordinate P[q] leaves, tight row T[e] loosens: both removed
            W = iu.remove(W, q, e)
            P[q], T[e] = P[m - 1], T[m - 1]
            KP[:, q] = KP[:, m - 1]
            KT[e] = KT[m - 1]
            P.pop()
            T.pop()
        return W

    def _failed(self, it):
        return DenseAnswer("failed", None, None, np.zeros(0, int), it, (np.inf,) * 4)

    def _primal_finish(self, kl, P, T, W, it, cap, KP, KT):
        """Primal simplex pivots on the true costs ``y`` from a primal feasible basis (optimal
        for the clipped costs): entering, a coordinate or a tight row's slack (never row
        ``kl``'s) of negative reduced cost.  Returns ``(W, pivots)``; ``W`` is ``None`` on a
        cap or an unbounded direction."""
        y, mJ = self.f.y, self.mJ
        while True:
            m = len(P)
            z = -(W.T @ y[P]) if m else np.zeros(0)
            d = y + (z @ KT[:m] if m else 0.0) + y * float(mJ[T] @ z if m else 0.0)
            d[P] = 0.0
            zs = z.copy()
            if kl in T:
                zs[T.index(kl)] = 0.0  # equality: its slack never enters
            e = int(np.argmin(d))
            j = int(np.argmin(zs)) if m else -1
            scale = max(float(np.abs(d).max()), float(np.abs(z).max(initial=0.0)), 1e-300)
            if min(d[e], zs[j] if m else np.inf) >= -PIV_TOL * scale:
                return W, it
            if it >= cap:
                return None, it
            sP = W @ self.star[T] if m else np.zeros(0)
            sJ = self.star - (KP[:, :m] @ sP if m else 0.0) - mJ * float(y[P] @ sP)
            sJ[T] = 0.0
            if m and zs[j] < d[e]:  # loosen tight row T[j]
                enter = ("slack", j)
                dP = -W[:, j]
                dS = -(KP[:, :m] @ dP + mJ * float(y[P] @ dP))
                dS[T[j]] = 1.0
            else:
                enter = ("coord", e)
                col = KT[:m, e] + mJ[T] * y[e] if m else np.zeros(0)
                dP = -(W @ col) if m else np.zeros(0)
                dS = -(KP[:, :m] @ dP + mJ * float(y[P] @ dP) + self.KF[:, e] + mJ * y[e])
                dS[T] = 0.0
            bl, bs = dP < -PIV_TOL, dS < -PIV_TOL
            bs[T] = False
            rl = np.where(bl, np.maximum(sP, 0.0) / np.where(bl, -dP, 1.0), np.inf)
            rs = np.where(bs, np.maximum(sJ, 0.0) / np.where(bs, -dS, 1.0), np.inf)
            if kl >= 0 and kl not in T and abs(dS[kl]) > PIV_TOL:
                rs[kl] = 0.0  # row k, tight but not in T, must stay tight: it enters T
            il = int(np.argmin(rl)) if m else -1
            is_ = int(np.argmin(rs))
            if not min(rl[il] if m else np.inf, rs[is_]) < np.inf:
                return None, it  # unbounded
            if m and rl[il] <= rs[is_]:
                kind, q, rowq = "coord", il, None
            else:
                kind, q = "row", is_
                rowq = self.K[q, P] + mJ[q] * y[P]
            W = self._update(W, P, T, kind, q, enter, rowq, KP, KT)
            it += 1
            if W is None:
                return None, it

    def _answer(self, k, P, T, W, it, verify=True):
        """The optimum in ``v`` with its multipliers on the tableau's rows, certified there
        (``verify=False``: status ``"unverified"``, for :meth:`_certify`)."""
        f, tab = self.f, self.tab
        lu = iu.factor(self._M(P, T)) if P else None  # fresh values for the answer
        if P and lu is None:
            return self._failed(it)
        sP = iu.solve(lu, self.star[T]) if P else np.zeros(0)
        v = f.x2 - sP @ f.ET[P] if P else f.x2.copy()
        lam = f.lam2 - (float(f.y[P] @ sP) if P else 0.0)
        z = -iu.solve(lu, f.y[P], trans=True) if P else np.zeros(0)  # the true costs now
        d = f.y + ((z @ self.K[T]) + f.y * float(self.mJ[T] @ z) if P else 0.0)
        nb = np.ones(len(f.B), bool)
        nb[P] = False
        Y = np.zeros(tab.R)
        Y[f.B[nb]] = d[nb] / self.gB[nb]
        Y[self.rows[T]] = z / self.g[T]
        x = np.r_[v, lam]
        basis = np.r_[f.B[nb], self.rows[T]].astype(int)
        if not verify:
            return DenseAnswer("unverified", x, Y, basis, it, (np.nan,) * 4)
        res = kkt_residuals(tab.A, tab.b, tab.e, x, Y, equal=() if k is None else (k,),
                            rownorm=np.ones(tab.R))
        return _judged(DenseAnswer("optimal", x, Y, basis, it, res))

    def _certify(self, done):
        """``(k, answer)`` for each ``(k, unverified answer)`` of ``done``, as :meth:`_answer`
        certifies one: the KKT residuals of all in one pass (unit-norm rows)."""
        todo = [g for g, (_, a) in enumerate(done) if a.status == "unverified"]
        out = list(done)
        if todo:
            tab = self.tab
            eq = np.zeros((len(todo), tab.R), bool)
            eq[np.arange(len(todo)), [done[g][0] for g in todo]] = True
            res = batch_residuals(tab.A, tab.b, tab.e, np.array([done[g][1].x for g in todo]),
                                  np.array([done[g][1].y for g in todo]), eq)
            for g, r in zip(todo, res, strict=True):
                a = done[g][1]
                out[g] = (done[g][0], _judged(replace(a, status="optimal", residuals=tuple(r))))
        return out


def _judged(ans):
    """``ans``, ``"failed"`` if its residuals exceed ``CERT_TOL`` (then solved another way)."""
    if max(ans.residuals) > CERT_TOL:
        return replace(ans, status="failed", residuals=(np.nan,) * 4)
    return ans


def _drive(steps):
    """Run a generator of :meth:`BasisLP._steps` to its end; its answer."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value
