"""Half-plane contact model (issue 11): influence coefficients, Hertz, Cattaneo-Mindlin, bad input.

Reference solutions: Flamant / Hertz (Johnson, *Contact Mechanics*, 1985, s.2.2, s.4.3),
Cattaneo (1938) / Mindlin (1949) in plane strain.  Every tolerance is relative to the problem's
own scales (``a``, ``p0``, ``P``) and justified by the measured discretisation error.
"""

import numpy as np
import pytest
from scipy import integrate

import shakedown as sd
from shakedown.models.half_plane import continuum as cont
from shakedown.models.half_plane import rigid_indenter_materials
from shakedown.models.half_plane.influence import cell_kernels

E, NU, R, F = 1.0, 0.3, 1.0, 0.5
E_STAR = E / (2 * (1 - NU**2))
P = 1e-3
A_H = cont.hertz_half_width(P, R, E_STAR)


def model(n, width_factor=3.0, **kw):
    kw.setdefault("materials", ((E, NU), (E, NU)))
    return sd.half_plane_model(radius=R, n_nodes=n, width=width_factor * A_H, friction=F, **kw)


def static(m, Q, Pn):
    """Apply Pn at Q = 0, then Q at constant Pn (two exact implicit steps, monotonic slip)."""
    s = m.system
    v = np.zeros(s.n_nodes)
    for qq in (0.0, Q):
        qw, pw = m.welded(qq, Pn)
        res = sd.solve_step(s, v, qw, pw)
        assert res.success
        v = res.slip
    qm, pm = m.reference_reactions(res.q, res.p, Q, Pn)
    return res, m.full(res.q, qm), m.full(res.p, pm)


def test_cell_kernels_match_quadrature():
    # closed-form double integrals of ln|x - s| and sgn(x - s) over two unit cells
    G, S = cell_kernels(6, 1.0)
    for i, j in [(0, 0), (0, 1), (0, 3), (5, 2)]:
        d = i - j
        g = integrate.dblquad(lambda s, x: np.log(abs(x - s) + 1e-300), -0.5, 0.5,
                              lambda x, d=d: d - 0.5, lambda x, d=d: d + 0.5)[0]
        sg = integrate.dblquad(lambda s, x: np.sign(x - s), -0.5, 0.5,
                               lambda x, d=d: d - 0.5, lambda x, d=d: d + 0.5)[0]
        # dblquad is accurate to ~1e-8 on the log singularity (i == j)
        assert G[j, i] == pytest.approx(g, abs=1e-7)
        assert S[j, i] == pytest.approx(sg, abs=1e-7)


def test_similar_materials_uncoupled_dissimilar_coupled_and_spd():
    assert not model(21).system.is_coupled
    m = model(21, materials=rigid_indenter_materials(0.3))
    assert m.system.is_coupled and m.beta == pytest.approx(0.3)
    assert np.linalg.eigvalsh(m.system.K)[0] > 0
    # Dundurs beta from the textbook formula (kappa = 3 - 4 nu, plane strain)
    (E1, n1), (E2, n2) = (2.0, 0.25), (1.0, 0.35)
    mu1, mu2 = E1 / (2 * (1 + n1)), E2 / (2 * (1 + n2))
    k1, k2 = 3 - 4 * n1, 3 - 4 * n2
    beta = (mu2 * (k1 - 1) - mu1 * (k2 - 1)) / (mu2 * (k1 + 1) + mu1 * (k2 + 1))
    assert model(21, materials=((E1, n1), (E2, n2))).beta == pytest.approx(beta, rel=1e-12)


def test_coupling_sign_pressure_draws_compliant_surface_inward():
    """Johnson eq. 2.19a: a normal load pulls the surface of the loaded half-plane towards it.

    Body 1 compliant, body 2 rigid (beta > 0): under pressure alone (slips free, q = 0) body 1's
    surface moves towards x = 0, so the slip v = u_x^(1) - u_x^(2) at x > 0 is below that at
    x < 0; magnitude ``v(x) - v(0) = -(2 beta/E*) int_0^x p``.
    """
    m = model(41, materials=rigid_indenter_materials(0.3))
    s = m.system
    res, _, _ = static(m, 0.0, P)
    # gaps held at the contact solution, q = 0 on every node: A v = -q_w - B w (eq. 5)
    qw, pw = m.welded(0.0, P)
    v_free = np.linalg.solve(s.A, -qw - s.B @ res.gap)
    q, p = s.reactions(v_free, res.gap, qw, pw)
    assert np.max(np.abs(q)) < 1e-12 * P
    right, left = m.x > 2 * m.h, m.x < -2 * m.h
    assert np.all(v_free[right] < 0) and np.all(v_free[left] > 0)
    p_full = m.full(p, P - p.sum())
    # cell mean of int sgn(x - s) p(s) ds for piecewise-constant p: sum_{k<i} p_k - sum_{k>i} p_k
    below = np.cumsum(p_full) - p_full
    sgn_int = below - (P - below - p_full)
    expect = -(m.beta / m.e_star) * (sgn_int - sgn_int[m.reference])
    # exact identity up to round-off (eq. 1 of influence.py), relative to the slip scale beta P/E*
    assert np.max(np.abs(v_free - np.delete(expect, m.reference))) < 1e-9 * m.beta * P / m.e_star


@pytest.mark.parametrize("n", [41, 81])
def test_hertz_half_width_and_pressure(n):
    m = model(n)
    res, q, p = static(m, 0.0, P)
    assert res.status == "unique"
    traction = p / m.h
    p0 = 2 * P / (np.pi * A_H)
    in_contact = traction > 1e-9 * p0
    # the last closed cell centre is within one cell of a (cells are closed or open)
    edge = np.max(np.abs(m.x_cells[in_contact]))
    assert abs(edge - A_H) <= m.h
    # second moment: int x^2 p = P a^2 / 4 -> a; measured error 3e-3 (n=41), 7e-4 (n=81), ~h^2
    a_mom = 2 * np.sqrt(np.sum(m.x_cells**2 * p) / P)
    assert a_mom == pytest.approx(A_H, rel=3 * (m.h / A_H) ** 2)
    # peak pressure: measured 2.2e-4 (n=41), 1.0e-4 (n=81): O(h/a)^2 plus the edge cell
    assert traction.max() == pytest.approx(p0, rel=2 * (m.h / A_H) ** 2)
    assert p.sum() == pytest.approx(P, rel=1e-12)
    assert np.all(q == pytest.approx(0.0, abs=1e-12 * P))


@pytest.mark.parametrize("profile,kw", [("flat_rounded", {"flat_half_width": 0.4 * A_H}),
                                        ("power", {"exponent": 4.0})])
def test_general_profiles_half_width(profile, kw):
    g = sd.models.half_plane.profile_function(profile, radius=R, **kw)
    a = cont.contact_half_width(P, g, E_STAR, a_max=10 * A_H)
    m = sd.half_plane_model(profile, radius=R, n_nodes=81, width=2.6 * a, friction=F,
                            materials=((E, NU), (E, NU)), **kw)
    _, _, p = static(m, 0.0, P)
    edge = np.max(np.abs(m.x_cells[p > 1e-9 * P / a]))
    assert abs(edge - a) <= m.h


@pytest.mark.parametrize("ratio", [0.3, 0.75])
def test_cattaneo_mindlin_stick_zone(ratio):
    m = model(81)
    Q = ratio * F * P
    res, q, p = static(m, Q, P)
    c = A_H * cont.cattaneo_mindlin_ratio(Q, P, F)
    slipping = np.abs(res.slip) > 1e-9 * np.abs(res.slip).max()
    stuck_x = np.abs(np.delete(m.x_cells, m.reference)[~slipping & (res.p > 0)])
    # outermost stuck cell centre within one cell of c
    assert abs(stuck_x.max() - c) <= m.h
    # slip zone: q = +f p (backward slip, MODEL.md s.1: Q > 0 pushes body 1 towards -x)
    assert np.allclose(res.q[slipping], F * res.p[slipping], rtol=1e-9, atol=1e-12 * P)
    # traction vs the Cattaneo-Mindlin closed form, relative to f p0; measured 1.1e-2 (edge cells)
    p0 = 2 * P / (np.pi * A_H)
    x = m.x_cells
    q_cm = F * p0 / A_H * (np.sqrt(np.clip(A_H**2 - x**2, 0, None))
                           - np.sqrt(np.clip(c**2 - x**2, 0, None)))
    inner = np.abs(x) < A_H - 2 * m.h
    assert np.max(np.abs(q / m.h - q_cm)[inner]) < 0.03 * F * p0


def test_reference_cell_stays_inside_the_cone():
    m = model(41)
    res, q, p = static(m, 0.6 * F * P, P)
    assert abs(q[m.reference]) < F * p[m.reference]


@pytest.mark.parametrize("kw,field", [
    ({"radius": -1.0}, "radius"), ({"n_nodes": 20}, "n_nodes"), ({"width": 0.0}, "width"),
    ({"friction": -0.1}, "friction"), ({"materials": ((1.0, 0.3),)}, "materials"),
    ({"materials": ((1.0, 0.7), (1.0, 0.3))}, "nu1"), ({"profile": "cone"}, "profile"),
    ({"profile": "flat_rounded"}, "flat_half_width"),
])
def test_bad_input_names_the_field(kw, field):
    args = dict(radius=1.0, n_nodes=21, width=0.1, friction=0.5)
    args.update(kw)
    profile = args.pop("profile", "hertz")
    with pytest.raises(sd.InputError, match=field):
        sd.half_plane_model(profile, **args)


def test_bad_load_names_the_field():
    m = model(21)
    with pytest.raises(sd.InputError, match="P0"):
        m.load_cycle(P0=-1.0)
    with pytest.raises(sd.InputError, match="phase"):
        m.load_cycle(P0=1.0, phase=float("nan"))


def test_sampled_load_matches_harmonic_load_at_the_samples():
    m = model(21)
    t = np.arange(16) / 16
    h = m.load_cycle(P0=P, P1=0.3 * P, Q1=0.2 * P, phase=0.7)
    s = m.load_from_samples(P, 0.3 * P * np.cos(2 * np.pi * t + 0.7), 0.2 * P * np.cos(2 * np.pi * t))
    for lam in (0.0, 1.0, 2.5):
        assert np.allclose(h.q_w(t, lam), s.q_w(t, lam), rtol=0, atol=1e-12 * P)
        assert np.allclose(h.p_w(t, lam), s.p_w(t, lam), rtol=0, atol=1e-12 * P)
