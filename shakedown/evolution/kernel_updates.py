"""Block updates of a cached assignment inverse (:mod:`.kernel_cache`; MODEL.md s.4).

From the inverse ``X`` of assignment ``b`` to that of a neighbouring assignment ``s``, in three
block steps of ``O(m^2 r)`` flops each (matrix products, BLAS-3), ``r`` the number of unknowns
concerned:

1. remove the unknowns (and their paired rows) that ``s`` fixes, positions ``R``:
   ``X' = X_KK - X_KR (X_RR)^-1 X_RK`` (the inverse of a principal submatrix);
2. change the coefficient of the a-rows of nodes that stay free but change direction or
   separate, positions ``C``: ``M' = M + E D^T`` with ``E`` the unit columns at ``C`` and
   ``D^T`` the coefficient changes times rows of ``K``, Woodbury
   ``X' = X - X E (I + D^T X E)^-1 D^T X``;
3. append the unknowns ``s`` frees, with their rows: bordering with the Schur complement
   ``S = D - V^T X U``: ``X' = [[X + X U S^-1 V^T X, -X U S^-1], [-S^-1 V^T X, S^-1]]``.

Each small inverse must exist (a singular block returns ``ok = False``); the caller checks the
solved equations and recomputes the inverse afresh when they fail.
"""

from __future__ import annotations

import numpy as np

from .kernel_cache import BACKWARD, FORWARD, SEPARATED, STICK, _slot
from .kernel_jit import njit


@njit(cache=True)
def _entry(K, r, c, col, n):
    """``M[row, col]`` of a row with K-index ``r`` and coefficient ``c``."""
    v = K[r, col]
    if r < n and c != 0.0:
        v += c * K[n + r, col]
    return v


@njit(cache=True)
def _small_inv(S):
    try:
        return np.ascontiguousarray(np.linalg.inv(S)), True
    except Exception:  # noqa: BLE001 - numba raises a generic error for a singular matrix
        return S, False


@njit(cache=True)
def _remove(X, free, coef, drop):
    """Drop the positions flagged in ``drop`` (bool, length m)."""
    m = free.size
    r = 0
    for i in range(m):
        if drop[i]:
            r += 1
    if r == 0:
        return X, free, coef, True
    keep = np.empty(m - r, np.int64)
    rm = np.empty(r, np.int64)
    a = 0
    b = 0
    for i in range(m):
        if drop[i]:
            rm[b] = i
            b += 1
        else:
            keep[a] = i
            a += 1
    mk = m - r
    XKK = np.empty((mk, mk))
    XKR = np.empty((mk, r))
    XRR = np.empty((r, r))
    XRK = np.empty((r, mk))
    for i in range(mk):
        for k in range(mk):
            XKK[i, k] = X[keep[i], keep[k]]
        for k in range(r):
            XKR[i, k] = X[keep[i], rm[k]]
    for i in range(r):
        for k in range(r):
            XRR[i, k] = X[rm[i], rm[k]]
        for k in range(mk):
            XRK[i, k] = X[rm[i], keep[k]]
    Rinv, ok = _small_inv(XRR)
    if not ok:
        return X, free, coef, False
    XKK -= XKR @ (Rinv @ XRK)
    return XKK, free[keep].copy(), coef[keep].copy(), True


@njit(cache=True)
def _change(X, free, coef, pos, c_new, K, n):
    """a-rows at positions ``pos`` take coefficients ``c_new``: Woodbury."""
    X = np.ascontiguousarray(X)
    m = free.size
    r = pos.size
    if r == 0:
        return X, coef, True
    DT = np.empty((r, m))
    for i in range(r):
        dc = c_new[i] - coef[pos[i]]
        row = K[n + free[pos[i]]]
        for k in range(m):
            DT[i, k] = dc * row[free[k]]
    XE = np.empty((m, r))
    for i in range(m):
        for k in range(r):
            XE[i, k] = X[i, pos[k]]
    DX = DT @ X
    cap = DT @ XE
    for i in range(r):
        cap[i, i] += 1.0
    Cinv, ok = _small_inv(cap)
    if not ok:
        return X, coef, False
    X = X - XE @ (Cinv @ DX)
    coef = coef.copy()
    for i in range(r):
        coef[pos[i]] = c_new[i]
    return X, coef, True


@njit(cache=True)
def _append(X, free, coef, idx, c, K, n):
    """Append unknowns ``idx`` (with their own rows, coefficients ``c``): bordering."""
    X = np.ascontiguousarray(X)
    m = free.size
    a = idx.size
    if a == 0:
        return X, free, coef, True
    U = np.empty((m, a))
    VT = np.empty((a, m))
    D = np.empty((a, a))
    for i in range(m):
        for l in range(a):
            U[i, l] = _entry(K, free[i], coef[i], idx[l], n)
    for l in range(a):
        for k in range(m):
            VT[l, k] = _entry(K, idx[l], c[l], free[k], n)
        for k in range(a):
            D[l, k] = _entry(K, idx[l], c[l], idx[k], n)
    XU = X @ U
    VX = VT @ X
    S = D - VT @ XU
    Sinv, ok = _small_inv(S)
    if not ok:
        return X, free, coef, False
    XUS = XU @ Sinv
    X2 = np.empty((m + a, m + a))
    X2[:m, :m] = X + XUS @ VX
    X2[:m, m:] = -XUS
    X2[m:, :m] = -(Sinv @ VX)
    X2[m:, m:] = Sinv
    free2 = np.empty(m + a, np.int64)
    free2[:m] = free
    free2[m:] = idx
    coef2 = np.empty(m + a)
    coef2[:m] = coef
    coef2[m:] = c
    return X2, free2, coef2, True


@njit(cache=True)
def _coef_of(state, fj):
    if state == FORWARD:
        return fj
    if state == BACKWARD:
        return -fj
    return 0.0


@njit(cache=True)
def changed_unknowns(sb, s, n):
    """Number of unknowns removed, re-weighted or appended from ``sb`` to ``s``."""
    r = 0
    for j in range(n):
        if sb[j] != s[j]:
            r += 1 + (sb[j] == SEPARATED) + (s[j] == SEPARATED)
    return r


@njit(cache=True)
def updated(s, kb, K, f, n, keys, offs, sizes, pool, ipool, fpool):
    """The inverse of assignment ``s`` from slot ``kb``: ``(X, free, coef, ok)``."""
    Xb, fb, cb = _slot(kb, offs, sizes, pool, ipool, fpool)
    sb = keys[kb]
    m = fb.size
    drop = np.zeros(m, np.bool_)
    for i in range(m):
        r = fb[i]
        j = r if r < n else r - n
        if sb[j] == s[j]:
            continue
        if r < n and s[j] == STICK:
            drop[i] = True  # the slip unknown goes
        if r >= n and s[j] != SEPARATED:
            drop[i] = True  # the gap unknown goes
    X, free, coef, ok = _remove(Xb.copy(), fb.copy(), cb.copy(), drop)  # never the pool itself
    if not ok:
        return X, free, coef, False
    n_c = 0
    for i in range(free.size):
        r = free[i]
        if r < n and coef[i] != _coef_of(s[r], f[r]):
            n_c += 1
    pos = np.empty(n_c, np.int64)
    cn = np.empty(n_c)
    n_c = 0
    for i in range(free.size):
        r = free[i]
        c = _coef_of(s[r], f[r]) if r < n else 0.0
        if r < n and coef[i] != c:
            pos[n_c] = i
            cn[n_c] = c
            n_c += 1
    X, coef, ok = _change(X, free, coef, pos, cn, K, n)
    if not ok:
        return X, free, coef, False
    n_a = 0
    for j in range(n):
        if sb[j] == STICK and s[j] != STICK:
            n_a += 1
        if sb[j] != SEPARATED and s[j] == SEPARATED:
            n_a += 1
    idx = np.empty(n_a, np.int64)
    cs = np.empty(n_a)
    n_a = 0
    for j in range(n):
        if sb[j] == STICK and s[j] != STICK:
            idx[n_a] = j
            cs[n_a] = _coef_of(s[j], f[j])
            n_a += 1
    for j in range(n):
        if sb[j] != SEPARATED and s[j] == SEPARATED:
            idx[n_a] = n + j
            cs[n_a] = 0.0
            n_a += 1
    return _append(X, free, coef, idx, cs, K, n)
