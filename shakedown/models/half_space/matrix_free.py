"""A matrix-free fretting cycle for similar materials at constant normal force (FFT products only).

Scope: ``beta = 0`` (uncoupled) and a constant normal force ``P0``.  The normal problem is then
independent of the tangential one and is solved once (:func:`.normal.normal_contact`); the cells'
pressures ``p_i`` fix the discs ``|q_i| <= f p_i`` (open cells: ``q_i = 0``).  The implicit step of
MODEL.md s.8.4 from ``q_k`` to the resultant ``Q_{k+1}`` is, in compliance form, the convex
problem (associated, because ``p`` is known and ``B = 0``)::

    min_q  1/2 (q - q_k)^T F_t (q - q_k)   s.t.  |q_i| <= f p_i,   sum_i q_i = Q_{k+1}      (1)

whose conditions are the Coulomb law with the slip increment ``dv = F_t (q - q_k) + ds``
(``ds``, the multiplier of the resultant, is the rigid tangential shift increment): ``dv_i = 0``
where ``|q_i| < f p_i`` and ``dv_i = -mu_i q_i`` (``mu_i >= 0``) where ``|q_i| = f p_i``.  It is
solved by FISTA with adaptive restart (projected gradient onto the discs, one FFT product of the
tangential compliance ``F_t`` per iteration) with the resultant kept exactly in the projection
(:func:`project_resultant`).
Every answer is checked by :func:`step_residual` (cone feasibility, resultant, stick and slip
conditions), independently of the iteration.  The same steps as the dense cone engine, so the
dissipation ``W = sum_k -q_{k+1} . dv_k`` matches it (``tests/models/test_half_space_matrix_free.py``).
"""

from __future__ import annotations

import time

import numpy as np

from ...model import InputError, SolverError
from .normal import normal_contact
from .operators import _circulant_fft, fft_size


class TangentialCompliance:
    """``F_t`` (all cells, tangential block) by FFT: ``q`` (N, 2) -> mean slips (N, 2)."""

    def __init__(self, model):
        self.n = model.n
        self.s = (fft_size(model.n),) * 2
        self.hat = {k: _circulant_fft(model.kernels[k], model.n) for k in ("xx", "xy", "yy")}

    def __call__(self, q):
        n, s = self.n, self.s
        fx = np.fft.rfft2(q[:, 0].reshape(n, n), s=s)
        fy = np.fft.rfft2(q[:, 1].reshape(n, n), s=s)
        ux = np.fft.irfft2(self.hat["xx"] * fx + self.hat["xy"] * fy, s=s)[:n, :n]
        uy = np.fft.irfft2(self.hat["xy"] * fx + self.hat["yy"] * fy, s=s)[:n, :n]
        return np.column_stack([ux.ravel(), uy.ravel()])


def _project(q, radius):
    norm = np.hypot(q[:, 0], q[:, 1])
    scale = np.where(norm > radius, radius / np.where(norm > 0, norm, 1.0), 1.0)
    return q * scale[:, None]


def step_residual(Ft, q, q_prev, radius, Q, ds, scale_q, scale_v):
    """Dimensionless residual of the step (1): ``max`` of the cone excess, the resultant error,
    the slip of sticking cells and the misalignment of slipping cells (``dv`` against ``-q``)."""
    dv = Ft(q - q_prev) + ds
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


def project_resultant(z, radius, Q, mu=None, tol=1e-14):
    """Euclidean projection of ``z`` (N, 2) onto ``{|q_i| <= r_i, sum q_i = Q}``.

    ``q_i = P_i(z_i + mu)`` (``P_i`` the projection onto disc ``i``) with the 2-vector ``mu`` solving
    ``sum_i P_i(z_i + mu) = Q``, a monotone equation solved by damped Newton (its Jacobian is
    ``sum_i dP_i``: ``I`` for cells inside their disc, ``r/|w| (I - w w^T/|w|^2)`` outside).
    """
    mu = np.zeros(2) if mu is None else mu.copy()
    scale = max(float(radius.sum()), 1e-300)
    for _ in range(100):
        w = z + mu
        nw = np.hypot(w[:, 0], w[:, 1])
        out = nw > radius
        f = np.where(out, radius / np.where(out, nw, 1.0), 1.0)
        q = w * f[:, None]
        res = q.sum(axis=0) - Q
        if np.max(np.abs(res)) <= tol * scale:
            return q, mu
        J = np.eye(2) * np.count_nonzero(~out)
        if np.any(out):
            u = w[out] / nw[out, None]
            fo = f[out]
            J += np.eye(2) * fo.sum() - np.einsum("k,ki,kj->ij", fo, u, u)
        J += 1e-12 * max(np.trace(J), 1.0) * np.eye(2)
        d = -np.linalg.solve(J, res)
        # damping: halve until the residual decreases
        r0 = np.linalg.norm(res)
        for _h in range(30):
            w2 = z + mu + d
            n2 = np.hypot(w2[:, 0], w2[:, 1])
            f2 = np.where(n2 > radius, radius / np.where(n2 > 0, n2, 1.0), 1.0)
            if np.linalg.norm((w2 * f2[:, None]).sum(axis=0) - Q) < r0:
                break
            d *= 0.5
        mu = mu + d
    return q, mu


def solve_step_fft(Ft, q_prev, radius, Q, L, tol=1e-11, max_iter=20000):
    """Step (1) by FISTA with adaptive restart and the exact projection of
    :func:`project_resultant`; returns ``(q, ds, iterations)``."""
    scale_q = max(float(np.max(radius)), 1e-300)
    x_old, mu = project_resultant(q_prev, radius, Q)
    y, t = x_old.copy(), 1.0
    its = 0
    while its < max_iter:
        its += 1
        g = Ft(y - q_prev)
        x, mu = project_resultant(y - g / L, radius, Q, mu)
        if np.sum((x - x_old) * (y - x)) > 0:  # adaptive restart: momentum uphill
            t, y = 1.0, x_old.copy()
            continue
        t_new = 0.5 * (1 + np.sqrt(1 + 4 * t * t))
        y = x + ((t - 1) / t_new) * (x - x_old)
        step = np.max(np.abs(x - x_old)) / scale_q
        x_old, t = x, t_new
        if step < tol:
            break
    q = x_old
    # the rigid shift increment ds: the multiplier of the resultant, from the sticking cells
    # (dv = F_t dq + ds = 0 there); the mean over them
    dv0 = Ft(q - q_prev)
    inside = np.hypot(q[:, 0], q[:, 1]) < radius * (1 - 1e-6)
    ds = -dv0[inside].mean(axis=0) if np.any(inside) else -L * mu
    return q, ds, its


def fretting_cycles_fft(model, P0, Qx_samples, Qy_samples=None, *, max_cycles: int = 10,
                        tol: float = 1e-9, step_tol: float = 1e-11, q0=None, progress=None):
    """Cycles of ``Q(t_k) = (Qx_samples[k], Qy_samples[k])`` at constant ``P0``, matrix-free.

    Parameters
    ----------
    model : HalfSpaceModel
        Similar materials (``model.beta == 0``).
    P0 : float
        Constant normal force [force].
    Qx_samples, Qy_samples : array_like, shape (S,)
        The tangential resultant at ``t = k / S`` [force] (one implicit step each).
    q0 : ndarray, shape (n^2, 2), optional
        Initial cell shear forces (default: zero, the state after ``P0`` alone).

    Returns
    -------
    dict
        ``W`` (per cycle), ``state_change`` (per cycle, ``max |dq| / (f max p)``), ``q`` (S, n^2, 2)
        of the last cycle, ``p`` (n^2,), ``stuck`` (cells sticking through the last cycle),
        ``residual`` (largest step residual), ``iterations`` (FISTA iterations per step),
        ``wall_time`` [s], ``status`` ("periodic" or "not_converged").
    """
    if model.beta != 0:
        raise InputError(f"the matrix-free fretting cycle needs similar materials (beta = 0); got "
                         f"beta = {model.beta:g}: use the dense model.system with sd.solve_cycles")
    t0 = time.perf_counter()
    Qx = np.asarray(Qx_samples, float)
    Qy = np.zeros_like(Qx) if Qy_samples is None else np.asarray(Qy_samples, float)
    Qs = np.column_stack([Qx, Qy])
    normal = normal_contact(model, P0)
    p = normal.p
    radius = model.friction * p
    if np.max(np.hypot(*Qs.T)) >= radius.sum():
        raise InputError("|Q| must stay below f P0 (gross slip) for the fretting cycle")
    Ft = TangentialCompliance(model)
    # Lipschitz constant of F_t (power iteration) and the penalty of the resultant
    v = np.random.default_rng(0).standard_normal((model.n_cells, 2))
    for _ in range(40):
        v = Ft(v)
        lmax = np.linalg.norm(v)
        v /= lmax
    L = 1.05 * lmax
    q = np.zeros((model.n_cells, 2)) if q0 is None else np.array(q0, float)
    scale_q = float(radius.max())
    scale_v = scale_q * lmax
    W, change, worst, iters = [], [], 0.0, []
    status = "not_converged"
    for cyc in range(max_cycles):
        q_start = q.copy()
        hist, slipped, Wc = [], np.zeros(model.n_cells, bool), 0.0
        for k in range(len(Qs)):
            q_new, ds, its = solve_step_fft(Ft, q, radius, Qs[k], L, tol=step_tol)
            res, dv = step_residual(Ft, q_new, q, radius, Qs[k], ds, scale_q, scale_v)
            if res > 1e-6:
                raise SolverError(f"matrix-free step {k} of cycle {cyc + 1}: residual {res:.1e}",
                                  partial=q_new)
            worst = max(worst, res)
            iters.append(its)
            Wc += float(-np.sum(q_new * dv))
            slipped |= np.hypot(*dv.T) > 1e-7 * scale_v
            q = q_new
            hist.append(q)
        W.append(Wc)
        change.append(float(np.max(np.abs(q - q_start)) / scale_q))
        if progress is not None:
            progress(cyc + 1, max_cycles, Wc)
        if change[-1] <= tol:
            status = "periodic"
            break
    return dict(W=np.array(W), state_change=np.array(change), q=np.array(hist), p=p,
                stuck=np.flatnonzero(~slipped & (p > 0)), residual=worst, iterations=iters,
                wall_time=time.perf_counter() - t0, status=status)
