"""The upper bound of the 3-D lam2 from multipliers of any accuracy (shakedown.bounds.cones.dual).

What these tests prove: the bound the cone engine computes from cut multipliers is never below
the certified lower end of ``lam2`` (a safe state, checked over the continuous cycle), whatever
is done to the multipliers -- noise of any size, scaling of single cuts chosen to push the old
formula down, sign flips, moves out of the cones; the former rule (residuals up to 1e-6
accepted, ``h . z / D`` reported) accepts such multipliers with a bound below ``lam2``; the
a-priori state bound it rests on (``||E||_2`` proven by a Cholesky factorisation) refuses a wrong
estimate; and where no bound can be proven (``||E||_2 >= 1`` with a residual left) the answer is
``inf``, not a number.
"""

from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_cone_dense_ipm import random_3d, random_load  # (tests/bounds on the path)

import shakedown as sd
from shakedown.bounds.cones.data import cone_data
from shakedown.bounds.cones.dual import bound_of, certified_bound, coupling_norm, residual
from shakedown.bounds.cones.engine import cone_bounds
from shakedown.bounds.cones.socp import LAM_CAP, dual_bound, naive_bound
from shakedown.model.verified import certified_lower_eig, certified_upper_eig


@cache
def solved(seed):
    """A coupled 4-node system bracketed to 1e-9 by Clarabel: ``(data, bounds)``."""
    s, load = random_3d(4, 20 + seed), random_load(4, 30 + seed)
    b = cone_bounds(s, load, only=("lam2",), solver="clarabel", rtol=1e-9)
    assert b.lam2_upper - b.lam2_lower <= 1e-9 * b.lam2_upper
    assert sd.bounds.cones.certify.check_safe_state(s, load, b.state_at_lam2, b.lam2_lower)[0]
    return cone_data(s, load), b


def adversarial(d, nodes, times, z, t):
    """Every cut scaled by ``1 +- t`` (still in its cone), the signs chosen to lower the
    exact-multiplier formula ``h . z / D`` (its gradient)."""
    a1, b1 = d.periodic(times, nodes)
    col = np.column_stack([b1, a1])
    h = np.column_stack([d.b0[nodes], d.a0[nodes]])
    nb = naive_bound(d, nodes, times, z)
    g = (h * z).sum(1) + nb * (col * z).sum(1)
    return z * (1 - t * np.sign(g))[:, None]


def test_the_former_rule_accepts_a_bound_below_lam2_and_the_new_one_does_not():
    """Residual 9e-7 (< the former DUAL_TOL = 1e-6), multipliers inside their cones: the former
    formula proves a value below the certified lower end of lam2; the bound is above it."""
    for seed in range(3):
        d, b = solved(seed)
        c, L = b.certificate, d.load_factor
        z0 = c.multipliers
        zs = np.abs(z0).max()
        r1 = np.abs(residual(d, c.nodes, adversarial(d, c.nodes, c.times, z0, 1.0))
                    - residual(d, c.nodes, z0)).max() / zs
        z = adversarial(d, c.nodes, c.times, z0, 0.9e-6 / r1)
        hi, res = dual_bound(d, c.nodes, c.times, z)
        assert res["cone"] == 0 and 0.5e-6 < res["stationarity"] <= 1e-6  # accepted before
        assert naive_bound(d, c.nodes, c.times, z) * L < b.lam2_lower  # a wrong "proof"
        assert hi * L >= b.lam2_lower
        # and it stays close to the bracket: the multipliers were nearly right
        assert hi * L <= b.lam2_upper * (1 + 1e-5)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2), kind=st.sampled_from(["noise", "adversarial", "flip", "scale"]),
       size=st.floats(1e-12, 1.0), rs=st.integers(0, 2**31))
def test_no_perturbation_of_the_multipliers_proves_a_bound_below_lam2(seed, kind, size, rs):
    d, b = solved(seed)
    c, L = b.certificate, d.load_factor
    z = c.multipliers.copy()
    rng = np.random.default_rng(rs)
    if kind == "noise":
        z = z + size * np.abs(z).max() * rng.normal(size=z.shape)
    elif kind == "adversarial":
        z = adversarial(d, c.nodes, c.times, z, size)
    elif kind == "flip":
        k = rng.integers(0, z.size)
        z.reshape(-1)[k] *= -1 - size
    else:
        z = z * np.exp(size * rng.normal(size=(z.shape[0], 1)))
    y_cap = float(rng.random() * size) if rng.random() < 0.3 else 0.0
    hi, _ = dual_bound(d, c.nodes, c.times, z, y_cap)
    assert hi * L >= b.lam2_lower


def test_exact_multipliers_lose_nothing_and_the_bound_is_unit_free():
    """The polished bound of the engine's own multipliers stays within the bracket's width of
    the exact-multiplier formula; a system rescaled in force and stiffness proves the same."""
    d, b = solved(0)
    c, L = b.certificate, d.load_factor
    hi, parts = certified_bound(d, c.nodes, c.times, c.multipliers, cap=LAM_CAP)
    assert parts["residual"] < 1e-12 and 0 < parts["coupling_norm"] < 1
    assert b.lam2_lower <= hi * L <= b.lam2_upper * (1 + 1e-9)
    s, load = random_3d(4, 20), random_load(4, 30)
    s2 = sd.DiscreteSystem(1e9 * s.A, 1e9 * s.B, 1e9 * s.C, friction=s.friction, dim=3)
    l2 = sd.LoadCycle.from_harmonics(q0=1e-5 * load.q0, p0=1e-5 * load.p0,
                                     q_cos=1e-5 * load.q_cos, q_sin=1e-5 * load.q_sin,
                                     p_cos=1e-5 * load.p_cos, p_sin=1e-5 * load.p_sin)
    d2 = cone_data(s2, l2)
    hi2, _ = certified_bound(d2, c.nodes, c.times, c.multipliers, cap=LAM_CAP)
    np.testing.assert_allclose(hi2 * d2.load_factor, hi * L, rtol=1e-12)


def test_coupling_norm_is_proven_and_refuses_a_wrong_estimate():
    d, _ = solved(1)
    e = coupling_norm(d.E)
    exact = np.linalg.norm(d.E, 2)
    assert exact <= e <= exact * (1 + 1e-6)
    G = d.E @ d.E.T
    lmin, lmax = np.linalg.eigvalsh(G)[[0, -1]]
    assert certified_upper_eig(G, lmax) >= lmax
    assert certified_upper_eig(G, 0.5 * lmax) == np.inf  # a wrong estimate is refused
    assert certified_lower_eig(G, 2.0 * lmin + 1e-3 * lmax) == -np.inf
    assert certified_lower_eig(G, lmin) <= lmin
    assert coupling_norm(None) == 0.0


def test_no_bound_without_a_state_bound():
    """With a state bound that does not hold (e = ||E||_2 >= 1 claimed) a residual left in the
    multipliers cannot be charged against the state, so the bound is inf, not a number; with
    the proven e the same multipliers prove a bound above lam2."""
    d, b = solved(2)
    c = b.certificate
    z = c.multipliers * (1 + 1e-3 * np.random.default_rng(0).normal(size=(c.multipliers.shape[0], 1)))
    hi, parts = bound_of(d, c.nodes, c.times, z, cap=LAM_CAP, e=1.5)
    assert hi == np.inf and parts["residual"] > 0
    hi, _ = bound_of(d, c.nodes, c.times, z, cap=LAM_CAP)
    assert np.isfinite(hi) and hi * d.load_factor >= b.lam2_lower


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_multipliers_prove_nothing(bad):
    d, b = solved(0)
    c = b.certificate
    z = c.multipliers.copy()
    z[0, 1] = bad
    assert dual_bound(d, c.nodes, c.times, z)[0] == np.inf


def test_an_open_bracket_without_violated_cuts_is_closed_by_the_dense_path(monkeypatch):
    """Clarabel's multipliers spoiled by 1e-6 relative noise certify its value only to ~1e-6:
    with no cut violated the bracket is then closed by the active cuts alone on the dense path
    (``melan._tighten``), to the rtol asked, not left open."""
    from dataclasses import replace

    from shakedown.bounds.cones import melan

    orig = melan.solve_round
    rng = np.random.default_rng(0)
    spoiled = []

    def noisy(*args, **kw):
        ans, bound = orig(*args, **kw)
        if kw.get("solver") == "clarabel" and ans.z is not None:
            spoiled.append(1)
            ans = replace(ans, z=ans.z * (1 + 1e-6 * rng.standard_normal(ans.z.shape)))
        return ans, bound

    monkeypatch.setattr(melan, "solve_round", noisy)
    s, load = random_3d(4, 21), random_load(4, 31)
    b = cone_bounds(s, load, only=("lam2",), solver="clarabel", rtol=1e-8)
    assert spoiled
    assert b.status == "bounded", b.message
    assert b.lam2_upper - b.lam2_lower <= 1e-8 * b.lam2_upper
    assert sd.bounds.cones.certify.check_safe_state(s, load, b.state_at_lam2, b.lam2_lower)[0]
