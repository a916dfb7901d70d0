"""Steps that keep the previous step's assignment, in ``O(N r)`` (issue 14: the warm step).

A step solved with the same node-state assignment ``s`` as the step before it is linear in the
welded increment: with ``F`` the free unknowns of ``s``, ``E_F`` its equation rows and
``X = (E_F K[:, F])^-1`` (the cached inverse of :mod:`.kernel_cache`), the previous answer
satisfies ``E_F (q, p) = 0``, so the new one is

    z_F = z_F^prev|gaps + delta,   delta = -X E_F dW,
    (q, p) = (q, p)^prev + dW + K[:, F] delta,

where ``dW`` is the increment of the welded reactions ``(q_w, p_w)`` and the slips of ``z`` are
increments (the gaps carry over).  The increments of one period span a small space (``r = 2``
for a one-harmonic load): with an orthonormal basis ``u_1 .. u_r`` of it and ``dW = sum c_l
u_l``, the responses ``Z_l = -X E_F u_l`` and ``G_l = u_l + K[:, F] Z_l`` are computed once per
assignment (``r`` solves with the cached inverse), and such a step costs ``O((2N + m) r)``
instead of the ``O(2N m)`` of reading the ``m`` rows of ``K`` (the floor of a solve, 6-10x one
``getrs`` at N = 1000).  The gap reactions ``T = K[:, gaps] w`` are kept alongside (responses
``H_l``), so that the next step's base reactions cost ``O(N)`` too.

The step is accepted only as the general one is: its equations to ``1e-3 feas_tol`` and its sign
checks (:func:`.kernel._violated`); otherwise the step is solved from its base as before.  The
responses are built after the assignment has been kept by two consecutive steps, and dropped
after any step not taken by this path.
"""

from __future__ import annotations

import numpy as np

from .kernel_cache import STICK, _hash, _lookup, _slot, _solve_with
from .kernel_jit import njit

#: Largest dimension of the increments' space for which the responses are kept (a load of
#: more harmonics, or a sampled record, runs every step by the general solve).
MAX_RANK = 8
#: Relative accuracy of a represented increment (of the largest increment ``dmax``); raised to
#: the round-off the increments carry themselves (``16 eps max|W|``: at many steps per cycle
#: the differences of the welded reactions are exact only to that).  A block's direction whose
#: singular value is below ``2 (sqrt(rows) + sqrt(2N))`` times this is dropped as round-off;
#: every increment must then be represented to that bound, else the shortcut is off.
RANK_RTOL = 1e-13
#: Increments per block of the basis scan (bounds its memory: no ``(S - 1)^2`` Gram matrix).
BLOCK = 256
#: Largest equation residual of a response to a unit increment (relative; a sanity check).
BUILD_RTOL = 1e-8
#: Consecutive steps an assignment must be kept (at the first active-set iteration) before its
#: responses are built (``r`` solves: worth it only for an assignment that persists).
PERSIST = 2

# sc_meta indices
VALID, M_FREE, RUN, ENABLED = 0, 1, 2, 3


def increment_basis(D: np.ndarray, noise: float = RANK_RTOL, max_rank: int = MAX_RANK,
                    block: int = BLOCK):
    """Orthonormal rows spanning the rows of ``D`` (n_incr, m) to ``noise``, in ``O(n_incr m r)``.

    The rows are taken ``block`` at a time: each block is projected (twice, for round-off) off
    the directions found so far; if an entry of what remains exceeds the drop level
    ``2 noise (sqrt(rows) + sqrt(m))`` (:func:`drop_level`), its right singular vectors with
    singular values above that level are added.  Memory is
    bounded by the block and the basis (never a Gram matrix of all the increments); the scan
    stops as soon as more than ``max_rank`` directions are found.

    Parameters
    ----------
    D : ndarray, shape (n_incr, m)
        The increments, scaled so that ``|D|.max() == 1`` (dimensionless).
    noise : float
        Accuracy of an entry of ``D`` (dimensionless).
    max_rank : int
    block : int
        Rows per block.

    Returns
    -------
    ndarray, shape (r, m), or None
        The basis (``r <= max_rank``), or None when the rows span more than ``max_rank``
        directions.
    """
    m = D.shape[1]
    return _basis((D[i0:i0 + block] for i0 in range(0, D.shape[0], block)), m, noise, max_rank)


def _basis(blocks, m: int, noise: float, max_rank: int):
    """:func:`increment_basis` of the row blocks ``blocks`` (an iterable of (rows, m) arrays)."""
    SB = np.zeros((0, m))
    for R in blocks:
        for _ in range(2):  # projection repeated: classical Gram-Schmidt twice is orthogonal
            R = R - (R @ SB.T) @ SB
        level = drop_level(noise, R.shape[0], m)
        if not np.abs(R).max(initial=0.0) > level:  # every row represented to the drop level
            continue  # (the common case: O(rows m r) per block, no decomposition)
        _, sv, Vt = np.linalg.svd(R, full_matrices=False)
        new = Vt[sv > level]
        if SB.shape[0] + new.shape[0] > max_rank:
            return None
        if new.shape[0]:
            SB = np.linalg.qr(np.vstack([SB, new]).T)[0].T  # re-orthonormalised (round-off)
    return SB


def drop_level(noise: float, rows: int, m: int) -> float:
    """Singular value below which a block's direction is round-off: twice the largest singular
    value of a ``rows x m`` block of independent errors of size ``noise``."""
    return 2.0 * noise * (np.sqrt(rows) + np.sqrt(m))


def state(n: int, qw: np.ndarray, pw: np.ndarray):
    """The shortcut's arrays for one period of welded reactions ``qw, pw`` (n_steps, n):
    ``(SB, SCc, RESP, T, key, free, coef, meta)``; disabled (``meta[ENABLED] = 0``) when the
    increments span more than :data:`MAX_RANK` directions.  Cost and memory linear in
    ``n_steps`` (:func:`increment_basis`)."""
    steps = qw.shape[0]

    def blocks(scale=1.0):  # the increments W[j] - W[j - 1], BLOCK rows at a time (no copy
        for i0 in range(0, steps - 1, BLOCK):  # of the whole period)
            i1 = min(i0 + BLOCK, steps - 1)
            with np.errstate(over="ignore", invalid="ignore"):
                yield i0, np.hstack([qw[i0 + 1:i1 + 1] - qw[i0:i1],
                                     pw[i0 + 1:i1 + 1] - pw[i0:i1]]) / scale

    dmax = max((float(np.abs(D).max()) for _, D in blocks()), default=0.0)
    r, SB = 0, np.zeros((0, 2 * n))
    enabled = 1 if np.isfinite(dmax) else 0  # (an overflowing load: the general path reports)
    if enabled and dmax > 0:
        wmax = max(np.abs(qw).max(initial=0.0), np.abs(pw).max(initial=0.0))
        noise = min(max(RANK_RTOL, 16 * np.finfo(float).eps * wmax / dmax), 1e-6)
        level = drop_level(noise, min(BLOCK, steps - 1), 2 * n)
        # (scaled by dmax: D itself could overflow in products)
        B = _basis((D for _, D in blocks(dmax)), 2 * n, noise, MAX_RANK)
        if B is None:
            enabled = 0
        else:
            SB, r = B, B.shape[0]
    SCc = np.zeros((steps, r))
    if enabled and dmax > 0:
        err = 0.0
        with np.errstate(over="ignore", invalid="ignore"):
            for i0, D in blocks():
                C = SCc[i0 + 1:i0 + 1 + D.shape[0]]
                C[:] = D @ SB.T  # row j: coefficients of W[j] - W[j - 1]
                err = max(err, float(np.abs(D - C @ SB).max()))
        if not err <= level * dmax:  # a real direction dropped, or an overflow
            enabled = 0
    meta = np.zeros(4, np.int64)
    meta[ENABLED] = enabled
    return (np.ascontiguousarray(SB), SCc, np.zeros((3, r, 2 * n)), np.zeros(2 * n),
            np.zeros(n, np.int8), np.zeros(2 * n, np.int64), np.zeros(2 * n), meta)


@njit(cache=True)
def build(s, z, K, f, n, mult, keys, hashes, offs, sizes, pool, ipool, fpool, meta,
          SB, RESP, T, key, sfree, scoef, smeta):
    """The responses of assignment ``s`` (cached inverse) and ``T`` of the gaps ``z[n:]``;
    False (shortcut invalid) when ``s`` has no cached inverse or a response fails its check."""
    smeta[VALID] = 0
    k = _lookup(s, _hash(s, mult), keys, hashes, meta)
    if k < 0:
        return False
    X, free, coef = _slot(k, offs, sizes, pool, ipool, fpool)
    r = SB.shape[0]
    qq = np.empty(n)
    pp = np.empty(n)
    for l in range(r):
        u = SB[l]
        # a sanity check of the inverse (round-off of a response: ~1e-16 cond(M_s) |u|); each
        # step using the responses checks its own equations to 1e-3 feas_tol
        tol = BUILD_RTOL * np.abs(u).max()
        if not _solve_with(X, free, coef, K, u[:n], u[n:], n, RESP[0, l], qq, pp) <= tol:
            return False
        RESP[1, l, :n] = qq
        RESP[1, l, n:] = pp
        gap_reactions(RESP[0, l], K, n, RESP[2, l])
    gap_reactions(z, K, n, T)
    m = free.size
    sfree[:m] = free
    scoef[:m] = coef
    key[:] = s
    smeta[M_FREE] = m
    smeta[VALID] = 1
    return True


@njit(cache=True)
def gap_reactions(z, K, n, out):
    """``out = K[:, n:] z[n:]`` over the non-zero gaps (rows of the symmetric ``K``)."""
    out[:] = 0.0
    for i in range(n):
        w = z[n + i]
        if w != 0.0:
            row = K[n + i]
            for k in range(2 * n):
                out[k] += w * row[k]


@njit(cache=True)
def usable(s, key, smeta):
    """The responses are built and belong to ``s``."""
    if smeta[VALID] == 0:
        return False
    for j in range(s.size):
        if s[j] != key[j]:
            return False
    return True


@njit(cache=True)
def advance(c, z, q, p, RESP, zn, qn, pn):
    """The step from the previous answer ``(z, q, p)`` by the responses, increment coefficients
    ``c``: fills ``zn, qn, pn``."""
    n = q.size
    for i in range(n):
        zn[i] = 0.0
        zn[n + i] = z[n + i]
        qn[i] = q[i]
        pn[i] = p[i]
    for l in range(c.size):
        cl = c[l]
        if cl == 0.0:
            continue
        Z = RESP[0, l]
        G = RESP[1, l]
        for i in range(2 * n):
            zn[i] += cl * Z[i]
        for i in range(n):
            qn[i] += cl * G[i]
            pn[i] += cl * G[n + i]


@njit(cache=True)
def equation_residual(qn, pn, sfree, scoef, smeta):
    """Largest residual of the assignment's equations (force units)."""
    n = qn.size
    err = 0.0
    for i in range(smeta[M_FREE]):
        r = sfree[i]
        e = abs(qn[r] + scoef[i] * pn[r]) if r < n else abs(pn[r - n])
        err = max(err, e)
    return err


@njit(cache=True)
def commit(c, RESP, T):
    """``T`` after an accepted step: the gap reactions of its gaps."""
    for l in range(c.size):
        cl = c[l]
        if cl != 0.0:
            H = RESP[2, l]
            for i in range(T.size):
                T[i] += cl * H[i]


@njit(cache=True)
def any_free(s):
    for j in range(s.size):
        if s[j] != STICK:
            return True
    return False
