"""Shakedown-bounds engine: cross-checks, certificates, extremes and bad input (MODEL.md s.3).

Tolerances: the engine's LP answers are vertices computed in double precision and certified
to residuals <= 1e-7 (``dense_lp.CERT_TOL``); on the well-conditioned random systems used here
the vertices agree with an independent vertex computation to ~1e-12, so 1e-8 relative leaves
four orders of margin.  HiGHS works to its default feasibility tolerance 1e-7, so comparisons
with HiGHS answers use 1e-6.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import shakedown as sd
from shakedown.bounds import extreme_constraints, safe_region, shakedown_bounds


def random_problem(n, seed=0, friction=0.3, coupling=0.3, harmonics=1):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n)) / np.sqrt(2 * n)
    K = M @ M.T + np.eye(2 * n)
    system = sd.DiscreteSystem(K[:n, :n], coupling * K[:n, n:], K[n:, n:], friction)
    shape = (harmonics, n)
    load = sd.LoadCycle.from_harmonics(
        0.1 * rng.standard_normal(n), 1 + rng.random(n),
        q_cos=rng.standard_normal(shape), q_sin=rng.standard_normal(shape),
        p_cos=0.3 * rng.standard_normal(shape),
    )
    return system, load


def brute_force(cs):
    """lam2 and activity intervals from every vertex of P = {(v, lam): G v - m lam <= c, lam >= 0}
    (all (N+1)-subsets of the 2N+1 rows; no LP)."""
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0]])
    b = np.r_[cs.c, 0.0]
    verts, tight = [], []
    for S in itertools.combinations(range(2 * n + 1), n + 1):
        M = A[list(S)]
        if abs(np.linalg.det(M)) < 1e-12:
            continue
        x = np.linalg.solve(M, b[list(S)])
        slack = b - A @ x
        if np.all(slack >= -1e-10 * (1 + np.abs(b))):
            verts.append(x)
            tight.append(np.abs(slack) <= 1e-10 * (1 + np.abs(b)))
    verts, tight = np.array(verts), np.array(tight)
    lam2 = verts[:, -1].max()
    lo = np.array([verts[tight[:, k], -1].min() if tight[:, k].any() else np.nan
                   for k in range(2 * n)])
    hi = np.array([verts[tight[:, k], -1].max() if tight[:, k].any() else np.nan
                   for k in range(2 * n)])
    return lam2, lo, hi


def check_certificate(b):
    """The lam2 certificate: G^T y = 0, y >= 0, lam2 = c.y / (-m.y) (Farkas for lam > lam2)."""
    cs, y = b.constraints, b.certificate
    scale = np.abs(cs.G).max() * np.abs(y).max()
    assert np.all(y >= -1e-12 * np.abs(y).max())
    assert np.abs(cs.G.T @ y).max() <= 1e-9 * scale
    assert np.isclose(cs.c @ y / (-(cs.m @ y)), b.lam2, rtol=1e-9)
    # the state at lam2 is safe and tight where y > 0 (complementarity)
    slack = cs.offsets(b.lam2) - cs.G @ b.state_at_lam2
    assert slack.min() >= -1e-9 * (1 + np.abs(cs.c).max())
    assert np.abs(y * slack).max() <= 1e-9 * np.abs(y).max() * (1 + np.abs(cs.c).max())


# ---------------------------------------------------------------------- cross-checks
@pytest.mark.parametrize("n", [2, 3])
@pytest.mark.parametrize("seed", range(6))
def test_vertex_enumeration(n, seed):
    system, load = random_problem(n, seed, coupling=0.5)
    b = shakedown_bounds(system, load, intervals=True)
    lam2, lo, hi = brute_force(b.constraints)
    assert b.lam2 == pytest.approx(lam2, rel=1e-8)
    np.testing.assert_allclose(b.lam_high, hi, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(b.lam_low, lo, rtol=1e-8, atol=1e-12)
    check_certificate(b)


@pytest.mark.parametrize("seed", range(3))
def test_against_cvxpy(seed):
    cp = pytest.importorskip("cvxpy")
    system, load = random_problem(6, seed, harmonics=2)
    b = shakedown_bounds(system, load, adjacency=False, intervals=True)
    cs = extreme_constraints(system, load)
    n = cs.n_nodes

    def solve(sense, extra=()):
        v, lam = cp.Variable(n), cp.Variable()
        cons = [cs.G @ v <= cs.c + lam * cs.m, lam >= 0]
        cons += [cs.G[k] @ v == cs.c[k] + lam * cs.m[k] for k in extra]
        p = cp.Problem(sense(lam), cons)
        p.solve(solver=cp.HIGHS)
        return p.value if p.status == "optimal" else np.nan

    assert b.lam2 == pytest.approx(solve(cp.Maximize), rel=1e-8)
    hi = np.array([solve(cp.Maximize, (k,)) for k in range(2 * n)])
    lo = np.array([solve(cp.Minimize, (k,)) for k in range(2 * n)])
    np.testing.assert_allclose(b.lam_high, hi, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(b.lam_low, lo, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("n,seed", [(4, 0), (12, 1), (40, 2)])
def test_auto_agrees_with_highs(n, seed):
    system, load = random_problem(n, seed)
    a = shakedown_bounds(system, load, adjacency=True, intervals=True)
    h = shakedown_bounds(system, load, solver="highs", adjacency=True)
    assert a.status == h.status == "bounded"
    for name in ("lam1", "lam2", "lam_adj", "lam_separation", "safe_margin"):
        assert getattr(a, name) == pytest.approx(getattr(h, name), rel=1e-6), name
    assert a.adjacency_node == h.adjacency_node
    np.testing.assert_allclose(a.lam_high, h.lam_high, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(a.lam_low, h.lam_low, rtol=1e-6, atol=1e-9)
    assert max(a.residuals.values()) <= 1e-7
    check_certificate(a)


def test_safe_state_is_safe_and_central():
    system, load = random_problem(8, 3)
    b = shakedown_bounds(system, load, lam=0.05)
    H = safe_region(system, load, 0.05)
    assert H.contains(b.safe_state)
    dist = H.slack(b.safe_state) / np.linalg.norm(H.normals, axis=1)
    assert dist.min() == pytest.approx(b.safe_margin, rel=1e-8)


# ---------------------------------------------------------------------- invariances
def test_permutation_invariance():
    system, load = random_problem(7, 4)
    perm = np.random.default_rng(0).permutation(7)
    ix = np.ix_(perm, perm)
    s2 = sd.DiscreteSystem(system.A[ix], system.B[ix], system.C[ix], system.friction[perm])
    b1 = shakedown_bounds(system, load, adjacency=True, intervals=True)
    b2 = shakedown_bounds(s2, load.permuted(perm), adjacency=True, intervals=True)
    assert b2.lam1 == pytest.approx(b1.lam1, rel=1e-9)
    assert b2.lam2 == pytest.approx(b1.lam2, rel=1e-9)
    assert b2.lam_adj == pytest.approx(b1.lam_adj, rel=1e-9)
    assert perm[b2.adjacency_node] == b1.adjacency_node
    idx = np.r_[perm, 7 + perm]
    np.testing.assert_allclose(b2.lam_high, b1.lam_high[idx], rtol=1e-9)


@pytest.mark.parametrize("factor", [1e-3, 7.0, 1e4])
def test_scaling(factor):
    system, load = random_problem(6, 5)
    b = shakedown_bounds(system, load)
    # K and loads together: slips unchanged, load factors unchanged
    sK = sd.DiscreteSystem(factor * system.A, factor * system.B, factor * system.C, 0.3)
    b2 = shakedown_bounds(sK, load.scaled(factor))
    assert (b2.lam1, b2.lam2) == pytest.approx((b.lam1, b.lam2), rel=1e-9)
    # K alone: slips scale as 1 / factor, load factors unchanged
    b3 = shakedown_bounds(sK, load)
    assert (b3.lam1, b3.lam2) == pytest.approx((b.lam1, b.lam2), rel=1e-9)
    np.testing.assert_allclose(b3.state_at_lam2, b.state_at_lam2 / factor, rtol=1e-7,
                               atol=1e-9 * np.abs(b.state_at_lam2).max() / factor)
    # the periodic part alone: lam scales inversely
    lo = sd.LoadCycle.from_harmonics(load.q0, load.p0, q_cos=factor * load.q_cos,
                                     q_sin=factor * load.q_sin, p_cos=factor * load.p_cos)
    b4 = shakedown_bounds(system, lo)
    assert (b4.lam1, b4.lam2) == pytest.approx((b.lam1 / factor, b.lam2 / factor), rel=1e-9)


def test_time_scaling_samples():
    """A sampled load and the same load given at twice the samples (midpoints inserted: the
    same piecewise-linear cycle) have the same bounds; harmonics vs dense samples converge."""
    system, load = random_problem(5, 6)
    s1 = load.to_samples(16)
    q, p = s1.q1, s1.p1
    q2 = np.empty((32, 5))
    p2 = np.empty((32, 5))
    q2[0::2], p2[0::2] = q, p
    q2[1::2], p2[1::2] = 0.5 * (q + np.roll(q, -1, 0)), 0.5 * (p + np.roll(p, -1, 0))
    s2 = sd.LoadCycle.from_samples(load.q0, load.p0, q2, p2)
    b1, b2 = shakedown_bounds(system, s1), shakedown_bounds(system, s2)
    assert (b2.lam1, b2.lam2) == pytest.approx((b1.lam1, b1.lam2), rel=1e-9)
    # sampling the harmonic load finely: extremes converge as O(1 / S^2)
    bh = shakedown_bounds(system, load)
    bs = shakedown_bounds(system, load.to_samples(4096))
    assert bs.lam2 == pytest.approx(bh.lam2, rel=1e-5)


# ---------------------------------------------------------------------- Melan (B = 0)
def _uncoupled(n, seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    A = M @ M.T + n * np.eye(n)
    system = sd.DiscreteSystem(A, np.zeros((n, n)), np.eye(n), rng.uniform(0.1, 1.0, n))
    load = sd.LoadCycle.from_harmonics(
        rng.standard_normal(n), 1 + rng.random(n),
        q_cos=rng.standard_normal(n), q_sin=rng.standard_normal(n),
        p_cos=0.3 * rng.standard_normal(n),
    )
    return system, load


def test_melan_uncoupled_property():
    hyp = pytest.importorskip("hypothesis")
    st = hyp.strategies

    @hyp.settings(max_examples=25, deadline=None)
    @hyp.given(st.integers(1, 30), st.integers(0, 2**31 - 1))
    def prop(n, seed):
        system, load = _uncoupled(n, seed)
        b = shakedown_bounds(system, load, adjacency=False, separation=False)
        if b.status == "bounded":
            assert b.lam1 == pytest.approx(b.lam2, rel=1e-9)
            check_certificate(b)
        else:
            assert b.status == "infeasible"  # the static load alone is outside the cone

    prop()


# ---------------------------------------------------------------------- extremes
def test_single_node_closed_form():
    a, bb, f, p0, q0, Q = 2.0, 0.5, 0.4, 3.0, 0.2, 1.3
    s = sd.DiscreteSystem([[a]], [[bb]], [[1.0]], friction=f)
    load = sd.LoadCycle.from_harmonics([q0], [p0], q_cos=[Q])
    b = shakedown_bounds(s, load)
    # (f p0 - q0 - lam Q)/(a - f b) = (-f p0 - q0 + lam Q)/(a + f b)
    lam = ((f * p0 - q0) * (a + f * bb) + (f * p0 + q0) * (a - f * bb)) / (
        Q * (a + f * bb) + Q * (a - f * bb))
    assert b.lam2 == pytest.approx(lam, rel=1e-12)
    assert b.lam1 == b.lam2


def test_no_periodic_part():
    system, _ = random_problem(4, 7)
    load = sd.LoadCycle.static(np.zeros(4), np.ones(4))
    b = shakedown_bounds(system, load)
    assert np.isinf(b.lam2) and b.status == "unbounded_no_periodic_part"
    assert "no periodic part" in b.message


def test_static_gross_slip_is_infeasible():
    # a tensile static normal load: I_0 and II_0 are inconsistent for every lam >= 0
    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.1)
    load = sd.LoadCycle.from_harmonics([0.0], [-1.0], q_cos=[1.0])
    b = shakedown_bounds(s, load)
    assert b.status == "infeasible" and np.isnan(b.lam2)


@pytest.mark.parametrize("friction", [1e-6, 50.0])
def test_friction_extremes(friction):
    system, load = random_problem(5, 8, friction=friction, coupling=0.3 / max(1, friction))
    a = shakedown_bounds(system, load)
    h = shakedown_bounds(system, load, solver="highs")
    assert a.lam2 == pytest.approx(h.lam2, rel=1e-6)
    assert a.lam1 == pytest.approx(h.lam1, rel=1e-6)
    assert a.lam1 <= a.lam2 * (1 + 1e-12)


def test_ill_conditioned_K():
    rng = np.random.default_rng(9)
    n = 6
    Q, _ = np.linalg.qr(rng.standard_normal((2 * n, 2 * n)))
    K = Q @ np.diag(np.logspace(0, 10, 2 * n)) @ Q.T
    K = 0.5 * (K + K.T)
    system = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], 0.05)
    assert system.condition_number == pytest.approx(1e10, rel=1e-2)
    load = sd.LoadCycle.from_harmonics(np.zeros(n), 1e5 * np.ones(n),
                                       q_cos=1e5 * rng.standard_normal(n))
    a = shakedown_bounds(system, load, adjacency=False)
    h = shakedown_bounds(system, load, adjacency=False, solver="highs")
    assert a.lam2 == pytest.approx(h.lam2, rel=1e-6)
    check_certificate(a)


@pytest.mark.slow  # (9 s; the default run keeps the 400-node and smaller certificates)
def test_n600_certified():
    """A fast stand-in for the N = 2000 run in the default suite: every LP certified, the lam2
    certificate checked independently, and lam1 the upper end of its limiting interval."""
    system, load = random_problem(600, 0)
    b = shakedown_bounds(system, load, separation=False)
    assert b.status == "bounded" and 0 < b.lam1 <= b.lam2
    assert max(b.residuals.values()) <= 1e-7
    check_certificate(b)
    assert b.lam1 == b.lam_high[b.limiting_constraint]
    assert np.all(b.lam_low == 0.0)


def test_kachanov_400_default_equals_exact_intervals():
    """The default-run stand-in for the large networks (issue 14): 400 cracks, where the
    pruned default path decides most rows without an LP; lam1 and its limiting row equal those
    of the full interval computation, and every answer is certified."""
    import crack_networks as cn

    cracks = cn.sample_crack_set(400, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(1))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    load = model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))
    b = shakedown_bounds(model.system, load)
    full = shakedown_bounds(model.system, load, intervals=True, separation=False)
    assert b.lam1 == pytest.approx(full.lam1, rel=1e-9) and b.lam2 == full.lam2
    assert b.limiting_constraint == full.limiting_constraint
    assert b.n_lps < full.n_lps and not b.lam_high_exact.all()
    assert max(b.residuals.values()) <= 1e-7
    check_certificate(b)


@pytest.mark.slow  # about 100 s (50 s) on the 2-core CI machine: the default run stays under 10 min
def test_n2000_finishes():
    """N = 2000, dense (issue 14: 803 s, then 595 s; about 45 s with the LPs and walks in the
    coordinates of the lam2 basis): every answer certified, the lam2 certificate (Farkas) and
    the limiting row's exact lam_high checked here."""
    system, load = random_problem(2000, 0)
    b = shakedown_bounds(system, load, adjacency=False, separation=False)
    assert b.status == "bounded" and 0 < b.lam1 <= b.lam2
    assert max(b.residuals.values()) <= 1e-7
    check_certificate(b)
    k = b.limiting_constraint
    assert b.lam_high_exact[k] and b.lam_high[k] == pytest.approx(b.lam1, rel=1e-12)
    assert np.all(b.lam_high >= b.lam1 * (1 - 1e-9)) and np.all(b.lam_low <= 1e-9 * b.lam2)


# ---------------------------------------------------------------------- bad input
def test_bad_input_messages():
    system, load = random_problem(3, 0)
    with pytest.raises(sd.InputError, match="system must be a shakedown.DiscreteSystem"):
        shakedown_bounds(np.eye(3), load)
    with pytest.raises(sd.InputError, match="load must be a shakedown.LoadCycle"):
        shakedown_bounds(system, "load")
    other = sd.LoadCycle.from_harmonics(np.zeros(2), np.ones(2), q_cos=np.ones(2))
    with pytest.raises(sd.ShapeError, match="load has 2 nodes but system has 3"):
        shakedown_bounds(system, other)
    for bad in (-1.0, np.nan, np.inf):
        with pytest.raises(sd.InputError, match="lam must be finite and >= 0"):
            shakedown_bounds(system, load, lam=bad)
    with pytest.raises(sd.InputError, match="lam must be a number"):
        safe_region(system, load, "x")
    with pytest.raises(sd.InputError, match="solver must be 'auto' or 'highs'"):
        shakedown_bounds(system, load, solver="glpk")


@pytest.mark.parametrize("solver", ["auto", "highs"])
def test_no_separation_limit_at_a_frictionless_node(solver):
    """With f > 0 the friction constraints imply p >= 0 inside H; a frictionless node can need
    tension.  Node 0 (f = 0) pins the state to the line A_0 v = -q0_0; its normal reaction
    p_0(t) = 0.3 + lam cos(2 pi t) + (B^T v)_0.  Independent check: scan the safe segment on that
    line just below and above the reported limit."""
    A = np.array([[2.0, 0.5], [0.5, 2.0]])
    B = np.array([[0.0, 0.3], [0.8, 0.0]])
    system = sd.DiscreteSystem(A, B, 3 * np.eye(2), [0.0, 0.5])
    load = sd.LoadCycle.from_harmonics([0.2, 0.0], [0.3, 2.0], q_cos=[0.0, 1.0], p_cos=[1.0, 0.0])
    b = sd.shakedown_bounds(system, load, solver=solver)
    assert b.lam_separation < b.lam2 and b.separation_nodes == (0,)
    assert "tensile" in b.message
    a0 = A[0]
    d, v0 = np.array([-a0[1], a0[0]]), -0.2 * a0 / (a0 @ a0)
    V = v0 + np.linspace(-5, 5, 200001)[:, None] * d
    best = []
    for lam in (0.99 * b.lam_separation, 1.01 * b.lam_separation):
        region = sd.safe_region(system, load, lam)
        safe = np.all(V @ region.normals.T <= region.offsets + 1e-12, axis=1)
        assert safe.any()
        best.append(np.max(0.3 - lam + (V[safe] @ B)[:, 0]))  # best min_t p_0 over safe states
    assert best[0] > 0 > best[1]


# ---------------------------------------------------------------------- options
def test_only_and_not_computed_fields():
    """``lam_adj`` is opt-in; a quantity not computed is ``nan`` (and says so in JSON), never a
    value that could be read as an answer (``inf`` means "the facets never meet")."""
    system, load = random_problem(5, 2)
    full = shakedown_bounds(system, load, adjacency=True)
    default = shakedown_bounds(system, load)
    assert np.isnan(default.lam_adj) and default.adjacency_node == -1
    assert default.to_dict()["lam_adj"] == "nan" and default.to_dict()["adjacency_node"] is None
    assert (default.lam1, default.lam2) == (full.lam1, full.lam2)
    two = shakedown_bounds(system, load, only=("lam1", "lam2"))
    assert (two.lam1, two.lam2) == (full.lam1, full.lam2)
    assert np.isnan(two.lam_adj) and np.isnan(two.lam_separation)
    adj = shakedown_bounds(system, load, only=["lam_adj"])
    assert adj.lam_adj == full.lam_adj and np.isnan(adj.lam1) and np.isnan(adj.lam_high).all()
    with pytest.raises(sd.InputError, match="only: unknown quantity 'lam3'"):
        shakedown_bounds(system, load, only=("lam1", "lam3"))


def test_people_read_nodes_from_1():
    system, load = random_problem(3, 0)
    b = shakedown_bounds(system, load, adjacency=True)
    assert b.constraints.labels() == ["I_1", "I_2", "I_3", "II_1", "II_2", "II_3"]
    assert list(b.table()["node"]) == [1, 2, 3, 1, 2, 3]
    assert b.to_dict()["adjacency_node"] == b.adjacency_node + 1


def test_bit_identical_across_runs():
    system, load = random_problem(30, 4)
    a = shakedown_bounds(system, load, adjacency=True)
    b = shakedown_bounds(system, load, adjacency=True)
    for name in ("lam_low", "lam_high", "state_at_lam2", "certificate", "safe_state"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.lam1, a.lam2, a.lam_adj, a.lam_separation) == (b.lam1, b.lam2, b.lam_adj,
                                                             b.lam_separation)


@pytest.mark.parametrize("n,seed", [(4, 1), (9, 2), (25, 3)])
def test_auto_agrees_with_highs_on_degenerate_systems(n, seed):
    """Uncoupled systems: the lam2 optimum is degenerate (one node's two parallel constraints
    meet, far fewer than N + 1 strongly active rows) and many interval LPs tie.  The fast path
    (with its shared answers) equals the reference path; 1e-6 = HiGHS's tolerance with margin."""
    system, load = _uncoupled(n, seed)
    a = shakedown_bounds(system, load, adjacency=True, intervals=True)
    h = shakedown_bounds(system, load, adjacency=True, solver="highs")
    assert a.status == h.status
    for name in ("lam1", "lam2", "lam_adj", "lam_separation"):
        assert getattr(a, name) == pytest.approx(getattr(h, name), rel=1e-6, nan_ok=True), name
    np.testing.assert_allclose(a.lam_high, h.lam_high, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(a.lam_low, h.lam_low, rtol=1e-6, atol=1e-9)
