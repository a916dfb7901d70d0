"""Stability check (MCEIP) on hand-made and random systems: classification, condensation,
cross-method agreement, verification, bad input.  MODEL.md s.5; seed 000 s.5-6; seed 001."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.model.errors import InputError, ShapeError
from shakedown.stability import (
    NodePartition,
    classify_nodes,
    classify_state,
    enumerate_solutions,
    mceip_mu,
    mceip_mu_all,
    residuals,
    slip_pencil,
)

# Verification tolerance of exact (dense) answers: relative residuals of a QZ solve are
# O(n eps cond) ~ 1e-13 here; 1e-9 leaves four orders of margin.
EXACT_TOL = 1e-9


def random_spd(rng, m, shift=0.3):
    a = rng.normal(size=(m, m))
    return a @ a.T + shift * np.eye(m)


# ----------------------------------------------------------------------------- classification
def test_classification_states_and_directions():
    # MODEL.md s.1/s.5: q = -f p is forward slip (chi = +1), q = +f p backward (chi = -1)
    gap = [0.0, 0.0, 0.0, 0.2, 0.0]
    p = [2.0, 2.0, 2.0, 0.0, 1.0]
    q = [-1.0, 1.0, 0.3, 0.0, 0.0]
    f = [0.5, 0.5, 0.5, 0.5, 0.0]
    part = classify_nodes(gap, q, p, f)
    assert part.states.tolist() == ["slip", "slip", "stick", "free", "frictionless"]
    assert part.chi.tolist() == [1.0, -1.0, 0.0, 0.0, 0.0]
    assert part.slip.tolist() == [0, 1]
    tab = part.table()
    assert list(tab.columns) == ["node", "state", "chi", "margin", "borderline"]


def test_classification_tolerance_and_borderline():
    # |q| = f p - 1e-6: stick with the default rtol 1e-7, slip with rtol 1e-5, borderline both
    q, p, f = [-(1.0 - 1e-6)], [2.0], [0.5]
    tight = classify_nodes([0.0], q, p, f)
    loose = classify_nodes([0.0], q, p, f, rtol=1e-5)
    assert tight.states[0] == "stick" and loose.states[0] == "slip"
    assert tight.borderline.tolist() == [0]
    assert "close to slip" in tight.borderline_reasons[0]
    # grazing node: closed, no reactions -> free and reported
    g = classify_nodes([0.0, 0.0], [0.0, -1.0], [0.0, 2.0], 0.5)
    assert g.states.tolist() == ["free", "slip"]
    assert "grazing" in g.borderline_reasons[0]


def test_classify_state_uses_system_reactions():
    s = sd.DiscreteSystem([[2.0]], [[0.5]], [[3.0]], friction=0.4)
    # v = 1: q = q_w + 2 = -0.4 * p with p = p_w + 0.5
    part = classify_state(s, [1.0], [0.0], [-2.0 - 0.4 * 2.5], [2.0])
    assert part.states[0] == "slip" and part.chi[0] == 1.0


def test_classification_bad_input():
    with pytest.raises(ShapeError, match="q must have shape"):
        classify_nodes([0.0, 0.0], [1.0], [1.0, 1.0], 0.3)
    with pytest.raises(InputError, match="friction must be >= 0"):
        classify_nodes([0.0], [1.0], [1.0], -0.3)
    with pytest.raises(InputError, match="compression positive"):
        classify_nodes([0.0], [0.3], [-1.0], 0.3)
    with pytest.raises(InputError, match="chi is required"):
        NodePartition.from_states(["slip"])
    with pytest.raises(InputError, match="states must be in"):
        NodePartition.from_states(["sliding"], 1.0)


# ----------------------------------------------------------------------------- condensation
def test_single_node_critical_friction_and_sign_convention():
    # One node, K = [[A, B], [B, C]]: y = chi q' + mu p' = (A + mu chi B) x  ->  mu* = A/|B|
    # in the direction chi = -sign(B) (MODEL.md s.5); the opposite direction is stable.
    K = np.array([[2.0, 0.5], [0.5, 3.0]])
    r = mceip_mu(K, NodePartition.all_slip(1, chi=-1.0))
    assert r.found and r.minimal and r.mu == pytest.approx(4.0, rel=1e-14)
    assert mceip_mu(K, NodePartition.all_slip(1, chi=1.0)).status == "none"
    # agrees with Klarbring's single-node critical friction of the DiscreteSystem
    s = sd.DiscreteSystem([[2.0]], [[0.5]], [[3.0]], friction=1.0)
    assert s.critical_friction().factor == pytest.approx(r.mu, rel=1e-14)


def test_pencil_schur_complement_matches_constrained_solve():
    rng = np.random.default_rng(3)
    n = 5
    K = random_spd(rng, 2 * n)
    part = NodePartition.from_states(["slip", "free", "stick", "slip", "frictionless"],
                                     [1.0, 0, 0, -1.0, 0])
    pen = slip_pencil(K, part)
    # impose v' on the slip nodes, zero on stick DOFs and slip normals; free DOFs unloaded
    v = np.array([0.7, -0.2])
    fixed = {0: v[0], 3: v[1], 2: 0.0, 2 + n: 0.0, 0 + n: 0.0, 3 + n: 0.0, 4 + n: 0.0}
    free_dofs = [1, 1 + n, 4]
    u = np.zeros(2 * n)
    for k, val in fixed.items():
        u[k] = val
    kf = np.ix_(free_dofs, free_dofs)
    u[free_dofs] = np.linalg.solve(K[kf], -K[np.ix_(free_dofs, list(fixed))] @ u[list(fixed)])
    r = K @ u
    assert np.allclose(r[free_dofs], 0, atol=1e-12)
    chi = np.array([1.0, -1.0])
    x = chi * v
    mu = 0.37
    y_expected = chi * r[[0, 3]] + mu * r[[0 + n, 3 + n]]
    assert np.allclose(pen.matrix(mu) @ x, y_expected, rtol=1e-12, atol=1e-12)
    assert np.allclose(pen.K0, pen.K0.T) and np.linalg.eigvalsh(pen.K0)[0] > 0


def test_pencil_bad_input():
    K = np.eye(4)
    with pytest.raises(ShapeError, match=r"\(2N, 2N\) = \(6, 6\)"):
        slip_pencil(K, NodePartition.all_slip(3, 1.0))
    with pytest.raises(InputError, match="no slip node"):
        slip_pencil(K, NodePartition.from_states(["stick", "free"]))
    with pytest.raises(InputError, match="needs a mass"):
        slip_pencil(K, NodePartition.all_slip(2, 1.0), lam=1.0)
    with pytest.raises(InputError, match="NodePartition"):
        slip_pencil(K, ["slip", "slip"])
    with pytest.raises(InputError, match="method must be one of"):
        mceip_mu(K, NodePartition.all_slip(2, 1.0), method="magic")
    with pytest.raises(InputError, match="partition is required"):
        mceip_mu(K)
    with pytest.raises(InputError, match="max_nodes"):
        mceip_mu(np.eye(40), NodePartition.all_slip(20, 1.0), method="enumeration", max_nodes=16)


# ----------------------------------------------------------------------------- cross-method
def _check_solution(pen, r, tol=EXACT_TOL):
    """Independent check of the MCEIP conditions (not via r's own residual fields)."""
    x = np.zeros(pen.size)
    x[:] = r.mode
    y = pen.matrix(r.mu) @ x
    scale = np.abs(pen.matrix(r.mu)).sum(axis=1).max()
    assert x.min() >= -tol and x.max() == pytest.approx(1.0)
    assert y.min() >= -tol * scale
    assert np.abs(x * y).max() <= tol * scale
    assert r.mu > 0


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 6))
def test_random_systems_every_answer_verified_and_enumeration_minimal(seed, n):
    rng = np.random.default_rng(seed)
    K = random_spd(rng, 2 * n)
    pen = slip_pencil(K, NodePartition.all_slip(n, rng.choice([-1.0, 1.0], n)))
    sols = enumerate_solutions(pen)
    best = mceip_mu(pen, method="enumeration")
    if sols:
        assert best.mu == sols[0].mu and best.minimal
    else:
        assert best.status == "none"
    for r in sols:
        _check_solution(pen, r)
    # every other method: if it returns a solution it is verified, it is one of the
    # enumerated solutions, and it is not below the certified minimum
    for method in ("linear-dense", "power", "active-set"):
        r = mceip_mu(pen, method=method)
        if r.found:
            _check_solution(pen, r)
            assert r.mu >= best.mu * (1 - 1e-9)
            assert any(abs(r.mu - s.mu) <= 1e-8 * s.mu for s in sols)


def test_random_systems_power_iteration_agreement_rate():
    # the power iteration has no convergence proof (seed 000 s.6); on random dense systems
    # it reaches the certified minimum in most cases.  Count agreements on 60 fixed systems.
    rng = np.random.default_rng(2024)
    agree = found = 0
    for _ in range(60):
        n = int(rng.integers(2, 6))
        pen = slip_pencil(random_spd(rng, 2 * n), NodePartition.all_slip(n, 1.0))
        e = mceip_mu(pen, method="enumeration")
        if not e.found:
            continue
        found += 1
        p = mceip_mu(pen, method="power")
        agree += p.found and abs(p.mu - e.mu) <= 1e-9 * e.mu
    assert found >= 30
    # measured on these 60 fixed systems: 52 with a solution, the power iteration finds one on
    # 41 and the certified minimum on 40 (77%); 70% leaves room for a change of start vector
    # without accepting an iteration that fails on a third of the cases
    assert agree >= 0.7 * found


def test_residuals_detect_violations():
    K = np.array([[2.0, 0.0, 0.5, 0.0], [0.0, 2.0, 0.0, 0.5],
                  [0.5, 0.0, 3.0, 0.0], [0.0, 0.5, 0.0, 3.0]])
    pen = slip_pencil(K, NodePartition.all_slip(2, -1.0))
    x, y, J, res, sign, comp = residuals(pen, 4.0, [1.0, 1.0])
    assert res < 1e-15 and sign == 0 and comp < 1e-15
    _, _, _, res, _, _ = residuals(pen, 3.0, [1.0, 1.0])
    assert res > 0.05  # wrong mu: the eigen-equation fails
    _, _, _, _, sign, _ = residuals(pen, 4.0, [1.0, -0.5])
    assert sign >= 0.5  # negative slip


def test_mceip_all_lists_branches_sorted():
    rng = np.random.default_rng(7)
    for _ in range(20):
        K = random_spd(rng, 8)
        sols = mceip_mu_all(K, NodePartition.all_slip(4, 1.0))
        if len(sols) >= 2:
            break
    assert len(sols) >= 2
    mus = [s.mu for s in sols]
    assert mus == sorted(mus) and all(s.verified for s in sols)
