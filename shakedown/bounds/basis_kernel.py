"""The pivots of :class:`~.basis_lp.BasisLP` compiled (numba): one call runs many pivots.

The dual simplex of :meth:`.BasisLP._steps` spends most of a pivot, at the working basis sizes
of the pruning's short LPs (``m`` up to ~100 at ``N = 2000``), in the overhead of some forty
small NumPy calls, not in its three ``O(N m)`` products (issue 26, a dense system of 2000
nodes: 0.41 ms a pivot, of which the products ~0.06 ms).  :func:`advance` is the same loop,
pivot for pivot the same rules (leaving row ``k`` first, then the most infeasible; Harris-style
ties to the largest pivot element; the same tolerances), with the working inverse ``W`` in the
leading ``m x m`` block of a buffer.  It stops and hands back to Python for everything that is
not a pivot: a recomputation of ``W`` from scratch (LU, :meth:`.BasisLP._inverse`), the
optimum (the answer is formed and certified in Python, :meth:`.BasisLP._answer`), the pivot cap
and failures.  Nothing is concluded here: the answers are certified as before.

The slacks of the rows outside the working basis, a pass over ``K_P`` per pivot, only choose
the leaving row ("the most infeasible"): that pass reads a single-precision copy of ``K_P``
(half the bytes; issue 26), the chosen row's slack is recomputed in double, and the pass is
redone in double when that row is not infeasible, so optimality is only ever concluded from
double slacks.  Ties within single precision's rounding may be broken otherwise than by NumPy.

The sums may be reassociated (``fastmath=FAST``, :mod:`shakedown.model.jit`) so that the
products with the working inverse vectorize, and the ``O(N m)`` passes over ``K_P`` and ``K_T``
take four columns or rows at a time: they round differently from NumPy's (issue 26, a crack
network's ``lam_high`` stage 1.4x faster with the same pivots).
"""

from __future__ import annotations

import numpy as np

from ..model.jit import FAST, HAVE_KERNEL, njit
from . import inverse_updates as iu
from .certificates import DenseAnswer

#: What :func:`advance` returns: pivots done (the budget), ``W`` due for a recomputation,
#: optimal, the pivot cap reached (``out[0]``: the dual bound), failed (no entering variable or
#: a vanishing pivot).
BUDGET, REFACTOR, OPTIMAL, CAPPED, FAILED = 0, 1, 2, 3, 4

__all__ = ["HAVE_KERNEL", "advance", "steps", "BUDGET", "REFACTOR", "OPTIMAL", "CAPPED", "FAILED"]


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
def _add_rows2(M, a, b, k, outa, outb):  # pragma: no cover - compiled
    """``outa += a[:k] @ M[:k]`` and ``outb += b[:k] @ M[:k]`` (C-order ``M``) in one pass
    over ``M``, two rows at a time."""
    n = outa.size
    j = 0
    while j + 2 <= k:
        a0, a1, b0, b1 = a[j], a[j + 1], b[j], b[j + 1]
        for e in range(n):
            m0, m1 = M[j, e], M[j + 1, e]
            outa[e] += a0 * m0 + a1 * m1
            outb[e] += b0 * m0 + b1 * m1
        j += 2
    if j < k:
        a0, b0 = a[j], b[j]
        for e in range(n):
            outa[e] += a0 * M[j, e]
            outb[e] += b0 * M[j, e]


@njit(cache=True, fastmath=FAST)
def _slacks(KP, star, mJ, ys, sP, m, T, sJ):  # pragma: no cover - compiled
    """``sJ = star - mJ ys - K_P sP`` (``KP`` in double or single precision), zero on the
    tight rows ``T``."""
    for j in range(sJ.size):
        sJ[j] = star[j] - mJ[j] * ys
    _sub_cols(KP, sP, m, sJ)
    for i in range(m):
        sJ[T[i]] = 0.0


@njit(cache=True, fastmath=FAST)
def _slack(KP, star, mJ, ys, sP, m, j):  # pragma: no cover - compiled
    """Row ``j`` of :func:`_slacks` in double precision (``j`` not tight)."""
    acc = star[j] - mJ[j] * ys
    for i in range(m):
        acc -= KP[j, i] * sP[i]
    return acc


@njit(cache=True, fastmath=FAST)
def advance(K, KF, mJ, y, c, star, lam2, tol, piv_tol, kl, cap, refactor, refactor_div,
            P, T, W, KP, KP32, KT, st, budget, out):  # pragma: no cover - compiled
    """Pivots of :meth:`.BasisLP._steps` from the state ``(P, T, W, KP, KT)`` with ``st =
    [m, pivots, pivots since W was recomputed]`` (updated in place) until one of the codes of
    this module; at most ``budget`` pivots (then :data:`BUDGET`).  ``out[0]``: the dual bound
    ``lam2 - c . sigma`` at the state reached."""
    nJ, ncol = K.shape
    sP = np.empty(ncol)
    sJ = np.empty(nJ)
    z = np.empty(ncol)
    d = np.empty(ncol)
    dc = np.empty(ncol)
    rowq = np.empty(ncol)
    rho = np.empty(ncol)
    ds = np.empty(ncol)
    tmp = np.empty(ncol)
    done = 0
    while True:
        m, it, since = st[0], st[1], st[2]
        if since >= max(refactor, m // refactor_div):
            return REFACTOR
        # primal values of the basic coordinates, the dual bound and (same pass over W) the
        # duals z = -W^T c_P of the tight rows
        cs = 0.0
        ys = 0.0
        for j in range(m):
            tmp[j] = star[T[j]]
            z[j] = 0.0
        for i in range(m):
            acc = 0.0
            a = c[P[i]]
            for j in range(m):
                w_ij = W[i, j]
                acc += w_ij * tmp[j]
                z[j] -= a * w_ij
            sP[i] = acc
            cs += c[P[i]] * acc
            ys += y[P[i]] * acc
        out[0] = lam2 - cs
        if done >= budget:
            return BUDGET
        # slacks of the rows J by a pass over K_P in single precision (half the bytes):
        # they only choose the leaving row, whose slack is then recomputed in double (as is
        # row k's); the pass is redone in double when that row is not infeasible
        _slacks(KP32, star, mJ, ys, sP, m, T, sJ)
        # duals of the tight rows (z above) and their weighted sum
        mz = 0.0
        for j in range(m):
            mz += mJ[T[j]] * z[j]
        kpos = -1
        for j in range(m):
            if T[j] == kl:
                kpos = j
                break
        # leaving: row k first, then the most infeasible
        if kl >= 0 and kpos < 0:
            sJ[kl] = _slack(KP, star, mJ, ys, sP, m, kl)
        if kl >= 0 and kpos < 0 and abs(sJ[kl]) > tol:
            is_row, q, sgn = True, kl, (-1.0 if sJ[kl] > 0 else 1.0)
        else:
            i = 0
            for j in range(1, nJ):
                if sJ[j] < sJ[i]:
                    i = j
            if m:
                sJ[i] = _slack(KP, star, mJ, ys, sP, m, i)
                if not sJ[i] < -tol:  # (none infeasible in single precision): in double
                    _slacks(KP, star, mJ, ys, sP, m, T, sJ)
                    i = 0
                    for j in range(1, nJ):
                        if sJ[j] < sJ[i]:
                            i = j
            r = -1
            worst = sJ[i]
            if m:
                r = 0
                for j in range(1, m):
                    if sP[j] < sP[r]:
                        r = j
                worst = min(sJ[i], sP[r])
            if worst >= -tol:
                return OPTIMAL
            sgn = 1.0
            if sJ[i] <= worst:
                is_row, q = True, i
            else:
                is_row, q = False, r
        if it >= cap:
            return CAPPED
        # pivot row: effect of a unit of each nonbasic variable on the leaving one
        if is_row:
            for i in range(m):
                rowq[i] = K[q, P[i]] + mJ[q] * y[P[i]]
            for j in range(m):
                rho[j] = 0.0
            for i in range(m):
                a = rowq[i]
                for j in range(m):
                    rho[j] += a * W[i, j]
            for e in range(ncol):
                dc[e] = -(K[q, e] + mJ[q] * y[e])
            for j in range(m):
                ds[j] = rho[j]
        else:
            for j in range(m):
                rho[j] = W[q, j]
                ds[j] = -W[q, j]
            for e in range(ncol):
                dc[e] = 0.0
        rm = 0.0
        for j in range(m):
            rm += rho[j] * mJ[T[j]]
        # reduced costs d = c + z K_T + (mJ_T . z) y and the pivot row: one pass over K_T
        for e in range(ncol):
            d[e] = c[e] + y[e] * mz
        _add_rows2(KT, z, rho, m, d, dc)
        for i in range(m):
            d[P[i]] = 0.0
        if is_row:
            for e in range(ncol):
                dc[e] += rm * y[e]
        else:
            for e in range(ncol):
                dc[e] = -(dc[e] + rm * y[e])
        for i in range(m):
            dc[P[i]] = 0.0
        if kpos >= 0:
            ds[kpos] = 0.0
        sc = 0.0
        for e in range(ncol):
            sc = max(sc, abs(dc[e]))
        for j in range(m):
            sc = max(sc, abs(ds[j]))
        thr = piv_tol * max(sc, 1e-300)
        # ratio test, ties (within 1e-12) to the largest pivot element
        tmin = np.inf
        for e in range(ncol):
            if sgn * dc[e] > thr:
                tmin = min(tmin, max(d[e], 0.0) / (sgn * dc[e]))
        for j in range(m):
            if sgn * ds[j] > thr:
                tmin = min(tmin, max(z[j], 0.0) / (sgn * ds[j]))
        if not np.isfinite(tmin):
            return FAILED
        near = tmin + 1e-12 * (1.0 + tmin)
        ic, ec = 0, -np.inf
        for e in range(ncol):
            if sgn * dc[e] > thr and max(d[e], 0.0) / (sgn * dc[e]) <= near and abs(dc[e]) > ec:
                ic, ec = e, abs(dc[e])
        is_, es = 0, -np.inf
        for j in range(m):
            if sgn * ds[j] > thr and max(z[j], 0.0) / (sgn * ds[j]) <= near and abs(ds[j]) > es:
                is_, es = j, abs(ds[j])
        enter_coord = m == 0 or ec >= es
        e = ic if enter_coord else is_
        # basis update (inverse_updates: border, replace_row, replace_column, remove)
        if is_row and enter_coord:
            for i in range(m):
                tmp[i] = KT[i, e] + mJ[T[i]] * y[e]
            schur = K[q, e] + mJ[q] * y[e]
            for i in range(m):  # wb = W tmp (in ds, free after the ratio test)
                acc = 0.0
                for j in range(m):
                    acc += W[i, j] * tmp[j]
                ds[i] = acc
            for i in range(m):
                schur -= rowq[i] * ds[i]
            if not abs(schur) > 0.0:
                return FAILED
            for i in range(m):
                a = ds[i] / schur
                for j in range(m):
                    W[i, j] += a * rho[j]
                W[i, m] = -ds[i] / schur
            for j in range(m):
                W[m, j] = -rho[j] / schur
            W[m, m] = 1.0 / schur
            P[m], T[m] = e, q
            for j in range(nJ):
                KP[j, m] = KF[j, e]
                KP32[j, m] = KF[j, e]
            for col in range(ncol):
                KT[m, col] = K[q, col]
            st[0] = m + 1
        elif is_row:  # row q replaces tight row T[e]
            for i in range(m):
                tmp[i] = rowq[i] - (KT[e, P[i]] + mJ[T[e]] * y[P[i]])
            for j in range(m):
                ds[j] = 0.0
            for i in range(m):
                a = tmp[i]
                for j in range(m):
                    ds[j] += a * W[i, j]
            den = 1.0 + ds[e]
            for i in range(m):
                tmp[i] = W[i, e]
            for i in range(m):
                a = tmp[i] / den
                for j in range(m):
                    W[i, j] -= a * ds[j]
            T[e] = q
            for col in range(ncol):
                KT[e, col] = K[q, col]
        elif enter_coord:  # coordinate e replaces basic coordinate P[q]
            for i in range(m):
                tmp[i] = KT[i, e] + mJ[T[i]] * y[e]
            for i in range(m):
                acc = 0.0
                for j in range(m):
                    acc += W[i, j] * tmp[j]
                ds[i] = acc
            for j in range(m):
                rho[j] = W[q, j] / ds[q]
            for i in range(m):
                a = ds[i]
                for j in range(m):
                    W[i, j] -= a * rho[j]
            for j in range(m):
                W[q, j] = rho[j]
            P[q] = e
            for j in range(nJ):
                KP[j, q] = KF[j, e]
                KP32[j, q] = KF[j, e]
        else:  # coordinate P[q] leaves, tight row T[e] loosens: both removed
            piv = W[q, e]
            for i in range(m):
                tmp[i] = W[i, e]
                rho[i] = W[q, i]
            for i in range(m):
                a = tmp[i] / piv
                for j in range(m):
                    W[i, j] -= a * rho[j]
            last = m - 1
            for j in range(m):  # swap row q with the last, then column e with the last
                W[q, j], W[last, j] = W[last, j], W[q, j]
            for i in range(m):
                W[i, e], W[i, last] = W[i, last], W[i, e]
            P[q], T[e] = P[last], T[last]
            for j in range(nJ):
                KP[j, q] = KP[j, last]
                KP32[j, q] = KP32[j, last]
            for col in range(ncol):
                KT[e, col] = KT[last, col]
            st[0] = last
        st[1] = it + 1
        st[2] = since + 1
        done += 1


def steps(lp, k, kl, max_pivots, KP, KT, piv_tol, verify=True, chunk=None):
    """:meth:`.BasisLP._steps` of ``lp`` with the pivots in :func:`advance`: the same generator
    protocol (yields ``(dual bound, pivots)``, at most every ``chunk`` pivots; returns the
    answer); ``piv_tol``: :data:`.basis_lp.PIV_TOL`."""
    f = lp.f
    ncol = lp.n + 1
    cap = max_pivots if max_pivots is not None else 4 * lp.n + 100
    chunk = cap + 1 if chunk is None else int(chunk)
    P = np.zeros(ncol + 1, np.int64)
    T = np.zeros(ncol + 1, np.int64)
    W = np.empty((ncol + 1, ncol + 1))
    st = np.zeros(3, np.int64)
    out = np.zeros(1)
    KP32 = np.empty(KP.shape, np.float32, order="F")  # K_P in single precision (advance)
    last = 0  # pivots at the last yield
    while True:
        code = advance(lp.K, lp.KF, lp.mJ, f.y, lp.cost, lp.star, f.lam2, lp.tol, piv_tol,
                       kl, cap, iu.REFACTOR, iu.REFACTOR_DIV, P, T, W, KP, KP32, KT, st,
                       max(chunk - (int(st[1]) - last), 1), out)
        m, it = int(st[0]), int(st[1])
        if code == BUDGET:
            last = it
            yield float(out[0]), it
        elif code == REFACTOR:
            Wn = lp._inverse(P[:m], T[:m], KT)
            if Wn is None:
                return lp._failed(it)
            W[:m, :m] = Wn
            st[2] = 0
        elif code == CAPPED:  # stopped: the dual bound ranks the row (screening)
            return DenseAnswer("failed", np.r_[np.full(lp.n, np.nan), out[0]], None,
                               np.zeros(0, int), it, (np.inf,) * 4)
        elif code == FAILED:
            return lp._failed(it)
        else:
            Pl, Tl = [int(p) for p in P[:m]], [int(t) for t in T[:m]]
            Wm = np.ascontiguousarray(W[:m, :m])
            if lp.clipped:
                Wm, it = lp._primal_finish(kl, Pl, Tl, Wm, it, cap, KP, KT)
                if Wm is None:
                    return lp._failed(it)
            return lp._answer(k, Pl, Tl, Wm, it, verify)
