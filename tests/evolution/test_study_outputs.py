"""Study outputs of the evolution checked against independent facts (issue 15):
the permanently stuck set excludes open nodes, and the uniqueness verdict near its tolerance."""

import numpy as np
import pytest

import shakedown as sd
from shakedown import gallery
from shakedown.evolution import natural_slip_scale, uniqueness_study


# ------------------------------------------------------------------ stuck against open nodes
@pytest.mark.parametrize("method", ["implicit", "events", "steady"])
def test_open_nodes_are_not_permanently_stuck(method):
    """Three uncoupled nodes (A = 2, C = 3, f = 0.5) under harmonic loads (MODEL.md s.1, s.4):

    * node 0: p = 2, |q| <= 0.3 < f p = 1: in contact and stuck all cycle -> in S0;
    * node 1: p_w = -1 < 0 all cycle: separated all cycle (w = 1/3, q = 0) -> never slips,
      but it is not in contact, so not in S0;
    * node 2: p_w = 0.5 + cos(t), q_w = 0: open for a third of the cycle, stuck otherwise -> not
      in contact throughout, not in S0.
    The S0 of MODEL.md s.4 is "the nodes that never slip" among those in contact throughout."""
    s = sd.DiscreteSystem(np.diag([2.0, 2.0, 2.0]), np.zeros((3, 3)), np.diag([3.0, 3.0, 3.0]),
                          friction=0.5)
    load = sd.LoadCycle.from_harmonics([0.1, 0.3, 0.0], [2.0, -1.0, 0.5], q_cos=[0.2, 0.0, 0.0],
                                       p_cos=[0.0, 0.0, 1.0])
    if method == "steady":
        run = sd.steady_cycle(s, load, 1.0)
    else:
        run = sd.solve_cycles(s, load, 1.0, method=method, steps_per_cycle=32)
    assert run.shook_down and run.steady_dissipation == 0.0
    np.testing.assert_array_equal(run.stuck_nodes, [0])


# ------------------------------------------------------------------ uniqueness verdict
@pytest.fixture(scope="module")
def near_states():
    """Seed 002 Fig. 4 system (gallery, lam between lam1 and lam2), where the steady W varies
    continuously with the initial slip: three initial states 1e-4 apart give steady
    dissipations that differ by 2.4e-5 (measured: W = 0.299846, 0.299846, 0.299822), 9.6e-6 of
    the verdict's W scale (2.45): a physically distinct outcome, 10x above the default
    tolerance (w_rtol = 1e-6) and 100x below a tolerance 1000x too loose."""
    p = gallery.fig4_triangle()
    study0 = uniqueness_study(p.system, p.load, p.lam, 12, rng=0, n_jobs=1,
                              steps_per_cycle=32, max_cycles=300)
    t = study0.table
    i = int(t["steady_dissipation"].idxmax())
    v = t.loc[i, ["initial_slip_0", "initial_slip_1"]].to_numpy(float)
    states = np.array([v, v + [1e-4, 0.0], v + [0.0, 1e-4]])
    return p, states


def w_scale(p, lam, W):
    """Documented scale of the verdict (UniquenessStudy.w_tol): max(max|W|, F s), F the largest
    friction / tangential force scale and s the largest natural slip, both from
    natural_slip_scale (the force of node j is s_j A_jj)."""
    s = natural_slip_scale(p.system, p.load, lam)
    return max(np.max(np.abs(W)), np.max(s * np.diag(p.system.A)) * np.max(s))


def test_uniqueness_verdict_near_its_tolerance(near_states):
    p, states = near_states
    study = uniqueness_study(p.system, p.load, p.lam, states, n_jobs=1, steps_per_cycle=32,
                             max_cycles=300)
    W = study.table["steady_dissipation"].to_numpy(float)
    assert study.fraction_steady == 1.0
    spread = W.max() - W.min()
    scale = w_scale(p, p.lam, W)
    # the premise: a real difference, far above the solver's accuracy (tol 1e-10 per cycle),
    # between 3x the default tolerance and 1/10 of a 1000x looser one
    assert 3e-6 < spread / scale < 1e-4
    assert study.dissipation_spread == pytest.approx(spread, rel=1e-12)
    # the tolerance is the documented one (1e-6 of the scale), computed independently here
    assert study.w_tol == pytest.approx(1e-6 * scale, rel=1e-9)
    assert not study.unique_dissipation, study.summary()
    # different dissipations come with different time-varying responses: measured spread
    # 2.3e-5 of the force scale (slip 2.0e-5, reactions 6.6e-5), of the order of the 1e-4
    # difference of the initial states; the solver's accuracy is ~1e-10
    assert 1e-6 < study.time_varying_spread < 1e-3
    assert study.slip_spread > 1e-6 and study.reaction_spread > 1e-6
    assert "NOT unique" in study.summary()
    # the verdict flips exactly at the tolerance: w_rtol bracketing spread / scale
    for factor, unique in ((0.5, False), (2.0, True)):
        s2 = uniqueness_study(p.system, p.load, p.lam, states, n_jobs=1, steps_per_cycle=32,
                              max_cycles=300, w_rtol=factor * spread / scale)
        assert s2.unique_dissipation is unique, (factor, s2.summary())


def test_a_node_slipping_a_little_every_cycle_is_not_stuck():
    """Single node (k = 2, f = 0.4, P = 3), tangential amplitude 1e-4 above the slip threshold
    f P: it slips 2 (lam Q1 - f P) / k = 1.2e-4 each way every cycle, 1e-4 of its natural slip
    f P / k (MODEL.md s.4; closed form W = 4 f P (lam Q1 - f P) / k).  Small, but 1e6 times the
    solver's steady-state tolerance: it is slipping, not stuck, and not shaken down."""
    k, f, P = 2.0, 0.4, 3.0
    s = sd.DiscreteSystem([[k]], [[0.0]], [[5.0]], friction=f)
    Q1 = f * P * (1 + 1e-4)
    load = sd.LoadCycle.from_harmonics([0.0], [P], q_cos=[Q1])
    for method in ("implicit", "events"):
        run = sd.solve_cycles(s, load, 1.0, method=method, steps_per_cycle=16)
        assert run.status == "periodic"
        assert run.stuck_nodes.size == 0 and not run.shook_down
        # implicit steps at t = 0, 1/2 hit the extremes: exact up to the steady tolerance
        # (1e-10 relative change per cycle) on a W that is itself 1e-4 of (f P)^2 / k
        W = 4 * f * P * (Q1 - f * P) / k
        assert run.steady_dissipation == pytest.approx(W, rel=1e-6)


def period_two_system():
    """The coupled system of test_evolution.test_period_two_orbit_detected (seeded search):
    its 32-step implicit evolution settles on a 2T orbit; its period-1 fixed point repels."""
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
    return s, load, lam, v0


def test_steady_cycle_finds_the_attracting_period_two_orbit():
    s, load, lam, v0 = period_two_system()
    plain = sd.solve_cycles(s, load, lam, initial_slip=v0, steps_per_cycle=32)
    assert plain.period == 2
    sc = sd.steady_cycle(s, load, lam, v0, steps_per_cycle=32)
    # verified by simulation: period 2, the plain cycling's W (both converge to tol = 1e-10
    # relative change per cycle; measured agreement 1e-15)
    assert sc.status == "converged" and sc.period == 2, sc.message
    assert sc.steady_dissipation == pytest.approx(plain.steady_dissipation, rel=1e-9)
    assert sc.n_evaluations < 100
    # restricted to period 1, the only fixed point repels (spectral radius 1.52 measured): it
    # must not be reported as a steady cycle; plain cycling then finds the 2T orbit
    sc1 = sd.steady_cycle(s, load, lam, v0, steps_per_cycle=32, period=1)
    assert sc1.status == "cycling" and "repelling" in sc1.message, sc1.message
    assert sc1.spectral_radius > 1.0 and sc1.period == 2
    assert sc1.steady_dissipation == pytest.approx(plain.steady_dissipation, rel=1e-9)


@pytest.mark.parametrize("units", [1.0, 1e-6, 2.5e9])
def test_natural_slip_scale_is_its_documented_formula(units):
    """s_k = (f_k |p0_k| + |q0_k| + lam (max_t |q1_k| + f_k max_t |p1_k|)) / A_kk: the scale of
    the sampled initial states and of the uniqueness verdict.  Maxima of the harmonics by dense
    sampling (2^14 points: relative error < 1e-7 of the amplitude); slips do not change when
    forces and stiffness change units together."""
    rng = np.random.default_rng(3)
    n = 3
    L = rng.normal(size=(2 * n, 2 * n))
    K = units * (L @ L.T + 2 * np.eye(2 * n))
    f = np.array([0.2, 0.5, 0.7])
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=f)
    q0, p0 = units * rng.normal(size=n), units * rng.uniform(1, 2, n)
    qc, qs, pc = units * rng.normal(size=(3, n))
    load = sd.LoadCycle.from_harmonics(q0, p0, q_cos=qc, q_sin=qs, p_cos=pc)
    t = np.arange(2**14) / 2**14
    q1, p1 = load.periodic(t)
    for lam in (0.0, 0.7, 2.0):
        expected = (f * np.abs(p0) + np.abs(q0)
                    + lam * (np.abs(q1).max(axis=0) + f * np.abs(p1).max(axis=0))) / np.diag(s.A)
        np.testing.assert_allclose(natural_slip_scale(s, load, lam), expected, rtol=1e-7)


def test_unsettled_runs_prevent_a_unique_verdict():
    """UniquenessStudy.unique_dissipation needs *every* run to reach a steady cycle.  Seed 002
    Fig. 8 system (memory fades by 0.67 per cycle): from its steady start a run settles at once,
    from (-0.3, 0.3) it needs ~100 cycles, so with max_cycles = 10 one run is unsettled; the one
    settled W alone (spread 0) must not make the verdict 'unique'."""
    p = gallery.fig8_coupled_one_at_a_time()
    sc = sd.steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle)
    states = np.array([sc.slip, [-0.3, 0.3]])
    study = uniqueness_study(p.system, p.load, p.lam, states, n_jobs=1,
                             steps_per_cycle=p.steps_per_cycle, max_cycles=10)
    assert list(study.table["period"] > 0) == [True, False], study.table
    assert study.fraction_steady == 0.5 and study.dissipation_spread == 0.0
    assert not study.unique_dissipation
