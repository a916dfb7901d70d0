"""Cycles of 3-D systems (MODEL.md s.8): solve_cycles / steady_cycle / uniqueness_study with
dim = 3, through shakedown/evolution/cone_cycles.py.

References (derived in the docstrings, checked here):

* one node, ``A = k I``, ``B = 0``, ``p = P``, tangential load rotating at constant magnitude
  ``Q``: steady full slip with ``k r = sqrt(Q^2 - (f P)^2)`` and ``W = 2 pi f P sqrt(Q^2 -
  f^2 P^2) / k`` per cycle; shakedown for ``Q <= f P``; the backward-Euler orbit with ``S``
  steps in closed form (below), converging to ``W`` at first order in ``1 / S``;
* a 3-D system whose second tangential direction is unloaded and uncoupled reproduces the 2-D
  run (cycles, W, stuck nodes, period) of random 2-D systems, coupled and uncoupled;
* an elliptic cone ``(f_x, f_y)`` under a load oscillating along ``x`` (``y``) gives the 2-D
  answer with ``f_x`` (``f_y``);
* the discrete energy identity; unit rescaling 1e-6..1e12; bad input.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.model.errors import InputError, ShapeError


def rotating_node(k=2.0, f=0.5, P=1.0, Q=1.3, c=1.0):
    s = sd.DiscreteSystem(k * np.eye(2), np.zeros((2, 1)), [[c]], friction=f, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=np.zeros((1, 2)), p0=[P], q_cos=[[Q, 0.0]],
                                       q_sin=[[0.0, Q]])
    return s, load


def discrete_rotating_W(k, f, P, Q, S):
    """Backward Euler with ``S`` steps: the orbit ``v_j = r e^{i theta_j}`` turns by
    ``a = 2 pi / S`` per step, ``dv_j`` has direction ``e^{i theta_j} e^{i(pi/2 - a/2)}`` and
    length ``2 r sin(a/2)``; ``q_j = -f P dv_j / |dv_j|`` and ``|q_j - k v_j| = Q`` give
    ``Q^2 = f^2 P^2 + k^2 r^2 + 2 f P k r sin(a/2)``, so
    ``k r = -f P sin(a/2) + sqrt(Q^2 - f^2 P^2 cos^2(a/2))`` and ``W_S = S f P 2 r sin(a/2)``."""
    a = 2 * np.pi / S
    kr = -f * P * np.sin(a / 2) + np.sqrt(Q**2 - (f * P * np.cos(a / 2)) ** 2)
    return S * f * P * 2 * kr / k * np.sin(a / 2), kr


@pytest.mark.parametrize("S", [8, 24, 64])
def test_rotating_load_on_one_node_matches_the_discrete_closed_form(S):
    k, f, P, Q = 2.0, 0.5, 1.0, 1.3
    s, load = rotating_node(k, f, P, Q)
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=S)
    W_S, kr = discrete_rotating_W(k, f, P, Q, S)
    assert run.status == "periodic" and run.period == 1 and not run.shook_down
    np.testing.assert_allclose(run.steady_dissipation, W_S, rtol=1e-10)
    np.testing.assert_allclose(np.hypot(*run.final_slip[0]), kr / k, rtol=1e-10)
    assert run.stuck_nodes.size == 0
    tab = run.steady_table
    assert set(tab["state"]) == {"slip"}
    np.testing.assert_allclose(np.hypot(tab["q_x"], tab["q_y"]), f * P, rtol=1e-10)
    assert run.energy_identity.discrete_relative_difference <= 1e-10


def test_rotating_load_converges_to_the_continuous_W_at_first_order():
    k, f, P, Q = 2.0, 0.5, 1.0, 1.3
    W = 2 * np.pi * f * P * np.sqrt(Q**2 - (f * P) ** 2) / k
    s, load = rotating_node(k, f, P, Q)
    err = []
    for S in (32, 64, 128):
        run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=S)
        err.append(abs(run.steady_dissipation - W) / W)
    order = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(np.abs(order - 1.0) < 0.1), order
    assert err[-1] < 0.02


@pytest.mark.parametrize("ratio", [0.5, 0.99])
def test_rotating_load_below_f_P_shakes_down_from_any_start(ratio):
    f, P = 0.5, 1.0
    s, load = rotating_node(f=f, P=P, Q=ratio * f * P)
    for v0 in ([[0.0, 0.0]], [[0.3, -0.2]], [[-1.0, 0.5]]):
        run = sd.solve_cycles(s, load, 1.0, initial_slip=v0, steps_per_cycle=64)
        assert run.shook_down and run.steady_dissipation <= 1e-12 and list(run.stuck_nodes) == [0]


def embed(A2, B2, C2, f, Ay=None):
    """The 3-D system whose y direction is unloaded and uncoupled."""
    n = C2.shape[0]
    A3 = np.zeros((2 * n, 2 * n))
    A3[0::2, 0::2] = A2
    A3[1::2, 1::2] = np.diag(np.diag(A2)) if Ay is None else Ay
    B3 = np.zeros((2 * n, n))
    B3[0::2] = B2
    return sd.DiscreteSystem(A3, B3, C2, friction=f, dim=3)


def embed_load(load2):
    def xy(a):
        a = np.asarray(a, float)
        return np.stack([a, np.zeros_like(a)], axis=-1)
    return sd.LoadCycle.from_harmonics(q0=xy(load2.q0), p0=load2.p0, q_cos=xy(load2.q_cos),
                                       q_sin=xy(load2.q_sin), p_cos=load2.p_cos,
                                       p_sin=load2.p_sin)


def random_2d(n, seed, coupled):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T / (2 * n) + np.eye(2 * n)
    A, B, C = K[:n, :n], (0.4 * K[:n, n:] if coupled else np.zeros((n, n))), K[n:, n:]
    s2 = sd.DiscreteSystem(A, B, C, friction=0.3)
    if coupled:
        s2 = s2.with_friction(min(0.3, 0.8 * s2.critical_friction().value))
    load = sd.LoadCycle.from_harmonics(q0=0.2 * rng.normal(size=n), p0=1 + rng.random(n),
                                       q_cos=rng.normal(size=n), q_sin=rng.normal(size=n),
                                       p_cos=0.1 * rng.normal(size=n))
    return s2, load


@pytest.mark.parametrize("seed,coupled,lam", [(0, False, 0.5), (1, True, 0.4), (2, True, 0.8),
                                              (3, False, 0.25)])
def test_unloaded_uncoupled_second_direction_reproduces_the_2d_run(seed, coupled, lam):
    n = 4
    s2, load2 = random_2d(n, seed, coupled)
    s3 = embed(s2.A, s2.B, s2.C, s2.friction)
    load3 = embed_load(load2)
    r2 = sd.solve_cycles(s2, load2, lam, steps_per_cycle=48)
    r3 = sd.solve_cycles(s3, load3, lam, steps_per_cycle=48)
    assert r2.status == r3.status == "periodic"
    assert (r2.period, r2.shook_down) == (r3.period, r3.shook_down)
    # the 2-D active set accepts a stick node up to feas_tol = 1e-9 of the force scale beyond
    # the friction limit where the cone step lets it slip by ~1e-10: the runs agree to that
    # tolerance, and a geometric approach may then be declared steady one period apart
    assert abs(r2.n_cycles - r3.n_cycles) <= 1
    np.testing.assert_array_equal(r2.stuck_nodes, r3.stuck_nodes)
    Wscale = np.abs(r2.dissipation).max()
    m = min(r2.n_cycles, r3.n_cycles)
    np.testing.assert_allclose(r3.dissipation[:m], r2.dissipation[:m], rtol=0,
                               atol=1e-8 * Wscale)
    np.testing.assert_allclose(r3.steady_dissipation, r2.steady_dissipation, rtol=1e-8)
    sl = r2.force_scale / np.diag(s2.A).min()  # the natural slip scale F / k
    np.testing.assert_allclose(r3.final_slip[:, 0], r2.final_slip, rtol=0, atol=1e-8 * sl)
    assert np.abs(r3.final_slip[:, 1]).max() <= 1e-12 * sl
    e = r3.energy_identity  # the exact discrete balance, relative to W or to F^2 / k
    assert abs(e.discrete_difference) <= 1e-9 * max(abs(e.dissipation), r2.force_scale * sl)


@pytest.mark.parametrize("axis", [0, 1])
def test_elliptic_cone_under_an_oscillating_load_gives_the_2d_answer(axis):
    """One node, ``A = k I``, elliptic cone (f_x, f_y); the load oscillates along one axis: the
    node slips along that axis only, as the 2-D node with that axis' friction."""
    k, P, Q = 2.0, 1.0, 1.0
    fxy = np.array([0.3, 0.6])
    s3 = sd.DiscreteSystem(k * np.eye(2), np.zeros((2, 1)), [[1.0]], friction=[fxy], dim=3)
    qc = np.zeros((1, 2))
    qc[0, axis] = Q
    load3 = sd.LoadCycle.from_harmonics(q0=np.zeros((1, 2)), p0=[P], q_cos=qc)
    s2 = sd.DiscreteSystem([[k]], [[0.0]], [[1.0]], friction=fxy[axis])
    load2 = sd.LoadCycle.from_harmonics(q0=[0.0], p0=[P], q_cos=[Q])
    r3 = sd.solve_cycles(s3, load3, 1.0, steps_per_cycle=40)
    r2 = sd.solve_cycles(s2, load2, 1.0, steps_per_cycle=40)
    np.testing.assert_allclose(r3.steady_dissipation, r2.steady_dissipation, rtol=1e-10)
    # the implicit 2-D orbit: 4 f P (Q cos(pi/S)-ish - f P) / k is checked in 2-D; here the
    # continuous value bounds it from above
    assert r2.steady_dissipation <= 4 * fxy[axis] * P * (Q - fxy[axis] * P) / k * (1 + 1e-12)
    assert np.abs(r3.final_slip[0, 1 - axis]) <= 1e-14


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(fexp=st.integers(-6, 12), kexp=st.integers(-6, 12))
def test_cycles_scale_with_the_units(fexp, kexp):
    """Forces x a, stiffnesses x b: W x a^2 / b, slips x a / b, same cycles and stuck nodes."""
    s2, load2 = random_2d(3, 11, True)
    s = embed(s2.A, s2.B, s2.C, s2.friction, Ay=np.asarray(s2.A) * 0.9 + 0.1 * np.eye(3))
    load = embed_load(load2)
    a, b = 10.0 ** fexp, 10.0 ** kexp
    run = sd.solve_cycles(s, load, 0.6, steps_per_cycle=24)
    s_b = sd.DiscreteSystem(b * s.A, b * s.B, b * s.C, friction=s.friction, dim=3)
    run_b = sd.solve_cycles(s_b, load.scaled(a), 0.6, steps_per_cycle=24)
    assert (run.n_cycles, run.period) == (run_b.n_cycles, run_b.period)
    np.testing.assert_array_equal(run.stuck_nodes, run_b.stuck_nodes)
    np.testing.assert_allclose(run_b.steady_dissipation * b / a**2, run.steady_dissipation,
                               rtol=1e-8)
    np.testing.assert_allclose(run_b.final_slip * b / a, run.final_slip, rtol=0,
                               atol=1e-9 * np.abs(run.final_slip).max())


def test_coupled_random_system_energy_identity_and_steady_tools():
    rng = np.random.default_rng(5)
    n = 3
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.3 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=0.3, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=0.1 * rng.normal(size=(n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)))
    run = sd.solve_cycles(s, load, 0.6, steps_per_cycle=32)
    assert run.status == "periodic" and run.final_slip.shape == (n, 2)
    assert run.cycle_start_slips.shape == (run.n_cycles + 1, n, 2)
    assert run.energy_identity.discrete_relative_difference <= 1e-9
    assert {"slip_x", "slip_y", "q_x", "q_y", "p"} <= set(run.steady_table.columns)
    sc = sd.steady_cycle(s, load, 0.6, steps_per_cycle=32)
    assert sc.status == "converged" and sc.slip.shape == (n, 2)
    np.testing.assert_allclose(sc.steady_dissipation, run.steady_dissipation, rtol=1e-8)
    study = sd.uniqueness_study(s, load, 0.6, 4, rng=0, steps_per_cycle=32, n_jobs=1)
    assert study.unique_dissipation and "initial_slip_2_y" in study.table.columns
    runs = sd.solve_cycles(s, load, 0.6, initial_slip=np.zeros((2, n, 2)), steps_per_cycle=32)
    assert len(runs) == 2 and runs[1].steady_dissipation == runs[0].steady_dissipation


def test_bad_input_is_refused_by_name():
    s, load = rotating_node()
    with pytest.raises(InputError, match="events"):
        sd.solve_cycles(s, load, 1.0, method="events")
    with pytest.raises(ShapeError, match="initial_slip"):
        sd.solve_cycles(s, load, 1.0, initial_slip=[0.0])
    load2 = sd.LoadCycle.from_harmonics(q0=[0.0], p0=[1.0], q_cos=[1.0])
    with pytest.raises(ShapeError, match="dim"):
        sd.solve_cycles(s, load2, 1.0)
    with pytest.raises(InputError, match="anderson_memory"):
        sd.solve_cycles(s, load, 1.0, anderson_memory=-1)
    with pytest.raises(InputError, match="anderson_memory"):
        sd.solve_cycles(s, load, 1.0, anderson_memory=2.5)
    s2 = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    with pytest.raises(InputError, match="steady_cycle"):
        sd.solve_cycles(s2, load2, 1.0, anderson_memory=3)


def slow_coupled_3d(n=6, seed=1):
    """A random coupled system (``K = M M^T / 3N + I``, ``B = 0.4 x`` its coupling block,
    ``f = 0.3``, harmonic load with independent cosine and sine parts) whose approach to the
    steady cycle is slow at ``lam = 0.5`` (about 80 plain periods at 32 steps)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = (M @ M.T) / (3 * n) + np.eye(3 * n)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.4 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=0.3, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=0.1 * rng.normal(size=(n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)))
    return s, load


def test_anderson_accelerator_reaches_the_plain_steady_cycle_in_fewer_periods():
    """The opt-in accelerator of the 3-D driver: the same steady cycle as plain cycling (no node
    stays stuck here, so the steady state is unique), to the steady test's tolerance, verified by
    a simulated steady period, in a fraction of the periods."""
    s, load = slow_coupled_3d()
    plain = sd.solve_cycles(s, load, 0.5, steps_per_cycle=32)
    fast = sd.solve_cycles(s, load, 0.5, steps_per_cycle=32, anderson_memory=5)
    assert plain.status == fast.status == "periodic" and plain.stuck_nodes.size == 0
    assert fast.n_cycles * 3 <= plain.n_cycles
    F = plain.force_scale
    k = np.diag(s.A).max()
    assert abs(fast.steady_dissipation - plain.steady_dissipation) <= 1e-8 * F * F / k
    np.testing.assert_allclose(fast.final_slip, plain.final_slip, rtol=0, atol=1e-8 * F / k)
    np.testing.assert_allclose(fast.steady_orbit[-1].q, plain.steady_orbit[-1].q, rtol=0,
                               atol=1e-8 * F)
    assert fast.state_change[-1] <= fast.tol and fast.cycle_start_slips.shape == (
        fast.n_cycles + 1, 6, 2)
    assert fast.energy_identity.discrete_relative_difference <= 1e-9


def test_warm_start_predictor_extrapolates_a_geometric_approach_exactly():
    """``_predictor``: increments approaching ``U*`` geometrically, ``U_k = U* + rho^k D``, are
    extrapolated to the next one exactly; an alternating approach (rho < 0) and a short history
    fall back to the last period's increments."""
    from shakedown.evolution.cone_cycles import _predictor
    from shakedown.evolution.cone_step import ConeStepSolver

    s, _ = slow_coupled_3d()
    d = ConeStepSolver(s).data
    rng = np.random.default_rng(0)
    Us, D = rng.normal(size=(8, 6, 3)), rng.normal(size=(8, 6, 3))
    for rho in (0.1, 0.55, 0.9):
        hist = [Us + rho ** k * D for k in (1, 2, 3)]
        np.testing.assert_allclose(_predictor(hist, d), Us + rho ** 4 * D, rtol=0, atol=1e-13)
    alternating = [Us + (-0.5) ** k * D for k in (1, 2, 3)]
    assert np.array_equal(_predictor(alternating, d), alternating[-1])
    assert np.array_equal(_predictor(alternating[:2], d), alternating[1])
    assert _predictor([], d) is None


def test_extrapolated_warm_starts_give_the_plain_answers_with_fewer_newton_iterations(
        monkeypatch):
    """The driver's extrapolated warm starts change only where each step's Newton method starts:
    the same periods, state changes, steady cycle and slips as the plain start (previous
    period's same step) to the step's tolerance, in fewer Newton iterations."""
    from shakedown.evolution import cone_cycles

    s, load = slow_coupled_3d()
    fast = sd.solve_cycles(s, load, 0.5, steps_per_cycle=32)
    monkeypatch.setattr(cone_cycles, "RHO_MAX", 0.0)  # rho clipped to 0: the plain start
    plain = sd.solve_cycles(s, load, 0.5, steps_per_cycle=32)
    F, k = plain.force_scale, np.diag(s.A).max()
    assert fast.status == plain.status == "periodic" and fast.n_cycles == plain.n_cycles
    np.testing.assert_allclose(fast.state_change, plain.state_change, rtol=1e-4, atol=1e-11)
    np.testing.assert_allclose(fast.final_slip, plain.final_slip, rtol=0, atol=1e-11 * F / k)
    np.testing.assert_allclose(fast.dissipation, plain.dissipation, rtol=1e-11)
    assert (fast.statistics["newton_iterations"]
            < 0.8 * plain.statistics["newton_iterations"])


def test_every_recorded_point_is_in_equilibrium_with_its_slips_and_gaps():
    """The driver takes each step's base reactions from the previous step's reactions (minus the
    gaps' share) and re-derives them from the slips once per period: every recorded point of a
    coupled run with separation satisfies ``q = q_w + A v + B w``, ``p = p_w + B^T v + C w``
    recomputed here from the load and the system's matrices."""
    rng = np.random.default_rng(3)
    n = 5
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.3 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=0.3, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=np.zeros((n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)),
                                       p_cos=np.r_[1.6, 1.6, np.zeros(n - 2)])
    run = sd.solve_cycles(s, load, 0.8, steps_per_cycle=16, max_cycles=6)
    assert run.max_residual <= 1e-9
    F = run.force_scale
    gaps = 0
    for rec in run.steady_orbit:
        qw, pw = load.evaluate(rec.t[1:] % 1.0, 0.8)
        v, w = rec.v[1:].reshape(len(rec.t) - 1, -1), rec.w[1:]
        q = qw.reshape(len(v), -1) + v @ s.A.T + w @ s.B.T
        p = pw + v @ s.B + w @ s.C.T
        np.testing.assert_allclose(rec.q[1:].reshape(len(v), -1), q, rtol=0, atol=1e-9 * F)
        np.testing.assert_allclose(rec.p[1:], p, rtol=0, atol=1e-9 * F)
        gaps += int(np.sum(w > 0))
    assert gaps > 0
