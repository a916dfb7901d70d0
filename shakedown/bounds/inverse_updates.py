"""``O(m^2)`` updates of an explicit inverse ``W = M^-1`` when ``M`` changes by one row or
column, grows by one of each, or loses one of each (the working bases of the walks and LPs in
the coordinates of the ``lam2`` basis, :mod:`.barycentric_walk`, :mod:`.basis_lp`).

Rows of ``W`` go with the columns of ``M`` and columns of ``W`` with its rows.  Every function
returns the new ``W`` (C-order; the argument may be overwritten) and takes the products it
needs precomputed by the caller, who has them from the ratio test anyway.  The pivot elements
are the ratio test's, bounded away from zero there; callers recompute ``W`` from scratch every
so many updates to bound the drift.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

#: Pivots between two recomputations of the working basis's inverse from scratch: at least
#: ``REFACTOR``, and ``m // REFACTOR_DIV`` for an ``m``-square basis: a recomputation costs
#: ``O(m^3)``, a pivot ``O(N m)`` (issue 26, N = 2000 crack networks: m ~ 600-940, a
#: recomputation ~85 ms against ~5 ms per pivot; every 50 pivots it was a fifth of the walks).
#: ``m // 2`` since the pivots run compiled (a walk pivot ~1.1 ms at ``m`` ~ 600, a
#: recomputation ~35 ms): the ``lam_high`` stage of the 2000-crack network i = 11 with the same
#: pivots 116.1 s against 122.2 s side by side (i = 2: 75.4 against 79.0 s), the walk's inverse
#: off its recomputation by at most 2.5e-11 of its largest entry (median 1.6e-13) against
#: 2.0e-11 (1.0e-13) every ``m // 4``.
REFACTOR = 50
REFACTOR_DIV = 2


#: A working basis whose LU factor has a pivot below this fraction of its largest counts as
#: singular (:func:`factor`).
SINGULAR = 1e-12


def factor(M):
    """The LU factorisation ``(lu, piv)`` of the square ``M`` (LAPACK ``getrf``), ``None`` if a
    pivot falls below :data:`SINGULAR` of the largest."""
    lu, piv, info = sla.lapack.dgetrf(M)
    d = np.abs(np.diag(lu))
    if info < 0 or not d.size or not d.min() > SINGULAR * d.max():
        return None
    return lu, piv


def inverse(M):
    """``M^-1`` (C-order) from :func:`factor` and LAPACK ``getri`` (a third cheaper than
    solving for the identity: issue 26, ``m = 600``, 19 against 29 ms), ``None`` where
    :func:`factor` is."""
    f = factor(M)
    if f is None:
        return None
    lwork = int(sla.lapack.dgetri_lwork(len(M))[0])
    W, info = sla.lapack.dgetri(f[0], f[1], lwork=max(lwork, 1), overwrite_lu=1)
    return np.ascontiguousarray(W) if info == 0 else None


def solve(f, b, trans=False):
    """``M^-1 b`` (``trans``: ``M^-T b``) with ``f = factor(M)``."""
    return sla.lu_solve(f, b, trans=1 if trans else 0, check_finite=False)


def refactor_due(since: int, m: int) -> bool:
    """Whether an ``m``-square explicit inverse updated ``since`` times is due for a
    recomputation from scratch (:data:`REFACTOR`, :data:`REFACTOR_DIV`)."""
    return since >= max(REFACTOR, m // REFACTOR_DIV)


def rank1(W, alpha, x, y):
    """``W + alpha x y^T`` in place (BLAS ``dger`` on the transposed view of C-order ``W``)."""
    if not W.flags.c_contiguous:
        W = np.ascontiguousarray(W)
    return sla.blas.dger(alpha, y, x, a=W.T, overwrite_a=True).T


def replace_column(W, q, wc):
    """Column ``q`` of ``M`` replaced by ``a``; ``wc = W a`` (``wc[q] != 0``)."""
    piv = W[q] / wc[q]
    W = rank1(W, -1.0, wc, piv)
    W[q] = piv
    return W


def replace_row(W, r, dw, denom):
    """Row ``r`` of ``M`` replaced: ``M' = M + e_r delta^T``; ``dw = delta^T W`` and
    ``denom = 1 + dw[r]`` (``!= 0``)."""
    return rank1(W, -1.0 / denom, W[:, r].copy(), dw)


def border(W, wb, cw, schur):
    """``M' = [[M, a], [c^T, d]]``; ``wb = W a``, ``cw = c^T W``, ``schur = d - c^T W a``."""
    m = W.shape[0]
    Wn = np.empty((m + 1, m + 1))
    Wn[:m, :m] = rank1(W, 1.0 / schur, wb, cw)
    Wn[:m, m] = -wb / schur
    Wn[m, :m] = -cw / schur
    Wn[m, m] = 1.0 / schur
    return Wn


def remove(W, q, r):
    """Column ``q`` and row ``r`` of ``M`` removed (``W[q, r] != 0``).  The last column and
    row of ``M`` take their places (swap with the last, then drop): the caller moves its labels
    the same way."""
    W = rank1(W, -1.0 / W[q, r], W[:, r].copy(), W[q].copy())
    last = W.shape[0] - 1
    W[[q, last]] = W[[last, q]]
    W[:, [r, last]] = W[:, [last, r]]
    return np.ascontiguousarray(W[:-1, :-1])
