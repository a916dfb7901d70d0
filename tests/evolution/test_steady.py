"""The direct steady-cycle solver (shakedown.steady.steady_cycle).

Organised by what the tests prove: agreement with plain cycling (cross-method), the cost
claim counted in period-map evaluations (seed 002 Fig. 8: slow geometric approach), locked-in
slips of permanently stuck nodes (seed 002 Fig. 5), shakedown, period-2 orbits, bad input.
"""

import dataclasses

import numpy as np
import pytest

import shakedown as sd
from shakedown import gallery
from shakedown.evolution.steady import natural_slip_scale, steady_cycle

# Plain cycling stops when the cycle-start state changes by less than tol = 1e-10 (relative)
# in one cycle; with a geometric rate rho ~ 0.6 (Fig. 8 system) it is then within
# tol * rho / (1 - rho) ~ 2e-10 of the fixed point.  1e-8 leaves a factor 50.
AGREE_RTOL = 1e-8


@pytest.fixture(scope="module")
def fig8():
    p = gallery.fig8_coupled_one_at_a_time()
    plain = sd.solve_cycles(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle,
                            max_cycles=400)
    return p, plain


def test_fig8_plain_cycling_is_slow_and_reaches_a_unique_slipping_cycle(fig8):
    p, plain = fig8
    # the premise of the speed claim: the approach is asymptotic (many cycles), S0 is empty
    assert plain.period == 1
    assert plain.n_cycles >= 20
    assert len(np.atleast_1d(plain.stuck_nodes)) == 0
    assert plain.steady_dissipation > 0


@pytest.mark.parametrize("accelerator", ["newton", "anderson"])
def test_steady_cycle_agrees_with_long_plain_cycling(fig8, accelerator):
    p, plain = fig8
    sc = steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle,
                      accelerator=accelerator)
    assert sc.status == "converged", sc.message
    assert sc.period == 1
    scale = np.max(natural_slip_scale(p.system, p.load, p.lam))
    starts = np.asarray(plain.cycle_start_slips)
    np.testing.assert_allclose(sc.slip, starts[-2], rtol=0, atol=AGREE_RTOL * scale)
    assert sc.steady_dissipation == pytest.approx(plain.steady_dissipation, rel=AGREE_RTOL)
    assert sc.residual <= 1e-9  # verification: one more period from the answer
    assert not sc.shook_down


def test_steady_cycle_uses_fewer_period_map_evaluations_on_fig8(fig8):
    p, plain = fig8
    sc = steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle)
    # evaluations = simulated load periods, verification included (no timing)
    assert sc.n_evaluations * 3 <= plain.n_cycles, (sc.n_evaluations, plain.n_cycles)


def test_steady_cycle_from_other_initial_states_finds_the_same_cycle(fig8):
    p, plain = fig8
    scale = np.max(natural_slip_scale(p.system, p.load, p.lam))
    for v0 in ([0.3, -0.2], [-0.5, 0.4]):
        sc = steady_cycle(p.system, p.load, p.lam, v0, steps_per_cycle=p.steps_per_cycle)
        assert sc.status == "converged"
        np.testing.assert_allclose(sc.slip, np.asarray(plain.cycle_start_slips)[-2],
                                   atol=AGREE_RTOL * scale, rtol=0)


def test_stuck_node_keeps_its_locked_in_slip_and_W_has_its_closed_form():
    # seed 002 Fig. 5: node 1 stuck; W = 4 f p (lam Q - f p) / A_00 with node 1 held
    p = gallery.fig5_uncoupled_stuck()
    f, P, Q, lam = 0.3, 1.0, 1.0, p.lam
    W_exact = 4 * f * P * (lam * Q - f * P) / p.system.A[0, 0]
    for v1 in (-0.1, 0.05, 0.12):
        sc = steady_cycle(p.system, p.load, lam, [0.0, v1], steps_per_cycle=p.steps_per_cycle)
        assert sc.status == "converged"
        assert list(np.atleast_1d(sc.stuck_nodes)) == [1]
        assert sc.slip[1] == pytest.approx(v1, abs=1e-12)  # never slipped: locked in
        # the load extremes t = 0, 1/2 are step times, so the implicit W is exact (to rounding)
        assert sc.steady_dissipation == pytest.approx(W_exact, rel=1e-9)


def test_shakedown_below_lam1():
    p = gallery.fig4_triangle()
    b = sd.shakedown_bounds(p.system, p.load)
    sc = steady_cycle(p.system, p.load, 0.5 * b.lam1, [0.2, -0.1], steps_per_cycle=32)
    assert sc.status == "converged"
    assert sc.shook_down
    assert sc.steady_dissipation == pytest.approx(0.0, abs=1e-12)
    assert sorted(np.atleast_1d(sc.stuck_nodes)) == [0, 1]


def test_period_two_search_on_a_period_one_system_returns_the_period_one_cycle(fig8):
    # A fixed point of P is one of P o P: the period-2 search must land on the same cycle and
    # solve_cycles' verification must classify it as period 1.  (No system with an attracting
    # period-2 orbit was found by a random search over coupled 2- and 3-node systems; see the
    # module docstring of shakedown.steady.)
    p, plain = fig8
    sc = steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle, period=2)
    assert sc.status == "converged"
    assert sc.period == 1
    assert sc.steady_dissipation == pytest.approx(plain.steady_dissipation, rel=AGREE_RTOL)


def test_spectral_radius_matches_the_observed_geometric_rate(fig8):
    # seed 002 Fig. 8: W_k - W_steady decays by the contraction factor of the affine piece
    p, plain = fig8
    sc = steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle)
    dW = np.abs(plain.dissipation[5:25] - plain.steady_dissipation)
    observed = float(np.exp(np.median(np.diff(np.log(dW)))))
    assert 0 < sc.spectral_radius < 1
    # both are the same linear rate; 1e-3 covers the rounding of dW ~ 1e-9 at cycle 25
    assert sc.spectral_radius == pytest.approx(observed, rel=1e-3)


def test_result_is_frozen_and_counts_are_consistent(fig8):
    p, _ = fig8
    sc = steady_cycle(p.system, p.load, p.lam, steps_per_cycle=p.steps_per_cycle)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sc.period = 2
    assert sc.n_evaluations >= sc.run.n_cycles
    assert sc.residual_history.ndim == 1 and sc.residual_history.size >= 1
    assert sc.steady_table is not None and len(sc.steady_table) > 0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(initial_slip=[0.0, 0.0, 0.0]), r"initial_slip must have shape \(2,\)"),
        (dict(initial_slip=[np.nan, 0.0]), "initial_slip must be finite"),
        (dict(lam=-1.0), "lam must be a finite number >= 0"),
        (dict(period=3), "period must be 'auto', 1 or 2"),
        (dict(accelerator="broyden"), "accelerator must be"),
        (dict(max_evaluations=2), "max_evaluations must be an integer >= 4"),
        (dict(tol=0.0), "tol must be a positive number"),
    ],
)
def test_bad_input(kwargs, match):
    p = gallery.fig8_coupled_one_at_a_time()
    args = dict(lam=p.lam)
    args.update(kwargs)
    lam = args.pop("lam")
    with pytest.raises(ValueError, match=match):
        steady_cycle(p.system, p.load, lam, **args)


def test_load_of_the_wrong_size_is_rejected():
    p = gallery.fig8_coupled_one_at_a_time()
    load3 = sd.LoadCycle.from_harmonics([0, 0, 0], [1, 1, 1], q_cos=[1, 0, 0])
    with pytest.raises(sd.ShapeError, match="load has 3 nodes but the system has 2"):
        steady_cycle(p.system, load3, 0.1)
