"""Bad arrays and numbers at the public entry points (issue 10, items 2, 6, 7, 9).

Each case failed before the checks were added (raw ValueError/TypeError, silent acceptance, a
memory corruption in LAPACK for NaN, a 'periodic' run with W = nan) and now ends in a subclass
of ``shakedown.InputError`` naming the field, or a result whose status says what failed.
"""

from __future__ import annotations

import numpy as np
import pytest

import shakedown as sd
from shakedown import stability as st


@pytest.fixture(scope="module")
def two_node():
    # the built-in scene two_node_coupled (seed 002 Fig. 4 type system)
    s = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                          [[1.5, 0.2], [0.2, 1.5]], 0.7)
    load = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0],
                                       q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
    return s, load


# ------------------------------------------------------------------ item 7: model objects
@pytest.mark.parametrize("blocks, match", [
    ((np.zeros((0, 0)),) * 3, "at least one contact node"),
    ((np.array([[2.0 + 1e-3j]]), [[0.0]], [[1.0]]), "A must be a real 2-D array; got complex"),
    ((np.diag([1.0, 1e-16]), np.zeros((2, 2)), np.eye(2)), "numerically singular"),
])
def test_system_refuses_empty_complex_singular(blocks, match):
    with pytest.raises(sd.InputError, match=match):
        sd.DiscreteSystem(*blocks, friction=0.3)


def test_condition_limit_is_not_scale_dependent():
    # the same well-conditioned K (cond 1e8) at any unit is accepted; cond 1e16 never is
    for c in (1e-6, 3.7e4, 1e12):
        sd.DiscreteSystem(c * np.diag([1.0, 1e-8]), np.zeros((2, 2)), c * np.eye(2), 0.3)
        with pytest.raises(sd.NotPositiveDefiniteError, match="numerically singular"):
            sd.DiscreteSystem(c * np.diag([1.0, 1e-16]), np.zeros((2, 2)), c * np.eye(2), 0.3)


def test_load_cycle_counts_and_permutations(two_node):
    _, load = two_node
    for bad in (float("nan"), 2.5, True, "10", 1):
        with pytest.raises(sd.InputError, match="n_samples must be an integer >= 2"):
            load.to_samples(bad)
    for order in ([0, 0], [1], [0, 2], [0.0, 1.0], "ab"):
        with pytest.raises(sd.InputError, match="order must be a permutation of 0..1"):
            load.permuted(order)
    assert np.array_equal(load.permuted([1, 0]).q_cos[0], [0.0, 0.5])
    with pytest.raises(sd.ShapeError, match="at least one node"):
        sd.LoadCycle.from_harmonics([], [])


@pytest.mark.parametrize("kw", [dict(steps_per_cycle=float("nan")), dict(max_cycles=np.inf),
                                dict(steps_per_cycle="200")])
def test_cycle_counts(two_node, kw):
    with pytest.raises(sd.InputError, match="must be an integer"):
        sd.solve_cycles(*two_node, 0.5, **kw)


def test_fe_mesh_sizes():
    for args in ((np.inf, 1.0, 2, 2), (1.0, np.nan, 2, 2), (1.0, 1.0, np.nan, 2)):
        with pytest.raises(sd.InputError, match="must be a finite number > 0|must be an integer"):
            sd.fe.rectangle(*args)
    with pytest.raises(sd.InputError, match="origin"):
        sd.fe.rectangle(1.0, 1.0, 2, 2, origin=(0.0, np.inf))


# ------------------------------------------------------------------ item 2: stability
def stiffness(two_node):
    return np.array(two_node[0].K)


def test_mceip_nan_never_reaches_lapack(two_node):
    K = stiffness(two_node)
    K[0, 0] = np.nan
    part = st.NodePartition.all_slip(2, chi=np.array([1.0, -1.0]))
    for method in st.METHODS:
        with pytest.raises(sd.InputError, match="K must be finite"):
            st.mceip_mu(K, part, method=method)
    # the process is intact: a good call still gives the same answer as before
    assert st.mceip_mu(stiffness(two_node), part).status in ("found", "none")


@pytest.mark.parametrize("mutate, err, match", [
    (lambda K: K + np.triu(np.ones_like(K), 1), sd.NotSymmetricError, "K must be symmetric"),
    (lambda K: -K, sd.NotPositiveDefiniteError, "positive definite"),
    (lambda K: K.astype(complex), sd.InputError, "complex"),
    (lambda K: K[:3, :3], sd.ShapeError, r"\(2N, 2N\)"),
])
def test_mceip_refuses_bad_stiffness(two_node, mutate, err, match):
    part = st.NodePartition.all_slip(2, chi=np.array([1.0, 1.0]))
    with pytest.raises(err, match=match):
        st.mceip_mu(mutate(stiffness(two_node)), part)


def test_friction_profile_and_pencil_checks(two_node):
    part = st.NodePartition.all_slip(2, chi=np.array([1.0, 1.0]))
    with pytest.raises(sd.ShapeError, match=r"friction_profile must have shape \(2,\)"):
        st.mceip_mu(two_node[0], part, friction_profile=[1.0, 1.0, 1.0])
    with pytest.raises(sd.InputError, match="friction_profile must be finite"):
        st.mceip_mu(two_node[0], part, friction_profile=[1.0, np.nan])
    with pytest.raises(sd.InputError, match="K0 must be finite"):
        st.SlipPencil(np.array([[np.nan]]), np.eye(1), np.arange(1), np.ones(1), np.ones(1))
    with pytest.raises(sd.InputError, match="K1 must be finite"):
        st.linear_dense(st.SlipPencil(np.eye(1), np.array([[np.inf]]), np.arange(1),
                                      np.ones(1), np.ones(1)))
    with pytest.raises(sd.InputError, match="must be finite"):
        st.restricted_eigenpairs(np.eye(2), np.array([[0.0, np.nan], [1.0, 0.0]]))
    with pytest.raises(sd.InputError, match="K\\(s = 0\\) must be finite"):
        st.mceip_mu(lambda s: np.full((4, 4), np.nan), part)


# ------------------------------------------------------------------ item 6: overflow
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the overflow itself warns
def test_overflow_is_a_failure(two_node):
    run = sd.solve_cycles(*two_node, 1e200, max_cycles=3)
    assert run.status == "non_finite" and not run.success and not run.shook_down
    assert "not finite" in run.message and "units" in run.message
    # a large but representable load factor is still an ordinary run
    assert sd.solve_cycles(*two_node, 1e100, max_cycles=3).status != "non_finite"
    # a load factor whose welded reactions are not even representable is refused up front
    with pytest.raises(sd.InputError, match="welded reactions overflow"):
        sd.solve_cycles(two_node[0], two_node[1].scaled(1e10), 1e300)


# ------------------------------------------------------------------ item 9: sampling error
def test_harmonic_sampling_error_closed_form():
    # worst case over the phase of one harmonic, measured on a fine grid: a (1 - cos(pi k/S))
    S, amp, k = 7, 1.3, 2
    t = np.linspace(0.0, 1.0, 100_001)
    worst = 0.0
    for phase in np.linspace(0.0, 1.0 / (k * S), 41):
        ang = 2 * np.pi * phase
        load = sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[[0.0], [amp * np.cos(ang)]],
                                           q_sin=[[0.0], [amp * np.sin(ang)]])
        worst = max(worst, np.abs(load.periodic(t)[0] - load.to_samples(S).periodic(t)[0]).max())
    err_q, err_p = load.sampling_error(S)
    # the grid of 1e5 points resolves the peak to (2 pi k 1e-5)^2 / 2 ~ 1e-8 relative
    assert err_q[0] == pytest.approx(worst, rel=1e-6)
    assert err_q[0] == pytest.approx(amp * (1 - np.cos(np.pi * k / S)), rel=1e-15)
    assert err_p[0] == 0.0


def test_sampled_samples_error_is_exact():
    load = sd.LoadCycle.from_samples([0.0], [1.0], [[0.0], [1.0], [0.5]], [[0.0], [0.0], [0.0]])
    assert load.sampling_error(6)[0][0] == 0.0  # the samples are a subset of the new grid
    assert load.sampling_error(4)[0][0] == pytest.approx(0.25, abs=1e-15)  # peak at t=1/3 missed


def test_shakedown_within_sampling_error_is_flagged(two_node):
    s, load = two_node
    lam2 = sd.shakedown_bounds(s, load).lam2
    # just above lam2 every initial state must keep slipping; 200 samples per period cut the
    # harmonic peak by 0.5 * (1 - cos(pi / 200)) ~ 6e-5 per unit lam, so some runs shake down
    flagged = 0
    for v0 in ([0.9, -0.3], [-0.2, 0.6], [0.3, 0.3], [-0.8, -0.1]):
        run = sd.solve_cycles(s, load, lam2 * (1 + 1e-5), initial_slip=v0)
        assert run.sampling_error == pytest.approx(
            lam2 * (1 + 1e-5) * 0.5 * (1 - np.cos(np.pi / 200)), rel=1e-12)
        if run.shook_down:
            assert run.within_sampling_error and "within the load's sampling error" in run.message
            flagged += 1
    assert flagged >= 1
    # far below lam1 a shakedown is certain and not flagged
    run = sd.solve_cycles(s, load, 0.2)
    assert run.shook_down and not run.within_sampling_error
