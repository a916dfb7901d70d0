"""Eigenvalue bounds of symmetric matrices proven by one floating-point Cholesky factorisation.

A computed eigenvalue is an estimate; a *bound* needs a proof.  The proof used here is the
backward error of Cholesky's algorithm (Demmel 1989; Higham, *Accuracy and Stability of
Numerical Algorithms*, 2nd ed., Theorem 10.5): when the floating-point factorisation of a
symmetric ``X`` runs to completion, the computed ``R`` satisfies ``R^T R = X + D`` with
``|D_ij| <= gamma_{n+1} d_i d_j``, ``d_i = sqrt(X_ii)``, ``gamma_k = k u / (1 - k u)`` (``u``
the unit round-off), so ``||D||_2 <= gamma_{n+1} trace(X)`` and ``X >= -gamma_{n+1} trace(X) I``.
Hence (Rump 2006, *Verification of positive definiteness*, BIT 46, 433-452): if the
factorisation of ``fl(M - s I)`` succeeds, every eigenvalue of ``M`` is at least
``s - gamma_{n+1} trace(fl(M - s I)) - (rounding of the shift)``.  A factor 2 on the rounding
terms covers the blocked (BLAS-3) factorisation of LAPACK, whose constant is of the same order.

:func:`certified_lower_eig` turns an estimate ``s~`` of ``lambda_min(M)`` (from Lanczos, or a
dense solver) into a proven lower bound, and refuses (returns ``-inf``) when the estimate is
wrong by more than the slack it is given; :func:`certified_upper_eig` is the same for
``lambda_max``.  No tolerance here depends on units: every margin is relative to ``M``'s own
diagonal.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

EPS = float(np.finfo(float).eps) / 2  # unit round-off


def gamma(k: int) -> float:
    """``k u / (1 - k u)``: the relative error bound of a ``k``-term floating-point sum."""
    return k * EPS / (1.0 - k * EPS)


def cholesky_succeeds(X) -> bool:
    """Whether LAPACK's Cholesky factorisation of ``X`` (dense, symmetric) runs to completion."""
    try:
        sla.cholesky(X, lower=False, overwrite_a=True, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return False
    return True


def proves_at_least(M, s) -> tuple[bool, float]:
    """Whether one Cholesky factorisation proves ``lambda_min(M) >= lb`` and that ``lb``.

    Parameters
    ----------
    M : ndarray, shape (n, n)
        Symmetric (only its upper triangle is read).
    s : float
        The shift tried: the factorisation of ``fl(M - s I)``.

    Returns
    -------
    ok : bool
        The factorisation succeeded (and ``lb`` is then a proven lower bound).
    lb : float
        ``s - 2 (gamma_{n+1} trace(|fl(M - s I)|) + u max_i |M_ii - s|)`` when ``ok``, else
        ``-inf``.
    """
    M = np.asarray(M, float)
    n = M.shape[0]
    X = np.array(M, order="F", copy=True)
    X[np.diag_indices(n)] -= s
    dg = np.abs(np.diag(X))
    if not np.all(np.isfinite(dg)):
        return False, -np.inf
    margin = 2.0 * (gamma(n + 1) * float(dg.sum()) * (1 + gamma(n)) + EPS * float(dg.max(initial=0.0))
                    + EPS * abs(s))
    if not cholesky_succeeds(X):
        return False, -np.inf
    return True, float(s - margin)


def certified_lower_eig(M, estimate, *, slack=(1e-9, 1e-6, 1e-3)) -> float:
    """A proven lower bound of ``lambda_min(M)`` near ``estimate`` (``-inf`` if none found).

    Tries the shifts ``estimate - t * scale`` for ``t`` in ``slack`` (``scale = max |M_ii|``,
    at least ``|estimate|``), and returns the bound of the first factorisation that succeeds
    (:func:`proves_at_least`).  A wrong ``estimate`` (above the true ``lambda_min`` by more
    than the largest slack) makes every factorisation fail: ``-inf``, never a wrong bound.
    """
    M = np.asarray(M, float)
    scale = max(float(np.abs(np.diag(M)).max(initial=0.0)), abs(float(estimate)), 1e-300)
    for t in slack:
        ok, lb = proves_at_least(M, float(estimate) - t * scale)
        if ok:
            return lb
    return -np.inf


def certified_upper_eig(M, estimate, *, slack=(1e-9, 1e-6, 1e-3)) -> float:
    """A proven upper bound of ``lambda_max(M)`` near ``estimate`` (``inf`` if none found):
    :func:`certified_lower_eig` of ``-M``."""
    return -certified_lower_eig(-np.asarray(M, float), -float(estimate), slack=slack)


__all__ = ["gamma", "cholesky_succeeds", "proves_at_least", "certified_lower_eig",
           "certified_upper_eig"]
