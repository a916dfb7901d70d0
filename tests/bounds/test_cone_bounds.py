"""3-D shakedown bounds on friction cones (MODEL.md s.8.3; shakedown.bounds.cones).

What these tests prove: ``lam2`` by cutting planes matches references that use no LP or SOCP
solver (uncoupled systems: per node the load's tangential curve must fit in the friction disc;
for an ellipse the smallest enclosing circle has the semi-major axis as radius), reproduces the
2-D engine exactly when the second tangential direction is unloaded and uncoupled, does not
depend on units, and is bracketed by certificates that object to wrong answers; a sampled SOCP
over-estimates ``lam2`` and the exact bracket lies below it.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.bounds.cones.certify import ConeCertificate, check_dual_bound, check_safe_state
from shakedown.model.errors import InputError


def random_3d(n, seed, friction=0.4, coupled=True):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    B = K[: 2 * n, 2 * n:] if coupled else np.zeros((2 * n, n))
    return sd.DiscreteSystem(K[: 2 * n, : 2 * n], B, K[2 * n:, 2 * n:], friction=friction, dim=3)


def random_load(n, seed, p_amp=0.2, harmonics=1):
    rng = np.random.default_rng(seed)
    h = harmonics
    return sd.LoadCycle.from_harmonics(
        q0=0.2 * n * rng.normal(size=(n, 2)), p0=n * (1 + rng.random(n)),
        q_cos=n * rng.normal(size=(h, n, 2)), q_sin=n * rng.normal(size=(h, n, 2)),
        p_cos=p_amp * n * rng.normal(size=(h, n)), p_sin=p_amp * n * rng.normal(size=(h, n)))


def contains(b, exact, slack=1e-8):
    """The certified bracket holds the exact value (``slack``: the SOCP solver's tolerance)."""
    return b.lam2_lower <= exact * (1 + slack) and exact <= b.lam2_upper * (1 + slack)


def bracket_ok(b, rtol=1e-6):
    return b.lam2_lower <= b.lam2_upper * (1 + 1e-9) and \
        b.lam2_upper - b.lam2_lower <= rtol * b.lam2_upper


@pytest.mark.parametrize("friction", [0.4, [[0.3, 0.6]] * 5])
def test_uncoupled_constant_p_is_the_semi_major_axis_reference(friction):
    """B = 0, constant p: node i needs lam * (semi-major axis of W q1's ellipse) <= p0_i (A v is
    free per node); lam2 = min_i p0_i / sigma_max(W [q_cos q_sin])."""
    n = 5
    s = random_3d(n, 1, friction=friction, coupled=False)
    load = random_load(n, 2, p_amp=0.0)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    W = 1.0 / s.friction_xy
    axes = [np.linalg.svd(W[i][:, None] * np.column_stack([load.q_cos[0, i], load.q_sin[0, i]]),
                          compute_uv=False)[0] for i in range(n)]
    ref = min(load.p0[i] / axes[i] for i in range(n))
    assert b.status == "bounded" and bracket_ok(b)
    assert contains(b, ref)


def _uncoupled_varying_p_reference(load, f, i, grid=1024):
    """Node i alone (B = 0, isotropic f): the largest lam for which discs of radius
    f p_i(t) centred at -lam q1_i(t) share a point; bisection on lam, the common point by a
    2-D convex minimisation (scipy's Nelder-Mead, no LP/SOCP) of max_t (|c + lam q1(t)| - f p(t))
    on a grid of times."""
    from scipy.optimize import minimize

    t = np.arange(grid) / grid
    q, p = load.periodic(t)
    q1, p1 = q[:, i], p[:, i]

    def worst(lam):
        def fun(c):
            return np.max(np.linalg.norm(c + load.q0[i] + lam * q1, axis=1)
                          - f * (load.p0[i] + lam * p1))
        c0 = -load.q0[i] - lam * q1.mean(axis=0)
        r = minimize(fun, c0, method="Nelder-Mead",
                     options=dict(xatol=1e-10, fatol=1e-12, maxiter=800))
        return r.fun

    lo, hi = 0.0, 1.0
    while worst(hi) <= 0:
        hi *= 2
    for _ in range(32):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst(mid) <= 0 else (lo, mid)
    return lo


def test_uncoupled_varying_p_matches_per_node_disc_intersection():
    n = 2
    s = random_3d(n, 3, friction=0.5, coupled=False)
    load = random_load(n, 4, p_amp=0.3)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    ref = min(_uncoupled_varying_p_reference(load, 0.5, i) for i in range(n))
    assert bracket_ok(b)
    # the reference sees 1024 times of the cycle (it misses the worst by (pi / 1024)^2 / 2 ~ 5e-6
    # relative at most) and its bisection stops at 2^-32 of the first bracket
    np.testing.assert_allclose(b.lam2, ref, rtol=2e-5)


def embed_2d(s2, load2, seed=0):
    """The 3-D system of a 2-D one with a second tangential direction that is unloaded and
    uncoupled (its own SPD block A_yy), and the load with q_y = 0."""
    n = s2.n_nodes
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    Ayy = M @ M.T + n * np.eye(n)
    A = np.zeros((2 * n, 2 * n))
    A[0::2, 0::2], A[1::2, 1::2] = s2.A, Ayy
    B = np.zeros((2 * n, n))
    B[0::2] = s2.B
    s3 = sd.DiscreteSystem(A, B, s2.C, friction=s2.friction, dim=3)

    def y0(a):
        return np.stack([a, np.zeros_like(a)], axis=-1)

    load3 = sd.LoadCycle.from_harmonics(
        q0=y0(load2.q0), p0=load2.p0, q_cos=y0(load2.q_cos), q_sin=y0(load2.q_sin),
        p_cos=load2.p_cos, p_sin=load2.p_sin)
    return s3, load3


def random_2d(n, seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=0.3 + 0.3 * rng.random(n))
    load = sd.LoadCycle.from_harmonics(
        0.3 * rng.normal(size=n), 2 + rng.random(n), q_cos=rng.normal(size=(2, n)),
        q_sin=rng.normal(size=(2, n)), p_cos=0.2 * rng.normal(size=(2, n)))
    return s, load


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_unloaded_uncoupled_second_direction_reproduces_2d(seed):
    s2, l2 = random_2d(4, seed)
    b2 = sd.shakedown_bounds(s2, l2, adjacency=True, solver="highs")
    s3, l3 = embed_2d(s2, l2, seed)
    b3 = sd.shakedown_bounds(s3, l3, adjacency=True, facets=8)
    assert bracket_ok(b3) and contains(b3, b2.lam2)
    # the inscribed polygons with vertices on the x axis cut q_y = 0 exactly at +-f p
    np.testing.assert_allclose(b3.lam2_polygon, b2.lam2, rtol=1e-7)
    np.testing.assert_allclose(b3.lam_adj_cone, b2.lam_adj, rtol=1e-7)


def test_certificates_object_to_wrong_answers():
    s = random_3d(4, 5)
    load = random_load(4, 6)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    ok, worst, _ = check_safe_state(s, load, b.state_at_lam2, b.lam2)
    assert ok and worst <= 0
    # the same state above lam2_upper cannot be safe; a perturbed state is not safe at lam2
    assert not check_safe_state(s, load, b.state_at_lam2, 1.01 * b.lam2_upper)[0]
    v = b.state_at_lam2.copy()
    v[0] += 1e-3 * np.abs(v).max()
    assert not check_safe_state(s, load, v, b.lam2)[0]
    ok, bound, res = check_dual_bound(s, load, b.certificate, b.lam2_upper)
    assert ok and bound <= b.lam2_upper * (1 + 1e-9) and bound >= b.lam2_lower
    # a claimed upper bound below the proven one is refused
    assert not check_dual_bound(s, load, b.certificate, 0.99 * b.lam2_lower)[0]
    # wrong multipliers prove a weaker bound or none, never one below lam2 (shakedown.bounds.
    # cones.dual): one normal component negated (moved back into its cone by the check)
    z = b.certificate.multipliers.copy()
    k = int(np.argmax(z[:, 0]))
    z[k, 0] = -z[k, 0]
    bad = ConeCertificate(b.certificate.nodes, b.certificate.times, z)
    ok, bound, res = check_dual_bound(s, load, bad, b.lam2_upper)
    assert res["cone"] > 0.5 and bound >= b.lam2_lower
    # multipliers that keep stationarity but leave their cones: move weight between two cuts of
    # one node along a1_m - a1_m' (u rows and h . z unchanged).  The former rule (residuals
    # ignored, cone residual reported) would compute a bound below lam2; the check does not.
    from shakedown.bounds.cones.data import cone_data
    from shakedown.bounds.cones.socp import naive_bound

    d = cone_data(s, load)
    nodes, times = b.certificate.nodes, b.certificate.times
    node = np.bincount(nodes).argmax()
    m, m2 = np.flatnonzero(nodes == node)[:2]
    a1, _ = d.periodic(times[[m, m2]], nodes[[m, m2]])
    e = a1[0] - a1[1]
    z = b.certificate.multipliers.copy()
    shift = -(2 * z[m, 0] + np.linalg.norm(z[m, 1:]) + 1.0) * e / np.linalg.norm(e)
    z[m, 1:] += shift
    z[m2, 1:] -= shift
    assert naive_bound(d, nodes, times, z) * d.load_factor < b.lam2_lower
    bad = ConeCertificate(nodes, times, z)
    ok, bound, res = check_dual_bound(s, load, bad, b.lam2_upper)
    assert not ok and res["cone"] > 0.1 and bound >= b.lam2_lower
    # multipliers moved to other times prove nothing as tight (stationarity fails)
    bad = ConeCertificate(b.certificate.nodes, np.mod(b.certificate.times + 0.3, 1.0),
                          b.certificate.multipliers)
    ok, bound, _ = check_dual_bound(s, load, bad, b.lam2_upper)
    assert not ok and bound >= b.lam2_lower


@settings(max_examples=6, deadline=None)
@given(force=st.floats(1e-6, 1e12), stiff=st.floats(1e-6, 1e12), amp=st.floats(1e-6, 1e12))
def test_units_do_not_change_lam2(force, stiff, amp):
    s = random_3d(3, 7)
    load = random_load(3, 8)
    ref = sd.shakedown_bounds(s, load, only=("lam2",))
    s2 = sd.DiscreteSystem(stiff * s.A, stiff * s.B, stiff * s.C, friction=s.friction, dim=3)
    l2 = sd.LoadCycle.from_harmonics(
        q0=force * load.q0, p0=force * load.p0, q_cos=force * amp * load.q_cos,
        q_sin=force * amp * load.q_sin, p_cos=force * amp * load.p_cos,
        p_sin=force * amp * load.p_sin)
    b = sd.shakedown_bounds(s2, l2, only=("lam2",))
    np.testing.assert_allclose(b.lam2 * amp, ref.lam2, rtol=1e-6)
    np.testing.assert_allclose(b.state_at_lam2 * stiff / force, ref.state_at_lam2,
                               rtol=1e-3, atol=1e-6 * np.abs(ref.state_at_lam2).max())


def test_sampled_socp_overestimates_and_the_exact_bracket_lies_below():
    s = random_3d(4, 9)
    load = random_load(4, 10, harmonics=2)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    assert bracket_ok(b)
    values = []
    for S in (4, 8, 16, 64):
        bs = sd.shakedown_bounds(s, load.to_samples(S), only=("lam2",))
        values.append(bs.lam2)
        # the sampled problem keeps only S times of the cycle: a relaxation
        assert bs.lam2_upper >= b.lam2_upper and bs.lam2_lower >= b.lam2_lower
    assert values[0] > b.lam2_upper * (1 + 1e-3)  # coarse sampling over-estimates visibly
    assert values[-1] - b.lam2 < values[0] - b.lam2  # and the error shrinks with S


def test_no_periodic_part_and_bad_input():
    s = random_3d(2, 11)
    static = sd.LoadCycle.static(np.zeros((2, 2)), [1.0, 1.0])
    b = sd.shakedown_bounds(s, static, only=("lam2",))
    assert b.status == "unbounded_no_periodic_part" and np.isinf(b.lam2)
    with pytest.raises(InputError, match="facets"):
        sd.shakedown_bounds(s, random_load(2, 1), facets=5)
    with pytest.raises(InputError, match="only"):
        sd.shakedown_bounds(s, random_load(2, 1), only=("lam3",))
    s0 = random_3d(2, 11, friction=[0.0, 0.3])
    with pytest.raises(InputError, match="friction_xy"):
        sd.shakedown_bounds(s0, random_load(2, 1))


def test_dissipation_figure_marks_the_3d_bounds():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from shakedown.plotting.bounds import plot_dissipation_vs_lam

    s = random_3d(3, 12)
    load = random_load(3, 13)
    b = sd.shakedown_bounds(s, load, adjacency=True, intervals=False, facets=8)
    lams = b.lam2 * np.array([0.5, 1.0, 1.5])
    W = np.array([[0.0, 0.0], [1e-9, 0.0], [0.3, 0.3]])
    ax = plot_dissipation_vs_lam(lams, W, b)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("cones, certified" in t and f"{b.lam2:.4g}" in t for t in labels)
    assert any("8-gons" in t and f"{b.lam_adj_cone:.4g}" in t for t in labels)
    assert not any(r"\lambda_1$ (8-gons)" in t for t in labels)  # not computed: nan, not drawn
    with pytest.raises(InputError, match="dissipation must have shape"):
        plot_dissipation_vs_lam(lams, W[:2], b)
    plt.close("all")


@pytest.mark.slow  # ~20 s on the loaded 2-core machine (3-D step solver set-up and 300 periods)
def test_uncoupled_cyclic_runs_shake_down_below_lam2_and_slip_above():
    """Klarbring, Ciavarella & Barber (2007): for B = 0 a non-empty H(lam) gives shakedown from
    every initial state.  Two uncoupled nodes with elliptic loads, 3 initial states each:
    below lam2 the dissipation dies out, above it every state dissipates the same W."""
    from shakedown.evolution.steady_maps import sample_initial_slips

    s = random_3d(2, 14, coupled=False)
    load = random_load(2, 15, p_amp=0.0)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    V0 = sample_initial_slips(s, load, 3, rng=3)
    below = sd.solve_cycles(s, load, 0.9 * b.lam2, initial_slip=V0, steps_per_cycle=12,
                            max_cycles=50, tol=1e-9)
    above = sd.solve_cycles(s, load, 1.1 * b.lam2, initial_slip=V0, steps_per_cycle=12,
                            max_cycles=50, tol=1e-9)
    w_above = np.array([r.dissipation[-1] for r in above])
    assert w_above.min() > 0.05 * w_above.max() > 0
    assert np.ptp(w_above) <= 1e-4 * w_above.max()  # the same steady dissipation
    for r in below:
        assert r.shook_down or r.dissipation[-1] <= 1e-6 * w_above.max()


@pytest.mark.slow  # cvxpy's canonicalisation: ~25 s on the loaded 2-core machine
def test_relaxation_value_matches_an_independent_cvxpy_model_in_the_slips():
    """The engine's last relaxation, rebuilt in the original unknowns (v, lam) and units by
    cvxpy (its own canonicalisation; the solver is Clarabel too, SCS did not reach 1e-6 in 80 s),
    has the value of the certified bracket: the reduced-variable transform (s = A v,
    E = B^T A^-1 diag(f)) and the nondimensional scaling lose nothing (elliptic cones here)."""
    import cvxpy as cp

    s = random_3d(3, 16, friction=[[0.3, 0.5], [0.4, 0.4], [0.6, 0.35]])
    load = random_load(3, 17)
    b = sd.shakedown_bounds(s, load, only=("lam2",))
    nodes, times = b.certificate.nodes, b.certificate.times
    q1, p1 = load.periodic(times)  # (M, N, 2), (M, N)
    v, lam = cp.Variable(6), cp.Variable()
    q = (s.A @ v).reshape((3, 2), order="C")
    p = s.B.T @ v
    W = 1.0 / s.friction_xy
    cons = [lam >= 0]
    for m, i in enumerate(nodes):
        qi = cp.multiply(W[i], load.q0[i] + lam * q1[m, i] + q[i])
        cons.append(cp.norm(qi) <= load.p0[i] + lam * p1[m, i] + p[i])
    prob = cp.Problem(cp.Maximize(lam), cons)
    prob.solve(solver="CLARABEL")
    assert prob.status == "optimal"
    np.testing.assert_allclose(lam.value, b.lam2_upper, rtol=1e-6)
    assert lam.value >= b.lam2_lower * (1 - 1e-7)


def test_verdict_table_and_json_of_a_3d_result():
    import json

    s = random_3d(3, 18)
    load = random_load(3, 19)
    only2 = sd.shakedown_bounds(s, load, only=("lam2",))
    assert "lam_adj_cone was not computed" in only2.verdict()
    b = sd.shakedown_bounds(s, load, adjacency=True, intervals=False, facets=8)
    text = b.verdict()
    assert f"lam2 = {b.lam2:.4g}" in text and f"lam_adj_cone = {b.lam_adj_cone:.4g}" in text
    assert "not a proof" in text
    d = json.loads(json.dumps(b.to_dict()))
    assert d["dim"] == 3 and d["facets"] == 8 and d["lam1_cone"] == "nan"
    t = b.table()
    assert list(t["node"]) == [1, 2, 3] and t["cuts"].sum() == b.n_cuts
    assert np.all((t["t_worst"] >= 0) & (t["t_worst"] < 1))
    assert b.lam_adj_cone <= b.lam2_polygon * (1 + 1e-7) <= b.lam2 * (1 + 1e-7)


def test_rtol_of_shakedown_bounds_reaches_the_cone_engine_and_is_checked():
    """``sd.shakedown_bounds(..., rtol=)`` sets the width of the 3-D ``lam2`` bracket (it was
    fixed at 1e-6 from the public function); it is refused, naming the field, for a 2-D
    system (exact LP vertices) and outside [1e-12, 1)."""
    s, load = random_3d(6, 21), random_load(6, 22)
    loose = sd.shakedown_bounds(s, load, only=("lam2",), rtol=1e-2, solver="dense")
    tight = sd.shakedown_bounds(s, load, only=("lam2",), rtol=1e-8, solver="dense")
    assert tight.status == "bounded"
    assert tight.lam2_upper - tight.lam2_lower <= 1e-8 * tight.lam2_upper
    assert loose.lam2_upper - loose.lam2_lower > tight.lam2_upper - tight.lam2_lower
    assert loose.lam2_lower <= tight.lam2_upper and tight.lam2_lower <= loose.lam2_upper
    for bad in (0.0, 1.0, -1e-6, float("nan"), "tight", True):
        with pytest.raises(InputError, match="rtol"):
            sd.shakedown_bounds(s, load, only=("lam2",), rtol=bad)
    s2 = sd.DiscreteSystem(np.array([[2.0]]), np.array([[0.0]]), np.array([[1.0]]), friction=0.5)
    load2 = sd.LoadCycle.from_harmonics(q0=[0.0], p0=[-1.0], q_cos=[0.3])
    with pytest.raises(InputError, match="rtol applies to three-dimensional"):
        sd.shakedown_bounds(s2, load2, rtol=1e-8)
