"""Lock-step dense dual simplex for many LPs ``max e.x s.t. A x <= b`` that share ``A, b, e``.

The LPs differ by rows that must hold with equality (the activity-interval and adjacency LPs of
the bounds engine) and all start from one dual-feasible basis ``T0``.  A basis is a set ``T`` of
``n`` rows (with signs) with ``B = A_T`` non-singular, ``x = B^-1 b_T`` and multipliers
``y = B^-T e >= 0``.  A violated row enters; the ratio test ``y_r / alpha_r`` with
``alpha = B^-T a_p`` picks the position ``r`` that leaves.

Basis update (issue 14): ``B0^-1`` and the tableau ``W = B0^-T A^T`` are formed once.  After
some pivots ``B = B0 + P^T Delta`` differs from ``B0`` in the ``k`` positions listed by ``P``, and
with ``H = Delta B0^-1`` (read off ``W``: row ``i`` is ``s_r W[:, T_r]^T - e_r^T``) the
Sherman-Morrison-Woodbury formula gives

    B^-T a = w - H^T S^-T w[P],     B^-1 c = B0^-1 (c - P^T S^-1 H c),    S = I_k + H P^T,

with ``w = B0^-T a`` a column of ``W``.  ``S^-1`` (``k x k``, ``k <=`` pivots of that LP) is kept
by bordering (a new position) or a rank-one update (a position changed again) and recomputed
from ``H`` every :data:`REINVERT_EVERY` pivots (periodic reinversion).  One pivot costs
``O(k n)`` for ``alpha`` plus one row of ``A B^-1`` (``O(n R)``, a matrix product for all LPs
of a round), vectorised over the LPs: no Python loop over earlier pivots.  Memory is
``O(L (k n + R))`` for the ``L`` LPs of a chunk, whatever the total number of LPs.  A run of
one or two LPs (a crossover, the ``min lam`` start) takes its first products from the LU factor
of ``B0`` instead (:data:`LAZY_LPS`): most end in a few pivots, where forming ``W`` would cost
more than all of them.
"""

from __future__ import annotations

import numpy as np

from .certificates import CERT_TOL, FEAS_TOL, PIVOT_TOL, DenseAnswer, batch_residuals
from .tableau import LAZY_LPS, Tableau

#: Pivots between two recomputations of the capacitance inverse ``S^-1`` from ``H``.
REINVERT_EVERY = 16
#: Bytes of working storage per chunk of LPs solved together.
CHUNK_BYTES = 2**27


def batch_dual_simplex(tab: Tableau, equal_rows, *, max_pivots=None, width=None, chunk=None,
                       on_answer=None, skip=None, stop=None):
    """Solve ``max e.x s.t. A x <= b`` plus, for LP ``l``, ``A_k x = b_k`` for ``k`` in
    ``equal_rows[l]``, all from the basis ``tab.T0``, in lock-step.

    ``width`` LPs pivot together (a pool: an LP that finishes frees its slot for the next one
    in order, so rounds stay full whatever the spread of pivot counts).  ``on_answer(l, answer)``
    is called as each LP finishes; ``skip(l)`` is asked before LP ``l`` is started (``True``:
    not solved, its entry is ``None``), so a caller can share answers between LPs.
    ``stop()`` is asked before each pivot round: ``True`` ends the run, the LPs still running
    are reported ``"failed"`` and those not started are skipped (``None``).

    Returns a list of :class:`~.certificates.DenseAnswer` (multipliers in the caller's row
    units), in the order of ``equal_rows``; with ``on_answer`` the answers are only streamed
    (the list holds ``None``).
    """
    n, R = tab.n, tab.R
    if max_pivots is None:
        max_pivots = max(60, 3 * n)
    if width is None:
        width = chunk
    if width is None:
        # working storage per LP: H (k x n, k up to ~100 typically), act/masks (R), S^-1
        width = int(max(8, min(256, CHUNK_BYTES / (8 * (100 * n + 6 * R + 100 * 100)))))
    return _batch(tab, list(equal_rows), max_pivots, int(width), on_answer, skip, stop)


class _State:
    """Working arrays of the LPs of one chunk that are still running (compacted on retire).

    ``Sinv`` is kept equal to the identity outside the leading ``k x k`` block of each LP and
    the rows of ``H`` beyond ``k`` are zero, so the products below need no masks except where
    ``pos`` (0 beyond ``k``) is used to gather.
    """

    _FIELDS = ("ids", "piv", "bas", "sgn", "eqmask", "free", "inbasis", "y", "act", "k",
               "pos", "where", "H", "Sinv")

    def __init__(self, tab, cap):
        n, R = tab.n, tab.R
        self.tab = tab
        self.ids = np.zeros(0, int)
        self.piv = np.zeros(0, int)
        self.bas = np.zeros((0, n), int)
        self.sgn = np.zeros((0, n))
        self.eqmask = np.zeros((0, R), bool)
        self.free = np.zeros((0, n), bool)
        self.inbasis = np.zeros((0, R), bool)
        self.y = np.zeros((0, n))
        self.act = np.zeros((0, R))
        self.k = np.zeros(0, int)  # changed positions per LP
        self.pos = np.zeros((0, cap), int)  # positions changed (first k valid)
        self.where = np.zeros((0, n), int)  # position -> index in pos (or -1)
        self.H = np.zeros((0, cap, n))
        self.Sinv = np.zeros((0, cap, cap))

    def admit(self, ids, eqs):
        """Append fresh LPs (start basis ``T0``) with ids ``ids`` and equality rows ``eqs``."""
        tab, L = self.tab, len(ids)
        n, R = tab.n, tab.R
        cap = self.H.shape[1]
        eqmask = np.zeros((L, R), bool)
        for l, rows in enumerate(eqs):
            eqmask[l, list(rows)] = True
        bas = np.tile(tab.T0, (L, 1))
        inbasis = np.zeros((L, R), bool)
        inbasis[:, tab.T0] = True
        fresh = dict(
            ids=np.asarray(ids, int), piv=np.zeros(L, int), bas=bas, sgn=np.ones((L, n)),
            eqmask=eqmask, free=eqmask[:, tab.T0], inbasis=inbasis,
            y=np.tile(tab.y0, (L, 1)), act=np.tile(tab.act0, (L, 1)), k=np.zeros(L, int),
            pos=np.zeros((L, cap), int), where=np.full((L, n), -1),
            H=np.zeros((L, cap, n)), Sinv=np.tile(np.eye(cap), (L, 1, 1)),
        )
        for f in self._FIELDS:
            setattr(self, f, np.concatenate([getattr(self, f), fresh[f]]))

    @property
    def ku(self) -> int:
        """Leading block size in use: ``max k`` (at least 1)."""
        return max(1, int(self.k.max(initial=0)))

    def keep(self, mask):
        for f in self._FIELDS:
            setattr(self, f, getattr(self, f)[mask])

    def grow(self):
        L, cap, n = self.H.shape
        new = 2 * cap
        H = np.zeros((L, new, n))
        H[:, :cap] = self.H
        S = np.tile(np.eye(new), (L, 1, 1))
        S[:, :cap, :cap] = self.Sinv
        pos = np.zeros((L, new), int)
        pos[:, :cap] = self.pos
        self.H, self.Sinv, self.pos = H, S, pos

    def gather(self, v, ku):
        """``v[P]`` per LP, shape (l, ku), zero beyond each LP's ``k``."""
        out = np.take_along_axis(v, self.pos[:, :ku], axis=1)
        out[np.arange(ku)[None, :] >= self.k[:, None]] = 0.0
        return out

    def reinvert(self, mask):
        """``S^-1 = (I + H[:, P])^-1`` recomputed from ``H`` for the LPs of ``mask``."""
        ku = max(1, int(self.k[mask].max()))
        Hp = np.take_along_axis(self.H[mask, :ku, :], self.pos[mask, None, :ku], axis=2)
        k = self.k[mask]
        Hp[np.broadcast_to(np.arange(ku)[None, None, :] >= k[:, None, None], Hp.shape)] = 0
        self.Sinv[np.flatnonzero(mask)[:, None, None], np.arange(ku)[None, :, None],
                  np.arange(ku)[None, None, :]] = np.linalg.inv(Hp + np.eye(ku)[None])


def _batch(tab, eqs, max_pivots, width, on_answer, skip, stop=None):  # noqa: C901
    n = tab.n
    A, b = tab.A, tab.b
    if len(eqs) > LAZY_LPS:
        tab.W  # noqa: B018 - many LPs: the tableau pays at once
    tolx = FEAS_TOL * tab.scale_x
    st = _State(tab, cap=min(16, n))
    answers = [None] * len(eqs)
    queue = iter(range(len(eqs)))
    exhausted = False

    def refill():
        nonlocal exhausted
        # fewer LPs in the pool once their basis updates have grown (capacity ``cap``):
        # working storage stays below about CHUNK_BYTES
        cap = st.H.shape[1]
        per_lp = 8 * (cap * (n + cap) + 6 * tab.R)
        want = min(width, max(1, CHUNK_BYTES // per_lp)) - st.ids.size
        new = []
        while len(new) < want and not exhausted:
            g = next(queue, None)
            if g is None:
                exhausted = True
            elif skip is None or not skip(g):
                new.append(g)
        if new:
            st.admit(new, [eqs[g] for g in new])

    def retire(mask, label):
        """Certify and record the LPs of ``mask`` with status ``label`` (str or per-LP)."""
        if not mask.any():
            return
        labels = np.broadcast_to(np.asarray(label, dtype=object), mask.shape)[mask]
        ids, bas, sgn, y = st.ids[mask], st.bas[mask], st.sgn[mask], st.y[mask]
        # x = B^-1 c = B0^-1 (c - P^T S^-1 H c),  c = sgn * b_T
        c = sgn * b[bas]
        ku = st.ku
        Hc = np.matmul(st.H[mask, :ku], c[:, :, None])[:, :, 0]
        corr = np.matmul(st.Sinv[mask, :ku, :ku], Hc[:, :, None])[:, :, 0]
        corr[np.arange(ku)[None, :] >= st.k[mask][:, None]] = 0.0
        np.add.at(c, (np.repeat(np.arange(c.shape[0]), ku), st.pos[mask, :ku].ravel()),
                  -corr.ravel())
        X = tab.basic(c)
        m = len(ids)
        Y = np.zeros((m, tab.R))
        np.add.at(Y, (np.repeat(np.arange(m), n), bas.ravel()), (y * sgn).ravel())
        res = batch_residuals(A, b, tab.e, X, Y, st.eqmask[mask])
        piv = st.piv[mask]
        st.keep(~mask)
        for i, g in enumerate(ids):
            lab = labels[i]
            if lab == "optimal" and max(res[i]) > CERT_TOL:
                lab = "failed"
            rr = tuple(float(v) for v in res[i]) if lab == "optimal" else (np.nan,) * 4
            ans = DenseAnswer(lab, X[i], Y[i] / tab.rownorm, bas[i].copy(), int(piv[i]), rr)
            if on_answer is None:
                answers[g] = ans
            else:  # streamed, not kept: memory stays linear in the pool width
                on_answer(int(g), ans)

    while True:
        retire(st.piv >= max_pivots, "failed")
        if stop is not None and stop():
            retire(np.ones(st.ids.size, bool), "failed")
            break
        if 4 * st.ids.size <= 3 * width:
            refill()
        l = st.ids.size
        if not l:
            break
        idx = np.arange(l)
        # ---- pricing: pending equalities first, then the most violated inequality
        viol = st.act - b
        pend = st.eqmask & ~st.inbasis
        eqv = np.where(pend, np.abs(viol), 0.0)
        ineq = np.where(st.inbasis | st.eqmask, -np.inf, viol)
        p_eq = np.argmax(eqv, axis=1)
        has_eq = eqv[idx, p_eq] > tolx
        p_in = np.argmax(ineq, axis=1)
        vin = ineq[idx, p_in] > tolx
        pend_any = pend.any(axis=1)
        # an equality row already satisfied still enters (it becomes basic and free)
        done = ~(has_eq | vin | pend_any)
        if done.any():
            retire(done, "optimal")
            keep = ~done
            p_eq, p_in, has_eq, vin = p_eq[keep], p_in[keep], has_eq[keep], vin[keep]
            l = st.ids.size
            idx = np.arange(l)
            if not l:
                continue
        p = np.where(has_eq, p_eq, np.where(vin, p_in, p_eq))
        zero_eq = ~(has_eq | vin)
        sp = np.where(st.eqmask[idx, p] & (st.act[idx, p] < b[p]), -1.0, 1.0)  # entering sign
        # ---- alpha = B^-T (sp a_p) = w - H^T S^-T w[P]
        w = tab.columns(p).T * sp[:, None]
        ku = st.ku
        g = np.matmul(st.gather(w, ku)[:, None, :], st.Sinv[:, :ku, :ku])  # (S^-T w[P])^T
        alpha = w - np.matmul(g, st.H[:, :ku, :])[:, 0, :]
        # ---- ratio test over non-free positions with alpha > tol
        flip = zero_eq & ~np.any((alpha > PIVOT_TOL) & ~st.free, axis=1)
        sp[flip] *= -1.0
        alpha[flip] *= -1.0
        w[flip] *= -1.0
        ok = (alpha > PIVOT_TOL) & ~st.free
        ratio = np.where(ok, np.maximum(st.y, 0.0) / np.where(ok, alpha, 1.0), np.inf)
        tmin = ratio.min(axis=1)
        infeas = ~np.isfinite(tmin)
        if infeas.any():
            # Farkas: the entering row cannot be satisfied; a satisfied equality that no pivot
            # can bring in is implied by the free rows (rare: let HiGHS decide)
            retire(infeas, np.where(zero_eq, "failed", "infeasible"))
            go = ~infeas
            p, sp, alpha, w, ratio, tmin, ok = (p[go], sp[go], alpha[go], w[go], ratio[go],
                                                tmin[go], ok[go])
            l = st.ids.size
            idx = np.arange(l)
            if not l:
                continue
        # Harris-style tie break: among ratios within a small tolerance take the largest alpha
        near = ok & (ratio <= tmin[:, None] + 1e-12 * (1 + np.abs(tmin[:, None])))
        r = np.argmax(np.where(near, alpha, -np.inf), axis=1)
        ar = alpha[idx, r]
        t_dual = np.maximum(st.y[idx, r], 0.0) / ar
        # ---- primal step: row p becomes tight; direction B^-1 e_r = B0^-1 u,
        # u = e_r - P^T S^-1 H e_r
        s = sp * (st.act[idx, p] - b[p]) / ar
        ku = st.ku
        h = np.matmul(st.Sinv[:, :ku, :ku], st.H[idx, :ku, r][:, :, None])[:, :, 0]
        h[np.arange(ku)[None, :] >= st.k[:, None]] = 0.0
        u = np.zeros((l, n))
        u[idx, r] = 1.0
        np.add.at(u, (np.repeat(idx, ku), st.pos[:, :ku].ravel()), -h.ravel())
        st.act -= s[:, None] * tab.times_w(u)
        # ---- dual and basis update
        st.y -= t_dual[:, None] * alpha
        st.y[idx, r] = t_dual
        st.inbasis[idx, st.bas[idx, r]] = False
        st.inbasis[idx, p] = True
        st.bas[idx, r] = p
        st.sgn[idx, r] = sp
        st.free[idx, r] = st.eqmask[idx, p]
        _update_capacitance(st, idx, r, w)
        st.piv += 1
        due = st.piv % REINVERT_EVERY == 0  # each LP on its own schedule
        if due.any():
            st.reinvert(due)
    return answers


def _update_capacitance(st, idx, r, w):
    """Record that position ``r`` of each LP now holds the row with ``B0^-T a = w``.

    New position: ``H`` gains the row ``w - e_r`` and ``S^-1`` is bordered; a position changed
    before: its ``H`` row is replaced and ``S^-1`` gets a Sherman-Morrison rank-one update.
    """
    hnew = w.copy()
    hnew[idx, r] -= 1.0
    j = st.where[idx, r]
    new = j < 0
    if new.any() and (st.k[new] >= st.H.shape[1]).any():
        st.grow()
    # --- replace (rank-one): S_new = S + e_j d^T, d = hnew[P] - H_j[P]
    rep = np.flatnonzero(~new)
    if rep.size == new.size:
        rep = slice(None)  # every LP: views instead of gathered copies
    if not isinstance(rep, np.ndarray) or rep.size:
        ku = st.ku
        jj = j[rep]
        m = np.arange(jj.size)
        ixr = m if isinstance(rep, slice) else rep  # pairs with jj in fancy indexing
        sub_k, sub_pos = st.k[rep], st.pos[rep, :ku]
        d = np.take_along_axis(hnew[rep], sub_pos, axis=1) - np.take_along_axis(
            st.H[ixr, jj], sub_pos, axis=1)
        d[np.arange(ku)[None, :] >= sub_k[:, None]] = 0.0
        Si = st.Sinv[rep, :ku, :ku]
        col = Si[m, :, jj]  # S^-1 e_j
        row = np.matmul(d[:, None, :], Si)[:, 0, :]  # d^T S^-1
        den = 1.0 + row[m, jj]
        st.Sinv[rep, :ku, :ku] = Si - col[:, :, None] * (row / den[:, None])[:, None, :]
        st.H[ixr, jj] = hnew[rep]
    # --- border: S_new = [[S, bcol], [c^T, dd]], bcol = H[:k, r], c = hnew[P], dd = 1 + hnew_r
    add = np.flatnonzero(new)
    if add.size == new.size:
        add = slice(None)
    if not isinstance(add, np.ndarray) or add.size:
        kk = st.k[add]
        ku = int(kk.max()) + 1
        m = np.arange(kk.size)
        ixa = m if isinstance(add, slice) else add
        ra = r[add]
        bcol = st.H[ixa, :ku, ra]  # rows beyond k are zero
        cvec = np.take_along_axis(hnew[add], st.pos[add, :ku], axis=1)
        cvec[np.arange(ku)[None, :] >= kk[:, None]] = 0.0
        dd = w[ixa, ra]  # S_kk = 1 + hnew_r = w_r
        Si = st.Sinv[add, :ku, :ku]
        Sb = np.matmul(Si, bcol[:, :, None])[:, :, 0]
        cS = np.matmul(cvec[:, None, :], Si)[:, 0, :]
        sigma = dd - np.einsum("li,li->l", cvec, Sb)
        Snew = Si + Sb[:, :, None] * (cS / sigma[:, None])[:, None, :]
        Snew[m, :, kk] = -Sb / sigma[:, None]
        Snew[m, kk, :] = -cS / sigma[:, None]
        Snew[m, kk, kk] = 1.0 / sigma
        st.Sinv[add, :ku, :ku] = Snew
        st.H[ixa, kk] = hnew[add]
        st.pos[ixa, kk] = ra
        st.where[ixa, ra] = kk
        st.k[add] += 1
