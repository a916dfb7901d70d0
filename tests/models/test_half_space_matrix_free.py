"""The matrix-free steps and cycles (FFT products, FISTA, Polonsky-Keer) against the dense cone
engine (issue 23): similar and dissimilar materials, constant and varying normal force.

Both solve the same implicit steps (MODEL.md s.8.4; for ``beta = 0`` and known ``p`` the step is a
strictly convex problem, so its answer is unique): the dissipation per cycle and the tractions must
agree to the solvers' tolerances.
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.models.half_space.matrix_free import (
    FFTStepper,
    TangentialCompliance,
    fretting_cycles_fft,
    path_fft,
    project_resultant,
    step_residual,
)
from shakedown.models.half_space.normal import check_normal_contact, normal_contact
from shakedown.studies import half_space as hs

E, R, P, F = 1.0, 1.0, 1e-3, 0.5


@pytest.fixture(scope="module")
def model():
    a = float(cont.hertz_radius(P, R, E / 2))
    return sd.half_space_model(radius=R, n_cells=9, width=2.4 * a, friction=F,
                               materials=((E, 0.0), (E, 0.0)))


@pytest.mark.parametrize("qy", [0.0, pytest.param(1.0, marks=pytest.mark.slow)])  # rotating: ~1 min
def test_matches_the_dense_engine(model, qy):
    S, X = 16, 0.5
    t = (np.arange(S) + 1) / S  # the dense run's steps end at t = 1/S, ..., 1
    out = fretting_cycles_fft(model, P, X * F * P * np.cos(2 * np.pi * t),
                              qy * X * F * P * np.sin(2 * np.pi * t), max_cycles=3, tol=1e-9)
    run = sd.solve_cycles(model.system, model.load_cycle(P0=P, Qx=X * F * P, Qy=qy * X * F * P),
                          1.0, initial_slip=hs.static_path(model, [(0, 0, P)])[-1][0].slip,
                          steps_per_cycle=S, max_cycles=3, tol=1e-9)
    # period 1 of the dense run starts from P alone (the state q = 0 of the FFT run) and steps to
    # Q(1/S) first; both runs then take the same steps
    n = min(len(out["W"]), len(run.dissipation))
    # the step solvers stop at 1e-11 (FISTA) and 1e-10 (Newton) of f p: W agrees to ~1e-7
    np.testing.assert_allclose(out["W"][:n], run.dissipation[:n], rtol=1e-6)
    assert out["residual"] < 1e-8
    tab = run.steady_table.sort_values(["t", "node"])
    qd = tab[["q_x", "q_y"]].to_numpy().reshape(-1, model.n_cells - 1, 2)[-1]
    np.testing.assert_allclose(np.delete(out["q"][-1], model.reference, axis=0), qd,
                               rtol=0, atol=1e-6 * F * P / model.n_cells)


def test_projection_keeps_the_discs_and_the_resultant():
    rng = np.random.default_rng(3)
    r = rng.uniform(0.0, 1.0, 50)
    z = rng.standard_normal((50, 2))
    Q = np.array([3.0, -2.0])
    q, _ = project_resultant(z, r, Q)
    assert np.all(np.hypot(*q.T) <= r * (1 + 1e-12))
    np.testing.assert_allclose(q.sum(axis=0), Q, atol=1e-12 * r.sum())


def test_step_verifier_objects_to_a_wrong_answer(model):
    out = fretting_cycles_fft(model, P, 0.25 * F * P * np.array([1.0, 0.0, -1.0, 0.0]),
                              max_cycles=2)
    Ft = TangentialCompliance(model)
    radius = F * out["p"][-1]
    q_prev, q = out["q"][-2], out["q"][-1]
    dv0 = Ft(q - q_prev)
    inside = np.hypot(*q.T) < radius * (1 - 1e-6)
    ds = -dv0[inside].mean(axis=0)
    scale_v = radius.max() * np.abs(Ft(np.ones((model.n_cells, 2)))).max()
    ok, _ = step_residual(Ft, q, q_prev, radius, q.sum(axis=0), ds, radius.max(), scale_v)
    assert ok < 1e-6
    bad = q.copy()
    k = int(np.argmax(np.where(inside, radius, 0)))
    bad[k] *= 0.5  # a sticking cell moved: the resultant and the stick condition break
    worse, _ = step_residual(Ft, bad, q_prev, radius, q.sum(axis=0), ds, radius.max(), scale_v)
    assert worse > 1e-3


@pytest.fixture(scope="module")
def coupled():
    """A rigid sphere on an elastic flat (beta = 0.29): normal and tangential problems coupled."""
    a = float(cont.hertz_radius(1.3 * P, R, E / 2))
    return sd.half_space_model(radius=R, n_cells=9, width=2.6 * a, friction=F,
                               materials=((E, 0.3), (np.inf, 0.0)))


def test_matrix_free_path_matches_the_dense_static_path(coupled):
    # loading by P alone: with beta != 0 the pressure makes the cells slip inwards
    qd, pd = hs.static_path(coupled, [(0.0, 0.0, P)])[-1][1:]
    qf, pf = path_fft(coupled, [(0.0, 0.0, P)])[-1]
    assert np.abs(qd).max() > 1e-3 * F * P  # the coupling acts
    np.testing.assert_allclose(qf, qd, rtol=0, atol=1e-8 * F * P)
    np.testing.assert_allclose(pf, pd, rtol=0, atol=1e-8 * P)


@pytest.mark.parametrize("which, P1", [("similar", 0.3), pytest.param("coupled", 0.0, marks=pytest.mark.slow),
                                       ("coupled", 0.3)])  # coupled: ~4 s each
def test_coupled_and_varying_normal_force_match_the_dense_engine(model, coupled, which, P1):
    m = coupled if which == "coupled" else model
    S, X, ph = 12, 0.4, 0.6
    t = (np.arange(S) + 1) / S
    start = hs.static_path(m, [(0.0, 0.0, P)])[-1]
    out = fretting_cycles_fft(m, P, X * F * P * np.cos(2 * np.pi * t),
                              0.5 * X * F * P * np.sin(2 * np.pi * t),
                              P_samples=P + P1 * P * np.cos(2 * np.pi * t + ph), max_cycles=2,
                              tol=1e-14, q0=start[1], p0=start[2])
    load = m.load_cycle(P0=P, P1=P1 * P, Qx=X * F * P, Qy=0.5 * X * F * P, phase=ph)
    run = sd.solve_cycles(m.system, load, 1.0, initial_slip=start[0].slip,
                          initial_gap=start[0].gap, steps_per_cycle=S, max_cycles=2, tol=1e-14)
    assert out["residual"] < 1e-8
    k = min(len(out["W"]), len(run.dissipation))
    np.testing.assert_allclose(out["W"][:k], run.dissipation[:k], rtol=1e-6)
    tab = run.steady_table.sort_values(["t", "node"])
    qd = tab[["q_x", "q_y"]].to_numpy().reshape(-1, m.n_cells - 1, 2)[-1]
    pd = tab["p"].to_numpy().reshape(-1, m.n_cells - 1)[-1]
    np.testing.assert_allclose(np.delete(out["q"][-1], m.reference, axis=0), qd, rtol=0,
                               atol=1e-8 * F * P)
    np.testing.assert_allclose(np.delete(out["p"][-1], m.reference), pd, rtol=0, atol=1e-8 * P)
    if which == "coupled":
        assert min(out["passes"]) > 1  # the alternation did work
    if P1:
        assert np.ptp(out["p"].sum(axis=1)) > 0.5 * P  # P did vary


def test_coupled_step_verifier_objects_to_a_wrong_pressure(coupled):
    st = FFTStepper(coupled)
    q0, p0 = path_fft(coupled, [(0.0, 0.0, P)], stepper=st)[-1]
    ok = st.step(q0, p0, np.array([0.2 * F * P, 0.0]), P)
    assert ok.residual < 1e-8
    sol = normal_contact(coupled, P, extra_gap=st.ops.zt(ok.q), p_init=ok.p)
    assert check_normal_contact(coupled, sol.p, sol.approach, P, st.ops.zt(ok.q)) < 1e-9
    # the same pressures judged without the gap of the shear forces: they do not fit
    assert check_normal_contact(coupled, sol.p, sol.approach, P) > 1e-4


def test_bad_samples_are_refused(model):
    with pytest.raises(sd.InputError, match="P_samples"):
        fretting_cycles_fft(model, P, [0.1 * P, -0.1 * P], P_samples=[P])
    with pytest.raises(sd.InputError, match="P_samples"):
        fretting_cycles_fft(model, P, [0.1 * P, -0.1 * P], P_samples=[P, -P])
    with pytest.raises(sd.InputError, match="gross slip"):
        fretting_cycles_fft(model, P, [0.6 * P, -0.1 * P])
