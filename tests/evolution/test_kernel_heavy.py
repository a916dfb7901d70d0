"""The heavy-switching path of the compiled kernel (issue 26): most nodes slip and many change
state at every step, so the kernel reaches each step's assignment from the same step of the
previous period (``kernel._probe``) and keeps the last period's answers through a reset of its
inverse cache (``kernel_cache._compact``).

References: the Python step (:meth:`StepSolver.solve`, ``StepSolver(kernel=False)``: LU
factors, its own active-set loop, no prediction) on the same runs; fresh LAPACK inverses for the
inverses kept through a reset; wrong predictions (assignments of other steps) that the probe must
reject.
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution import fast_period, kernel, kernel_cache
from shakedown.evolution.complementarity import FEAS_TOL, StepSolver

pytestmark = pytest.mark.skipif(not kernel.HAVE_KERNEL, reason="numba kernel not available")


def heavy_problem(seed, n=30):
    """Random coupled SPD system (friction at half the sufficient bound: unique steps) and a
    two-harmonic tangential load of twice the friction: ~80 % of the nodes slip, ~8 of 30
    change state per step at ``lam = 2.5`` and 16 steps per period."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(0.5 * min(s.critical_friction().value, 2.0))
    f = float(s.friction.max())
    load = sd.LoadCycle.from_harmonics(0.1 * rng.normal(size=n), np.full(n, 1.0),
                                       q_cos=2 * f * rng.normal(size=n),
                                       q_sin=2 * f * rng.normal(size=n),
                                       p_sin=0.3 * rng.normal(size=n))
    return s, load


KW = dict(steps_per_cycle=16, max_cycles=20, tol=1e-10)
LAM = 2.5


def assert_same(a, b, s):
    """Same run to the solver's tolerance (relative to the run's force scale)."""
    assert a.status == b.status and a.n_cycles == b.n_cycles and a.period == b.period
    F = a.force_scale
    W = F ** 2 / s.A.diagonal().min()
    np.testing.assert_allclose(a.dissipation, b.dissipation, rtol=0, atol=1e-10 * W)
    tol = 10 * FEAS_TOL * F / s.A.diagonal().min()
    np.testing.assert_allclose(a.final_slip, b.final_slip, rtol=0, atol=tol)
    np.testing.assert_allclose(a.final_gap, b.final_gap, rtol=0, atol=tol)
    np.testing.assert_array_equal(a.final_active_sets, b.final_active_sets)


def switching(run):
    A = np.asarray(run.final_active_sets)
    return (A != 0).mean(), np.mean([(A[k] != A[k - 1]).sum() for k in range(len(A))])


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_heavy_switching_equals_python_steps(seed):
    """Runs to the periodic orbit and the next two periods (the predictions kept by the solver)
    equal the Python step's, and the prediction did answer steps."""
    s, load = heavy_problem(seed)
    fast = StepSolver(s)
    a = sd.solve_cycles(s, load, LAM, solver=fast, **KW)
    b = sd.solve_cycles(s, load, LAM, solver=StepSolver(s, kernel=False), **KW)
    slipping, changed = switching(a)
    assert a.status == "periodic" and slipping > 0.6 and changed > 0.1 * s.n_nodes
    assert_same(a, b, s)
    c0 = fast.kernel_cache.counters.copy()
    kw = dict(KW, max_cycles=2)
    a2 = sd.solve_cycles(s, load, LAM, solver=fast, initial_slip=a.final_slip, **kw)
    b2 = sd.solve_cycles(s, load, LAM, solver=StepSolver(s, kernel=False),
                         initial_slip=a.final_slip, **kw)
    assert_same(a2, b2, s)
    d = fast.kernel_cache.counters - c0
    steps = d[kernel.C_STEPS]
    assert steps == a2.statistics["n_steps"]
    # on the orbit: every step by its guess or the prediction, both cached; nothing inverted
    assert d[kernel.C_FACT] == 0 and d[kernel.C_UPD] == 0 and d[kernel.C_LU] == 0
    assert d[kernel.C_PROBE] >= 0.5 * steps and d[kernel.C_ITER] <= 2 * steps


def test_wrong_predictions_are_rejected():
    """Predictions shifted by two steps (cached assignments of other steps, wrong for these):
    the probe must reject them (their sign checks fail) and the steps be the Python step's."""
    s, load = heavy_problem(12)
    fast = StepSolver(s)
    a = sd.solve_cycles(s, load, LAM, solver=fast, **KW)
    kc = fast.kernel_cache
    qw, pw, act = kc._pred
    wrong = np.roll(act, 2, axis=0)
    assert np.count_nonzero(np.any(wrong != act, axis=1)) > len(act) // 2
    kc._pred = (qw, pw, wrong)
    kw = dict(KW, max_cycles=1)
    a1 = sd.solve_cycles(s, load, LAM, solver=fast, initial_slip=a.final_slip, **kw)
    b1 = sd.solve_cycles(s, load, LAM, solver=StepSolver(s, kernel=False),
                         initial_slip=a.final_slip, **kw)
    assert_same(a1, b1, s)


def test_reset_keeps_the_last_period_answers():
    """A full cache keeps (bit for bit, findable) the inverses that answered the last
    ``WINDOW`` steps and drops the rest; the last solved slot follows its inverse."""
    rng = np.random.default_rng(5)
    n = 6
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    f = np.full(n, 0.3)
    kc = fast_period.KernelCache(n, 8 * 5 * 36, 4)  # room for five 6 x 6 inverses
    assert kc.pool.size == 5 * 36
    sets, inverses = [], []
    for i in range(5):  # five assignments, every node slipping (6 unknowns), directions differ
        s = (1 + (np.arange(n) + i) % 2).astype(np.int8)
        s[i] = 3 - s[i]
        free, coef = kernel_cache._layout(s, f, n)
        X = np.linalg.inv(kernel_cache._matrix(K, free, coef, n))
        kernel_cache._store(s, kernel_cache._hash(s, kc.mult), free, coef, X, 0, kc.keys,
                            kc.hashes, kc.offs, kc.sizes, kc.pool, kc.ipool, kc.fpool, kc.meta)
        sets.append(s)
        inverses.append(X)
    kc.meta[kernel_cache.WINDOW] = 2
    for i in (1, 3, 4):  # answers of steps 0, 1, 2: the last two (3, 4) are in the window
        kernel_cache.stamp(sets[i], kc.mult, kc.keys, kc.hashes, kc.offs, kc.meta)
    kc.meta[kernel_cache.LAST_SLOT] = 4
    assert kc.meta[kernel_cache.N_SLOTS] == 5
    s6 = np.ones(n, np.int8)  # one more: the pool is full
    free, coef = kernel_cache._layout(s6, f, n)
    X6 = np.linalg.inv(kernel_cache._matrix(K, free, coef, n))
    k6 = kernel_cache._store(s6, kernel_cache._hash(s6, kc.mult), free, coef, X6, 0, kc.keys,
                             kc.hashes, kc.offs, kc.sizes, kc.pool, kc.ipool, kc.fpool, kc.meta)
    assert kc.meta[kernel_cache.RESETS] == 1 and kc.meta[kernel_cache.N_SLOTS] == 3
    for i, s in enumerate(sets):
        k = kernel_cache._lookup(s, kernel_cache._hash(s, kc.mult), kc.keys, kc.hashes, kc.meta)
        if i in (3, 4):
            X, fr, co = kernel_cache._slot(k, kc.offs, kc.sizes, kc.pool, kc.ipool, kc.fpool)
            np.testing.assert_array_equal(X, inverses[i])
            np.testing.assert_array_equal(fr, kernel_cache._layout(s, f, n)[0])
        else:
            assert k < 0
    X, _, _ = kernel_cache._slot(k6, kc.offs, kc.sizes, kc.pool, kc.ipool, kc.fpool)
    np.testing.assert_array_equal(X, X6)
    assert kc.meta[kernel_cache.LAST_SLOT] == k6
