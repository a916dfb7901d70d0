"""Shakedown bounds of a sparse system (issue 14): HiGHS on the sparse constraint matrix, lam1
by covering LPs and incumbent pruning (shakedown.bounds.highs_pruning), never densified."""

import numpy as np
import pytest
import scipy.sparse as sp

import shakedown as sd
from shakedown.bounds import highs_pruning
from shakedown.bounds.constraints import Scales, extreme_constraints

crack_networks = pytest.importorskip("crack_networks")


def network(n, radius, seed=1):
    cs = crack_networks.sample_crack_set(n, density=0.1, half_length=1, min_spacing=0.1,
                                         rng=seed)
    m = crack_networks.kachanov_model(cs, 1, 0.25, 0.6, interaction_radius=radius)
    return m, m.load_cycle((-1, 0, -1), (0, 1, 0))


@pytest.mark.parametrize("n, radius, seed", [(40, 3, 1), (80, 5, 2), (120, 8, 3)])
def test_sparse_bounds_equal_the_dense_twin_and_exact_highs(n, radius, seed):
    m, load = network(n, radius, seed)
    s = m.system
    assert s.is_sparse
    cs = extreme_constraints(s, load)
    assert sp.issparse(cs.G) and sp.issparse(cs.sep_G)
    b = sd.shakedown_bounds(s, load)
    d = sd.shakedown_bounds(s.to_dense(), load)
    e = sd.shakedown_bounds(s.to_dense(), load, solver="highs", intervals=True)
    for x in (d, e):
        assert b.lam2 == pytest.approx(x.lam2, rel=1e-7)
        assert b.lam1 == pytest.approx(x.lam1, rel=1e-7)
        assert b.lam_separation == pytest.approx(x.lam_separation, rel=1e-6)
    assert b.limiting_constraint == e.limiting_constraint
    # exact rows equal the exact intervals; the others are proven lower bounds >= lam1
    ex = b.lam_high_exact
    assert ex[b.limiting_constraint]
    np.testing.assert_allclose(b.lam_high[ex], e.lam_high[ex], rtol=1e-7)
    assert np.all(b.lam_high[~ex] <= e.lam_high[~ex] * (1 + 1e-7))
    assert np.all(b.lam_high >= b.lam1 * (1 - 1e-9))
    np.testing.assert_allclose(b.lam_low, 0.0, atol=1e-9)
    assert max(b.residuals.values()) < 1e-6
    assert b.safe_state.shape == (n,) and np.isfinite(b.safe_margin)


def test_sparse_bounds_units():
    m, load = network(60, 4, 5)
    s = m.system
    k, f = 3e7, 2e4  # stiffness and force units
    s2 = sd.DiscreteSystem(s.A * k, s.B * k, s.C * k, s.friction)
    parts = {key: getattr(load, key) * f for key in ("q_cos", "q_sin", "p_cos", "p_sin")
             if getattr(load, key) is not None}
    load2 = sd.LoadCycle.from_harmonics(load.q0 * f, load.p0 * f, **parts)
    a, b = sd.shakedown_bounds(s, load), sd.shakedown_bounds(s2, load2)
    assert b.lam1 == pytest.approx(a.lam1, rel=1e-8)
    assert b.lam2 == pytest.approx(a.lam2, rel=1e-8)
    np.testing.assert_allclose(b.safe_state, a.safe_state * f / k, rtol=1e-6,
                               atol=1e-8 * np.abs(a.safe_state).max() * f / k)


def test_tight_rows_rejects_a_point_off_the_face():
    """The vertex check behind every shared certificate: a point moved off the facets is not
    counted tight on them (and an infeasible point's violated rows are not tight either)."""
    m, load = network(30, 3, 7)
    cs = Scales.of(extreme_constraints(m.system, load))
    ch = cs.nondimensional(extreme_constraints(m.system, load))
    b = sd.shakedown_bounds(m.system, load)
    v = b.state_at_lam2 / cs.slip
    lam = b.lam2 / cs.load_factor
    tight = highs_pruning.tight_rows(ch, v, lam)
    assert tight.size >= 1
    k = int(tight[0])
    g = np.asarray(ch.G[k].todense()).ravel()
    moved = v - 1e-6 * g / np.dot(g, g)  # off row k's hyperplane, into the region
    assert k not in highs_pruning.tight_rows(ch, moved, lam)
    assert k not in highs_pruning.tight_rows(ch, v + 1e-6 * g / np.dot(g, g), lam)


@pytest.mark.parametrize("seed, never", [(4, True), (7, False)])
def test_sparse_lam1_zero_cases_take_the_exact_path(seed, never):
    """A facet redundant from lam = 0 on (never active) or first touched above 0: lam1 = 0,
    every interval exact, as on the dense path (the systems of tests/bounds/test_pruning.py)."""
    from test_pruning import _biased  # the same systems as the dense path's test

    d, load = _biased(seed)
    b = sd.shakedown_bounds(d.to_sparse(), load)
    e = sd.shakedown_bounds(d, load, solver="highs", intervals=True)
    assert b.lam1 == 0.0 and b.lam2 == pytest.approx(e.lam2, rel=1e-7) and b.lam2 > 0
    assert b.lam_high_exact.all() and b.limiting_constraint == e.limiting_constraint
    assert np.isnan(b.lam_high).any() == never
    np.testing.assert_allclose(b.lam_low, e.lam_low, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("skip", [("family_vertices",), ("family_vertices", "cover")])
def test_sparse_lam_low_paths_agree(monkeypatch, skip):
    """The lam_low phase without its cheap steps (the family points; then the covering LPs
    too): the per-row LPs alone give the same lam1 and every lam_low = 0."""
    m, load = network(50, 4, 9)
    ref = sd.shakedown_bounds(m.system, load)
    for name in skip:
        monkeypatch.setattr(highs_pruning, name, lambda *a, **k: 0)
    b = sd.shakedown_bounds(m.system, load)
    assert b.lam1 == pytest.approx(ref.lam1, rel=1e-9)
    assert b.limiting_constraint == ref.limiting_constraint
    np.testing.assert_allclose(b.lam_low, 0.0, atol=1e-9)
    assert b.n_lps > ref.n_lps  # the skipped steps did save LPs


def test_family_point_outside_the_region_decides_nothing():
    """A family point that violates a row of the other family proves nothing (wrong-answer check
    of the cheap covering step)."""
    m, load = network(30, 3, 7)
    cs0 = extreme_constraints(m.system, load)
    ch = Scales.of(cs0).nondimensional(cs0)
    lam_big = 50.0  # far beyond lam2: H is empty, no point can be in it
    undecided = np.ones(60, bool)
    highs_pruning.family_vertices(ch, lam_big, undecided)
    assert undecided.all()
    undecided = np.ones(60, bool)
    highs_pruning.family_vertices(ch, 0.0, undecided)
    assert not undecided.all()  # at lam = 0 under compression both family points are safe


def test_loose_sparse_answer_is_solved_again():
    """A simplex answer whose own certificate is loose (here: corrupted x, residual 1e-3) is
    solved again by interior point + crossover; the dense reference path keeps HiGHS's answer."""
    import dataclasses

    from shakedown.bounds.highs_path import HighsModel

    m, load = network(30, 3, 2)
    cs0 = extreme_constraints(m.system, load)
    ch = Scales.of(cs0).nondimensional(cs0)
    eng = HighsModel(ch)
    good = eng.run("max")
    real = eng.lp.solve
    calls = []

    def corrupt():
        ans = real()
        calls.append(ans)
        if len(calls) == 1:  # the first answer is off by 1e-3 in every slip
            return dataclasses.replace(ans, x=ans.x + 1e-3, primal_residual=1e-3)
        return ans

    eng.lp.solve = corrupt
    again = eng.run("max")
    assert eng.resolved == 1 and len(calls) == 2
    assert again.max_residual < 1e-6
    assert again.x[-1] == pytest.approx(good.x[-1], rel=1e-8)


@pytest.mark.parametrize("case", ["one node", "uncoupled", "frictionless"])
def test_sparse_extremes_equal_dense(case):
    """One node, B = 0 (lam1 = lam2, the frictional Melan theorem) and f = 0, sparse against
    dense: bounds and a cyclic run."""
    rng = np.random.default_rng(3)
    n = 1 if case == "one node" else 12
    M = rng.normal(size=(2 * n, 2 * n)) * (rng.random((2 * n, 2 * n)) < 0.2)
    K = M @ M.T + 2 * n * np.eye(2 * n)
    if case == "uncoupled":
        K[:n, n:] = 0.0
        K[n:, :n] = 0.0
    f = 0.0 if case == "frictionless" else 0.4
    d = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], f)
    s = d.to_sparse()
    load = sd.LoadCycle.from_harmonics(0.1 * rng.normal(size=n), np.full(n, 1.0),
                                       q_cos=rng.normal(size=n))
    a, b = sd.shakedown_bounds(s, load), sd.shakedown_bounds(d, load)
    assert a.status == b.status
    for name in ("lam1", "lam2"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x == y) or x == pytest.approx(y, rel=1e-7), name
    if case == "uncoupled":
        assert a.lam1 == pytest.approx(a.lam2, rel=1e-9)
    ra = sd.solve_cycles(s, load, 1.3, steps_per_cycle=16, max_cycles=30)
    rb = sd.solve_cycles(d, load, 1.3, steps_per_cycle=16, max_cycles=30)
    assert ra.status == rb.status
    np.testing.assert_allclose(ra.dissipation, rb.dissipation, rtol=1e-9,
                               atol=1e-12 * max(1.0, abs(rb.dissipation).max()))


def test_sparse_degenerate_twin_network():
    """A network and its uncoupled copy side by side (every constraint tied with its twin, a
    degenerate LP at every vertex): the same lam1 and lam2 as the single network."""
    m, load = network(25, 3, 6)
    s = m.system
    two = sd.DiscreteSystem(sp.block_diag([s.A, s.A]), sp.block_diag([s.B, s.B]),
                            sp.block_diag([s.C, s.C]), np.r_[s.friction, s.friction])
    parts = {k: np.hstack([getattr(load, k), getattr(load, k)])
             for k in ("q_cos", "q_sin", "p_cos", "p_sin") if getattr(load, k) is not None}
    load2 = sd.LoadCycle.from_harmonics(np.r_[load.q0, load.q0], np.r_[load.p0, load.p0], **parts)
    one, both = sd.shakedown_bounds(s, load), sd.shakedown_bounds(two, load2)
    assert two.is_sparse
    assert both.lam1 == pytest.approx(one.lam1, rel=1e-7)
    assert both.lam2 == pytest.approx(one.lam2, rel=1e-7)
    assert both.limiting_constraint % 25 == one.limiting_constraint % 25 or \
        both.lam_high[one.limiting_constraint] == pytest.approx(one.lam1, rel=1e-7)
