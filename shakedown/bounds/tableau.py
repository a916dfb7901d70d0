"""The shared data of a family of dense LPs ``max e.x s.t. A x <= b`` started from one basis
(:mod:`.dual_simplex`): the scaled rows, the LU factor of the basis, and the tableau ``W = B^-T
A^T`` formed on use, or products with it taken from the LU factor while few are asked for."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import scipy.linalg as sla

#: A run of at most this many LPs starts without the tableau ``W`` (:meth:`Tableau.columns`,
#: :meth:`Tableau.times_w`): its products come from the LU factor, ``O(n^2 + R n)`` each,
#: until :data:`LAZY_PRODUCTS` of them have been asked for; then ``W`` (``O(n^2 R)``) is formed.
#: Issue 26, 2000-crack networks: a crossover of 0-2 pivots and the ``min lam`` start each
#: formed a tableau of ~1.4 s for it.
LAZY_LPS, LAZY_PRODUCTS = 2, 64
#: :meth:`Tableau.rebased`: the largest fraction of changed positions updated, and the largest
#: residual of the updated tableau's check (relative), else it is formed afresh.
REBASE_FRACTION, REBASE_TOL = 0.25, 1e-9


class Tableau:
    """The shared data of a family of LPs: rows ``A`` (unit-norm), ``b``, start basis ``T0``.

    Parameters
    ----------
    A : ndarray, shape (R, n)
    b : ndarray, shape (R,)
    e : ndarray, shape (n,)
        Objective (maximised).
    T0 : ndarray of int, shape (n,)
        Starting basis; ``A_T0^-T e >= 0`` up to rounding (dual feasible) is required.
    like : Tableau, optional
        A tableau of the same ``A`` and ``b`` (another basis, or another objective) whose
        scaled rows are shared instead of scaled again (issue 26, N = 2000: ~0.2 s a tableau,
        four to six of them per ``lam2`` crossover and ``min lam`` start).
    """

    def __init__(self, A, b, e, T0, like=None):
        if like is not None and like.A.shape == A.shape:
            self.rownorm, self.A, self.b = like.rownorm, like.A, like.b
        else:
            self.rownorm = np.linalg.norm(A, axis=1)
            self.rownorm[self.rownorm == 0] = 1.0
            self.A = A / self.rownorm[:, None]
            self.b = b / self.rownorm
        self.e = np.asarray(e, float)
        self.T0 = np.asarray(T0, int)
        R, n = self.A.shape
        self.R, self.n = R, n
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(self.A[self.T0], check_finite=False)
        d = np.abs(np.diag(lu[0]))
        self.singular = bool(not d.min() > 1e-13 * d.max())
        if self.singular:
            self.y0 = np.full(n, -np.inf)
            return
        self._lu = lu
        # the multipliers now (one solve); the inverse and the tableau on first use: a basis
        # whose multipliers are refused is dropped without them (issue 26, N = 2000: an
        # O(n^2 R) tableau of ~2 s for each of the crossover's refused bases)
        self.y0 = sla.lu_solve(lu, self.e, trans=1, check_finite=False)

    @functools.cached_property
    def Binv(self):
        """``A_T0^-1``, shape (n, n)."""
        return sla.lu_solve(self._lu, np.eye(self.n), check_finite=False)

    @functools.cached_property
    def W(self):
        """``A_T0^-T A^T``, shape (n, R): column ``i`` = row ``i`` in basis coordinates."""
        return self.Binv.T @ self.A.T

    def rebased(self, T):
        """The tableau of the same LP at the basis ``T`` (positions as in :attr:`T0`).  Where
        this tableau's ``W`` is formed and at most :data:`REBASE_FRACTION` of the positions
        changed, the new ``W`` comes from it by the Sherman-Morrison-Woodbury formula, ``O(n k
        R)`` for ``k`` changed rows instead of ``O(n^2 R)`` (issue 26, the ``min lam`` start of
        a 2000-crack network: 249 changed rows, 0.5 s against 1.9 s), and is kept only if it
        satisfies ``B^T W = A^T`` on a random combination to :data:`REBASE_TOL` (else ``W`` is
        formed afresh on use)."""
        T = np.asarray(T, int)
        out = Tableau(self.A, self.b, self.e, T, like=self)
        P = np.flatnonzero(self.T0 != T)
        if out.singular or "W" not in self.__dict__ or len(P) > REBASE_FRACTION * self.n:
            return out
        if not len(P):
            out.W = self.W
            return out
        W = self.W
        U = W[:, T[P]].copy()  # B^-T (a_new - a_old) for each changed position
        U[P, np.arange(len(P))] -= 1.0
        try:
            Wn = W - U @ np.linalg.solve(W[np.ix_(P, T[P])], W[P, :])
        except np.linalg.LinAlgError:
            return out
        # checked against its definition B^T W = A^T on a fixed random combination of the
        # basis rows (O(n R)): the formula would carry an error of this W into every column
        r = np.random.default_rng(0).standard_normal(self.n)
        want = self.A @ r
        if np.abs((self.A[T] @ r) @ Wn - want).max() <= REBASE_TOL * max(1.0, np.abs(want).max()):
            out.W = Wn
        return out

    def _lazy(self) -> bool:
        """Whether the next product is taken from the LU factor (``W`` not formed, fewer than
        :data:`LAZY_PRODUCTS` asked for so far)."""
        if "W" in self.__dict__ or getattr(self, "_products", 0) >= LAZY_PRODUCTS:
            return False
        self._products = getattr(self, "_products", 0) + 1
        return True

    def columns(self, p):
        """``W[:, p]`` (shape ``(n, len(p))``), from the LU factor while :meth:`_lazy`."""
        if self._lazy():
            return sla.lu_solve(self._lu, self.A[p].T, trans=1, check_finite=False)
        return self.W[:, p]

    def times_w(self, U):
        """``U @ W`` (``U`` of shape ``(l, n)``), from the LU factor while :meth:`_lazy`."""
        if self._lazy():
            return (self.A @ sla.lu_solve(self._lu, U.T, check_finite=False)).T
        return U @ self.W

    def basic(self, C):
        """``C @ B^-T`` (each row of ``C`` solved with ``A_T0``), from the LU factor unless the
        inverse is formed."""
        if "Binv" in self.__dict__:
            return C @ self.Binv.T
        return sla.lu_solve(self._lu, C.T, check_finite=False).T

    @functools.cached_property
    def x0(self):  # the basic solution, shape (n,); act0 = A x0, shape (R,)
        return sla.lu_solve(self._lu, self.b[self.T0], check_finite=False)

    act0 = functools.cached_property(lambda self: self.A @ self.x0)
    scale_x = functools.cached_property(lambda self: max(float(np.abs(self.x0).max()), 1.0))

    @property
    def dual_feasible(self) -> bool:
        ys = max(float(np.abs(self.y0).max()), np.finfo(float).tiny)
        return bool(self.y0.min(initial=0.0) >= -1e-9 * ys)
