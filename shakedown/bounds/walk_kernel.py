"""The pivots of :class:`~.barycentric_walk.BarycentricWalk` compiled (numba).

:func:`pivots` is the loop of :meth:`.BarycentricWalk._pivot` and :meth:`._update`, pivot for
pivot the same rules (Dantzig pricing, the target's row first among ties of the ratio test, then
the largest pivot element; the same tolerances), on the walk's state kept in buffers of fixed
capacity.  It hands back to Python (:func:`walk`) for what is not a pivot: the recomputation of
the working inverse from scratch, the check of a batch of vertices in ``v``, the end of the walk.
Nothing is concluded here: the vertices are checked in ``v`` as before (issue 26: at ``m`` ~ 50
rows tight outside the ``lam2`` basis a pivot spent ~0.3 ms in small NumPy calls).

At ``m`` ~ 600 (2000-crack networks) a pivot streams ~20 MB (``K_P``, ``K_T``, the inverse
``W``), so two passes are spared (issue 26): the multipliers ``W^T g_P`` of the next pivot are
summed while the update writes ``W``, and the pricing pass reads a single-precision copy of
``K_T`` (:data:`SINGLE_MARGIN`).  That pass only picks the entering coordinate: its reduced
cost is recomputed in double, the pass is redone in double when that one does not improve, and
optimality is only ever concluded from the double pass.  Ties within single precision's
rounding (~1e-7 of the scale) may be broken otherwise than by NumPy's Dantzig pricing.

The sums may be reassociated (``fastmath=FAST``, :mod:`shakedown.model.jit`) so that the
products with the working inverse vectorize, and the ``O(N m)`` passes over ``K_P`` and ``K_T``
take four columns or rows at a time: they round differently from NumPy's (issue 26, a crack
network's ``lam_high`` stage 1.4x faster with the same pivots).
"""

from __future__ import annotations

import numpy as np

from ..model.jit import FAST, HAVE_KERNEL, njit
from . import inverse_updates as iu

#: What :func:`pivots` returns: the budget spent, ``W`` due for a recomputation, the batch of
#: vertices to check is full, the target row became tight, optimal (the target stays slack),
#: broken (unbounded, or more tight rows than allowed).
BUDGET, REFACTOR, FLUSH, REACHED, OPTIMAL, BROKEN = 0, 1, 2, 3, 4, 5
#: The entering coordinate picked in single precision is taken if its reduced cost, recomputed
#: in double, exceeds this many times the pivot tolerance (else the pricing is redone in
#: double): the single-precision pass errs by ~1e-7 of the scale.
SINGLE_MARGIN = 1e5

__all__ = ["HAVE_KERNEL", "pivots", "walk"]


@njit(cache=True, fastmath=FAST)
def _sub_rows(M, a, k, out):  # pragma: no cover - compiled
    """``out -= a[:k] @ M[:k]`` (C-order ``M``), four rows a pass over ``out``."""
    n = out.size
    j = 0
    while j + 4 <= k:
        a0, a1, a2, a3 = a[j], a[j + 1], a[j + 2], a[j + 3]
        for e in range(n):
            out[e] -= a0 * M[j, e] + a1 * M[j + 1, e] + a2 * M[j + 2, e] + a3 * M[j + 3, e]
        j += 4
    for jr in range(j, k):
        a0 = a[jr]
        for e in range(n):
            out[e] -= a0 * M[jr, e]


@njit(cache=True, fastmath=FAST)
def _sub_cols(M, a, k, out):  # pragma: no cover - compiled
    """``out -= M[:, :k] @ a[:k]`` (Fortran-order ``M``), four columns a pass over ``out``."""
    n = out.size
    i = 0
    while i + 4 <= k:
        a0, a1, a2, a3 = a[i], a[i + 1], a[i + 2], a[i + 3]
        for r in range(n):
            out[r] -= M[r, i] * a0 + M[r, i + 1] * a1 + M[r, i + 2] * a2 + M[r, i + 3] * a3
        i += 4
    for ic in range(i, k):
        a0 = a[ic]
        for r in range(n):
            out[r] -= M[r, ic] * a0


@njit(cache=True, fastmath=FAST)
def _price(g, y, z, nT, KT, P, m, rc):  # pragma: no cover - compiled
    """Dantzig pricing: ``rc = g - z_0 y - z_T K_T`` (``KT`` in double or single precision)
    with the basic coordinates zeroed; returns ``(e, best, jj, scale)``: the entering
    coordinate (``-1``: the slack of tight row ``jj``), its reduced cost, and the scale of the
    reduced costs and multipliers."""
    ncol = rc.size
    w = z[0]
    for e in range(ncol):
        rc[e] = g[e] - w * y[e]
    _sub_rows(KT, z[1:], nT, rc)
    for i in range(m):
        rc[P[i]] = 0.0
    scale = 1e-300
    for e in range(ncol):
        scale = max(scale, abs(rc[e]))
    for j in range(nT):
        scale = max(scale, abs(z[1 + j]))
    e = 0
    for c in range(1, ncol):
        if rc[c] > rc[e]:
            e = c
    best = rc[e]
    jj = -1
    if nT:
        jj = 0
        for j in range(1, nT):
            if z[1 + j] < z[1 + jj]:
                jj = j
        if -z[1 + jj] > best:
            best, e = -z[1 + jj], -1
    return e, best, jj, scale


@njit(cache=True, fastmath=FAST)
def pivots(K, KF, y, g, kl, piv_tol, limit, refactor, refactor_div, P, Tl, W, KP, KT, KT32, sP,
           sJ, covered, unchecked, Jrows, S, room, st, budget):  # pragma: no cover - compiled
    """Pivots of ``max g . sigma`` from the state ``(P, Tl, W, KP, KT, sP, sJ)`` with ``st =
    [m, pivots since W was recomputed, vertices written to S, whether the current vertex is
    held]`` (updated in place), at most ``budget``; a code of this module."""
    nJ, ncol = K.shape
    z = np.empty(ncol)
    rc = np.empty(ncol)
    col = np.empty(ncol)
    dP = np.empty(ncol)
    dS = np.empty(nJ)
    zn = np.empty(ncol + 1)  # W^T g_P of the next pivot, summed as its update writes W
    fresh = False  # zn holds it
    done = 0
    while done < budget:
        m, since = st[0], st[1]
        nT = m - 1
        # pricing: reduced costs per unit of slack
        if fresh:
            for j in range(m):
                z[j] = zn[j]
        else:
            for j in range(m):  # z = W^T g_P, by rows of W (contiguous)
                z[j] = 0.0
            for i in range(m):
                a = g[P[i]]
                for j in range(m):
                    z[j] += a * W[i, j]
        fresh = False
        # the pass over K_T in single precision (half the bytes) picks the entering
        # coordinate; its reduced cost is then recomputed in double, and the pass is redone in
        # double when that one does not improve or nothing seems to
        e, best, jj, scale = _price(g, y, z, nT, KT32, P, m, rc)
        if e >= 0:
            exact = g[e] - z[0] * y[e]
            for j in range(nT):
                exact -= z[1 + j] * KT[j, e]
            best = exact
        if not best > SINGLE_MARGIN * piv_tol * scale:
            e, best, jj, scale = _price(g, y, z, nT, KT, P, m, rc)
        if not best > piv_tol * scale:
            return OPTIMAL
        # the edge: basic coordinates and slacks per unit of the entering variable
        if e >= 0:
            col[0] = y[e]
            for i in range(nT):
                col[1 + i] = KT[i, e]
            for i in range(m):
                acc = 0.0
                for j in range(m):
                    acc += W[i, j] * col[j]
                dP[i] = -acc
            for r in range(nJ):
                dS[r] = -KF[r, e]
        else:
            for i in range(m):
                dP[i] = -W[i, 1 + jj]
            for r in range(nJ):
                dS[r] = 0.0
        _sub_cols(KP, dP, m, dS)
        for i in range(nT):
            dS[Tl[i]] = 0.0
        if e < 0:
            dS[Tl[jj]] = 1.0
        # ratio test over the basic coordinates and the slacks of the rows not tight
        mp = 1.0
        for i in range(m):
            mp = max(mp, abs(dP[i]))
        ms = 1.0
        for r in range(nJ):
            ms = max(ms, abs(dS[r]))
        tl, ts = piv_tol * mp, piv_tol * ms
        tmin = np.inf
        for i in range(m):
            if dP[i] < -tl:
                tmin = min(tmin, max(sP[i], 0.0) / -dP[i])
        for r in range(nJ):
            if dS[r] < -ts:
                tmin = min(tmin, max(sJ[r], 0.0) / -dS[r])
        if not np.isfinite(tmin):
            return BROKEN
        near = tmin + 1e-12 * (1.0 + tmin)
        if dS[kl] < -ts and max(sJ[kl], 0.0) / -dS[kl] <= near:
            is_row, q = True, kl
        else:
            il, cl = 0, -np.inf
            for i in range(m):
                if dP[i] < -tl and max(sP[i], 0.0) / -dP[i] <= near and -dP[i] > cl:
                    il, cl = i, -dP[i]
            is_, cs = 0, -np.inf
            for r in range(nJ):
                if dS[r] < -ts and max(sJ[r], 0.0) / -dS[r] <= near and -dS[r] > cs:
                    is_, cs = r, -dS[r]
            is_row, q = (False, il) if cl >= cs else (True, is_)
        if is_row and nT + (1 if e >= 0 else 0) > limit:
            return BROKEN
        if e < 0 and st[3] == 0 and not covered[Jrows[Tl[jj]]] and not unchecked[Jrows[Tl[jj]]]:
            # row Tl[jj] is about to loosen: the vertex joins the batch (BarycentricWalk._hold)
            v = st[2]
            for c in range(ncol):
                S[v, c] = 0.0
            for i in range(m):
                S[v, P[i]] = sP[i]
            for i in range(nT):
                unchecked[Jrows[Tl[i]]] = True
            st[2], st[3] = v + 1, 1
            if v + 1 >= room:
                return FLUSH  # this pivot is taken again after the check
        # move to the adjacent vertex
        step = tmin
        for i in range(m):
            sP[i] += step * dP[i]
        for r in range(nJ):
            sJ[r] += step * dS[r]
        if is_row:
            sJ[q] = 0.0
        else:
            sP[q] = 0.0
        if not is_row and e >= 0:  # column q of M replaced by column e: wc = -dP
            pq = -dP[q]
            for j in range(m):
                col[j] = W[q, j] / pq
                zn[j] = 0.0
            P[q] = e
            for i in range(m):  # (and the next multipliers from the rows written)
                if i == q:
                    for j in range(m):
                        W[q, j] = col[j]
                else:
                    a = -dP[i]
                    for j in range(m):
                        W[i, j] -= a * col[j]
                a = g[P[i]]
                for j in range(m):
                    zn[j] += a * W[i, j]
            fresh = True
            sP[q] = step
            for r in range(nJ):
                KP[r, q] = KF[r, e]
        elif not is_row:  # column q and row 1 + jj of M removed (the last ones move in)
            rr = 1 + jj
            piv = W[q, rr]
            for i in range(m):
                col[i] = W[i, rr]
                z[i] = W[q, i]
            for i in range(m):
                a = col[i] / piv
                for j in range(m):
                    W[i, j] -= a * z[j]
            last = m - 1
            for j in range(m):
                W[q, j], W[last, j] = W[last, j], W[q, j]
            for i in range(m):
                W[i, rr], W[i, last] = W[i, last], W[i, rr]
            P[q], Tl[jj] = P[last], Tl[nT - 1]
            sP[q] = sP[last]
            for r in range(nJ):
                KP[r, q] = KP[r, last]
            for c in range(ncol):
                KT[jj, c] = KT[nT - 1, c]
                KT32[jj, c] = KT32[nT - 1, c]
            st[0] = m - 1
        elif e >= 0:  # column e and row q added: schur = -dS[q]
            schur = -dS[q]
            for j in range(m):  # cw = K[q, P] W
                z[j] = 0.0
            for i in range(m):
                a = K[q, P[i]]
                for j in range(m):
                    z[j] += a * W[i, j]
            for j in range(m + 1):
                zn[j] = 0.0
            for i in range(m):  # (and the next multipliers from the rows written)
                a = -dP[i] / schur
                for j in range(m):
                    W[i, j] += a * z[j]
                W[i, m] = dP[i] / schur
                a = g[P[i]]
                for j in range(m + 1):
                    zn[j] += a * W[i, j]
            for j in range(m):
                W[m, j] = -z[j] / schur
            W[m, m] = 1.0 / schur
            a = g[e]
            for j in range(m + 1):
                zn[j] += a * W[m, j]
            fresh = True
            P[m], Tl[nT] = e, q
            sP[m] = step
            for r in range(nJ):
                KP[r, m] = KF[r, e]
            for c in range(ncol):
                KT[nT, c] = K[q, c]
                KT32[nT, c] = K[q, c]
            st[0] = m + 1
        else:  # row 1 + jj of M replaced by row q of K
            rr = 1 + jj
            for i in range(m):
                col[i] = K[q, P[i]] - KT[jj, P[i]]
            for j in range(m):
                z[j] = 0.0
            for i in range(m):
                a = col[i]
                for j in range(m):
                    z[j] += a * W[i, j]
            den = dS[q]
            for i in range(m):
                col[i] = W[i, rr] / den
                zn[i] = 0.0
            for i in range(m):  # (and the next multipliers from the rows written)
                a = col[i]
                for j in range(m):
                    W[i, j] -= a * z[j]
                a = g[P[i]]
                for j in range(m):
                    zn[j] += a * W[i, j]
            fresh = True
            Tl[jj] = q
            for c in range(ncol):
                KT[jj, c] = K[q, c]
                KT32[jj, c] = K[q, c]
        done += 1
        st[1] = since + 1
        st[3] = 0
        m = st[0]
        if st[1] >= max(refactor, m // refactor_div):
            return REFACTOR
        for i in range(m - 1):
            if Tl[i] == kl:
                return REACHED
    return BUDGET


def walk(bw, g, kl, cap, check_batch, piv_tol):
    """Up to ``cap + 1`` pivots of ``bw`` (a :class:`.BarycentricWalk`) towards ``max g .
    sigma`` in :func:`pivots`, as its Python loop: ``"optimal"``, ``"reached"`` (row ``kl``
    tight), ``None`` (broken) or ``"cap"``.  The kernel's buffers live on the walk; its
    ``W`` and ``sP`` are views of them between calls (copied in only after Python replaced
    them, as a recomputation does)."""
    f = bw.f
    if getattr(bw, "_kbuf", None) is None:
        capm = bw.KP.shape[1]
        bw._kbuf = (np.zeros(capm, np.int64), np.zeros(capm, np.int64), np.empty((capm, capm)),
                    np.empty(capm), np.empty((check_batch, f.K.shape[1])), np.zeros(4, np.int64))
        bw.KT32 = np.empty(bw.KT.shape, np.float32)  # K_T in single precision (pricing)
        bw.kt32_rows = -1
    P, Tl, W, sP, S, st = bw._kbuf

    def load():
        m = len(bw.P)
        P[:m], Tl[: m - 1] = bw.P, bw.Tl
        st[3] = bw._held
        if not (bw.W.base is W and bw.W.shape == (m, m)):
            W[:m, :m] = bw.W
        if not (bw.sP.base is sP and len(bw.sP) == m):
            sP[:m] = bw.sP
        st[0], st[1], st[2] = m, bw.since, 0
        if bw.kt32_rows != m - 1:  # K_T set by Python (a recomputation): copied anew
            bw.KT32[: m - 1] = bw.KT[: m - 1]
        bw.kt32_rows = m - 1

    def store():
        m = int(st[0])
        bw.P, bw.Tl = P[:m].tolist(), Tl[: m - 1].tolist()
        bw.W, bw.sP, bw.since, bw._held = W[:m, :m], sP[:m], int(st[1]), bool(st[3])
        bw._buffer.extend(S[i].copy() for i in range(int(st[2])))
        st[2] = 0

    load()
    left = cap + 1
    while left > 0:
        before = int(st[1])
        code = pivots(f.K, f.KF, f.y, g, kl, piv_tol, bw.limit, iu.REFACTOR, iu.REFACTOR_DIV,
                      P, Tl, W, bw.KP, bw.KT, bw.KT32, sP, bw.sJ, bw.covered, bw.unchecked, f.J, S,
                      check_batch - len(bw._buffer), st, left)
        done = int(st[1]) - before
        bw.pivots += done
        left -= done
        store()
        bw.kt32_rows = int(st[0]) - 1
        if code == OPTIMAL:
            return "optimal"
        if code == BROKEN:
            return None
        if code == REFACTOR:
            if not bw._refactor():
                return None
        elif code == FLUSH and not bw._flush():
            return None
        if code in (REACHED, BUDGET) or kl in bw.Tl:
            return "reached" if kl in bw.Tl else "cap"
        load()
    return "cap"
