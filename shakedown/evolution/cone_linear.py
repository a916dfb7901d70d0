"""The linear solve of the 3-D semismooth Newton step (:mod:`.cone_kernel`): block-Jacobi
preconditioned restarted GMRES for the reduced systems above ``DENSE_MAX`` unknowns (smaller
ones by LU in :func:`.cone_reduced._newton_point`), numba."""

from __future__ import annotations

import numpy as np

from .cone_states import SEPARATED, SLIP
from .kernel_jit import FAST, njit

#: Reduced systems up to this size are solved by LU; larger ones by GMRES first (below).
DENSE_MAX = 64


@njit(cache=True)
def _preconditioner(J, states, n):
    """The block-Jacobi preconditioner of :func:`_krylov`: ``(Pinv, starts, nb)``, the inverses
    of ``J``'s node blocks (rows of 2 or 3 entries, (m, 3)), the first row of each block
    ((n + 1,), ``starts[nb] = m``) and the number of blocks."""
    m = J.shape[0]
    Pinv = np.zeros((m, 3))
    starts = np.empty(n + 1, np.int64)
    nb = 0
    pos = 0
    for i in range(n):
        if states[i] == SLIP or states[i] == SEPARATED:
            starts[nb] = pos
            pos += 2 if states[i] == SLIP else 3
            nb += 1
    starts[nb] = pos
    for b in range(nb):
        _block_inverse(J, Pinv, starts, b)
    return Pinv, starts, nb


@njit(cache=True)
def _block_inverse(J, Pinv, starts, b):
    """Block ``b`` of the preconditioner from ``J``: 2 x 2 in closed form, 3 x 3 by LAPACK."""
    a0 = starts[b]
    if starts[b + 1] - a0 == 2:
        p, q, r, s = J[a0, a0], J[a0, a0 + 1], J[a0 + 1, a0], J[a0 + 1, a0 + 1]
        det = p * s - q * r
        Pinv[a0, 0], Pinv[a0, 1] = s / det, -q / det
        Pinv[a0 + 1, 0], Pinv[a0 + 1, 1] = -r / det, p / det
    else:
        blk = np.linalg.inv(J[a0:a0 + 3, a0:a0 + 3].copy())
        for a in range(3):
            for c in range(3):
                Pinv[a0 + a, c] = blk[a, c]


@njit(cache=True, fastmath=FAST)
def _krylov(J, h, r0, x0, eta, hn, Pinv, starts, nb, exact, J32):
    """Restarted GMRES for ``J x = h`` preconditioned by ``Pinv`` (:func:`_preconditioner`),
    started from ``x0`` whose residual ``r0 = h - J x0`` the caller gives (it may know it
    without a product with ``J``), to ``|h - J x| <= max(1e-14 hn, eta |r0|)`` (``hn = |h|``;
    ``eta``: the forcing term of the inexact Newton method, ``0`` for an exact solve; the
    Arnoldi estimate of the residual, with a factor 2 of margin, ends the solve), with LU when it
    does not get there in 120 iterations (a ``O(m^2)``-per-iteration path for the large,
    well-conditioned systems where the LU's ``O(m^3)`` dominates the step).

    ``exact=False``: ``J`` only approximates the matrix whose residual ``r0`` is (the rows of
    nodes whose directions moved by less than the forcing term kept from an earlier iteration,
    :func:`.cone_reduced._newton_point`); the solve then ends after the first restart cycle
    (no residual is recomputed with ``J``, no LU) and reports ``ok = False`` if the estimate
    did not reach the target.

    ``J32``: the matrix in single precision (empty: none); the Arnoldi products then use it
    (half the memory traffic of the products that dominate the solve; a relative perturbation
    of ``J`` of ~1e-7, i.e. a slightly more inexact Newton direction, which the Newton method
    checks by its own residual, :mod:`.cone_kernel` "Precision").  The residuals between restart
    cycles and the LU use ``J``: with ``J32`` and an empty ``J``, ``exact`` must be False.
    Returns ``(x, ok)``."""
    m = r0.size
    x = x0.copy()
    if hn == 0.0:
        return np.zeros(m), True
    restart = 40
    V = np.empty((restart + 1, m))
    H = np.zeros((restart + 1, restart))
    cs = np.empty(restart)
    sn = np.empty(restart)
    g = np.empty(restart + 1)
    z = np.empty(m)
    w = np.empty(m)
    single = J32.shape[0] == m
    z32 = np.empty(m if single else 0, np.float32)
    rres = r0.copy()
    target = -1.0
    total = 0
    while total < 120:
        if total > 0:
            if not exact:
                return x, False
            _residual(J, h, x, rres)
        beta = np.sqrt(np.sum(rres * rres))
        if target < 0.0:
            target = max(1e-14 * hn, eta * beta)
        if beta <= target:
            return x, True
        for a in range(m):
            V[0, a] = rres[a] / beta
        g[:] = 0.0
        g[0] = beta
        k_used = 0
        for k in range(restart):
            total += 1
            _precondition(Pinv, starts, nb, V[k], z)
            if single:
                for a in range(m):
                    z32[a] = z[a]
                w[:] = J32 @ z32
            else:
                _matvec(J, z, w)
            for j in range(k + 1):  # modified Gram-Schmidt
                Vj = V[j]
                acc = 0.0
                for a in range(m):
                    acc += w[a] * Vj[a]
                H[j, k] = acc
                for a in range(m):
                    w[a] -= acc * Vj[a]
            hk = np.sqrt(np.sum(w * w))
            H[k + 1, k] = hk
            if hk > 0.0:
                for a in range(m):
                    V[k + 1, a] = w[a] / hk
            for j in range(k):
                t = cs[j] * H[j, k] + sn[j] * H[j + 1, k]
                H[j + 1, k] = -sn[j] * H[j, k] + cs[j] * H[j + 1, k]
                H[j, k] = t
            den = np.hypot(H[k, k], H[k + 1, k])
            cs[k], sn[k] = H[k, k] / den, H[k + 1, k] / den
            H[k, k] = den
            H[k + 1, k] = 0.0
            g[k + 1] = -sn[k] * g[k]
            g[k] = cs[k] * g[k]
            k_used = k + 1
            if abs(g[k + 1]) <= 0.5 * target or H[k, k] == 0.0:
                break
        converged = abs(g[k_used]) <= 0.5 * target
        y = np.zeros(k_used)
        for j in range(k_used - 1, -1, -1):
            acc = g[j]
            for c in range(j + 1, k_used):
                acc -= H[j, c] * y[c]
            y[j] = acc / H[j, j]
        w[:] = 0.0
        for j in range(k_used):
            Vj = V[j]
            yj = y[j]
            for a in range(m):
                w[a] += yj * Vj[a]
        _precondition(Pinv, starts, nb, w, z)
        for a in range(m):
            x[a] += z[a]
        if converged:  # the Arnoldi estimate, with a factor 2 of margin (the Newton method
            return x, True  # checks its own residual after the step)
    if not exact:
        return x, False
    _residual(J, h, x, rres)
    if np.sqrt(np.sum(rres * rres)) <= 10.0 * target:
        return x, True
    return np.linalg.solve(J, h), True


@njit(cache=True)
def _matvec(J, z, out):
    """``out = J z`` (BLAS)."""
    out[:] = J @ z


@njit(cache=True)
def _residual(J, h, x, out):
    """``out = h - J x``."""
    _matvec(J, x, out)
    for a in range(h.size):
        out[a] = h[a] - out[a]


@njit(cache=True)
def _precondition(Pinv, starts, nb, v, out):
    """``out = P^-1 v`` with the block inverses ``Pinv`` (rows of 2 or 3 entries per block)."""
    for b in range(nb):
        a0, a1 = starts[b], starts[b + 1]
        for a in range(a1 - a0):
            acc = 0.0
            for c in range(a1 - a0):
                acc += Pinv[a0 + a, c] * v[a0 + c]
            out[a0 + a] = acc


__all__ = ["DENSE_MAX", "_krylov", "_preconditioner", "_block_inverse"]
