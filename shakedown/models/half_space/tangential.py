"""The tangential step of the half-space contact with FFT products only (MODEL.md s.8.4).

With the cell pressures ``p`` of the step known, the implicit step from ``q_k`` to the resultant
``Q_{k+1}`` is, in compliance form (:mod:`.model` eq. (1)), the convex problem::

    min_q  1/2 (q - q_k)^T F_t (q - q_k) + c^T q   s.t.  |q_i| <= f p_i,   sum_i q_i = Q_{k+1}   (1)

with ``c = -F_tz (p - p_k)`` the slip the pressure change causes (zero for similar materials,
``beta = 0``).  Its conditions are the Coulomb law with the slip increment
``dv = F_t (q - q_k) + c + ds`` (``ds``, the multiplier of the resultant, is the rigid tangential
shift increment): ``dv_i = 0`` where ``|q_i| < f p_i`` and ``dv_i = -mu_i q_i`` (``mu_i >= 0``)
where ``|q_i| = f p_i``.

* :class:`SurfaceCompliance` -- the four blocks ``F_tt``, ``F_tz``, ``F_zt``, ``F_zz`` of the cell
  compliance as FFT convolutions (float64 ``rfft2`` on the ``M x M`` circulant of
  :func:`.operators.fft_size`, kernels transformed once, both shear components in one call);
* :func:`project_resultant` -- the exact Euclidean projection onto the discs and the resultant
  (a 2-vector multiplier by damped Newton; compiled with numba when available);
* :func:`solve_tangential_step` -- (1) by FISTA with adaptive restart, warm-started from the
  best of several candidates (the previous state, an extrapolation, the previous period's
  answer), stopped by its gradient mapping relative to the force scale ``f max p``;
* :func:`step_residual` -- the conditions of (1) checked independently of the iteration.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft

from .operators import _circulant_fft, fft_size

try:  # pragma: no cover - which branch runs depends on the environment
    from numba import njit
except ImportError:  # pragma: no cover
    def njit(*args, **kwargs):  # noqa: D103
        return (lambda fn: fn) if not (args and callable(args[0])) else args[0]


class SurfaceCompliance:
    """The cell compliance of a :class:`.model.HalfSpaceModel` in blocks, applied by FFT.

    ``tt(q)``: mean slips of shear forces ``q`` (N, 2) -> (N, 2); ``tz(p)``: slips of cell
    pressures ``p`` (N,) -> (N, 2); ``zt(q)``: gaps of shear forces -> (N,); ``zz(p)``: gaps of
    pressures -> (N,) [length] (``N = n^2`` cells, forces [force]).  ``coupled`` is ``False`` for
    similar materials (``tz``, ``zt`` are then zero).
    """

    def __init__(self, model):
        n = self.n = model.n
        self.s = (fft_size(n),) * 2
        k = model.kernels
        self.coupled = bool(np.any(k["zx"]) or np.any(k["zy"]))
        self._tt = np.stack([[_circulant_fft(k["xx"], n), _circulant_fft(k["xy"], n)],
                             [_circulant_fft(k["xy"], n), _circulant_fft(k["yy"], n)]])
        self._zz = _circulant_fft(k["zz"], n)
        self._zt = np.stack([_circulant_fft(k["zx"], n), _circulant_fft(k["zy"], n)]) \
            if self.coupled else None

    def _fwd(self, a):
        return sfft.rfft2(a, s=self.s, axes=(-2, -1))

    def _inv(self, a):
        n = self.n
        return sfft.irfft2(a, s=self.s, axes=(-2, -1))[..., :n, :n]

    def _grid_q(self, q):
        return np.asarray(q, float).T.reshape(2, self.n, self.n)

    def tt(self, q):
        fx, fy = self._fwd(self._grid_q(q))
        h = self._tt
        u = self._inv(np.stack([h[0, 0] * fx + h[0, 1] * fy, h[1, 0] * fx + h[1, 1] * fy]))
        return u.reshape(2, -1).T

    def tz(self, p):
        if not self.coupled:
            return np.zeros((self.n * self.n, 2))
        fp = self._fwd(np.asarray(p, float).reshape(self.n, self.n))
        return -self._inv(self._zt * fp).reshape(2, -1).T

    def zt(self, q):
        if not self.coupled:
            return np.zeros(self.n * self.n)
        fq = self._fwd(self._grid_q(q))
        return self._inv(np.sum(self._zt * fq, axis=0)).ravel()

    def zz(self, p):
        return self._inv(self._zz * self._fwd(np.asarray(p, float).reshape(self.n, self.n))).ravel()

    __call__ = tt

    def lipschitz(self, iterations: int = 40) -> float:
        """Largest eigenvalue of ``F_tt`` by power iteration [length/force]."""
        v = np.random.default_rng(0).standard_normal((self.n * self.n, 2))
        lmax = 1.0
        for _ in range(iterations):
            v = self.tt(v)
            lmax = float(np.linalg.norm(v))
            v /= lmax
        return lmax


@njit(cache=True)
def _project_kernel(z, radius, Q, mu, tol):  # pragma: no cover - compiled
    N = z.shape[0]
    q = np.empty_like(z)
    for _it in range(100):
        sx = 0.0
        sy = 0.0
        jxx = 0.0
        jxy = 0.0
        jyy = 0.0
        for i in range(N):
            wx = z[i, 0] + mu[0]
            wy = z[i, 1] + mu[1]
            nw = np.sqrt(wx * wx + wy * wy)
            if nw > radius[i]:
                f = radius[i] / nw
                ux = wx / nw
                uy = wy / nw
                jxx += f * (1.0 - ux * ux)
                jxy -= f * ux * uy
                jyy += f * (1.0 - uy * uy)
            else:
                f = 1.0
                jxx += 1.0
                jyy += 1.0
            q[i, 0] = wx * f
            q[i, 1] = wy * f
            sx += q[i, 0]
            sy += q[i, 1]
        rx = sx - Q[0]
        ry = sy - Q[1]
        if max(abs(rx), abs(ry)) <= tol:
            return q, mu
        reg = 1e-12 * max(jxx + jyy, 1.0)
        jxx += reg
        jyy += reg
        det = jxx * jyy - jxy * jxy
        dx = -(jyy * rx - jxy * ry) / det
        dy = -(-jxy * rx + jxx * ry) / det
        r0 = np.sqrt(rx * rx + ry * ry)
        for _h in range(30):  # damping: halve until the residual decreases
            sx = 0.0
            sy = 0.0
            for i in range(N):
                wx = z[i, 0] + mu[0] + dx
                wy = z[i, 1] + mu[1] + dy
                nw = np.sqrt(wx * wx + wy * wy)
                f = radius[i] / nw if nw > radius[i] else 1.0
                sx += wx * f
                sy += wy * f
            if np.sqrt((sx - Q[0]) ** 2 + (sy - Q[1]) ** 2) < r0:
                break
            dx *= 0.5
            dy *= 0.5
        mu = mu + np.array([dx, dy])
    return q, mu


def project_resultant(z, radius, Q, mu=None, tol=1e-14):
    """Euclidean projection of ``z`` (N, 2) onto ``{|q_i| <= r_i, sum q_i = Q}``.

    ``q_i = P_i(z_i + mu)`` (``P_i`` the projection onto disc ``i``) with the 2-vector ``mu`` solving
    ``sum_i P_i(z_i + mu) = Q``, a monotone equation solved by damped Newton (its Jacobian is
    ``sum_i dP_i``: ``I`` for cells inside their disc, ``r/|w| (I - w w^T/|w|^2)`` outside) to
    ``tol * sum r``.  Returns ``(q, mu)``.
    """
    mu = np.zeros(2) if mu is None else np.asarray(mu, float).copy()
    scale = max(float(np.sum(radius)), 1e-300)
    return _project_kernel(np.ascontiguousarray(z, dtype=float), np.asarray(radius, float),
                           np.asarray(Q, float), mu, tol * scale)


def step_residual(Ft, q, q_prev, radius, Q, ds, scale_q, scale_v, c=None):
    """Dimensionless residual of the step (1): ``max`` of the cone excess and the resultant error
    (over ``scale_q``), the slip of sticking cells and the misalignment of slipping cells
    (``dv`` against ``-q``, over ``scale_v``).  Returns ``(residual, dv)``, ``dv`` (N, 2)."""
    dv = Ft(q - q_prev) + ds
    if c is not None:
        dv = dv + c
    norm = np.hypot(q[:, 0], q[:, 1])
    slip = norm >= radius * (1 - 1e-9) - 1e-14 * scale_q
    cone = np.max(np.maximum(norm - radius, 0.0)) / scale_q
    res = np.max(np.abs(q.sum(axis=0) - Q)) / scale_q
    stick = np.max(np.hypot(*dv[~slip].T), initial=0.0) / scale_v
    # slipping: dv = -mu q with mu >= 0: the part of dv not along -q, and dv . q <= 0
    cross = np.abs(dv[slip, 0] * q[slip, 1] - dv[slip, 1] * q[slip, 0]) / np.maximum(norm[slip], 1e-300)
    along = np.maximum(np.sum(dv[slip] * q[slip], axis=1), 0.0) / np.maximum(norm[slip], 1e-300)
    align = max(np.max(cross, initial=0.0), np.max(along, initial=0.0)) / scale_v
    return float(max(cone, res, stick, align)), dv


def solve_tangential_step(Ft, q_prev, radius, Q, L, *, c=None, guesses=(), tol=1e-10,
                          max_iter=20000):
    """Step (1) by FISTA with adaptive restart and the exact projection of :func:`project_resultant`.

    Parameters
    ----------
    Ft : callable
        ``F_tt`` products (N, 2) -> (N, 2) [length/force].
    q_prev : ndarray, shape (N, 2)
        Shear forces at the start of the step [force].
    radius : ndarray, shape (N,)
        ``f p_i`` of the step [force].
    Q : ndarray, shape (2,)
        Resultant at the end of the step [force].
    L : float
        Upper bound of ``F_tt``'s largest eigenvalue [length/force].
    c : ndarray, shape (N, 2), optional
        Linear term (slip of the pressure change) [length].
    guesses : sequence of ndarray (N, 2)
        Starting points besides ``q_prev``; each is projected and the one of least objective is
        taken (one FFT product each).
    tol : float
        Stop when the gradient mapping ``max |x - y|`` is below ``tol * max(radius)``.

    Returns
    -------
    q : ndarray, shape (N, 2)
    ds : ndarray, shape (2,)
        Rigid tangential shift increment [length].
    iterations : int
    """
    scale_q = max(float(np.max(radius)), 1e-300)
    lin = np.zeros_like(q_prev) if c is None else c
    best, best_f, mu = None, np.inf, np.zeros(2)
    for g0 in (q_prev, *guesses):
        x, m = project_resultant(g0, radius, Q, mu)
        d = x - q_prev
        fval = 0.5 * float(np.sum(d * Ft(d))) + float(np.sum(lin * x))
        if fval < best_f:
            best, best_f, mu = x, fval, m
    x_old = best
    y, t = x_old.copy(), 1.0
    its = 0
    while its < max_iter:
        its += 1
        g = Ft(y - q_prev) + lin
        x, mu = project_resultant(y - g / L, radius, Q, mu)
        if np.max(np.abs(x - y)) < tol * scale_q:
            x_old = x
            break
        if np.sum((x - x_old) * (y - x)) > 0:  # adaptive restart: momentum uphill
            t, y = 1.0, x_old.copy()
            continue
        t_new = 0.5 * (1 + np.sqrt(1 + 4 * t * t))
        y = x + ((t - 1) / t_new) * (x - x_old)
        x_old, t = x, t_new
    q = x_old
    # the rigid shift increment ds: the multiplier of the resultant, from the sticking cells
    # (dv = F_t dq + c + ds = 0 there); the mean over them
    dv0 = Ft(q - q_prev) + lin
    inside = np.hypot(q[:, 0], q[:, 1]) < radius * (1 - 1e-6)
    ds = -dv0[inside].mean(axis=0) if np.any(inside) else -L * mu
    return q, ds, its
