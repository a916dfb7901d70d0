"""One load period of one state by the compiled kernel (:mod:`.kernel`), with the Python step
(:meth:`StepSolver.solve`) for the steps the kernel hands back (issue 13/14; MODEL.md s.4).

:class:`~.kernel_warm.KernelCache` is the kernel's bounded cache of assignment inverses, kept with the
:class:`~.complementarity.StepSolver` (``solver.kernel_cache``) so that the runs of one task
share it.  An inverse reached by rank-one updates differs from a fresh one in the last bits, so
a run's numbers can depend, at round-off level, on which runs the same solver did before (as
with the Python step's LU cache and Woodbury updates): the study gives every (realisation,
load factor) task a fresh solver and runs its states in a fixed order, so its rows are
bit-identical for any number of workers.
"""

from __future__ import annotations

import numpy as np

from . import kernel as _k
from . import kernel_warm as _kw
from .kernel_warm import KernelCache, warm_up  # noqa: F401 - (complementarity, workers.py)


def usable(solver) -> bool:
    """The kernel applies: numba available, enabled on the solver, and every step's status
    known without enumeration (friction below critical, or more nodes than are enumerated)."""
    if not (_k.HAVE_KERNEL and solver.kernel):
        return False
    wp = solver.well_posed
    return wp is True or solver.n > solver.enumerate_max_nodes


def step_status(solver) -> str:
    """The status the Python step gives a verified active-set answer."""
    return "unique" if solver.well_posed is True else "solved"


def run_period(solver, qw, pw, v0, guess, V, Wg, Q, P, st, act, scales, res, statuses,
               pred=None):
    """Steps of one period of one state; fills rows of the period arrays (as
    :func:`~.multistate._implicit_cycles` does) and returns ``(W, guess, failure)`` where
    ``failure`` is ``(j, StepResult)`` of a failed step or ``None``.  ``pred``: this state's
    assignments in its previous period (``(n_steps, N)`` int8), tried first by the kernel;
    None: the last period completed with the same load by this solver (any state), if any."""
    kc = solver.kernel_cache
    n_steps, n = qw.shape
    V[0] = v0
    base = v0 @ solver.K[:n]  # the first step's base from scratch: (A v, B^T v)
    q0, p0 = qw[0] + base[:n], pw[0] + base[n:]
    s = np.array(guess, np.int8)
    wd = np.zeros(1)
    status = step_status(solver)
    c0 = kc.counters.copy()
    j = 0
    K, f, diag = _readonly(solver.K), _readonly(solver.f), _readonly(solver.diag)
    qw, pw = _kw.writable(qw), _kw.writable(pw)
    sc = kc.shortcut_state(qw, pw)
    pred = kc.prediction(qw, pw) if pred is None else np.ascontiguousarray(pred, np.int8)
    if pred.shape != (n_steps, n):
        pred = np.zeros((0, n), np.int8)
    while j < n_steps:
        done = _k.march(K, f, diag, qw, pw, j, q0, p0, s, solver.feas_tol,
                        solver.max_iter, kc.mult, kc.keys, kc.hashes, kc.offs, kc.sizes,
                        kc.pool, kc.ipool, kc.fpool, kc.meta, kc.counters, kc.seen, V, Wg, Q, P,
                        st, act, scales, res, wd, *sc, pred)
        if done > j:
            statuses[status] = statuses.get(status, 0) + done - j
        j = done
        if j == n_steps:
            break
        r = solver.solve(V[j], qw[j], pw[j], s, base=(q0, p0), verify=False)
        statuses[r.status] = statuses.get(r.status, 0) + 1
        res[j] = r.residual
        if not r.success:
            _book(solver, kc, c0)
            return wd[0], s, (j, r)
        wd[0] -= float(r.q @ r.slip_increment)
        V[j + 1], Wg[j + 1], Q[j + 1], P[j + 1] = r.slip, r.gap, r.q, r.p
        st[j + 1], act[j] = r.states, r.active_set
        s = np.array(r.active_set, np.int8)
        scales[j] = r.force_scale
        if j + 1 < n_steps:
            q0, p0 = solver.next_base(r.q, r.p, r.gap, qw[j + 1] - qw[j], pw[j + 1] - pw[j])
        j += 1
    _book(solver, kc, c0)
    kc.keep_prediction(qw, pw, act)
    return wd[0], s, None


def _readonly(a):
    """A read-only C-contiguous view (:func:`.kernel_warm.readonly`: the kernel is compiled
    for one array type, not once per flag or layout)."""
    return _kw.readonly(a)


def _book(solver, kc, c0):
    d = kc.counters - c0
    t = solver.totals
    t["steps"] += int(d[_k.C_STEPS])
    t["iterations"] += int(d[_k.C_ITER])
    t["cache_hits"] += int(d[_k.C_HITS])
    t["factorizations"] += int(d[_k.C_FACT])
    t["updates"] += int(d[_k.C_UPD])
