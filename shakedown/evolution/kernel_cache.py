"""Bounded cache of assignment inverses of the compiled kernel, and their rank-one updates
(:mod:`.kernel`; MODEL.md s.4).

An assignment ``s`` has free unknowns ``free`` (indices into ``z = (dv, w)``; each paired with
its equation row: the a-row ``q_j + c_j p_j`` of a slip unknown ``j < N``, ``c_j = 0`` for a
separated node, the b-row ``p_j`` of a gap unknown ``N + j``) and ``M_s[i, k] = K[free_i,
free_k] + c_i K[N + free_i, free_k]``.  Its inverse is stored in a flat pool with ``free`` and
the row coefficients (their order is the slot's own).  A neighbouring assignment is reached
from a stored inverse by the rank-one formulas (``O(m^2)`` each): a row's coefficient changed
(Sherman-Morrison), an unknown and its row appended (bordering with the Schur complement), an
unknown and its row removed (``X' = X_{-a,-a} - X_{-a,a} X_{a,-a} / X_{aa}``).
"""

from __future__ import annotations

import numpy as np

from .kernel_jit import njit

STICK, FORWARD, BACKWARD, SEPARATED = 0, 1, 2, 3
#: Largest accepted 1-norm condition number of an assignment matrix (inverse kept in cache).
COND_MAX = 1e12
# meta indices
N_SLOTS, POOL_USED, IPOOL_USED, LAST_SLOT, RESETS = 0, 1, 2, 3, 4


@njit(cache=True)
def _hash(s, mult):
    h = np.uint64(0)
    for j in range(s.size):
        h += np.uint64(s[j] + 1) * mult[j]
    return h


@njit(cache=True)
def _lookup(s, h, keys, hashes, meta):
    for k in range(meta[N_SLOTS]):
        if hashes[k] == h:
            same = True
            for j in range(s.size):
                if keys[k, j] != s[j]:
                    same = False
                    break
            if same:
                return k
    return -1


@njit(cache=True)
def _layout(s, f, n):
    """Free unknowns (indices into z = (dv, w)) and row coefficients of assignment s."""
    m = 0
    for j in range(n):
        if s[j] != STICK:
            m += 1
            if s[j] == SEPARATED:
                m += 1
    free = np.empty(m, np.int64)
    coef = np.zeros(m)
    i = 0
    for j in range(n):
        if s[j] != STICK:
            free[i] = j
            if s[j] == FORWARD:
                coef[i] = f[j]
            elif s[j] == BACKWARD:
                coef[i] = -f[j]
            i += 1
    for j in range(n):
        if s[j] == SEPARATED:
            free[i] = n + j
            i += 1
    return free, coef


@njit(cache=True)
def _matrix(K, free, coef, n):
    m = free.size
    M = np.empty((m, m))
    for i in range(m):
        r = free[i]
        c = coef[i]
        for k in range(m):
            M[i, k] = K[r, free[k]]
        if r < n and c != 0.0:
            for k in range(m):
                M[i, k] += c * K[n + r, free[k]]
    return M


@njit(cache=True)
def _invert(M):
    """``(M^-1, ok)``: ok when finite with 1-norm condition number below COND_MAX."""
    m = M.shape[0]
    try:
        X = np.linalg.inv(M)
    except Exception:  # noqa: BLE001 - numba raises a generic error for a singular matrix
        return np.zeros((m, m)), False
    a = 0.0
    b = 0.0
    for k in range(m):
        sa = 0.0
        sb = 0.0
        for i in range(m):
            sa += abs(M[i, k])
            sb += abs(X[i, k])
        a = max(a, sa)
        b = max(b, sb)
    ok = np.isfinite(b) and a * b < COND_MAX
    return X, ok


@njit(cache=True)
def _store(s, h, free, coef, X, gen, keys, hashes, offs, sizes, pool, ipool, fpool, meta):
    """Cache assignment ``s`` (reset the whole cache when it is full); slot index or -1."""
    m = free.size
    if m * m > pool.size or m > ipool.size or meta[N_SLOTS] >= hashes.size and hashes.size == 0:
        return -1
    if (meta[N_SLOTS] >= hashes.size or meta[POOL_USED] + m * m > pool.size
            or meta[IPOOL_USED] + m > ipool.size):
        meta[N_SLOTS] = 0
        meta[POOL_USED] = 0
        meta[IPOOL_USED] = 0
        meta[RESETS] += 1
    k = meta[N_SLOTS]
    keys[k, :] = s
    hashes[k] = h
    offs[k, 0] = meta[POOL_USED]
    offs[k, 1] = meta[IPOOL_USED]
    offs[k, 2] = gen
    sizes[k] = m
    o = meta[POOL_USED]
    pool[o:o + m * m] = X.ravel()
    oi = meta[IPOOL_USED]
    ipool[oi:oi + m] = free
    fpool[oi:oi + m] = coef
    meta[POOL_USED] += m * m
    meta[IPOOL_USED] += m
    meta[N_SLOTS] += 1
    meta[LAST_SLOT] = k
    return k


@njit(cache=True)
def _slot(k, offs, sizes, pool, ipool, fpool):
    m = sizes[k]
    o, oi = offs[k, 0], offs[k, 1]
    return pool[o:o + m * m].reshape((m, m)), ipool[oi:oi + m], fpool[oi:oi + m]


@njit(cache=True)
def _solve_with(X, free, coef, K, q0, p0, n, z, q, p):
    """z = (dv, w) of the assignment with inverse X; q, p its reactions; returns the largest
    equation residual (force units)."""
    m = free.size
    h = np.empty(m)
    for i in range(m):
        r = free[i]
        h[i] = -(q0[r] + coef[i] * p0[r]) if r < n else -p0[r - n]
    x = np.zeros(m)
    for i in range(m):
        acc = 0.0
        for k in range(m):
            acc += X[i, k] * h[k]
        x[i] = acc
    z[:] = 0.0
    q[:] = q0
    p[:] = p0
    for i in range(m):
        z[free[i]] = x[i]
        xi = x[i]
        row = K[free[i]]
        for k in range(n):
            q[k] += xi * row[k]
            p[k] += xi * row[n + k]
    err = 0.0
    for i in range(m):
        r = free[i]
        e = abs(q[r] + coef[i] * p[r]) if r < n else abs(p[r - n])
        err = max(err, e)
    return err


@njit(cache=True)
def _entry(K, r, c, col, n):
    """``M[row, col]`` of a row with K-index ``r`` and coefficient ``c``."""
    v = K[r, col]
    if r < n and c != 0.0:
        v += c * K[n + r, col]
    return v


@njit(cache=True)
def _row_change(X, free, coef, a, c_new, K, n):
    """Row ``a`` (an a-row) takes coefficient ``c_new``: Sherman-Morrison."""
    m = free.size
    dc = c_new - coef[a]
    d = np.empty(m)
    for k in range(m):
        d[k] = dc * K[n + free[a], free[k]]
    dX = d @ X  # d^T X
    den = 1.0 + dX[a]
    if den == 0.0 or not np.isfinite(den):
        return X, False
    Xa = X[:, a].copy()
    for i in range(m):
        g = Xa[i] / den
        for k in range(m):
            X[i, k] -= g * dX[k]
    coef[a] = c_new
    return X, True


@njit(cache=True)
def _append(X, free, coef, idx, c, K, n):
    """Append unknown ``idx`` with its own row (coefficient ``c``): bordering."""
    m = free.size
    u = np.empty(m)
    v = np.empty(m)
    for i in range(m):
        u[i] = _entry(K, free[i], coef[i], idx, n)
        v[i] = _entry(K, idx, c, free[i], n)
    d = _entry(K, idx, c, idx, n)
    Xu = X @ u
    vX = v @ X
    sigma = d - v @ Xu
    if sigma == 0.0 or not np.isfinite(sigma):
        return X, free, coef, False
    X2 = np.empty((m + 1, m + 1))
    for i in range(m):
        g = Xu[i] / sigma
        for k in range(m):
            X2[i, k] = X[i, k] + g * vX[k]
        X2[i, m] = -g
    for k in range(m):
        X2[m, k] = -vX[k] / sigma
    X2[m, m] = 1.0 / sigma
    free2 = np.empty(m + 1, np.int64)
    free2[:m] = free
    free2[m] = idx
    coef2 = np.empty(m + 1)
    coef2[:m] = coef
    coef2[m] = c
    return X2, free2, coef2, True


@njit(cache=True)
def _remove(X, free, coef, a):
    """Remove unknown ``a`` and its row: ``X_{-a,-a} - X_{-a,a} X_{a,-a} / X_{aa}``."""
    m = free.size
    piv = X[a, a]
    if piv == 0.0 or not np.isfinite(piv):
        return X, free, coef, False
    X2 = np.empty((m - 1, m - 1))
    ii = 0
    for i in range(m):
        if i == a:
            continue
        g = X[i, a] / piv
        kk = 0
        for k in range(m):
            if k == a:
                continue
            X2[ii, kk] = X[i, k] - g * X[a, k]
            kk += 1
        ii += 1
    free2 = np.empty(m - 1, np.int64)
    coef2 = np.empty(m - 1)
    ii = 0
    for i in range(m):
        if i != a:
            free2[ii] = free[i]
            coef2[ii] = coef[i]
            ii += 1
    return X2, free2, coef2, True


@njit(cache=True)
def _position(free, idx):
    for i in range(free.size):
        if free[i] == idx:
            return i
    return -1


@njit(cache=True)
def _updated(s, kb, K, f, n, keys, offs, sizes, pool, ipool, fpool):
    """The inverse of assignment ``s`` from slot ``kb`` by rank-one updates:
    ``(X, free, coef, ok)`` (removals first, then coefficient changes, then appends)."""
    Xb, fb, cb = _slot(kb, offs, sizes, pool, ipool, fpool)
    X = Xb.copy()
    free = fb.copy()
    coef = cb.copy()
    sb = keys[kb]
    ok = True
    for phase in range(3):
        for j in range(n):
            old, new = sb[j], s[j]
            if old == new:
                continue
            c_new = 0.0
            if new == FORWARD:
                c_new = f[j]
            elif new == BACKWARD:
                c_new = -f[j]
            if phase == 0:  # removals
                if old == SEPARATED:
                    X, free, coef, ok = _remove(X, free, coef, _position(free, n + j))
                    if not ok:
                        return X, free, coef, False
                if old != STICK and new == STICK:
                    X, free, coef, ok = _remove(X, free, coef, _position(free, j))
            elif phase == 1:  # a-rows that stay, with a new coefficient
                if old != STICK and new != STICK:
                    a = _position(free, j)
                    if coef[a] != c_new:
                        X, ok = _row_change(X, free, coef, a, c_new, K, n)
            else:  # appends
                if old == STICK and new != STICK:
                    X, free, coef, ok = _append(X, free, coef, j, c_new, K, n)
                    if not ok:
                        return X, free, coef, False
                if new == SEPARATED:
                    X, free, coef, ok = _append(X, free, coef, n + j, 0.0, K, n)
            if not ok:
                return X, free, coef, False
    return X, free, coef, True
