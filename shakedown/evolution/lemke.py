"""Lemke's complementary pivoting method with the lexicographic ratio test.

The textbook algorithm (Cottle, Pang & Stone, *The Linear Complementarity Problem*, 1992,
s.4.4): find ``z >= 0`` with ``w = M z + q >= 0`` and ``z . w = 0``.  A dense tableau is
pivoted; the lexicographic minimum ratio test makes every basis distinct, so the method
terminates (with a solution, or on a secondary ray) even on degenerate problems.

It is used as the robust fallback of the incremental-step solver
(:mod:`shakedown.complementarity`) and as the from-scratch baseline of the benchmarks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import citations


@dataclass(frozen=True)
class LemkeResult:
    """Outcome of :func:`lemke`.

    Attributes
    ----------
    z, w : ndarray, shape (n,)
        The complementary pair (``w = M z + q``); meaningful when ``status == "solved"``.
    status : {"solved", "ray", "max_pivots"}
        ``"ray"``: secondary ray termination (no solution found; for copositive-plus ``M``
        this proves infeasibility, in general it does not).
    pivots : int
        Number of pivots (the initial one included).
    basis : ndarray of int, shape (n,)
        Final basic variables: ``i < n`` is ``w_i``, ``n <= i < 2n`` is ``z_{i-n}``, ``2n`` is
        the artificial ``z0``.
    """

    z: np.ndarray
    w: np.ndarray
    status: str
    pivots: int
    basis: np.ndarray

    @property
    def success(self) -> bool:
        return self.status == "solved"


def _lexmin_row(T, rows, col, n):
    """Among candidate ``rows``, the lexicographic minimum of ``(rhs, B^-1 rows) / col``."""
    cand = np.asarray(rows)
    if cand.size == 1:
        return int(cand[0])
    piv = T[cand, col]
    ratio = T[cand, -1] / piv
    scale = max(1.0, float(np.abs(ratio).max()))
    keep = ratio <= ratio.min() + 1e-12 * scale
    cand, piv = cand[keep], piv[keep]
    k = 0
    while cand.size > 1 and k < n:
        vals = T[cand, k] / piv
        sc = max(1.0, float(np.abs(vals).max()))
        keep = vals <= vals.min() + 1e-12 * sc
        cand, piv = cand[keep], piv[keep]
        k += 1
    return int(cand[0])


def lemke(M, q, *, d=None, max_pivots: int | None = None, pivot_tol: float = 1e-11) -> LemkeResult:
    """Solve the LCP ``0 <= z  perp  M z + q >= 0`` by Lemke's method.

    Parameters
    ----------
    M : array_like, shape (n, n)
    q : array_like, shape (n,)
    d : array_like, shape (n,), optional
        Covering vector (positive); ones by default.
    max_pivots : int, optional
        Pivot budget (default ``50 n + 50``).
    pivot_tol : float
        Column entries below ``pivot_tol * max|column|`` are not pivot candidates.

    Returns
    -------
    LemkeResult
    """
    citations.register("lemke1965")
    M = np.asarray(M, float)
    q = np.asarray(q, float)
    n = q.shape[0]
    if n == 0 or np.all(q >= 0):
        return LemkeResult(np.zeros(n), q.copy(), "solved", 0, np.arange(n))
    d = np.ones(n) if d is None else np.asarray(d, float)
    max_pivots = 50 * n + 50 if max_pivots is None else int(max_pivots)
    # tableau  I w - M z - d z0 = q   (columns: w_0..w_{n-1}, z_0..z_{n-1}, z0, rhs)
    T = np.empty((n, 2 * n + 2))
    T[:, :n] = np.eye(n)
    T[:, n : 2 * n] = -M
    T[:, 2 * n] = -d
    T[:, -1] = q
    basis = np.arange(n)
    z0 = 2 * n

    def pivot(r, c):
        T[r] /= T[r, c]
        col = T[:, c].copy()
        col[r] = 0.0
        T[:] -= np.outer(col, T[r])
        basis[r] = c

    # initial pivot: z0 enters at the level max(-q / d); lexicographic choice among ties
    ratios = q / d
    tie = np.flatnonzero(ratios <= ratios.min() + 1e-12 * max(1.0, abs(ratios.min())))
    # lexicographic minimum of (q_i, e_i) / d_i among the ties is the largest index
    r = int(tie[-1])
    pivot(r, z0)
    leaving = r  # w_r left the basis
    entering = n + leaving
    pivots = 1
    status = "max_pivots"
    while pivots < max_pivots:
        col = T[:, entering]
        cmax = float(np.abs(col).max())
        cand = np.flatnonzero(col > pivot_tol * max(cmax, 1e-300))
        if cand.size == 0:
            status = "ray"
            break
        ratio = T[cand, -1] / col[cand]
        rmin = ratio.min()
        ties = cand[ratio <= rmin + 1e-12 * max(1.0, abs(rmin))]
        z0_row = np.flatnonzero(basis[ties] == z0)
        r = int(ties[z0_row[0]]) if z0_row.size else _lexmin_row(T, ties, entering, n)
        out = int(basis[r])
        pivot(r, entering)
        pivots += 1
        if out == z0:
            status = "solved"
            break
        entering = out + n if out < n else out - n
    x = np.zeros(2 * n + 1)
    x[basis] = np.maximum(T[:, -1], 0.0)
    z = x[n : 2 * n]
    w = M @ z + q
    return LemkeResult(z, w, status, pivots, basis.copy())
