"""Compiled period loop of the implicit step (issue 13/14; MODEL.md s.4).

The same active-set method as :class:`~.complementarity.StepSolver` (the guess is the previous
step's assignment; all violated nodes switch at once; on a repeated assignment one at a time,
the most violated first), compiled with numba so that a step costs its linear algebra, not
Python bookkeeping.  Each state assignment's reduced matrix ``M_s`` (rows ``q_j + c_j p_j`` of
the slipping nodes, ``q_j``, ``p_j`` of the separated ones; columns their slips and gaps) is
kept as its explicit inverse in a bounded cache keyed by the assignment, so that a step whose
assignment was met before costs one matrix-vector product with ``M_s^-1`` (``2 m^2`` flops, as
a pair of triangular solves) and one with the ``m`` rows of ``K``; a new assignment near the
last solved one is reached by block updates of that inverse (:mod:`.kernel_updates`: unknowns
removed, row coefficients changed, unknowns appended, ``O(m^2 r)`` for ``r`` changes, chosen
when a flop count says they are cheaper than inverting afresh) and otherwise inverted afresh
(LAPACK through numpy); :mod:`.kernel_cache` holds the inverses.  A step that keeps the
previous step's assignment (after two steps that kept it) costs ``O(N r)`` by the responses of
that assignment to the ``r`` directions of the period's load increments
(:mod:`.kernel_shortcut`), checked like every other answer.  A step whose assignment may
change first tries the assignment of the same step in the previous period, when its inverse is
cached and its answer is strictly inside every sign check (:func:`_probe`, issue 26): on a
periodic orbit the assignments repeat, so where many nodes change state at every step (heavy
switching) a step costs one solve with a cached inverse instead of an iteration through new
inverses and block updates; a full cache keeps the last period's answers
(:func:`.kernel_cache._compact`).  Every solve must satisfy
its equations to ``1e-3 feas_tol`` (relative) and a fresh inverse must have a 1-norm
condition number below ``1e12``: an updated inverse that fails is recomputed afresh; an
ill-conditioned assignment, whose explicit inverse is not backward stable, is solved once by
LU with partial pivoting (not cached, and verified like the Python step's LU answers: by the
sign checks and residuals below); a singular one hands the step back.

What the kernel does not do, it hands back: a step whose iteration repeats an assignment twice,
exhausts its budget or meets a singular matrix returns to Python at that step, where
:meth:`StepSolver.solve` finishes it (Lemke, enumeration, statuses), and the kernel resumes
with the next step.  Every accepted step is verified as in the Python path: its sign checks
and its complementarity residual; the equilibrium of the whole period is recomputed with ``K``
by the caller.

Without numba (``pip install numba`` is a core dependency; ``SHAKEDOWN_KERNEL=numpy`` switches
it off) the Python path runs instead: same answers to the solver tolerance, slower.
"""

from __future__ import annotations

import numpy as np

from . import kernel_shortcut as _ks
from .kernel_cache import (
    BACKWARD,
    FORWARD,
    LAST_SLOT,
    N_SLOTS,
    SEPARATED,
    STICK,
    WINDOW,
    _hash,
    _invert,
    _layout,
    _lookup,
    _matrix,
    _slot,
    _solve_lu,
    _solve_with,
    _store,
    stamp,
)
from .kernel_jit import HAVE_KERNEL, njit
from .kernel_updates import changed_unknowns, updated

#: Relative accuracy the solved equations must reach (times ``feas_tol``).
EQ_TOL = 1e-3
#: Rank-one updates of a cached inverse allowed (in a chain) before it is recomputed afresh.
MAX_UPDATES = 32
#: An assignment of ``m_t`` unknowns that differ in ``r`` places from the last solved one's
#: (``m`` unknowns, ``m >= UPDATE_MIN_SIZE``) is reached by block updates
#: (:mod:`.kernel_updates`, about ``4 m^2 r + r^3`` flops) while
#: ``UPDATE_COST * (4 m^2 r + r^3) < m_t^3``, the flops of a fresh inverse (``2 m_t^3``) with
#: LAPACK's better speed per flop counted in ``UPDATE_COST``.
UPDATE_COST = 1.0
UPDATE_MIN_SIZE = 8

__all__ = ["march", "HAVE_KERNEL"]

# counter indices
C_ITER, C_HITS, C_FACT, C_UPD, C_STEPS, C_LU, C_SHORT, C_PROBE = 0, 1, 2, 3, 4, 5, 6, 7


@njit(cache=True)
def _solve_set(s, K, f, q0, p0, n, ft, mult, keys, hashes, offs, sizes, pool, ipool, fpool,
               meta, counters, z, q, p):
    """Solve assignment ``s`` into ``z, q, p``: a cached inverse, else block updates of the
    last solved assignment's inverse, else a fresh inverse, else (ill-conditioned) one LU
    solve.  False when the matrix is singular or the solved equations fail their check."""
    any_free = False
    for j in range(n):
        if s[j] != STICK:
            any_free = True
            break
    if not any_free:
        z[:] = 0.0
        q[:] = q0
        p[:] = p0
        return True
    tol = EQ_TOL * ft
    h = _hash(s, mult)
    k = _lookup(s, h, keys, hashes, meta)
    if k >= 0:
        counters[C_HITS] += 1
        X, free, coef = _slot(k, offs, sizes, pool, ipool, fpool)
        if _solve_with(X, free, coef, K, q0, p0, n, z, q, p) <= tol:
            meta[LAST_SLOT] = k
            return True
    else:
        kb = meta[LAST_SLOT]
        if (0 <= kb < meta[N_SLOTS] and sizes[kb] >= UPDATE_MIN_SIZE
                and offs[kb, 2] < MAX_UPDATES):
            r = changed_unknowns(keys[kb], s, n)
            mt = 0
            for j in range(n):
                mt += (s[j] != STICK) + (s[j] == SEPARATED)
            if UPDATE_COST * (4.0 * sizes[kb] ** 2 * r + float(r) ** 3) < float(mt) ** 3:
                X, free, coef, ok = updated(s, kb, K, f, n, keys, offs, sizes, pool, ipool,
                                            fpool)
                counters[C_UPD] += 1
                if ok and _solve_with(X, free, coef, K, q0, p0, n, z, q, p) <= tol:
                    _store(s, h, free, coef, X, offs[kb, 2] + 1, keys, hashes, offs, sizes,
                           pool, ipool, fpool, meta)
                    return True
    free, coef = _layout(s, f, n)
    M = _matrix(K, free, coef, n)
    X, ok = _invert(M)
    counters[C_FACT] += 1
    if not ok or _solve_with(X, free, coef, K, q0, p0, n, z, q, p) > tol:
        # ill-conditioned: an explicit inverse is not backward stable, LU with partial
        # pivoting is.  Solve this once by LU and keep nothing; as the Python step's LU, its
        # answer is then verified by the sign checks, the complementarity residual and the
        # period's equilibrium, not by the inverse's equation tolerance (a singular or
        # non-finite answer returns False)
        counters[C_LU] += 1
        return np.isfinite(_solve_lu(M, free, coef, K, q0, p0, n, z, q, p))
    if k >= 0:  # a cached (updated) inverse that lost accuracy: replace it in its slot
        o, oi = offs[k, 0], offs[k, 1]
        m = free.size
        pool[o:o + m * m] = X.ravel()
        ipool[oi:oi + m] = free
        fpool[oi:oi + m] = coef
        offs[k, 2] = 0
        meta[LAST_SLOT] = k
    else:
        _store(s, h, free, coef, X, 0, keys, hashes, offs, sizes, pool, ipool, fpool, meta)
    return True


@njit(cache=True)
def _violated(s, z, q, p, f, ft, dtol, n, mag, target):
    """Sign checks of the step problem (``ActiveSet._violations_step``): fills ``mag`` and
    ``target`` and returns the largest normalised violation (> 1: violated)."""
    worst = -np.inf
    for j in range(n):
        fp = f[j] * p[j]
        sj = s[j]
        c0 = -np.inf
        c1 = -np.inf
        c2 = -np.inf
        c3 = -np.inf
        if sj != SEPARATED:
            c3 = -p[j] / ft
        if sj == STICK:
            c1 = -(fp + q[j]) / ft
            c2 = (q[j] - fp) / ft
        elif sj == FORWARD:
            c0 = -(z[j] / dtol[j])
        elif sj == BACKWARD:
            c0 = z[j] / dtol[j]
        else:
            c0 = -z[n + j] / dtol[n + j]
        t = 0
        best = c0
        if c1 > best:
            t, best = 1, c1
        if c2 > best:
            t, best = 2, c2
        if c3 > best:
            t, best = 3, c3
        mag[j] = best
        target[j] = t
        worst = max(worst, best)
    return worst


@njit(cache=True)
def _visited(s, seen, n_seen):
    for k in range(n_seen):
        same = True
        for j in range(s.size):
            if seen[k, j] != s[j]:
                same = False
                break
        if same:
            return True
    return False


@njit(cache=True)
def _step(s, K, f, q0, p0, n, ft, dtol, max_iter, mult, keys, hashes, offs, sizes, pool,
          ipool, fpool, meta, counters, seen, z, q, p, mag, target, g):
    """The active-set iteration of one step from the guess ``s`` (updated in place).  The
    prediction ``g`` (the step's assignment in the previous period) is tried first if it
    differs from the guess and its inverse is cached (:func:`_probe`: accepted only strictly
    inside its checks, where it is the assignment the iteration would end with when the step's
    answer is unique); else the iteration runs from the guess as before."""
    n_seen = 0
    single = False
    it = 0
    if _differ(g, s) and _probe(g, K, f, q0, p0, n, ft, dtol, mult, keys, hashes, offs, sizes,
                                pool, ipool, fpool, meta, counters, z, q, p, mag, target):
        s[:] = g
        return True
    while it < max_iter:
        it += 1
        if _visited(s, seen, n_seen):
            if single:
                break
            single = True
            n_seen = 0
        if n_seen < seen.shape[0]:
            seen[n_seen, :] = s
            n_seen += 1
        if not _solve_set(s, K, f, q0, p0, n, ft, mult, keys, hashes, offs, sizes, pool, ipool,
                          fpool, meta, counters, z, q, p):
            break
        if _violated(s, z, q, p, f, ft, dtol, n, mag, target) <= 1.0:
            counters[C_ITER] += it
            return True
        if single:
            j = int(np.argmax(mag))
            s[j] = target[j]
        else:
            for j in range(n):
                if mag[j] > 1.0:
                    s[j] = target[j]
    counters[C_ITER] += it
    return False


@njit(cache=True)
def _probe(g, K, f, q0, p0, n, ft, dtol, mult, keys, hashes, offs, sizes, pool, ipool, fpool,
           meta, counters, z, q, p, mag, target):
    """The predicted assignment ``g`` (the same step's of the previous period) as this step's
    answer, when its inverse is cached: its equations to ``EQ_TOL`` and its sign checks, every
    node's by a margin of the tolerance (its state strict, not at a boundary).  True (``z, q,
    p`` filled) when it passes; no inverse is computed or updated for a prediction."""
    k = _lookup(g, _hash(g, mult), keys, hashes, meta)
    if k < 0:
        return False
    X, free, coef = _slot(k, offs, sizes, pool, ipool, fpool)
    if not _solve_with(X, free, coef, K, q0, p0, n, z, q, p) <= EQ_TOL * ft:
        return False
    # strictly inside its checks at every node (no node at a state boundary, where another
    # assignment gives the same answer): then the answer's states determine the assignment,
    # and it is the one the iteration from the guess ends with (when the answer is unique)
    if not _violated(g, z, q, p, f, ft, dtol, n, mag, target) < -1.0:
        return False
    meta[LAST_SLOT] = k
    counters[C_ITER] += 1
    counters[C_HITS] += 1
    counters[C_PROBE] += 1
    return True


@njit(cache=True)
def _differ(a, b):
    for j in range(a.size):
        if a[j] != b[j]:
            return True
    return False


@njit(cache=True)
def _maxabs(x):
    a = 0.0
    for v in x:
        a = max(a, abs(v))
    return a


@njit(cache=True)
def march(K, f, diag, QW, PW, j0, q0, p0, s, feas_tol, max_iter, mult, keys, hashes, offs,
          sizes, pool, ipool, fpool, meta, counters, seen, V, WG, Q, P, ST, ACT, SC, RES, WD,
          SB, SCc, RESP, T, skey, sfree, scoef, smeta, PRED):
    """Implicit steps ``j0 .. K-1`` of one period of one state (see the module docstring).

    ``q0, p0``: the base reactions of step ``j0`` (updated in place to those of the step
    handed back); ``s``: the guess (updated in place); ``V[j0]`` the slips at its start.
    Fills rows ``j + 1`` of ``V, WG, Q, P, ST`` and rows ``j`` of ``ACT, SC, RES``; adds the
    dissipation to ``WD[0]``.  Returns the number of steps done (``K`` when the period is
    complete; otherwise the index of the step handed back to Python).  ``SB .. smeta``: the
    state of :mod:`.kernel_shortcut` (:func:`~.kernel_shortcut.state`), for the steps that keep
    the previous step's assignment.  ``PRED`` (``(K, N)`` int8, or ``(0, N)`` for none): the
    assignments of the same steps in the previous period; a step whose assignment differs from
    the previous step's first tries ``PRED[j]`` when its inverse is cached (:func:`_probe`: in a
    steady cycle the assignments repeat, so a step costs one solve with a cached inverse
    instead of an active-set iteration through new assignments), else iterates as before.
    """
    n = f.size
    n_steps = QW.shape[0]
    z = np.empty(2 * n)
    q = np.empty(n)
    p = np.empty(n)
    zn = np.empty(2 * n)
    qn = np.empty(n)
    pn = np.empty(n)
    mag = np.empty(n)
    target = np.empty(n, np.int8)
    trial = s.copy()
    meta[WINDOW] = n_steps  # a reset keeps the answers of the last period (kernel_cache)
    smeta[_ks.VALID] = 0  # no answer of this call yet
    smeta[_ks.RUN] = 0
    for j in range(j0, n_steps):
        scale = max(_maxabs(QW[j]), _maxabs(PW[j]), _maxabs(q0), _maxabs(p0))
        if scale <= 0.0:
            scale = 1.0
        ft = feas_tol * scale
        dtol = ft / diag
        short = False
        if j > j0 and _ks.usable(s, skey, smeta):
            c = SCc[j]
            _ks.advance(c, z, q, p, RESP, zn, qn, pn)
            if (_ks.equation_residual(qn, pn, sfree, scoef, smeta) <= EQ_TOL * ft
                    and _violated(s, zn, qn, pn, f, ft, dtol, n, mag, target) <= 1.0):
                short = True
                z[:] = zn
                q[:] = qn
                p[:] = pn
                _ks.commit(c, RESP, T)
                counters[C_ITER] += 1
                counters[C_HITS] += 1
                counters[C_SHORT] += 1
        if not short:
            smeta[_ks.VALID] = 0
            trial[:] = s
            it0 = counters[C_ITER]
            pr0 = counters[C_PROBE]
            g = PRED[j] if PRED.shape[0] == n_steps else s
            if not _step(trial, K, f, q0, p0, n, ft, dtol, max_iter, mult, keys, hashes, offs,
                         sizes, pool, ipool, fpool, meta, counters, seen, z, q, p, mag, target,
                         g):
                return j
            kept = counters[C_ITER] - it0 == 1 and counters[C_PROBE] == pr0  # the guess held
            smeta[_ks.RUN] = smeta[_ks.RUN] + 1 if kept else 0
            s[:] = trial
            if (smeta[_ks.ENABLED] and smeta[_ks.RUN] >= _ks.PERSIST and j + 1 < n_steps
                    and _ks.any_free(s)):
                _ks.build(s, z, K, f, n, mult, keys, hashes, offs, sizes, pool, ipool, fpool,
                          meta, SB, RESP, T, skey, sfree, scoef, smeta)
        counters[C_STEPS] += 1
        stamp(s, mult, keys, hashes, offs, meta)
        comp = 0.0
        wd = 0.0
        for i in range(n):
            dv = z[i]
            w = z[n + i]
            V[j + 1, i] = V[j, i] + dv
            WG[j + 1, i] = w
            Q[j + 1, i] = q[i]
            P[j + 1, i] = p[i]
            wd += q[i] * dv
            fp = f[i] * p[i]
            a = dv * diag[i]
            comp = max(comp, abs(min(w * diag[n + i], p[i])),
                       abs(min(max(a, 0.0), fp + q[i])), abs(min(max(-a, 0.0), fp - q[i])))
            st = STICK
            if w > dtol[n + i]:
                st = SEPARATED
            elif dv > dtol[i]:
                st = FORWARD
            elif dv < -dtol[i]:
                st = BACKWARD
            ST[j + 1, i] = st
            ACT[j, i] = s[i]
        WD[0] -= wd
        SC[j] = scale
        RES[j] = comp / scale
        if j + 1 < n_steps:  # the next step's base from this step's reactions (next_base)
            for i in range(n):
                q0[i] = q[i] + QW[j + 1, i] - QW[j, i]
                p0[i] = p[i] + PW[j + 1, i] - PW[j, i]
            if not smeta[_ks.VALID]:  # else T holds them (kept by the shortcut)
                _ks.gap_reactions(z, K, n, T)
            for i in range(n):
                q0[i] -= T[i]
                p0[i] -= T[n + i]
    return n_steps
