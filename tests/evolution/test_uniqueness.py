"""Uniqueness experiments (shakedown.steady.uniqueness_study).

What is proven, and therefore tested: for uncoupled systems the steady dissipation and the
time-varying part of the response are the same from every initial state (seed 002 s.3 /
MODEL.md s.4; property test over random uncoupled systems); for two nodes every initial state
shakes down below ``lam1`` (Ahn, Bertocchi & Barber 2008) and none does above ``lam2`` (no
safe state exists).  The seed's N-node ``lam1`` criterion is *not* proven (MODEL.md s.3) and
is not asserted here: the notebook 02_cycles reports the 3-node experiments.
"""

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown import gallery
from shakedown.evolution import sample_initial_slips, uniqueness_study

FAST = dict(steps_per_cycle=32, max_cycles=300)


# ------------------------------------------------------------------ property: uncoupled systems
@st.composite
def uncoupled_problems(draw):
    n = draw(st.integers(2, 3))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    L = rng.normal(size=(n, n))
    A = L @ L.T + n * np.eye(n)  # SPD, diagonally dominant enough to be well conditioned
    C = np.diag(rng.uniform(0.5, 2.0, n))
    f = rng.uniform(0.1, 0.6, n)
    p0 = rng.uniform(0.5, 2.0, n)
    system = sd.DiscreteSystem(A, np.zeros((n, n)), C, f)
    load = sd.LoadCycle.from_harmonics(
        rng.normal(size=n) * 0.3 * f * p0, p0,
        q_cos=rng.normal(size=n), q_sin=rng.normal(size=n),
        p_cos=0.3 * rng.uniform(-1, 1, n) * p0,  # keeps p_w > 0 for lam <= 2
    )
    lam = draw(st.floats(0.2, 2.0))
    return system, load, lam, seed


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(uncoupled_problems())
def test_uncoupled_systems_have_one_steady_W_from_every_initial_state(problem):
    system, load, lam, seed = problem
    study = uniqueness_study(system, load, lam, 5, rng=seed, n_jobs=1, solver="steady",
                             **FAST)
    assert study.fraction_steady == 1.0, study.table[["status", "period"]]
    # w_tol = 1e-6 x the W scale: far above the solver tolerance, far below distinct outcomes
    assert study.dissipation_spread <= study.w_tol, study.summary()
    assert study.unique_dissipation
    # the time-varying part of slips and reactions is unique too (relative to the load scale)
    assert study.time_varying_spread <= 1e-6, study.summary()


# ------------------------------------------------------------------ two nodes: lam1, lam2
@pytest.fixture(scope="module")
def triangle():
    p = gallery.fig4_triangle()
    return p, sd.shakedown_bounds(p.system, p.load)


def test_two_nodes_below_lam1_every_sampled_state_shakes_down(triangle):
    p, b = triangle
    assert b.lam1 < b.lam2  # the premise: a window where the initial state matters
    study = uniqueness_study(p.system, p.load, 0.9 * b.lam1, 10, rng=7, n_jobs=1,
                             solver="steady", **FAST)
    assert study.fraction_shook_down == 1.0, study.table
    assert np.all(study.table["steady_dissipation"].abs() <= 1e-12)


def test_two_nodes_above_lam2_no_sampled_state_shakes_down(triangle):
    p, b = triangle
    study = uniqueness_study(p.system, p.load, 1.1 * b.lam2, 10, rng=7, n_jobs=1, **FAST)
    assert study.fraction_steady == 1.0
    assert study.fraction_shook_down == 0.0
    assert np.all(study.table["steady_dissipation"] > 0)


def test_between_lam1_and_lam2_the_initial_state_decides(triangle):
    # seed 002 Fig. 4: reproduced with the designed gallery system (fixed seed)
    p, b = triangle
    assert b.lam1 < p.lam < b.lam2
    study = uniqueness_study(p.system, p.load, p.lam, 12, rng=0, n_jobs=1, **FAST)
    assert 0.0 < study.fraction_shook_down < 1.0, study.table
    assert not study.unique_dissipation


def test_fig5_locked_in_slips_differ_but_W_is_unique():
    p = gallery.fig5_uncoupled_stuck()
    study = uniqueness_study(p.system, p.load, p.lam, 8, rng=3, n_jobs=1,
                             steps_per_cycle=p.steps_per_cycle, max_cycles=100)
    assert study.unique_dissipation
    assert set(study.table["stuck"]) == {"1"}
    assert study.table["steady_slip_1"].nunique() > 1  # different locked-in slips
    assert study.table["steady_dissipation"].iloc[0] == pytest.approx(0.24, rel=1e-9)


# ------------------------------------------------------------------ determinism, parallelism
def test_table_does_not_depend_on_n_jobs():
    p = gallery.fig5_uncoupled_stuck()
    kw = dict(steps_per_cycle=16, max_cycles=100, rng=11)
    one = uniqueness_study(p.system, p.load, p.lam, 6, n_jobs=1, **kw)
    two = uniqueness_study(p.system, p.load, p.lam, 6, n_jobs=2, **kw)
    pd.testing.assert_frame_equal(one.table, two.table, check_exact=True)
    assert one.time_varying_spread == two.time_varying_spread
    assert one.dissipation_spread == two.dissipation_spread


def test_given_states_are_used_in_order_and_reported():
    p = gallery.fig5_uncoupled_stuck()
    states = np.array([[0.0, 0.1], [0.2, -0.05], [-0.1, 0.0]])
    study = uniqueness_study(p.system, p.load, p.lam, states, n_jobs=1, steps_per_cycle=16,
                             max_cycles=100)
    np.testing.assert_array_equal(
        study.table[["initial_slip_0", "initial_slip_1"]].to_numpy(), states
    )
    assert list(study.table["state"]) == [0, 1, 2]
    assert "uniqueness study at lam = 0.5" in study.summary()


def test_sampling_is_reproducible_starts_virgin_and_keeps_contact():
    p = gallery.fig4_triangle()
    a = sample_initial_slips(p.system, p.load, 50, rng=5, scale=5.0)
    b = sample_initial_slips(p.system, p.load, 50, rng=5, scale=5.0)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (50, 2)
    np.testing.assert_array_equal(a[0], 0.0)
    assert len(np.unique(a[1:, 0])) == 49
    # every state keeps at least half the static normal reaction (relative rounding 1e-12)
    p_start = p.load.p0 + a @ p.system.B
    assert np.all(p_start >= 0.5 * p.load.p0 - 1e-12 * np.abs(p.load.p0))


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(initial_slips=np.zeros((3, 3))), r"initial_slips must have shape \(n_states, 2\)"),
        (dict(initial_slips=0), "initial_slips as a count must be >= 1"),
        (dict(initial_slips=[[np.inf, 0.0]]), "initial_slips must be finite"),
        (dict(n_jobs=0), "n_jobs must be an integer >= 1"),
        (dict(solver="magic"), "solver must be 'cycles' or 'steady'"),
        (dict(lam=np.nan), "lam must be a finite number >= 0"),
        (dict(scale=-1.0), "scale must be a positive number"),
    ],
)
def test_bad_input(kwargs, match):
    p = gallery.fig5_uncoupled_stuck()
    args = dict(lam=p.lam, initial_slips=2)
    args.update(kwargs)
    lam = args.pop("lam")
    with pytest.raises(ValueError, match=match):
        uniqueness_study(p.system, p.load, lam, n_jobs=args.pop("n_jobs", 1), **args)
