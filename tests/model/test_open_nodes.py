"""``condense_open``: the system of the closed nodes with the open ones free (issue 23: the
bounds of a bolted lap joint whose rim the preload opens)."""

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution.cone_step import ConeStepSolver
from shakedown.model.errors import InputError
from shakedown.model.open_nodes import condense_open


def _random(n, dim, seed):
    rng = np.random.default_rng(seed)
    m = (dim - 1) * n + n
    G = rng.normal(size=(m, m))
    K = G @ G.T + m * np.eye(m)
    k = (dim - 1) * n
    s = sd.DiscreteSystem(K[:k, :k], K[:k, k:], K[k:, k:], 0.4, dim=dim)
    shape = (n, 2) if dim == 3 else (n,)
    load = sd.LoadCycle.from_harmonics(rng.normal(size=shape), 2.0 + rng.random(n),
                                       q_cos=rng.normal(size=shape), p_sin=rng.normal(size=n))
    return s, load, K


@pytest.mark.parametrize("dim", [2, 3])
def test_schur_complement_is_the_inverse_of_the_compliance_block(dim):
    """Independent check: ``(K^-1)_cc = (K_cc - K_co K_oo^-1 K_oc)^-1``; the welded reactions
    of the closed nodes follow from the same identity."""
    s, load, K = _random(6, dim, 1)
    closed = [0, 2, 5]
    cs = condense_open(s, load, closed)
    n = 6
    c = np.array(closed)
    if dim == 3:
        ic = np.r_[np.stack([2 * c, 2 * c + 1], -1).ravel(), 2 * n + c]
    else:
        ic = np.r_[c, n + c]
    Fc = np.linalg.inv(K)[np.ix_(ic, ic)]
    np.testing.assert_allclose(cs.system.K, np.linalg.inv(Fc), rtol=1e-10, atol=1e-10 * np.abs(K).max())
    # r_c' = K' (K^-1 r)_c: the closed nodes' welded reaction reproduces the full displacement
    r = np.r_[np.asarray(load.q0).ravel(), load.p0]
    rc = np.r_[np.asarray(cs.load.q0).ravel(), cs.load.p0]
    np.testing.assert_allclose(rc, cs.system.K @ (np.linalg.solve(K, r)[ic]), rtol=1e-9,
                               atol=1e-9 * np.abs(r).max())
    assert cs.open.tolist() == [1, 3, 4] and cs.system.dim == dim


def test_keeping_every_node_changes_nothing():
    s, load, _ = _random(4, 3, 2)
    cs = condense_open(s, load, range(4))
    np.testing.assert_array_equal(cs.system.K, s.K)
    np.testing.assert_array_equal(cs.load.q_cos, load.q_cos)
    assert cs.open.size == 0


def test_sampled_load_is_condensed_sample_by_sample():
    s, load, _ = _random(5, 3, 3)
    cs_h = condense_open(s, load, [1, 4])
    cs_s = condense_open(s, load.to_samples(8), [1, 4])
    t = np.arange(8) / 8
    for a, b in zip(cs_h.load.evaluate(t, 0.7), cs_s.load.evaluate(t, 0.7), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_step_on_the_closed_nodes_reproduces_the_full_step():
    """A 3-D step whose solution opens some nodes: the same step on the closed nodes alone gives
    the same reactions, and ``open_displacements`` the open nodes' slips and gaps."""
    n = 8
    rng = np.random.default_rng(4)
    s, _, _ = _random(n, 3, 4)
    p0 = np.where(np.arange(n) % 3 == 0, -3.0, 4.0)  # every third node pulled open
    load = sd.LoadCycle.from_harmonics(0.3 * rng.normal(size=(n, 2)), p0,
                                       q_cos=rng.normal(size=(n, 2)))
    res = ConeStepSolver(s).solve(np.zeros((n, 2)), load.q0, load.p0)
    assert res.success
    closed = np.flatnonzero(res.gap <= 0)
    assert 0 < closed.size < n
    cs = condense_open(s, load, closed)
    sub = ConeStepSolver(cs.system).solve(np.zeros((closed.size, 2)), cs.load.q0, cs.load.p0)
    scale = np.abs(res.p).max()
    np.testing.assert_allclose(sub.p, res.p[closed], atol=1e-9 * scale)
    np.testing.assert_allclose(sub.q, res.q[closed], atol=1e-9 * scale)
    slip_o, gap_o = cs.open_displacements(sub.slip, sub.gap, [0.25], 0.0)
    np.testing.assert_allclose(gap_o[0], res.gap[cs.open], rtol=1e-8)
    np.testing.assert_allclose(slip_o[0], res.slip[cs.open], atol=1e-9 * np.abs(res.gap).max())
    assert np.all(cs.open_gaps(sub.slip, sub.gap, 0.0) > 0)


@pytest.mark.parametrize("closed, match", [
    ([], "at least one node"), ([0, 9], r"0\.\.3"), ([-1], r"0\.\.3"), ("ab", "node indices"),
])
def test_bad_closed_sets_are_refused(closed, match):
    s, load, _ = _random(4, 3, 5)
    with pytest.raises(InputError, match=match):
        condense_open(s, load, closed)


def test_load_of_another_system_is_refused():
    s, _, _ = _random(4, 3, 6)
    _, other, _ = _random(5, 3, 6)
    with pytest.raises(InputError, match="same model"):
        condense_open(s, other, [0])


def test_open_nodes_carry_no_reaction_in_any_state_of_the_closed_ones():
    """For any slips and gaps of the closed nodes, the open nodes' displacements from
    ``open_displacements`` leave them without reaction (q = 0, p = 0) at every instant."""
    n = 6
    s, load, _ = _random(n, 3, 7)
    cs = condense_open(s, load, [0, 3, 4])
    rng = np.random.default_rng(8)
    vc, wc = rng.normal(size=(3, 2)), rng.random(3)
    t = np.array([0.0, 0.3, 0.71])
    slip_o, gap_o = cs.open_displacements(vc, wc, t, 1.3)
    for k in range(t.size):
        v = np.zeros((n, 2))
        w = np.zeros(n)
        v[cs.closed], w[cs.closed] = vc, wc
        v[cs.open], w[cs.open] = slip_o[k], gap_o[k]
        qw, pw = load.evaluate(t[k], 1.3)
        q, p = s.reactions(v, w, qw, pw)
        scale = np.abs(s.K).max() * (np.abs(vc).max() + 1)
        np.testing.assert_allclose(q[cs.open], 0.0, atol=1e-10 * scale)
        np.testing.assert_allclose(p[cs.open], 0.0, atol=1e-10 * scale)
        # and the closed nodes' reactions are those of the condensed system
        qc, pc = cs.system.reactions(vc, wc, *cs.load.evaluate(t[k], 1.3))
        np.testing.assert_allclose(q[cs.closed], qc, atol=1e-10 * scale)
        np.testing.assert_allclose(p[cs.closed], pc, atol=1e-10 * scale)
