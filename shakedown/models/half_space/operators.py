"""Matrix-free half-space operators: the cell compliance as a convolution applied by FFT.

The compliance of an ``n x n`` grid of equal cells depends only on the offset between cells
(:func:`.influence.offset_kernels`), so ``u = F r`` is a discrete 2-D convolution.  Embedding
each kernel of ``(2n - 1)^2`` offsets in an ``M x M`` circulant, ``M >= 2n - 1`` (the
discrete-convolution FFT of Liu, Wang & Liu, *Wear* 243, 2000), makes the product exact (no
periodic images) at
``O(n^2 log n)`` cost and ``O(n^2)`` memory, against ``O(n^4)`` for the dense ``F``.

* :class:`CellCompliance`: ``F`` over all ``N = n^2`` cells, ``(3N, 3N)``, MODEL.md s.8 order.
* :class:`ReducedCompliance`: ``F' = T^T F T`` over the ``N - 1`` non-reference cells (the
  rigid-body modes condensed out, :mod:`.model`); symmetric positive definite.
* :class:`ReducedStiffness`: ``K = F'^-1`` applied by conjugate gradients on ``F'`` (each
  iteration one FFT product); the products of the dense ``K`` of
  :attr:`HalfSpaceModel.system`, to the CG tolerance.

All three are :class:`scipy.sparse.linalg.LinearOperator` objects (``@``, ``matvec``,
``matmat``, ``shape``, ``dtype``), so code written for a dense or sparse ``K`` takes them.
"""

from __future__ import annotations

import numpy as np
from scipy.fft import next_fast_len
from scipy.sparse.linalg import LinearOperator, cg

from ...model import SolverError


def fft_size(n: int) -> int:
    """Side ``M >= 2n - 1`` of the circulant embedding, a fast FFT length (5-smooth)."""
    return next_fast_len(2 * int(n) - 1, real=True)


def _circulant_fft(kernel: np.ndarray, n: int) -> np.ndarray:
    """``rfft2`` of a ``(2n - 1)^2`` offset kernel embedded in an ``M x M`` circulant."""
    M = fft_size(n)
    c = np.zeros((M, M))
    c[: 2 * n - 1, : 2 * n - 1] = kernel
    c = np.roll(c, (-(n - 1), -(n - 1)), axis=(0, 1))  # offset d stored at index d mod M
    return np.fft.rfft2(c)


class CellCompliance(LinearOperator):
    """The cell compliance ``F`` (all ``n^2`` cells) applied by FFT; shape ``(3N, 3N)``.

    Parameters
    ----------
    kernels : dict
        :func:`.influence.offset_kernels` of the grid [length/force].
    n : int
        Cells per side.
    """

    def __init__(self, kernels: dict, n: int):
        self.n = int(n)
        N = self.n * self.n
        super().__init__(dtype=np.float64, shape=(3 * N, 3 * N))
        self.coupled = bool(np.any(kernels["zx"]) or np.any(kernels["zy"]))
        names = ("xx", "xy", "yy", "zz") + (("zx", "zy") if self.coupled else ())
        self._hat = {k: _circulant_fft(kernels[k], self.n) for k in names}

    def _fields(self, r):
        n, N = self.n, self.n * self.n
        return r[0:2 * N:2].reshape(n, n, -1), r[1:2 * N:2].reshape(n, n, -1), \
            r[2 * N:].reshape(n, n, -1)

    def _matmat(self, X):
        X = np.asarray(X, float)
        n, N = self.n, self.n * self.n
        qx, qy, p = self._fields(X)
        s = (fft_size(n),) * 2
        fx = np.fft.rfft2(qx, s=s, axes=(0, 1))
        fy = np.fft.rfft2(qy, s=s, axes=(0, 1))
        fp = np.fft.rfft2(p, s=s, axes=(0, 1))
        H = {k: v[:, :, None] for k, v in self._hat.items()}
        vx = H["xx"] * fx + H["xy"] * fy
        vy = H["xy"] * fx + H["yy"] * fy
        w = H["zz"] * fp
        if self.coupled:
            vx -= H["zx"] * fp
            vy -= H["zy"] * fp
            w += H["zx"] * fx + H["zy"] * fy
        out = np.empty_like(X)
        for arr, sl in ((vx, slice(0, 2 * N, 2)), (vy, slice(1, 2 * N, 2)), (w, slice(2 * N, None))):
            out[sl] = np.fft.irfft2(arr, s=s, axes=(0, 1))[:n, :n].reshape(N, -1)
        return out

    def _matvec(self, x):
        return self._matmat(np.asarray(x, float).reshape(-1, 1))[:, 0]

    def _adjoint(self):
        return self  # symmetric (Betti)


def reduction_indices(n_cells: int, reference: int):
    """``(full, ref)``: positions in the ``3N`` cell vector of each of the ``3(N - 1)`` reduced
    unknowns and of the reference cell's same component (MODEL.md s.8 order in both)."""
    N = int(n_cells)
    keep = np.delete(np.arange(N), reference)
    full = np.concatenate([np.stack([2 * keep, 2 * keep + 1], axis=1).ravel(), 2 * N + keep])
    comp = np.concatenate([np.tile([0, 1], N - 1), np.full(N - 1, 2)])
    ref = np.where(comp < 2, 2 * reference + comp, 2 * N + reference)
    return full, ref


class ReducedCompliance(LinearOperator):
    """``F' = T^T F T`` on the non-reference cells: ``T r' `` puts ``-sum r'`` on the reference."""

    def __init__(self, F: CellCompliance, reference: int):
        self.F = F
        N = F.shape[0] // 3
        self.full, self.ref = reduction_indices(N, reference)
        self.reference = int(reference)
        super().__init__(dtype=np.float64, shape=(3 * (N - 1), 3 * (N - 1)))

    def expand(self, Xr):
        """``T X'``: reduced forces (3(N-1), k) -> cell forces (3N, k) with zero resultant."""
        X = np.zeros((self.F.shape[0], Xr.shape[1]))
        X[self.full] = Xr
        t = self.shape[0] - self.shape[0] // 3  # tangential rows of the reduced vector
        X[self.ref[0]] = -Xr[0:t:2].sum(axis=0)
        X[self.ref[1]] = -Xr[1:t:2].sum(axis=0)
        X[self.ref[t]] = -Xr[t:].sum(axis=0)
        return X

    def restrict(self, U):
        """``T^T U``: cell displacements (3N, k) -> relative to the reference cell (3(N-1), k)."""
        return U[self.full] - U[self.ref]

    def _matmat(self, X):
        return self.restrict(self.F @ self.expand(np.asarray(X, float)))

    def _matvec(self, x):
        return self._matmat(np.asarray(x, float).reshape(-1, 1))[:, 0]

    def _adjoint(self):
        return self


class ReducedStiffness(LinearOperator):
    """``K = F'^-1`` applied by conjugate gradients on :class:`ReducedCompliance` (FFT products).

    Parameters
    ----------
    Fr : ReducedCompliance
    rtol : float
        CG tolerance on ``||F' x - b|| / ||b||``; the relative error of ``K b`` is at most
        ``cond(F') rtol``.
    maxiter : int
    """

    def __init__(self, Fr: ReducedCompliance, rtol: float = 1e-10, maxiter: int = 2000):
        self.Fr = Fr
        self.rtol = float(rtol)
        self.maxiter = int(maxiter)
        self.iterations = []  # CG iterations of each product (for benchmarks)
        super().__init__(dtype=np.float64, shape=Fr.shape)

    def _matvec(self, b):
        b = np.asarray(b, float).ravel()
        if not np.any(b):
            return np.zeros_like(b)
        count = [0]

        def cb(_):
            count[0] += 1

        x, info = cg(self.Fr, b, rtol=self.rtol, atol=0.0, maxiter=self.maxiter, callback=cb)
        self.iterations.append(count[0])
        if info != 0:
            raise SolverError(f"CG on the half-space compliance did not reach rtol = {self.rtol:g} "
                              f"in {self.maxiter} iterations (info = {info})", partial=x)
        return x

    def _matmat(self, X):
        X = np.asarray(X, float)
        return np.column_stack([self._matvec(X[:, k]) for k in range(X.shape[1])])

    def _adjoint(self):
        return self

