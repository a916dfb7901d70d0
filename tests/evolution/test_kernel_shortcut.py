"""Steps that keep the previous step's assignment by the kept responses
(``shakedown.evolution.kernel_shortcut``) against the Python step and against the kernel's
general solve: the basis of the period's increments, and whole runs with persistent slip and
persistent separation (the gaps' reactions carried from step to step)."""

import warnings

import numpy as np
import pytest
from test_kernel import assert_same_run  # (this folder: kernel against Python runs)

import shakedown as sd
from shakedown.evolution import kernel, kernel_shortcut
from shakedown.evolution.complementarity import FEAS_TOL, StepSolver

pytestmark = pytest.mark.skipif(not kernel.HAVE_KERNEL, reason="numba kernel not available")


def test_increment_basis_and_its_representation():
    rng = np.random.default_rng(0)
    n, steps = 7, 48
    t = np.arange(steps)[:, None] / steps * 2 * np.pi
    a, b, c, d = (rng.standard_normal((1, n)) for _ in range(4))
    qw = 0.3 + np.cos(t) * a + np.sin(t) * b
    pw = 1.0 + np.cos(t) * c
    SB, SCc, RESP, T, key, free, coef, meta = kernel_shortcut.state(n, qw, pw)
    assert SB.shape == (2, 2 * n) and meta[kernel_shortcut.ENABLED] == 1
    np.testing.assert_allclose(SB @ SB.T, np.eye(2), atol=1e-14)
    D = np.hstack([np.diff(qw, axis=0), np.diff(pw, axis=0)])
    np.testing.assert_allclose(SCc[1:] @ SB, D, rtol=0, atol=1e-14 * np.abs(D).max())
    assert RESP.shape == (3, 2, 2 * n) and T.shape == (2 * n,)
    # two harmonics: four directions
    qw2 = qw + np.cos(2 * t) * d + np.sin(2 * t) * c
    assert kernel_shortcut.state(n, qw2, pw)[0].shape[0] == 4
    # no increments: nothing to keep, still enabled (the steps only carry the answer over)
    z = kernel_shortcut.state(n, np.ones((steps, n)), np.ones((steps, n)))
    assert z[0].shape == (0, 2 * n) and z[-1][kernel_shortcut.ENABLED] == 1
    # a sampled record spans more than MAX_RANK directions: off
    rec = kernel_shortcut.state(n, rng.standard_normal((steps, n)),
                                rng.standard_normal((steps, n)))
    assert rec[-1][kernel_shortcut.ENABLED] == 0
    # a small but real direction (1e-9 of the largest) is kept as a third direction
    small = kernel_shortcut.state(n, qw + 1e-9 * np.cos(3 * t) * d, pw)
    assert small[0].shape[0] == 3 and small[-1][kernel_shortcut.ENABLED] == 1
    # round-off (1e-14 of the largest increment) is dropped and the shortcut stays on; every
    # increment is represented to the drop level (2 noise (sqrt(rows) + sqrt(2N)) of the largest)
    noise = kernel_shortcut.state(n, qw + 1e-14 * np.cos(3 * t) * d, pw)
    assert noise[0].shape[0] == 2 and noise[-1][kernel_shortcut.ENABLED] == 1
    level = kernel_shortcut.drop_level(kernel_shortcut.RANK_RTOL, steps - 1, 2 * n)
    np.testing.assert_allclose(noise[1][1:] @ noise[0], D, rtol=0, atol=level * np.abs(D).max())
    # extremes: forces near overflow keep their basis; increments that overflow turn it off,
    # silently (the general path reports the overflow)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        huge = kernel_shortcut.state(n, 1e300 * qw, pw)
        assert huge[0].shape[0] == 2 and huge[-1][kernel_shortcut.ENABLED] == 1
        alt = 1.5e308 * (-1.0) ** np.arange(steps)[:, None] * np.ones((1, n))
        over = kernel_shortcut.state(n, alt, pw)  # differences 3e308: inf
        assert over[-1][kernel_shortcut.ENABLED] == 0


def test_increment_basis_is_linear_in_the_steps_per_cycle():
    # issue 24: the basis was an eigendecomposition of the (S - 1)^2 Gram matrix of the period's
    # increments (10^6 steps: 7 TiB; 4000 steps: 13 s).  Now it is scanned in blocks: 65 536
    # steps of one node and of 8 nodes give the basis of the load's two directions, representing
    # every increment to the drop level (at this many steps the increments' own round-off,
    # 16 eps max|W|, dominates)
    n_steps = 65536
    t = np.arange(n_steps)[:, None] / n_steps * 2 * np.pi
    for n in (1, 8):
        qw = 0.3 + np.cos(t) * np.linspace(1, 2, n)
        pw = 1.0 + np.sin(t) * np.ones(n)
        SB, SCc, *_, meta = kernel_shortcut.state(n, qw, pw)
        assert SB.shape == (2, 2 * n) and meta[kernel_shortcut.ENABLED] == 1
        D = np.hstack([np.diff(qw, axis=0), np.diff(pw, axis=0)])
        noise = 16 * np.finfo(float).eps * 2.3 / np.abs(D).max()
        level = kernel_shortcut.drop_level(noise, kernel_shortcut.BLOCK, 2 * n)
        assert np.abs(SCc[1:] @ SB - D).max() <= level * np.abs(D).max()
    # more directions than MAX_RANK are found in the first block and the scan stops there
    rng = np.random.default_rng(1)
    assert kernel_shortcut.increment_basis(rng.standard_normal((4096, 20))) is None


def persistent_problem(seed, n=12):
    """Strongly loaded nodes that slip over long stretches of the period, two nodes kept open
    by a tensile normal preload (gaps that change with the load), 256 steps per period."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(0.5 * min(s.critical_friction().value, 2.0))
    f = float(s.friction.max())
    p0 = np.full(n, 1.0)
    p0[:2] = -0.6  # open all period (|p_cos| < 0.6)
    qc = 3.0 * f * rng.normal(size=n)
    load = sd.LoadCycle.from_harmonics(0.1 * rng.normal(size=n), p0, q_cos=qc,
                                       p_cos=0.3 * rng.normal(size=n), q_sin=0.5 * qc)
    return s, load


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("lam", [0.7, 1.5])
def test_shortcut_runs_equal_python_steps(seed, lam):
    s, load = persistent_problem(seed)
    kw = dict(steps_per_cycle=256, max_cycles=30, tol=1e-10)
    fast = StepSolver(s)
    c0 = fast.kernel_cache.counters.copy()
    a = sd.solve_cycles(s, load, lam, solver=fast, **kw)
    b = sd.solve_cycles(s, load, lam, solver=StepSolver(s, kernel=False), **kw)
    d = fast.kernel_cache.counters - c0
    assert d[kernel.C_SHORT] > 0.2 * d[kernel.C_STEPS], d  # the path is exercised
    assert np.any(a.final_gap > 0)  # with gaps carried over
    assert_same_run(a, b, s)
    assert a.max_residual <= FEAS_TOL


def test_shortcut_reactions_equal_a_fresh_product():
    """Over a period with the shortcut, each step's reactions equal ``q_w + K z`` recomputed
    from its slips and gaps (the accumulated responses do not drift)."""
    s, load = persistent_problem(1)
    fast = StepSolver(s)
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=256, max_cycles=6, solver=fast,
                          record_history=True)
    assert fast.kernel_cache.counters[kernel.C_SHORT] > 100
    n = s.n_nodes
    tab = run.history
    last = tab[tab["t"] >= tab["t"].max() - 1 + 1e-9]
    times = np.unique(last["t"].to_numpy())
    qw, pw = load.evaluate(times % 1.0, 1.0)
    worst = 0.0
    for i, t in enumerate(times):
        rows = last[last["t"] == t].drop_duplicates("node", keep="last").sort_values("node")
        v, w = rows["slip"].to_numpy(float), rows["gap"].to_numpy(float)
        r = s.K @ np.concatenate([v, w])
        worst = max(worst, np.abs(rows["q"].to_numpy(float) - qw[i] - r[:n]).max(),
                    np.abs(rows["p"].to_numpy(float) - pw[i] - r[n:]).max())
    assert worst <= 1e-9 * run.force_scale


@pytest.mark.parametrize("force, length", [(1e6, 1.0), (1.0, 1e-4), (1e-9, 1e3)])
def test_shortcut_is_unit_free(force, length):
    """Forces x F, lengths x L (K x F / L): the same steps take the shortcut, slips scale by L,
    dissipation by F L."""
    s, load = persistent_problem(2)
    k = force / length
    s2 = sd.DiscreteSystem(s.A * k, s.B * k, s.C * k, s.friction)
    parts = {key: getattr(load, key) * force for key in ("q_cos", "q_sin", "p_cos", "p_sin")
             if getattr(load, key) is not None}
    load2 = sd.LoadCycle.from_harmonics(load.q0 * force, load.p0 * force, **parts)
    kw = dict(steps_per_cycle=256, max_cycles=30, tol=1e-10)
    counts = []
    runs = []
    for system, lc in ((s, load), (s2, load2)):
        solver = StepSolver(system)
        runs.append(sd.solve_cycles(system, lc, 1.0, solver=solver, **kw))
        counts.append(int(solver.kernel_cache.counters[kernel.C_SHORT]))
    a, b = runs
    assert counts[0] > 0 and counts[0] == counts[1]
    assert a.n_cycles == b.n_cycles and a.status == b.status
    np.testing.assert_allclose(b.final_slip, a.final_slip * length, rtol=1e-7,
                               atol=1e-9 * length * np.abs(a.final_slip).max())
    np.testing.assert_allclose(b.dissipation, a.dissipation * force * length, rtol=1e-7,
                               atol=1e-9 * np.abs(a.dissipation).max() * force * length)
