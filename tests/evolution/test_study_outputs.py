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
