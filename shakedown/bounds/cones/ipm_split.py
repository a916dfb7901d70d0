"""The Newton systems of the dense interior point in a split, augmented form (accuracy).

The normal matrix ``N = G^T W^-2 G`` of :mod:`.dense_ipm` sums, per cone, ``W_m^-2 = eta_m^-2
(2 w^ w^T - J)`` (``w^ = J w``, ``w`` the Nesterov-Todd scaling point, ``w^T J w = 1``,
``J = diag(1, -1, -1)``).  Near the optimum an active cone has ``w0^2 ~ 1 / mu``: its rank-one
part is huge, ``N`` spans ``mu .. 1 / mu`` and its rounding errors (``~ eps / mu`` absolute)
swamp its smallest eigenvalues once ``mu`` falls below ``~ 1e-8``: the directions lose their
accuracy and the iteration stalls (measured: ``benchmarks/RESULTS_3d_bounds.md``).

Here the rank-one parts of the cones with ``w0^2 > SPLIT_W0SQ`` are kept out of ``N``:

    N = N0 + U U^T,   N0 = sum_{split} eta^-2 G_m^T (-J) G_m + sum_{others} G_m^T W_m^-2 G_m,
                      U = [sqrt(2) eta_m^-1 G_m^T w^_m]_{split} ,

and ``(N0 + U U^T) dx = r`` is solved through the augmented matrix ``[[N0, U], [U^T, -I]]``
(symmetrically equilibrated, LU with partial pivoting): no entry of order ``1 / mu`` is ever
summed with one of order 1 (the large and the small parts cancel inside a backward-stable
factorisation instead).  Its size is ``2N + 1 + k`` (``k`` split cones: few while the iterate is
far from the optimum, at most about the number of active cuts near it).  ``eta`` and ``w`` are
read from the maintained scaling ``W`` (``W^T J W = eta^2 J``); the small mismatch of the split
with ``W^-2`` is removed by the iterative refinement of :meth:`.dense_ipm._Newton.solve`, which
computes its residuals with ``W`` itself.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

#: A cone's rank-one part is split off when ``w0^2`` exceeds this.
SPLIT_W0SQ = 1e2
#: The split form is used from the iteration at which some cone has ``w0^2`` above this
#: (before, the normal equations are accurate and cheaper).
SPLIT_LATE = 1e5
#: Largest augmented matrix (``2N + 1 + k``): beyond it only the cones with the largest
#: rank-one parts ``eta^-2 w0^2`` are split (near the optimum of a tight bracket almost every
#: cut is active, ``k ~ M``).  Measured at N = 200, rtol = 1e-9 (benchmarks/
#: RESULTS_3d_bounds.md): 4000 closes the bracket to 2e-11 with no fallback in ~100 s of CPU
#: (peak 486 MB); 1500 takes ~30 s but leaves 2e-9 .. 1e-8 and 2-4 Clarabel fallbacks.
SPLIT_MAX = 4000
_J = np.array([1.0, -1.0, -1.0])


def split_parts(W):
    """``(eta^-2 (M,), w^ (M, 3), w0sq (M,))`` of the scalings ``W`` (M, 3, 3); ``w0sq = 0``
    (not split) where ``eta^2`` is lost to cancellation."""
    row = W[:, 0, :]
    eta2 = row[:, 0] ** 2 - row[:, 1] ** 2 - row[:, 2] ** 2  # (W^T J W)_00 = eta^2
    ok = np.isfinite(eta2) & (eta2 > 1e-15 * row[:, 0] ** 2)
    eta2 = np.where(ok, eta2, 1.0)
    w = row / np.sqrt(eta2)[:, None]
    return 1.0 / eta2, w * _J, np.where(ok, w[:, 0] ** 2, 0.0)


def adjoint_columns(G, V):
    """``G_m^T v_m`` for the rows ``v`` (k, 3) of cuts ``idx``: ``(2N + 1, k)``, with
    ``V = (idx, v)``."""
    idx, v = V
    n = G.n
    out = np.zeros((2 * n + 1, idx.size))
    nodes = G.nodes[idx]
    out[: 2 * n] = -(G.E[nodes].T * v[:, 0][None, :])
    cols = np.arange(idx.size)
    out[2 * nodes, cols] -= v[:, 1]
    out[2 * nodes + 1, cols] -= v[:, 2]
    out[2 * n] = -np.einsum("ma,ma->m", G.col[idx], v)
    return out


class SplitSolver:
    """``N^-1`` by the split augmented matrix (module docstring); ``solve(rhs)``."""

    def __init__(self, G, W, Hm, hc):
        ieta2, wh, w0sq = split_parts(W)
        idx = np.flatnonzero(w0sq > SPLIT_W0SQ)
        room = max(SPLIT_MAX - (2 * G.n + 1), 0)
        if idx.size > room:  # the largest rank-one parts first
            big = ieta2[idx] * w0sq[idx]
            idx = np.sort(idx[np.argsort(big)[::-1][:room]])
        H0 = Hm.copy()
        H0[idx] = ieta2[idx, None, None] * np.diag(-_J)[None]
        N0 = G.normal_matrix(H0, hc, signed=True)
        a = wh[idx] * np.sqrt(2.0 * ieta2[idx])[:, None]  # W_m^-2 = H0_m + a a^T
        Uc = adjoint_columns(G, (idx, a))
        self.G, self.H0, self.idx, self.a = G, H0, idx, a
        nx, k = N0.shape[0], idx.size
        K = np.empty((nx + k, nx + k))
        K[:nx, :nx] = N0
        K[:nx, nx:] = Uc
        K[nx:, :nx] = Uc.T
        K[nx:, nx:] = -np.eye(k)
        if not np.all(np.isfinite(K)):
            raise ValueError("non-finite split Newton matrix")
        d = 1.0 / np.sqrt(np.maximum(np.abs(K).max(axis=1), 1e-300))
        self.d, self.nx, self.k = d, nx, k
        with warnings.catch_warnings():
            warnings.simplefilter("error", sla.LinAlgWarning)  # singular: a LinAlgError
            try:
                self.lu = sla.lu_factor(d[:, None] * K * d[None, :], check_finite=False)
            except sla.LinAlgWarning as exc:
                raise np.linalg.LinAlgError(str(exc)) from exc

    def solve(self, rhs, rhs_tau=None):
        """``(dx, tau)`` of ``[[N0, U], [U^T, -I]] (dx, tau) = (rhs, rhs_tau)``."""
        full = np.concatenate([rhs, np.zeros(self.k) if rhs_tau is None else rhs_tau])
        x = self.d * sla.lu_solve(self.lu, self.d * full, check_finite=False)
        return x[: self.nx], x[self.nx:]

    def newton(self, bx_u, bx_l, c, cc):
        """``(du, dlam, dz, dzc-free part)`` of ``G^T dz = bx``, ``dz = W^-2 (G dx - c)``
        with the split cones' rank-one parts carried by ``tau = a^T (G_m dx - c_m)``, so that
        ``dz`` is never a huge matrix times a small difference."""
        G, idx, a = self.G, self.idx, self.a
        au, al = G.adjoint(np.einsum("mab,mb->ma", self.H0, c), 0.0)
        return au, al, np.einsum("ma,ma->m", a, c[idx])
