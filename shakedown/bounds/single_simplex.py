"""One LP of the dense dual simplex with an explicit, refactorised basis inverse (issue 14).

:func:`single_dual_simplex` follows the pivoting rules of :func:`.dual_simplex.batch_dual_simplex`
and returns the same certified :class:`~.certificates.DenseAnswer`; it is used for a lone long
LP (the start LP of :mod:`.pruning`, the crossover fallback of :mod:`.dense_lp`), where the
pool's Woodbury update grows with the path.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from .certificates import CERT_TOL, FEAS_TOL, PIVOT_TOL, DenseAnswer, batch_residuals
from .dual_simplex import Tableau
from .inverse_updates import rank1

#: Pivots between two refactorisations of the explicit inverse in :func:`single_dual_simplex`.
REFACTOR_EVERY = 256


def single_dual_simplex(tab: Tableau, equal_rows=(), *, max_pivots=None) -> DenseAnswer:
    """One LP of :func:`batch_dual_simplex` (the same pivoting rules, the same certificate)
    with an explicit basis inverse instead of the Woodbury update: for long paths.

    The pool's update costs ``O(k n)`` per pivot and ``O(k^3)`` per reinversion after ``k``
    pivots, and ``L k n`` memory; on a path of ``k ~ N`` pivots (the "max lam" LPs of the
    rows with the smallest ``lam_high`` on large crack networks) that dominates.  Here one
    pivot is ``B^-T a_p`` and ``A (B^-1 e_r)`` (``O(n^2 + R n)``) and a rank-one update of
    ``B^-1`` (``O(n^2)``, in place); ``B^-1``, ``x``, ``A x`` and ``y`` are recomputed from an
    LU factorisation every :data:`REFACTOR_EVERY` pivots.  Memory ``O(n^2 + R)``.
    """
    n, R = tab.n, tab.R
    if max_pivots is None:
        max_pivots = max(60, 3 * n)
    A, b, e = tab.A, tab.b, tab.e
    tolx = FEAS_TOL * tab.scale_x
    eqmask = np.zeros(R, bool)
    eqmask[list(equal_rows)] = True
    bas = tab.T0.copy()
    sgn = np.ones(n)
    free = eqmask[bas].copy()
    inbasis = np.zeros(R, bool)
    inbasis[bas] = True
    Binv = np.array(tab.Binv, order="C")  # Binv.T is Fortran-ordered: dger works in place
    x, act, y = tab.x0.copy(), tab.act0.copy(), tab.y0.copy()
    piv = 0
    label = "failed"
    def refactor():
        """``B^-1``, ``x``, ``y`` of the current basis from scratch (``None``: singular)."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(sgn[:, None] * A[bas], check_finite=False)
        dg = np.abs(np.diag(lu[0]))
        if not dg.min() > 1e-13 * dg.max():
            return None
        return (lu, sla.lu_solve(lu, sgn * b[bas], check_finite=False),
                sla.lu_solve(lu, e, trans=1, check_finite=False))

    while piv < max_pivots:
        if piv and piv % REFACTOR_EVERY == 0:
            f = refactor()
            if f is None:
                break
            Binv = np.ascontiguousarray(sla.lu_solve(f[0], np.eye(n), check_finite=False))
            x, y = f[1], f[2]
            act = A @ x
        viol = act - b
        pend = eqmask & ~inbasis
        if pend.any():
            pe = np.flatnonzero(pend)
            p = int(pe[np.argmax(np.abs(viol[pe]))])
            has_eq = abs(viol[p]) > tolx
        else:
            has_eq = False
        ineq = np.where(inbasis | eqmask, -np.inf, viol)
        p_in = int(np.argmax(ineq))
        vin = ineq[p_in] > tolx
        if not (has_eq or vin or pend.any()):
            label = "optimal"
            break
        if not has_eq and vin:
            p = p_in
        zero_eq = not (has_eq or vin)
        sp = -1.0 if eqmask[p] and act[p] < b[p] else 1.0
        alpha = sp * (Binv.T @ A[p])
        if zero_eq and not np.any((alpha > PIVOT_TOL) & ~free):
            sp, alpha = -sp, -alpha
        ok = (alpha > PIVOT_TOL) & ~free
        if not ok.any():
            label = "failed" if zero_eq else "infeasible"
            break
        ratio = np.where(ok, np.maximum(y, 0.0) / np.where(ok, alpha, 1.0), np.inf)
        tmin = ratio.min()
        near = ok & (ratio <= tmin + 1e-12 * (1 + abs(tmin)))
        r = int(np.argmax(np.where(near, alpha, -np.inf)))
        ar = alpha[r]
        t_dual = max(y[r], 0.0) / ar
        s = sp * (act[p] - b[p]) / ar
        d = Binv[:, r].copy()  # B^-1 e_r
        x -= s * d
        act -= s * (A @ d)
        y -= t_dual * alpha
        y[r] = t_dual
        w = alpha.copy()
        w[r] -= 1.0
        # B^-1 -= d w^T / alpha_r (row r of B becomes sp a_p), in place on the C view
        Binv = rank1(Binv, -1.0 / ar, d, w)
        inbasis[bas[r]] = False
        inbasis[p] = True
        bas[r] = p
        sgn[r] = sp
        free[r] = eqmask[p]
        piv += 1
    if label == "optimal":  # the answer from the final basis itself, not the updates
        f = refactor()
        if f is None:
            label = "failed"
        else:
            x, y = f[1], f[2]
    Y = np.zeros(R)
    Y[bas] = y * sgn
    res = batch_residuals(A, b, e, x[None, :], Y[None, :], eqmask[None, :])[0]
    if label == "optimal" and max(res) > CERT_TOL:
        label = "failed"
    rr = tuple(float(v) for v in res) if label == "optimal" else (np.nan,) * 4
    return DenseAnswer(label, x, Y / tab.rownorm, bas, piv, rr)
