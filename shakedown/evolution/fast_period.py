"""One load period of one state by the compiled kernel (:mod:`.kernel`), with the Python step
(:meth:`StepSolver.solve`) for the steps the kernel hands back (issue 13/14; MODEL.md s.4).

:class:`KernelCache` is the kernel's bounded cache of assignment inverses, kept with the
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
from . import kernel_shortcut as _ks


class KernelCache:
    """Storage of the kernel's inverse cache for one system (``cache_bytes`` bounds the pool
    of inverses; when full the cache keeps the last period's answers, drops the rest and is
    refilled: :func:`.kernel_cache._compact`).  It also keeps the last period's assignments as
    the prediction of the next period with the same load (:meth:`prediction`)."""

    def __init__(self, n: int, cache_bytes: float, max_iter: int):
        self.n = n
        # room for 128 of the largest inverses ((2N)^2 numbers each; typical ones are 16x
        # smaller) within the budget, and always for one: a small system does not reserve
        # the whole budget
        n_doubles = max(min(int(cache_bytes // 8), 128 * (2 * n) ** 2), (2 * n) ** 2)
        self.pool = np.empty(n_doubles)  # pages are touched only as inverses are stored
        slots = int(min(4096, max(64, n_doubles // max(n, 1))))
        self.keys = np.zeros((slots, n), np.int8)
        self.hashes = np.zeros(slots, np.uint64)
        # pool offset, index offset, updates, step it answered last (kernel_cache.stamp)
        self.offs = np.zeros((slots, 4), np.int64)
        self.sizes = np.zeros(slots, np.int64)
        self.ipool = np.zeros(slots * 2 * n if slots * 2 * n <= 8_000_000 else 8_000_000,
                              np.int64)
        self.fpool = np.zeros(self.ipool.size)
        self.meta = np.zeros(8, np.int64)
        self.meta[3] = -1  # no last solved assignment
        self.counters = np.zeros(8, np.int64)
        self.seen = np.zeros((max_iter + 1, n), np.int8)
        rng = np.random.default_rng(20261123)
        self.mult = rng.integers(1, 2**63 - 1, size=n, dtype=np.int64).astype(np.uint64) | 1
        self._shortcut = None
        self._pred = None

    def prediction(self, qw: np.ndarray, pw: np.ndarray) -> np.ndarray:
        """The assignments ``(n_steps, N)`` of the last period completed with the welded
        reactions ``qw, pw`` (:meth:`keep_prediction`), or an empty ``(0, N)`` array."""
        c = self._pred
        if (c is not None and c[0].shape == qw.shape and np.array_equal(c[0], qw)
                and np.array_equal(c[1], pw)):
            return c[2]
        return np.zeros((0, self.n), np.int8)

    def keep_prediction(self, qw: np.ndarray, pw: np.ndarray, act: np.ndarray) -> None:
        """Keep a completed period's assignments ``act`` (n_steps, N) as the prediction of
        the next period with the same ``qw, pw`` (the kernel's :func:`~.kernel._probe`)."""
        c = self._pred
        if c is None or c[0].shape != qw.shape or not (np.array_equal(c[0], qw)
                                                       and np.array_equal(c[1], pw)):
            c = (qw.copy(), pw.copy(), np.empty(act.shape, np.int8))
            self._pred = c
        c[2][:] = act

    def shortcut_state(self, qw: np.ndarray, pw: np.ndarray):
        """:func:`.kernel_shortcut.state` of a period's welded reactions, kept for the next
        periods with the same ``qw, pw`` (its basis costs ~0.3 ms at N = 100, a fifth of a
        period there)."""
        c = self._shortcut
        if (c is not None and c[0].shape == qw.shape and np.array_equal(c[0], qw)
                and np.array_equal(c[1], pw)):
            return c[2]
        st = _ks.state(self.n, qw, pw)
        self._shortcut = (qw.copy(), pw.copy(), st)
        return st


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
    K, f = _readonly(solver.K), _readonly(solver.f)
    qw, pw = np.ascontiguousarray(qw), np.ascontiguousarray(pw)
    sc = kc.shortcut_state(qw, pw)
    pred = kc.prediction(qw, pw) if pred is None else np.ascontiguousarray(pred, np.int8)
    if pred.shape != (n_steps, n):
        pred = np.zeros((0, n), np.int8)
    while j < n_steps:
        done = _k.march(K, f, solver.diag, qw, pw, j, q0, p0, s, solver.feas_tol,
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
    """A read-only view: the kernel is compiled for one array type (numba types a read-only
    array apart from a writable one), so that it is compiled once, not once per flag."""
    v = np.asarray(a, float).view()
    v.setflags(write=False)
    return v


def _book(solver, kc, c0):
    d = kc.counters - c0
    t = solver.totals
    t["steps"] += int(d[_k.C_STEPS])
    t["iterations"] += int(d[_k.C_ITER])
    t["cache_hits"] += int(d[_k.C_HITS])
    t["factorizations"] += int(d[_k.C_FACT])
    t["updates"] += int(d[_k.C_UPD])


def warm_up() -> float:
    """Compile the kernel (first use after installing: 10-25 s, written to numba's cache) or
    load it from the cache (about 0.5 s), once per process; the seconds spent.

    A study calls this before it starts worker processes, so that they load the cache
    instead of compiling the kernel each at the same time.
    """
    import time

    if not _k.HAVE_KERNEL:
        return 0.0
    t = time.perf_counter()
    n = 1
    K = np.array([[1.0, 0.0], [0.0, 1.0]])
    kc = KernelCache(n, 1e5, 4)
    qw = np.array([[-2.0], [2.0]])
    pw = np.ones((2, 1))
    V, Wg, Q, P = (np.zeros((3, n)) for _ in range(4))
    st, act = np.zeros((3, n), np.int8), np.zeros((2, n), np.int8)
    _k.march(_readonly(K), _readonly([0.5]), np.ones(2), qw, pw, 0, qw[0].copy(), pw[0].copy(),
             np.zeros(n, np.int8), 1e-9, 4, kc.mult, kc.keys, kc.hashes, kc.offs, kc.sizes,
             kc.pool, kc.ipool, kc.fpool, kc.meta, kc.counters, kc.seen, V, Wg, Q, P, st, act,
             np.zeros(2), np.zeros(2), np.zeros(1), *_ks.state(n, qw, pw),
             np.zeros((0, n), np.int8))
    return time.perf_counter() - t
