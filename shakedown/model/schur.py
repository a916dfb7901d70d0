"""The reduced stiffness as the Schur complement of a sparse stiffness, never formed.

An FE interface with thousands of contact nodes has a sparse stiffness ``K_z`` in the contact
unknowns ``z = (v, w)`` and the interior DOFs ``u``:

    K_z = [[K_cc, K_ci],
           [K_ic, K_ii]],        K = K_cc - K_ci K_ii^-1 K_ic   (shape (2N, 2N)).

The condensed ``K`` is dense (every contact node sees every other through the body), so
forming it costs ``O(N^2)`` memory and ``2N`` solves with ``K_ii``, or, by the boundary-layer
ordering of :mod:`shakedown.fe`, a dense trailing factor.  :class:`SchurStiffness` keeps
``K_z`` and one sparse LU of ``K_ii`` and behaves like the dense ``K`` where the analyses read
it: products ``K @ X`` and ``X @ K`` (one block solve with ``K_ii``), rows and columns
(solves for those columns only), its diagonal (``2N`` solves in blocks, once), and
``toarray()`` (the condensation, in blocks of columns, for the analyses that need the dense
``K``).  The step of :mod:`shakedown.evolution` does not use it: it factorizes each node-state
assignment's system together with ``K_ii`` (one sparse LU of the assignment's rows of ``K_z``
and the interior rows, see :class:`~shakedown.evolution.factors.FactorCache`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import InputError, NotPositiveDefiniteError, ShapeError

#: Memory budget [bytes] of one block of dense solves with ``K_ii`` (columns of ``K``).
BLOCK_BYTES = 64 * 2**20

#: Largest dense ``C`` block [bytes] kept from the diagonal's columns for the uniqueness
#: certificate (``lambda_max(F C F)``): ``N <= 5792``.  A long interface's ``C`` has a tight
#: cluster of largest eigenvalues (relative gap ~5e-6 on a 1000-node strip): Lanczos needs
#: 1400-3100 products at N = 1000-2000, more than the ``N`` solves of the block, while
#: the dense symmetric eigensolver on the kept block costs ~1 s at N = 2000.
DENSE_C_BYTES = 256 * 2**20


class SchurStiffness:
    """``K = K_cc - K_ci K_ii^-1 K_ic`` of a sparse symmetric ``K_z`` (see module doc).

    Parameters
    ----------
    Kz : scipy.sparse matrix, shape (dim N + m, dim N + m)
        Symmetric; its first ``dim N`` rows and columns are the contact unknowns in the order
        ``(v_1 .. v_N, w_1 .. w_N)`` (2-D) or ``(v_1x, v_1y, .., v_Nx, v_Ny, w_1 .. w_N)``
        (3-D) [force / length], the last ``m`` the interior DOFs.
    n_nodes : int
        ``N``.
    dim : {2, 3}
        Space dimension (``dim - 1`` tangential unknowns per node).
    """

    ndim = 2
    dtype = np.dtype(float)
    __array_ufunc__ = None  # ``ndarray @ K`` defers to ``K.__rmatmul__``

    def __init__(self, Kz, n_nodes: int, dim: int = 2):
        if not sp.issparse(Kz):
            raise InputError(f"Kz must be a scipy.sparse matrix; got {type(Kz).__name__}")
        if dim not in (2, 3):
            raise InputError(f"dim must be 2 or 3; got {dim!r}")
        Kz = sp.csr_matrix(Kz, dtype=float)
        n = int(n_nodes)
        if Kz.shape[0] != Kz.shape[1] or n < 1 or Kz.shape[0] < dim * n:
            raise ShapeError(f"Kz must be square with at least {dim} * n_nodes = {dim * n} rows; "
                             f"got shape {Kz.shape}")
        Kz.sum_duplicates()
        Kz.sort_indices()
        self.dim, self.nt, self.m = dim, (dim - 1) * n, dim * n
        self.Kz, self.n, self.n_interior = Kz, n, Kz.shape[0] - dim * n
        c = dim * n
        self.Kcc = Kz[:c, :c].tocsr()
        self.Kci = Kz[:c, c:].tocsr()
        self.Kic = Kz[c:, :c].tocsc()  # columns of K_ic: right-hand sides of the solves
        self.Kii = Kz[c:, c:].tocsc()
        self.interior_rows = Kz[c:].tocsr()  # [K_ic, K_ii]: the step's always-free equations
        self._lu = None
        self._diag = self._diag_b = self._C = None

    def __getstate__(self):  # the SuperLU factor does not pickle: refactorized on first use
        state = dict(self.__dict__)
        state["_lu"] = None
        state["_C"] = None
        return state

    # ------------------------------------------------------------------ basics
    @property
    def shape(self) -> tuple[int, int]:
        return (self.m, self.m)

    @property
    def T(self) -> SchurStiffness:
        return self  # symmetric

    @property
    def nnz(self) -> int:
        """Stored entries of ``K_z`` (the dense ``K`` would hold ``(dim N)^2``)."""
        return int(self.Kz.nnz)

    @property
    def lu(self):
        """SuperLU factor of ``K_ii`` (computed once, on first use)."""
        if self._lu is None and self.n_interior:
            try:
                self._lu = spla.splu(self.Kii)
            except RuntimeError:
                raise NotPositiveDefiniteError(
                    "K_ii (the interior block of Kz) is singular: the body has a rigid-body "
                    "mode that the contact nodes do not hold; hold a boundary") from None
        return self._lu

    def solve_interior(self, rhs: np.ndarray) -> np.ndarray:
        """``K_ii^-1 rhs`` (rhs shape (m,) or (m, k))."""
        return self.lu.solve(np.asarray(rhs, float))

    # ------------------------------------------------------------------ products
    def __matmul__(self, x):
        x = np.asarray(x, float)
        if x.shape[0] != self.m:
            raise ShapeError(f"K @ x needs x with {self.m} rows; got shape {x.shape}")
        if x.ndim == 2 and x.shape[1] > 1:  # blocks of columns within the memory budget
            out = np.empty((self.m, x.shape[1]))
            for s in self._blocks(x.shape[1]):
                out[:, s] = self._apply(x[:, s])
            return out
        return self._apply(x)

    def _apply(self, x):
        y = self.Kcc @ x
        if self.n_interior:
            y -= self.Kci @ self.lu.solve(np.asarray(self.Kic @ x))
        return y

    def __rmatmul__(self, x):
        x = np.asarray(x, float)
        return (self @ x.T).T  # K symmetric: x K = (K x^T)^T

    def _blocks(self, k: int):
        size = max(1, int(BLOCK_BYTES // (8 * max(self.n_interior, 1))))
        return [slice(s, min(s + size, k)) for s in range(0, k, size)]

    # ------------------------------------------------------------------ entries
    def columns(self, idx) -> np.ndarray:
        """Dense columns ``K[:, idx]``, shape (dim N, len(idx)) (one solve per column,
        blocked)."""
        idx = np.arange(self.m)[idx] if isinstance(idx, slice) else np.atleast_1d(
            np.asarray(idx, int))
        out = np.empty((self.m, idx.size))
        for s in self._blocks(idx.size):
            cols = idx[s]
            block = self.Kcc[:, cols].toarray()
            if self.n_interior:
                block -= self.Kci @ self.lu.solve(self.Kic[:, cols].toarray())
            out[:, s] = block
        return out

    def __getitem__(self, key):
        """Dense rows ``K[rows]`` or a block ``K[np.ix_(rows, cols)]`` (K is symmetric: rows are
        computed as columns)."""
        if isinstance(key, tuple):
            if len(key) != 2:
                raise IndexError("K takes at most two indices")
            rows, cols = key
            rows = np.ravel(rows) if not isinstance(rows, slice) else rows
            cols = np.ravel(cols) if not isinstance(cols, slice) else cols
            return self.columns(rows).T[:, cols] if _count(rows, self.m) <= _count(
                cols, self.m) else self.columns(cols)[rows]
        single = np.ndim(key) == 0 and not isinstance(key, slice)
        rows = self.columns(key).T
        return rows[0] if single else rows

    def diagonal(self) -> np.ndarray:
        """``diag(K)`` (``dim N`` solves with ``K_ii`` in blocks, computed once), shape (dim N,)."""
        if self._diag is None:
            self._diag = self._diagonals()[0]
        return self._diag.copy()

    def _diagonals(self):
        """``diag(K)`` and ``diag(B)`` (the coupling ``K[j, N + j]``; in 3-D the node blocks
        ``K[2j + a, 2N + j]``, shape (N, 2)), from the columns in blocks; the dense ``C``
        block is kept from the same columns within :data:`DENSE_C_BYTES`."""
        n, nt, t = self.n, self.nt, self.dim - 1
        d = np.empty(self.m)
        db = np.empty(n) if t == 1 else np.empty((n, 2))
        C = np.empty((n, n)) if 8 * n * n <= DENSE_C_BYTES else None
        for s in self._blocks(n):
            j = np.arange(n)[s]
            k = np.arange(j.size)
            colsw = self.columns(nt + j)
            for a in range(t):
                colsv = self.columns(t * j + a)
                d[t * j + a] = colsv[t * j + a, k]
                if t == 1:
                    db[j] = colsw[j, k]
                else:
                    db[j, a] = colsw[t * j + a, k]
            d[nt + j] = colsw[nt + j, k]
            if C is not None:
                C[:, j] = colsw[nt:]
        self._diag, self._diag_b = d, db
        if C is not None:
            self._C = 0.5 * (C + C.T)
        return d, db

    def dense_C(self) -> np.ndarray | None:
        """The dense ``C`` block (``N x N``, exactly symmetric) when it fits
        :data:`DENSE_C_BYTES` (from the diagonal's columns, kept), else ``None``."""
        if self._C is None and 8 * self.n * self.n <= DENSE_C_BYTES:
            self._diagonals()
        return self._C

    def block_diagonals(self):
        """``(diag A, diag B, diag C)`` of ``K = [[A, B], [B^T, C]]``, shapes (N,) in 2-D; in
        3-D (2N,), (N, 2) (see :meth:`_diagonals`) and (N,)."""
        if self._diag_b is None:
            self._diagonals()
        nt = self.nt
        return self._diag[:nt].copy(), self._diag_b.copy(), self._diag[nt:].copy()

    def toarray(self) -> np.ndarray:
        """The dense ``K`` (the condensation, ``dim N`` solves in blocks; exactly symmetric)."""
        K = self.columns(np.arange(self.m))
        return 0.5 * (K + K.T)


def _count(idx, m) -> int:
    return m if isinstance(idx, slice) else np.size(idx)


class SchurBlock:
    """A block ``K[rows, cols]`` of a :class:`SchurStiffness` (``A``, ``B``, ``B^T``, ``C``):
    products, transpose, diagonal and ``toarray()`` through the parent."""

    ndim = 2
    __array_ufunc__ = None

    def __init__(self, K: SchurStiffness, rows: int, cols: int):
        self.K, self.rows, self.cols = K, rows, cols  # 0: the v half, 1: the w half

    @property
    def shape(self):
        return (self._sl(self.rows).stop - self._sl(self.rows).start,
                self._sl(self.cols).stop - self._sl(self.cols).start)

    @property
    def T(self) -> SchurBlock:
        return SchurBlock(self.K, self.cols, self.rows)

    def _sl(self, half):
        nt = self.K.nt
        return slice(0, nt) if half == 0 else slice(nt, self.K.m)

    def __matmul__(self, x):
        x = np.asarray(x, float)
        full = np.zeros((self.K.m,) + x.shape[1:])
        full[self._sl(self.cols)] = x
        return (self.K @ full)[self._sl(self.rows)]

    def __rmatmul__(self, x):
        return (self.T @ np.asarray(x, float).T).T

    def diagonal(self) -> np.ndarray:
        a, b, c = self.K.block_diagonals()
        return {(0, 0): a, (0, 1): b, (1, 0): b, (1, 1): c}[(self.rows, self.cols)]

    def toarray(self) -> np.ndarray:
        return self.K.columns(np.arange(self.K.m)[self._sl(self.cols)])[self._sl(self.rows)]
