"""Cyclic evolution (MODEL.md s.4): closed forms, implicit vs events, energy identity, the
step oracle along a run, uncoupled uniqueness (seed 002 s.3), bounds vs evolution, extremes and
bad input."""


import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_complementarity import oracle

import shakedown as sd
from shakedown.evolution.complementarity import StepSolver


def single_node(k=2.0, f=0.4, P=3.0):
    return sd.DiscreteSystem([[k]], [[0.0]], [[5.0]], friction=f), k, f, P


def closed_form_W(k, f, P, lam, Q1):
    """Single node, constant normal reaction P, tangential amplitude lam Q1 (MODEL.md s.4 test):
    per cycle the node slips 2 (lam Q1 - f P) / k each way under |q| = f P."""
    return max(0.0, 4 * f * P * (lam * Q1 - f * P) / k)


def random_coupled(seed, n, frac=0.5, p0=3.0, amp=1.0, samples=7):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(frac * min(s.critical_friction().value, 1.0))
    load = sd.LoadCycle.from_samples(rng.normal(size=n) * 0.3, np.full(n, p0),
                                     rng.normal(size=(samples, n)) * amp,
                                     rng.normal(size=(samples, n)) * amp)
    return s, load


# ---------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("lam", [0.5, 0.99, 1.5, 4.0])
def test_single_node_events_exact(lam):
    s, k, f, P = single_node()
    rng = np.random.default_rng(int(lam * 100))
    # unimodal samples (one rise, one fall per period: no inner hysteresis loops), random phase
    q1 = np.cos(2 * np.pi * np.arange(9) / 9 + rng.uniform(0, 2 * np.pi))[:, None]
    Q1 = (q1.max() - q1.min()) / 2
    q1 -= (q1.max() + q1.min()) / 2  # centred: the threshold is exactly lam Q1 = f P
    lam_eff = lam * f * P / Q1
    load = sd.LoadCycle.from_samples([0.2], [P], q1, np.zeros((9, 1)))
    run = sd.solve_cycles(s, load, lam_eff, method="events")
    W = closed_form_W(k, f, P, lam_eff, Q1)
    assert run.status == "periodic" and run.period == 1
    # exact up to round-off: 1e-12 relative to the energy scale (f P)^2 / k
    assert run.steady_dissipation == pytest.approx(W, abs=1e-12 * (f * P) ** 2 / k)
    assert run.shook_down == (lam < 1)
    np.testing.assert_array_equal(run.stuck_nodes, [0] if lam < 1 else [])
    assert abs(run.energy_identity.difference) <= 1e-12 * (f * P) ** 2 / k


def test_single_node_implicit_converges_with_order_two():
    """Peak half a step away from the grid: the implicit run sees the amplitude lam Q1 cos(pi/n)
    exactly (the single-node backward Euler step is exact at the grid for monotone pieces), so
    W_n = 4 f P (lam Q1 cos(pi / n) - f P) / k, an O(n^-2) error."""
    s, k, f, P = single_node()
    lam, Q1 = 2.0, 1.0
    W = closed_form_W(k, f, P, lam, Q1)
    errs = []
    for n in (8, 16, 32, 64, 128):
        a = np.pi / n
        load = sd.LoadCycle.from_harmonics([0.0], [P], q_cos=[Q1 * np.cos(a)],
                                           q_sin=[Q1 * np.sin(a)])
        run = sd.solve_cycles(s, load, lam, steps_per_cycle=n)
        Wn = closed_form_W(k, f, P, lam * np.cos(a), Q1)
        assert run.steady_dissipation == pytest.approx(Wn, rel=1e-12)
        errs.append(abs(run.steady_dissipation - W))
    order = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    np.testing.assert_allclose(order, 2.0, atol=0.05)


def test_events_with_harmonic_load_uses_documented_interpolant():
    s, k, f, P = single_node()
    load = sd.LoadCycle.from_harmonics([0.0], [P], q_cos=[1.0])
    run = sd.solve_cycles(s, load, 3.0, method="events", steps_per_cycle=16)
    assert "to_samples" in run.message and run.load.kind == "samples"
    assert run.load.n_samples == 16
    # 16 samples contain both extremes of cos: the exact W of the interpolant is the closed form
    assert run.steady_dissipation == pytest.approx(closed_form_W(k, f, P, 3.0, 1.0), rel=1e-12)


# ---------------------------------------------------------------------------- cross-method
@pytest.mark.parametrize("n, p0", [(2, 3.0), (3, 1.0)])
def test_implicit_converges_to_events_first_order(n, p0):
    s, load = random_coupled(n, n, p0=p0)
    ev = sd.solve_cycles(s, load, 1.0, method="events")
    assert ev.status == "periodic" and ev.steady_dissipation > 0
    errs = []
    for m in (70, 280, 1120):
        run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=m)
        # every step verified to FEAS_TOL = 1e-9 (relative natural residual)
        assert run.status == "periodic" and run.max_residual <= 1e-9
        errs.append(abs(run.steady_dissipation - ev.steady_dissipation) / ev.steady_dissipation)
    # backward Euler with end-of-step q: first order in 1/m (factor 4 per refinement; >= 2.5)
    assert errs[1] < errs[0] / 2.5 and errs[2] < errs[1] / 2.5
    assert errs[2] < 5e-3


def test_energy_identity_every_steady_cycle():
    """Events: W equals the closed integral of u . d r_w to round-off.  Implicit: the gap is the
    O(1/m) discretisation error and shrinks with m."""
    for seed, n, p0 in [(1, 2, 3.0), (2, 3, 0.8), (3, 5, 0.5), (4, 8, 3.0)]:
        s, load = random_coupled(seed, n, p0=p0)
        ev = sd.solve_cycles(s, load, 1.2, method="events")
        assert ev.status == "periodic"
        assert ev.energy_identity.relative_difference <= 1e-9
        gaps = [sd.solve_cycles(s, load, 1.2, steps_per_cycle=m).energy_identity
                .relative_difference for m in (50, 400)]
        assert gaps[1] < gaps[0] and gaps[1] < 0.02


def test_oracle_step_by_step_along_an_evolution_with_separation():
    """Each implicit step of a run (nodes open and close) equals the enumeration oracle's
    unique solution from the previous step's slips."""
    rng = np.random.default_rng(7)
    n = 3
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(0.6 * s.critical_friction().value)
    load = sd.LoadCycle.from_harmonics(rng.normal(size=n), [0.5, 0.3, 1.0],
                                       q_cos=rng.normal(size=n) * 2, p_sin=[1.5, 1.0, 0.3])
    m = 24
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=m, max_cycles=3, record_history=True)
    h = run.history
    seen = set(h["state"])
    assert {"separation", "stick"} <= seen and seen & {"forward", "backward"}
    v = np.zeros(n)
    for c in range(1, run.n_cycles + 1):
        for k in range(1, m + 1):
            t = c - 1 + k / m
            rows = h[(h["cycle"] == c) & np.isclose(h["t"], t)].sort_values("node")
            q_w, p_w = load.evaluate(t, 1.0)
            (vv, ww, qq, pp), = oracle(s, v, q_w, p_w)
            # two solves of the same small linear systems (force and stiffness ~1): ~1e-13
            np.testing.assert_allclose(rows["slip"], vv, atol=1e-9)
            np.testing.assert_allclose(rows["gap"], ww, atol=1e-9)
            np.testing.assert_allclose(rows["p"], pp, atol=1e-9)
            v = rows["slip"].to_numpy()


# ---------------------------------------------------------------------------- uniqueness
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 3))
def test_uncoupled_same_steady_W_from_every_initial_state(seed, n):
    """B = 0: W is independent of the initial state (MODEL.md s.4, seed 002 s.3)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    A = M @ M.T + n * np.eye(n)
    Mc = rng.normal(size=(n, n))
    C = Mc @ Mc.T + n * np.eye(n)
    s = sd.DiscreteSystem(A, np.zeros((n, n)), C, friction=rng.uniform(0.1, 0.8, n))
    load = sd.LoadCycle.from_harmonics(rng.normal(size=n), rng.uniform(1, 3, n),
                                       q_cos=rng.normal(size=n), q_sin=rng.normal(size=n),
                                       p_cos=0.3 * rng.normal(size=n))
    lam = rng.uniform(0.5, 3)
    Ws = []
    for _ in range(3):
        v0 = rng.normal(size=n) * 3 / np.diag(A)
        run = sd.solve_cycles(s, load, lam, initial_slip=v0, steps_per_cycle=24, max_cycles=400)
        assert run.status == "periodic"
        Ws.append(run.steady_dissipation)
    # the steady states agree to the period-detection tolerance (1e-10 of the force scale)
    energy = run.force_scale**2 / np.diag(A).min()
    np.testing.assert_allclose(Ws, Ws[0], rtol=1e-7, atol=1e-9 * energy)


def _two_node_coupled(f=0.3):
    A = np.array([[3.0, -1.0], [-1.0, 2.0]])
    B = np.array([[0.8, 0.3], [-0.4, 0.6]])
    C = np.array([[4.0, 0.5], [0.5, 3.0]])
    s = sd.DiscreteSystem(A, B, C, friction=f)
    load = sd.LoadCycle.from_harmonics([0.2, -0.1], [2.0, 1.5], q_cos=[1.0, 0.4],
                                       q_sin=[0.0, 0.8], p_cos=[0.2, 0.0])
    return s, load


def test_above_lam2_no_initial_state_shakes_down_and_below_lam1_all_do():
    s, load = _two_node_coupled()
    b = sd.shakedown_bounds(s, load)
    assert np.isfinite(b.lam1) and np.isfinite(b.lam2) and b.lam1 <= b.lam2
    rng = np.random.default_rng(0)
    starts = rng.normal(size=(6, 2)) * 0.5
    for lam in (b.lam2 * 1.05, b.lam2 * 1.5):
        for v0 in starts:
            run = sd.solve_cycles(s, load, lam, initial_slip=v0, steps_per_cycle=64,
                                  max_cycles=400, tol=1e-9)
            assert run.status == "periodic" and not run.shook_down
            assert run.steady_dissipation > 0
    for lam in (b.lam1 * 0.5, b.lam1 * 0.95):
        for v0 in starts:
            run = sd.solve_cycles(s, load, lam, initial_slip=v0, steps_per_cycle=64,
                                  max_cycles=400, tol=1e-9)
            assert run.status == "periodic" and run.shook_down
            np.testing.assert_array_equal(run.stuck_nodes, [0, 1])


def test_period_two_orbit_detected():
    """A coupled 2-node system (found by a seeded search, friction 0.86 of critical) whose
    32-step implicit evolution settles on a 2T orbit: W alternates between two values."""
    rng = np.random.default_rng(231)
    n = int(rng.integers(2, 4))
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 0.3 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(rng.uniform(0.3, 0.95) * min(s.critical_friction().value, 2.0))
    load = sd.LoadCycle.from_harmonics(
        rng.normal(size=n), rng.uniform(0.5, 3, n), q_cos=rng.normal(size=n),
        q_sin=rng.normal(size=n), p_cos=rng.normal(size=n), p_sin=rng.normal(size=n))
    lam, v0 = rng.uniform(0.5, 2), rng.normal(size=n)
    run = sd.solve_cycles(s, load, lam, initial_slip=v0, steps_per_cycle=32)
    assert run.period == 2 and set(run.step_statuses) == {"unique"}
    W1, W2 = run.dissipation[-2:]
    assert abs(W1 - W2) > 0.05 * W1  # a genuine alternation, not a tolerance artefact
    assert run.steady_dissipation == pytest.approx((W1 + W2) / 2, rel=1e-14)
    assert run.state_change[-1] > 1e3 * run.tol  # consecutive starts differ ...
    np.testing.assert_allclose(run.cycle_start_slips[-1], run.cycle_start_slips[-3],
                               atol=1e-9)  # ... every second one repeats
    t = run.steady_table["t"]
    assert t.max() - t.min() == pytest.approx(2.0)
    again = sd.solve_cycles(s, load, lam, initial_slip=run.final_slip, steps_per_cycle=32)
    assert again.period == 2 and again.cycles_to_steady == 0


# ---------------------------------------------------------------------------- extremes
def test_friction_near_zero_and_near_critical():
    s, load = _two_node_coupled()
    fc = s.critical_friction()
    assert fc.exact
    for f in (1e-6, 0.99 * fc.value):
        sf = s.with_friction(f)
        for method in ("implicit", "events"):
            run = sd.solve_cycles(sf, load, 1.0, method=method, steps_per_cycle=64,
                                  max_cycles=300)
            assert run.status == "periodic", (f, method, run.message)
            assert run.max_residual <= 1e-9
            assert set(run.step_statuses) == {"unique"}
            if method == "events":
                assert run.energy_identity.relative_difference <= 1e-9


def test_stiffness_ratio_1e8():
    A = np.diag([1.0, 1e8])
    B = np.array([[0.1, 0.0], [0.0, 1e7]])
    C = np.diag([2.0, 2e8])
    s = sd.DiscreteSystem(A, B, C, friction=0.3)
    load = sd.LoadCycle.from_samples([0.0, 0.0], [2.0, 2.0], [[1.0, 1.0], [-1.0, -1.0],
                                                              [0.5, 0.2]],
                                     [[0.0, 0.3], [0.0, -0.3], [0.0, 0.0]])
    ev = sd.solve_cycles(s, load, 1.0, method="events")
    im = sd.solve_cycles(s, load, 1.0, steps_per_cycle=3000)
    assert ev.status == im.status == "periodic"
    # steps verified to FEAS_TOL = 1e-9; the event path's energy identity is exact (affine
    # between events) up to the same tolerance
    assert ev.max_residual <= 1e-9 and im.max_residual <= 1e-9
    assert ev.energy_identity.relative_difference <= 1e-9
    # implicit (3000 steps, on the sample breakpoints) vs exact events: measured 1.3e-5
    # relative (second-order time discretisation); 4e-5 is 3x that
    assert im.steady_dissipation == pytest.approx(ev.steady_dissipation, rel=4e-5)
    # both nodes slip: the stiff one with slips ~1e-8, still detected as slipping
    assert ev.stuck_nodes.size == 0 and np.ptp(ev.steady_table.query("node == 1")["slip"]) > 0


def test_nodes_open_and_close_every_cycle():
    s, load = random_coupled(5, 3, p0=0.2, amp=1.0)
    for method in ("events", "implicit"):
        run = sd.solve_cycles(s, load, 1.0, method=method, steps_per_cycle=400)
        assert run.status == "periodic"
        tab = run.steady_table
        opened = tab.groupby("node")["state"].apply(lambda x: (x == "separation").any())
        closed = tab.groupby("node")["state"].apply(lambda x: (x != "separation").any())
        assert (opened & closed).any()
        gap_open = tab[tab["state"] == "separation"]
        # separated during the step / segment ending at t: p = 0 there, gap >= 0 (0 if it just
        # closed, events)
        assert (gap_open["gap"] >= 0).all() and (gap_open["gap"] > 0).any()
        np.testing.assert_allclose(gap_open["p"], 0, atol=1e-9 * run.force_scale)
    ev = sd.solve_cycles(s, load, 1.0, method="events")
    # implicit with 400 steps vs exact events: measured -8.9e-3 relative (opening and closing
    # events fall between steps: first-order error there); 1.5e-2 is 1.7x that
    assert run.steady_dissipation == pytest.approx(ev.steady_dissipation, rel=1.5e-2)


# in the default run since the step work of issue 14: 4.4 s on 2 busy cores (load 7), mostly
# building and checking the 4000 x 4000 K (Cholesky) and four fresh LU factorizations
def test_n2000_a_few_steps():
    rng = np.random.default_rng(0)
    n = 2000
    # banded coupled SPD stiffness (diagonally dominant)
    off = np.full(n - 1, 1.0)
    A = np.diag(np.full(n, 10.0)) - 2 * np.diag(off, 1) - 2 * np.diag(off, -1)
    B = np.diag(rng.uniform(-1, 1, n)) + np.diag(rng.uniform(-0.5, 0.5, n - 1), 1)
    C = np.diag(np.full(n, 12.0)) + np.diag(off, 1) + np.diag(off, -1)
    s = sd.DiscreteSystem(A, B, C, friction=0.2)
    load = sd.LoadCycle.from_harmonics(rng.normal(size=n) * 0.1, np.full(n, 5.0),
                                       q_cos=rng.normal(size=n) * 2.0)
    solver = StepSolver(s, check_uniqueness=False)
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=4, max_cycles=1, solver=solver)
    assert run.n_cycles == 1 and run.max_residual <= 1e-9
    assert set(run.step_statuses) == {"solved"}
    assert run.dissipation[0] > 0 and run.final_slip.shape == (n,)


# ---------------------------------------------------------------------------- run plumbing
def test_progress_history_and_fields():
    s, load = random_coupled(9, 2)
    calls = []
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=16, record_history=True,
                          progress=lambda c, m, W: calls.append((c, m, W)))
    assert [c for c, _, _ in calls] == list(range(1, run.n_cycles + 1))
    np.testing.assert_allclose([W for *_, W in calls], run.dissipation)
    assert run.cycle_start_slips.shape == (run.n_cycles + 1, 2)
    np.testing.assert_allclose(run.cycle_start_slips[-1], run.final_slip)
    assert run.state_change.shape == (run.n_cycles,) and run.state_change[-1] <= run.tol
    assert run.cycles_to_steady == run.n_cycles - run.period
    assert len(run.history) == 2 * (run.n_cycles * 16 + 1)  # the start, then every step
    assert set(run.steady_table.columns) >= {"t", "node", "slip", "gap", "q", "p", "state"}
    assert run.final_active_sets.shape == (16, 2)
    assert run.statistics["n_steps"] == 16 * run.n_cycles


def test_not_converged_status():
    s, load = random_coupled(9, 2)
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=16, max_cycles=1, tol=1e-300)
    assert run.status == "not_converged" and run.period == 0
    assert np.isnan(run.steady_dissipation) and run.energy_identity is None
    assert run.cycles_to_steady == -1 and not run.shook_down


# ---------------------------------------------------------------------------- bad input
def test_bad_input_messages():
    s, load = random_coupled(0, 2)
    with pytest.raises(sd.ShapeError, match=r"initial_slip must have shape \(2,\)"):
        sd.solve_cycles(s, load, 1.0, initial_slip=[0.0, 0.0, 0.0])
    with pytest.raises(sd.InputError, match="initial_gap must be >= 0.*node 2 has -0.1"):
        sd.solve_cycles(s, load, 1.0, initial_gap=[0.0, -0.1])
    with pytest.raises(sd.InputError, match="initial_slip must be finite"):
        sd.solve_cycles(s, load, 1.0, initial_slip=[np.inf, 0.0])
    with pytest.raises(sd.InputError, match="steps_per_cycle must be an integer >= 2; got 1"):
        sd.solve_cycles(s, load, 1.0, steps_per_cycle=1)
    with pytest.raises(sd.InputError, match="steps_per_cycle must be an integer >= 2; got 2.5"):
        sd.solve_cycles(s, load, 1.0, steps_per_cycle=2.5)
    with pytest.raises(sd.InputError, match="method must be 'implicit' or 'events'; got 'rk4'"):
        sd.solve_cycles(s, load, 1.0, method="rk4")
    with pytest.raises(sd.InputError, match="max_cycles must be an integer >= 1"):
        sd.solve_cycles(s, load, 1.0, max_cycles=0)
    with pytest.raises(sd.InputError, match="lam must be a finite number >= 0; got -1"):
        sd.solve_cycles(s, load, -1.0)
    with pytest.raises(sd.InputError, match="tol must be a positive number"):
        sd.solve_cycles(s, load, 1.0, tol=0.0)
    with pytest.raises(sd.ShapeError, match="load has 3 nodes but the system has 2"):
        sd.solve_cycles(s, sd.LoadCycle.static([0, 0, 0], [1, 1, 1]), 1.0)
    with pytest.raises(sd.InputError, match="load must be a LoadCycle"):
        sd.solve_cycles(s, "load", 1.0)


def test_runs_are_bit_reproducible_whatever_ran_before():
    # each solve_cycles call builds a fresh step solver: a run's result cannot depend on the
    # factorizations cached by earlier runs in the same process
    rng = np.random.default_rng(0)
    n = 12
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], 0.3 * K[:n, n:], K[n:, n:], 0.3)
    load = sd.LoadCycle.from_harmonics(rng.normal(size=n), 5 + rng.random(n) * 5,
                                       q_cos=3 * rng.normal(size=n), q_sin=3 * rng.normal(size=n))
    lam2 = sd.shakedown_bounds(s, load, intervals=False, adjacency=False).lam2
    first = sd.solve_cycles(s, load, 1.3 * lam2, steps_per_cycle=32)
    sd.solve_cycles(s, load, 1.1 * lam2, steps_per_cycle=32, initial_slip=rng.normal(size=n) * 0.01)
    again = sd.solve_cycles(s, load, 1.3 * lam2, steps_per_cycle=32)
    assert np.array_equal(first.dissipation, again.dissipation)
    assert np.array_equal(first.final_slip, again.final_slip)


def test_load_factor_exactly_at_lam1_and_lam2():
    """Two-node coupled system (built-in scene two_node_coupled) at the bounds themselves.

    At lam1 every constraint is still active (closed interval), so every sampled state shakes down
    (Ahn et al. 2008 for two nodes). At lam2 the safe region is a single point: a run that shakes
    down must end exactly there, and one that does not has W > 0. Both methods must agree.
    """
    from shakedown.scenes.files import build, load_scene

    s, load, _ = build(load_scene("two_node_coupled"))
    b = sd.shakedown_bounds(s, load)
    assert sd.safe_region(s, load, b.lam2).area() == pytest.approx(0.0, abs=1e-12)
    starts = [np.zeros(2), *np.random.default_rng(1).normal(size=(5, 2)) * 0.5]
    outcomes = []
    for v0 in starts:
        runs = [sd.solve_cycles(s, load, b.lam1, initial_slip=v0, steps_per_cycle=64,
                                max_cycles=400, method=m) for m in ("implicit", "events")]
        assert all(r.status == "periodic" and r.shook_down for r in runs)
        for method in ("implicit", "events"):
            r = sd.solve_cycles(s, load, b.lam2, initial_slip=v0, steps_per_cycle=64,
                                max_cycles=400, method=method)
            # at lam2 the steps are degenerate (a constraint is tight): 10 x FEAS_TOL allowed,
            # the Lemke fallback's acceptance threshold
            assert r.status == "periodic" and r.max_residual <= 1e-8
            if r.shook_down:
                # the only safe state left.  The approach to it is geometric and the run stops once
                # the per-cycle change is below tol; the distance left is about that change over
                # (1 - rate), here ~1e-5 on slips of order 0.1: atol 1e-4 (0.1 % of the scale)
                np.testing.assert_allclose(r.final_slip, b.state_at_lam2, atol=1e-4)
            else:
                assert r.steady_dissipation > 0
            outcomes.append((method, r.shook_down))
    # the initial state decides at lam2; both methods see the same outcome for each start
    assert [o for m, o in outcomes if m == "implicit"] == [o for m, o in outcomes if m == "events"]


@pytest.mark.parametrize("steps", [8, 64])
def test_discrete_energy_balance_holds_to_solver_tolerance_for_implicit_steps(steps):
    """Backward Euler has an exact discrete balance (EnergyIdentity docstring): W equals the
    left-point load work minus the discretisation losses 1/2 du^T K du + p_k w_(k-1).  It must hold
    to rounding whatever the step count, while the continuous identity is off by O(1/steps)."""
    from shakedown.gallery import get

    g = get("fig8_coupled_one_at_a_time")
    run = sd.solve_cycles(g.system, g.load, g.lam, steps_per_cycle=steps, max_cycles=400)
    e = run.energy_identity
    assert run.status == "periodic" and e.dissipation > 0
    assert e.discrete_relative_difference <= 1e-10
    assert e.numerical_dissipation > 0
    # the continuous identity is the discrete one plus the losses, up to the quadrature rule
    assert e.relative_difference > 1e3 * e.discrete_relative_difference
    # with separation (nodes open and close): the p_k w_(k-1) term must be accounted for
    s, load = random_coupled(0, 4, p0=1.0, amp=3.0)
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=steps, max_cycles=300)
    assert run.status == "periodic" and run.steady_table["gap"].max() > 0.1  # nodes do open
    assert run.energy_identity.discrete_relative_difference <= 1e-10
