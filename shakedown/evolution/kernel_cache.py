"""Bounded cache of assignment inverses of the compiled kernel, and their rank-one updates
(:mod:`.kernel`; MODEL.md s.4).

An assignment ``s`` has free unknowns ``free`` (indices into ``z = (dv, w)``; each paired with
its equation row: the a-row ``q_j + c_j p_j`` of a slip unknown ``j < N``, ``c_j = 0`` for a
separated node, the b-row ``p_j`` of a gap unknown ``N + j``) and ``M_s[i, k] = K[free_i,
free_k] + c_i K[N + free_i, free_k]``.  Its inverse is stored in a flat pool with ``free`` and
the row coefficients (their order is the slot's own).  A neighbouring assignment is reached
from a stored inverse by the block updates of :mod:`.kernel_updates`.  Each slot records the
last step it answered (:func:`stamp`), so that a full cache keeps the inverses of the last
period's answers, which a periodic orbit meets again (:func:`_compact`).
"""

from __future__ import annotations

import numpy as np

from .kernel_jit import njit

STICK, FORWARD, BACKWARD, SEPARATED = 0, 1, 2, 3
#: Largest accepted 1-norm condition number of an assignment matrix (inverse kept in cache).
COND_MAX = 1e12
# meta indices
N_SLOTS, POOL_USED, IPOOL_USED, LAST_SLOT, RESETS, CLOCK, WINDOW = 0, 1, 2, 3, 4, 5, 6
#: Fraction of the pool that the inverses kept through a reset may fill (:func:`_compact`).
KEEP_FRACTION = 0.75


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
        X = np.ascontiguousarray(np.linalg.inv(M))
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
    """Cache assignment ``s``; slot index or -1.  A full cache is reset: it keeps the last
    period's answers (:func:`_compact`), or nothing if there is still no room."""
    m = free.size
    if m * m > pool.size or m > ipool.size or meta[N_SLOTS] >= hashes.size and hashes.size == 0:
        return -1
    if (meta[N_SLOTS] >= hashes.size or meta[POOL_USED] + m * m > pool.size
            or meta[IPOOL_USED] + m > ipool.size):
        _compact(keys, hashes, offs, sizes, pool, ipool, fpool, meta)
        if (meta[N_SLOTS] >= hashes.size or meta[POOL_USED] + m * m > pool.size
                or meta[IPOOL_USED] + m > ipool.size):
            meta[N_SLOTS] = 0
            meta[POOL_USED] = 0
            meta[IPOOL_USED] = 0
            meta[LAST_SLOT] = -1
    k = meta[N_SLOTS]
    keys[k, :] = s
    hashes[k] = h
    offs[k, 0] = meta[POOL_USED]
    offs[k, 1] = meta[IPOOL_USED]
    offs[k, 2] = gen
    offs[k, 3] = -1  # not yet the answer of a step (:func:`stamp`)
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
def stamp(s, mult, keys, hashes, offs, meta):
    """Mark the inverse of assignment ``s`` (if cached) as the answer of the step numbered
    ``meta[CLOCK]`` (then advanced): kept through a reset while in the last ``meta[WINDOW]``
    steps (:func:`_compact`)."""
    k = _lookup(s, _hash(s, mult), keys, hashes, meta)
    if k >= 0:
        offs[k, 3] = meta[CLOCK]
    meta[CLOCK] += 1


@njit(cache=True)
def _compact(keys, hashes, offs, sizes, pool, ipool, fpool, meta):
    """The reset of a full cache: keep (moved to the front, in order) the inverses that
    answered one of the last ``meta[WINDOW]`` steps (:func:`stamp`), within
    :data:`KEEP_FRACTION` of the pool, and drop the others (the active-set iterates that were
    not answers, older answers).  A steady cycle's next period then finds each step's
    assignment of this period (:func:`.kernel._probe`) instead of recomputing them."""
    meta[RESETS] += 1
    oldest = meta[CLOCK] - meta[WINDOW]
    budget = KEEP_FRACTION * pool.size
    last = meta[LAST_SLOT]
    meta[LAST_SLOT] = -1
    nk, po, io = 0, 0, 0
    for k in range(meta[N_SLOTS]):
        m = sizes[k]
        if offs[k, 3] < 0 or offs[k, 3] < oldest or po + m * m > budget:
            continue
        o, oi = offs[k, 0], offs[k, 1]
        for t in range(m * m):  # forward copy to a lower offset: safe when overlapping
            pool[po + t] = pool[o + t]
        for t in range(m):
            ipool[io + t] = ipool[oi + t]
            fpool[io + t] = fpool[oi + t]
        if nk != k:
            keys[nk, :] = keys[k]
            hashes[nk] = hashes[k]
            offs[nk, 2] = offs[k, 2]
            offs[nk, 3] = offs[k, 3]
            sizes[nk] = m
        offs[nk, 0] = po
        offs[nk, 1] = io
        if k == last:
            meta[LAST_SLOT] = nk
        nk += 1
        po += m * m
        io += m
    meta[N_SLOTS] = nk
    meta[POOL_USED] = po
    meta[IPOOL_USED] = io


@njit(cache=True)
def _slot(k, offs, sizes, pool, ipool, fpool):
    m = sizes[k]
    o, oi = offs[k, 0], offs[k, 1]
    return (np.ascontiguousarray(pool[o:o + m * m]).reshape((m, m)), ipool[oi:oi + m],
            fpool[oi:oi + m])


@njit(cache=True)
def _rhs(free, coef, q0, p0, n):
    """Right-hand side of the assignment's equations at base reactions ``(q0, p0)``."""
    m = free.size
    h = np.empty(m)
    for i in range(m):
        r = free[i]
        h[i] = -(q0[r] + coef[i] * p0[r]) if r < n else -p0[r - n]
    return h


@njit(cache=True)
def _apply(x, free, coef, K, q0, p0, n, z, q, p):
    """``z`` from the free unknowns ``x``, its reactions ``q, p``; returns the largest
    equation residual (force units)."""
    m = free.size
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
def _solve_with(X, free, coef, K, q0, p0, n, z, q, p):
    """z = (dv, w) of the assignment with inverse X; q, p its reactions; returns the largest
    equation residual (force units)."""
    h = _rhs(free, coef, q0, p0, n)
    # BLAS gemv: a compiled scalar loop is a serial chain of adds per row (without fastmath no
    # reordering), 215 us against 31 us at m = 510
    x = np.dot(X, h)
    return _apply(x, free, coef, K, q0, p0, n, z, q, p)


@njit(cache=True)
def _solve_lu(M, free, coef, K, q0, p0, n, z, q, p):
    """The backward-stable solve (LAPACK gesv) of an assignment whose inverse is not accurate
    enough; the equation residual, or ``inf`` when ``M`` is singular."""
    try:
        x = np.linalg.solve(M, _rhs(free, coef, q0, p0, n))
    except Exception:  # noqa: BLE001 - numba raises a generic error for a singular matrix
        return np.inf
    return _apply(x, free, coef, K, q0, p0, n, z, q, p)
