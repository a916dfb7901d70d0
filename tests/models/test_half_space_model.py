"""Half-space contact model (issue 23): condensation, FFT operators, Hertz, bad input.

Reference: Hertz (Johnson, *Contact Mechanics*, 1985, s.4.2).  Cross-checks: the FFT products
against the dense matrices; the Polonsky-Keer normal solver (FFT, all cells) against a bounded
least-squares solve on the condensed dense stiffness (reference cell, welded reactions).
Tolerances are relative to the problem's scales (``P``, ``a``, ``p0``, ``K``'s norm).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import cholesky, solve_triangular
from scipy.optimize import lsq_linear

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.models.half_space.normal import check_normal_contact, normal_contact

E, NU, R, P = 1.0, 0.3, 1.0, 1e-3
MATS = ((E, NU), (E, NU))
E_STAR = E / (2 * (1 - NU**2))
A_H = float(cont.hertz_radius(P, R, E_STAR))


def model(n, width_factor=3.0, **kw):
    kw.setdefault("materials", MATS)
    kw.setdefault("radius", R)
    return sd.half_space_model(n_cells=n, width=width_factor * A_H, friction=0.5, **kw)


@pytest.mark.parametrize("mats", [MATS, ((E, NU), (np.inf, 0.0)), ((1.0, 0.1), (3.0, 0.45))])
def test_stiffness_symmetric_positive_definite_and_fft_products(mats):
    m = model(7, materials=mats)
    K = m.stiffness
    assert np.array_equal(K, K.T)
    ev = np.linalg.eigvalsh(K)
    assert ev[0] > 0
    rng = np.random.default_rng(1)
    X = rng.standard_normal((K.shape[0], 3))
    # F' by FFT is the inverse of the dense K (rounding of the Cholesky inverse, cond ~ 25)
    np.testing.assert_allclose(K @ (m.reduced_compliance_operator @ X), X, atol=1e-12)
    Xc = rng.standard_normal((3 * m.n_cells, 2))
    np.testing.assert_allclose(m.compliance_operator @ Xc, m.dense_compliance() @ Xc,
                               rtol=0, atol=1e-13 * np.abs(m.dense_compliance()).max())
    S = m.stiffness_operator(rtol=1e-12)
    Y = S @ X
    # CG to rtol 1e-12 on F' (cond ~ 25): error well below 1e-10 of |K X|
    np.testing.assert_allclose(Y, K @ X, rtol=0, atol=1e-10 * np.abs(K @ X).max())
    # B = 0 exactly for similar materials, and only then
    t = 2 * (m.n_cells - 1)
    assert (np.abs(K[:t, t:]).max() == 0) == (m.beta == 0)


def test_welded_reactions_solve_the_condensed_equation():
    # eq. (2) with u' = 0: F' r_w + T^T (g~ + F e_m R) = 0, checked with the FFT operators only
    m = model(9, materials=((E, NU), (np.inf, 0.0)))
    Qx, Qy, Pn = 0.2 * P, -0.1 * P, P
    q, p = m.welded(Qx, Qy, Pn)
    rw = np.concatenate([q.ravel(), p])
    red = m.reduced_compliance_operator
    N = m.n_cells
    u = np.zeros(3 * N)
    u[2 * N:] = m.gap
    em = np.zeros(3 * N)
    em[[2 * m.reference, 2 * m.reference + 1, 2 * N + m.reference]] = (Qx, Qy, Pn)
    u += m.compliance_operator @ em
    resid = red @ rw + red.restrict(u[:, None])[:, 0]
    scale = np.abs(red.restrict(u[:, None])).max()
    assert np.abs(resid).max() < 1e-11 * scale
    # the reference cell closes the resultants
    qm, pm = m.reference_reactions(q, p, Qx, Qy, Pn)
    assert np.sum(q, axis=0) + qm == pytest.approx([Qx, Qy])
    assert np.sum(p) + pm == pytest.approx(Pn)


def test_hertz_normal_contact_converges():
    # contact radius from the contact area, peak pressure of the centre cell, approach d:
    # errors measured 1.6 %, 0.6 %, 0.24 % at n = 15 and 0.13 %, 0.02 %, 0.004 % at n = 63
    errs = []
    p0 = cont.hertz_peak_pressure(P, R, E_STAR)
    for n in (15, 63):
        m = model(n)
        sol = normal_contact(m, P)
        assert sol.residual < 1e-9
        a = np.sqrt(np.count_nonzero(sol.contact) * m.h**2 / np.pi)
        errs.append([abs(a / A_H - 1), abs(sol.p.max() / m.h**2 / p0 - 1),
                     abs(sol.approach / cont.hertz_approach(P, R, E_STAR) - 1)])
    errs = np.array(errs)
    assert np.all(errs[1] < errs[0])
    assert np.all(errs[1] < [3e-3, 1e-3, 1e-3])


def test_normal_solver_matches_the_condensed_stiffness():
    # frictionless, beta = 0: p' = p_w + C w, w >= 0, p' >= 0, complementarity, i.e.
    # min 1/2 w^T C w + p_w^T w over w >= 0: a bounded least-squares problem with C = L L^T
    m = model(9)
    K = m.stiffness
    t = 2 * (m.n_cells - 1)
    C = K[t:, t:]
    _, pw = m.welded(0.0, 0.0, P)
    L = cholesky(C, lower=True)
    w = lsq_linear(L.T, -solve_triangular(L, pw, lower=True), bounds=(0, np.inf), tol=1e-14).x
    pr = pw + C @ w
    _, pm = m.reference_reactions(np.zeros((pr.size, 2)), pr, 0.0, 0.0, P)
    p_lsq = m.full(pr, pm)
    sol = normal_contact(m, P, rtol=1e-13)
    # the contact set is the same; forces agree to the least-squares tolerance
    assert np.array_equal(sol.p > 1e-9 * P, p_lsq > 1e-9 * P)
    np.testing.assert_allclose(sol.p, p_lsq, rtol=0, atol=1e-8 * P)


def test_normal_contact_verifier_objects_to_a_wrong_answer():
    m = model(15)
    sol = normal_contact(m, P)
    assert check_normal_contact(m, sol.p, sol.approach, P) < 1e-9
    bad = sol.p.copy()
    bad[sol.p.argmax()] *= 1.01
    bad *= P / bad.sum()
    assert check_normal_contact(m, bad, sol.approach, P) > 1e-4
    assert check_normal_contact(m, sol.p, 1.01 * sol.approach, P) > 1e-4


@settings(max_examples=10, deadline=None)
@given(st.floats(-6, 12), st.floats(-6, 12))
def test_unit_rescaling(log_len, log_force):
    # lengths x sL, forces x sF: E x sF/sL^2, K x sF/sL, welded reactions x sF
    sL, sF = 10.0**log_len, 10.0**log_force
    base = sd.half_space_model(radius=1.0, n_cells=5, width=0.3, materials=MATS)
    m = sd.half_space_model(radius=sL, n_cells=5, width=0.3 * sL,
                            materials=((E * sF / sL**2, NU), (E * sF / sL**2, NU)))
    np.testing.assert_allclose(m.stiffness, base.stiffness * sF / sL,
                               rtol=0, atol=1e-12 * np.abs(base.stiffness).max() * sF / sL)
    q0, p0 = base.welded(0.1, 0.0, 1.0)
    q1, p1 = m.welded(0.1 * sF, 0.0, sF)
    np.testing.assert_allclose(p1, p0 * sF, rtol=0, atol=1e-12 * sF)
    np.testing.assert_allclose(q1, q0 * sF, rtol=0, atol=1e-12 * sF)


def test_profiles():
    n, L = 9, 0.3
    sphere = sd.half_space_model("sphere", radius=2.0, n_cells=n, width=L)
    ell = sd.half_space_model("ellipsoid", radii=(2.0, 2.0), n_cells=n, width=L)
    np.testing.assert_allclose(ell.gap, sphere.gap)
    # cell mean of x^2 + y^2 is the centre value + 2 h^2 / 12
    xy = sphere.xy_cells
    np.testing.assert_allclose(sphere.gap, (np.sum(xy**2, axis=1) + sphere.h**2 / 6) / 4.0)
    flat = sd.half_space_model("flat_rounded", radius=1.0, flat_radius=0.1, n_cells=n, width=L)
    assert np.all(flat.gap[np.hypot(*xy.T) < 0.1 - sphere.h] == 0)
    hm = sd.half_space_model("height_map", heights=sphere.gap.reshape(n, n), n_cells=n, width=L)
    np.testing.assert_array_equal(hm.gap, sphere.gap)
    assert hm.reference == sphere.reference == n * n // 2
    assert sphere.xy.shape == (n * n - 1, 2)


@pytest.mark.parametrize("kw, field", [
    (dict(n_cells=1), "n_cells"), (dict(n_cells=True), "n_cells"), (dict(width=-1.0), "width"),
    (dict(profile="cone"), "profile"), (dict(profile="ellipsoid", radii=1.0), "radii"),
    (dict(profile="height_map", heights=np.zeros((2, 2))), "heights"),
    (dict(friction=-0.1), "friction"), (dict(materials=((1.0, 0.7), (1.0, 0.3))), "nu1"),
    (dict(radius=0.0), "radius"), (dict(materials=((np.inf, 0.3), (np.inf, 0.3))), "rigid"),
])
def test_bad_input(kw, field):
    args = dict(profile="sphere", radius=1.0, n_cells=5, width=0.3)
    args.update(kw)
    with pytest.raises(sd.InputError, match=field):
        sd.half_space_model(args.pop("profile"), **args)


def test_dense_limit_and_bad_loads():
    from shakedown.models.half_space import model as hs_model

    m = model(5)
    with pytest.raises(sd.InputError, match="P0"):
        m.load_cycle(P0=-1.0)
    with pytest.raises(sd.InputError, match="Qx"):
        m.load_cycle(P0=1.0, Qx=np.nan)
    big = model(int(np.sqrt(hs_model.DENSE_MAX_CELLS)) + 1)
    with pytest.raises(sd.InputError, match="stiffness_operator"):
        _ = big.stiffness


def test_load_cycle_welded_reactions_and_samples_agree():
    # the harmonic load at any t is the welded reaction of the resultants at t, and the sampled
    # load interpolates the same values at its samples
    m = model(5, materials=((E, NU), (np.inf, 0.0)))
    P0, P1, Qx, Qy, ph = P, 0.3 * P, 0.2 * P, 0.1 * P, 0.6
    load = m.load_cycle(P0=P0, P1=P1, Qx=Qx, Qy=Qy, phase=ph)
    assert load.dim == 3 and load.q0.shape == (m.n_cells - 1, 2)
    t = np.linspace(0, 1, 7, endpoint=False)
    q, p = load.evaluate(t, 1.0)
    qe, pe = m.welded(Qx * np.cos(2 * np.pi * t), Qy * np.sin(2 * np.pi * t),
                      P0 + P1 * np.cos(2 * np.pi * t + ph))
    scale = np.abs(pe).max()
    np.testing.assert_allclose(q, qe, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(p, pe, rtol=0, atol=1e-12 * scale)
    samples = m.load_from_samples(P0, P1 * np.cos(2 * np.pi * t + ph), Qx * np.cos(2 * np.pi * t),
                                  Qy * np.sin(2 * np.pi * t))
    qs, ps = samples.evaluate(t, 1.0)
    np.testing.assert_allclose(qs, qe, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(ps, pe, rtol=0, atol=1e-12 * scale)
