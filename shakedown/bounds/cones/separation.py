"""Exact worst times of the moving cone constraints (the separation step of the cone engine).

For a state ``(u, lam)`` node ``i`` violates its cone by ``g_i(t) = |a_i(t)| - b_i(t)`` with
``a_i(t) = a0_i + u_i + lam a1_i(t)`` and ``b_i(t) = b0_i + (E u)_i + lam b1_i(t)``
(:mod:`.data`).  This module computes ``max_t g_i(t)`` exactly (to rounding) and where it is
reached, for every node at once:

* sampled loads (piecewise linear between samples): on each segment ``|a|`` is the norm of an
  affine function (convex) and ``b`` is affine, so ``g`` is convex there and its maximum is at a
  sample;
* harmonic loads of ``H`` harmonics: ``g`` is smooth except where ``a = 0``, a kink that is never
  a local maximum (``|a|`` has a minimum there), so every maximum is a root of
  ``g' = a.a' / |a| - b'``, hence of the trigonometric polynomial ``(a.a')^2 - b'^2 (a.a)`` of
  degree ``4H``: the roots of ``z^{4H} Q(z)`` (``z = exp(2 pi i t)``, degree ``8H``), polished by
  Newton steps on ``g'`` and evaluated together with a grid of ``16H`` times (which also covers
  the degenerate case ``Q = 0``: ``g`` constant).  Evaluating ``g`` at extra candidates can only
  raise the maximum found towards the true one, never past it.
"""

from __future__ import annotations

import numpy as np


def state_parts(data, u, lam):
    """``(a_base (N, 2), b_base (N,))``: the time-independent parts of ``a_i``, ``b_i``."""
    u = np.asarray(u, float).reshape(-1, 2)
    return data.a0 + u, data.b0 + data.coupling(u)


def violation(data, u, lam, t):
    """``g_i(t)`` for times ``t`` of shape (M,) at every node: shape (M, N)."""
    a_base, b_base = state_parts(data, u, lam)
    a1, b1 = data.periodic(np.asarray(t, float))
    a = a_base + lam * a1
    return np.linalg.norm(a, axis=-1) - (b_base + lam * b1)


def worst_times(data, u, lam):
    """Per node, ``max_t g_i(t)`` and a time where it is reached.

    Returns
    -------
    gmax : ndarray, shape (N,)
        Largest violation [units of F]; ``<= 0`` means the node is safe over the whole cycle.
    t_worst : ndarray, shape (N,)
        Time (cycles, in ``[0, 1)``).
    """
    return worst_times_of(data, *state_parts(data, u, lam), lam)


def worst_times_of(data, a_base, b_base, lam):
    """:func:`worst_times` from the time-independent parts ``a_base`` (N, 2), ``b_base`` (N,)
    (e.g. computed from a slip state directly, without ``E``)."""
    if data.kind == "samples":
        S = data.b1s.shape[0]
        t = np.arange(S) / S
        g = np.linalg.norm(a_base + lam * data.a1s, axis=-1) - (b_base + lam * data.b1s)
        i = np.argmax(g, axis=0)
        return g[i, np.arange(g.shape[1])], t[i]
    return _harmonic_max(a_base, b_base, lam * data.ac, lam * data.as_, lam * data.bc,
                         lam * data.bs)


def _coefficients(base, cos, sin):
    """Complex Fourier coefficients ``C_{-H..H}`` (last axis) of ``base + sum cos + sin``."""
    H = cos.shape[0]
    C = np.zeros(base.shape + (2 * H + 1,), complex)
    C[..., H] = base
    for k in range(H):
        C[..., H + k + 1] = 0.5 * (cos[k] - 1j * sin[k])
        C[..., H - k - 1] = 0.5 * (cos[k] + 1j * sin[k])
    return C


def _derivative(C):
    H = (C.shape[-1] - 1) // 2
    return C * (1j * np.arange(-H, H + 1))


def _conv(X, Y):
    out = np.zeros(X.shape[:-1] + (X.shape[-1] + Y.shape[-1] - 1,), complex)
    for i in range(X.shape[-1]):
        out[..., i: i + Y.shape[-1]] += X[..., i: i + 1] * Y
    return out


def _evaluate(a_base, b_base, ac, as_, bc, bs, theta):
    """``g``, ``g'``, ``g''`` (per radian) at angles ``theta`` (N, M)."""
    H = ac.shape[0]
    a = np.repeat(a_base[:, None, :], theta.shape[1], axis=1)
    da = np.zeros_like(a)
    dda = np.zeros_like(a)
    b = np.repeat(b_base[:, None], theta.shape[1], axis=1)
    db = np.zeros_like(b)
    ddb = np.zeros_like(b)
    for k in range(1, H + 1):
        c, s = np.cos(k * theta), np.sin(k * theta)
        ack, ask = ac[k - 1][:, None, :], as_[k - 1][:, None, :]
        a = a + c[..., None] * ack + s[..., None] * ask
        da = da + k * (-s[..., None] * ack + c[..., None] * ask)
        dda = dda - k * k * (c[..., None] * ack + s[..., None] * ask)
        b = b + c * bc[k - 1][:, None] + s * bs[k - 1][:, None]
        db = db + k * (-s * bc[k - 1][:, None] + c * bs[k - 1][:, None])
        ddb = ddb - k * k * (c * bc[k - 1][:, None] + s * bs[k - 1][:, None])
    na = np.linalg.norm(a, axis=-1)
    safe = np.maximum(na, 1e-300)
    ada = np.einsum("nmc,nmc->nm", a, da)
    g = na - b
    g1 = ada / safe - db
    g2 = (np.einsum("nmc,nmc->nm", da, da) + np.einsum("nmc,nmc->nm", a, dda)) / safe \
        - ada ** 2 / safe ** 3 - ddb
    return g, g1, g2


def _roots_on_circle(Q):
    """Angles of the roots of ``sum_m Q[..., m] z^m`` for every row (all roots, any modulus:
    extra candidates are harmless), shape (N, 8H); rows with ``Q = 0`` give none (nan)."""
    n, d1 = Q.shape
    deg = d1 - 1
    out = np.full((n, deg), np.nan)
    scale = np.abs(Q).max(axis=1)
    lead = np.abs(Q[:, -1])
    regular = lead > 1e-10 * np.maximum(scale, 1e-300)
    if np.any(regular):
        P = Q[regular] / Q[regular, -1:]
        comp = np.zeros((P.shape[0], deg, deg), complex)
        comp[:, 0, :] = -P[:, -2::-1]
        comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
        out[regular] = np.angle(np.linalg.eigvals(comp))
    for i in np.flatnonzero(~regular & (scale > 0)):
        coef = Q[i, ::-1]
        nz = np.flatnonzero(np.abs(coef) > 1e-13 * scale[i])
        if nz.size and nz[-1] > nz[0]:
            r = np.roots(coef[nz[0]: nz[-1] + 1])
            out[i, : r.size] = np.angle(r)
    return out


def _harmonic_max(a_base, b_base, ac, as_, bc, bs):
    n = a_base.shape[0]
    H = ac.shape[0]
    # complex coefficients per component: (N, 2, 2H+1); b: (N, 2H+1)
    Ac = np.stack([_coefficients(a_base[:, c], ac[:, :, c], as_[:, :, c]) for c in range(2)], 1)
    Bc = _coefficients(b_base, bc, bs)
    dA, dB = _derivative(Ac), _derivative(Bc)
    ada = _conv(Ac[:, 0], dA[:, 0]) + _conv(Ac[:, 1], dA[:, 1])  # degree 2H
    aa = _conv(Ac[:, 0], Ac[:, 0]) + _conv(Ac[:, 1], Ac[:, 1])
    Q = _conv(ada, ada) - _conv(_conv(dB, dB), aa)  # degree 4H: powers -4H..4H
    theta = _roots_on_circle(Q)  # z^{4H} Q(z): index m = power + 4H
    grid = 2 * np.pi * np.arange(16 * H) / (16 * H)
    raw = np.where(np.isnan(theta), 0.0, theta)
    cand = raw.copy()
    for _ in range(3):  # Newton on g' = 0
        _, g1, g2 = _evaluate(a_base, b_base, ac, as_, bc, bs, cand)
        step = np.where(np.abs(g2) > 1e-300, g1 / np.where(g2 == 0, 1.0, g2), 0.0)
        cand = cand - np.clip(step, -0.5, 0.5)
    allc = np.concatenate([raw, cand, np.broadcast_to(grid, (n, grid.size))], axis=1)
    g, _, _ = _evaluate(a_base, b_base, ac, as_, bc, bs, allc)
    i = np.argmax(g, axis=1)
    rows = np.arange(n)
    return g[rows, i], np.mod(allc[rows, i] / (2 * np.pi), 1.0)
