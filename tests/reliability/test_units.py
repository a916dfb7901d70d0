"""Unit invariance of every analysis (issue 10, item 1; ARCHITECTURE rule 8).

Changing units multiplies the stiffness by ``ck`` and the forces by ``cf`` (both drawn
log-uniformly from 1e-6 .. 1e12, so almost never powers of two, plus fixed corner examples).
Then, exactly in real arithmetic:

* ``lam1``, ``lam2``, ``lam_adj``, ``mu*``, the critical friction, stuck nodes and the verdicts
  are unchanged (they are ratios of forces or of stiffnesses),
* slips scale as ``cf / ck`` and the steady dissipation ``W`` as ``cf^2 / ck``,
* growth rates scale as ``sqrt(ck / cm)`` when the mass is multiplied by ``cm``,
* FE and Kachanov models built in SI units (moduli ~1e10 Pa, lengths ~1e-3 m, stresses ~1e8 Pa)
  give the same dimensionless answers as their unit-modulus versions.

Tolerances: the reference and the rescaled problem differ only by rounding of the scaled data
(relative 1e-16 per entry); every solver behind them certifies its answer to a *relative*
tolerance, so they may differ by that tolerance and no more.  Each bound is stated where it is
used.  Cases that failed only because of the bounds LP / step solver code (owned by other
branches) are marked xfail until those branches are merged (issue 10 split).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import crack_networks as cn
import shakedown as sd
from shakedown import stability as stab

#: log10 of a unit-change factor, 1e-6 .. 1e12 (issue 10 item 1)
EXPONENT = st.floats(min_value=-6.0, max_value=12.0, allow_nan=False)

PENDING_BOUNDS = pytest.mark.xfail(
    reason="scale-free bounds/step solver pending on its branch", strict=False)

FAST = settings(max_examples=15, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=6, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])


def rescaled(system, load, ck, cf):
    return (sd.DiscreteSystem(ck * system.A, ck * system.B, ck * system.C, system.friction),
            load.scaled(cf))


def two_node():
    # built-in scene two_node_coupled (seed 002 Fig. 4 type): lam1 < lam_adj-type triangle
    s = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                          [[1.5, 0.2], [0.2, 1.5]], 0.7)
    load = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0],
                                       q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
    return s, load


def four_node():
    rng = np.random.default_rng(7)
    M = rng.standard_normal((8, 8))
    K = M @ M.T + 2.0 * np.eye(8)
    s = sd.DiscreteSystem(K[:4, :4], 0.4 * K[:4, 4:], K[4:, 4:], [0.5, 0.6, 0.4, 0.7])
    load = sd.LoadCycle.from_harmonics(rng.uniform(-0.2, 0.2, 4), rng.uniform(1.0, 2.0, 4),
                                       q_cos=rng.uniform(-1, 1, 4), q_sin=rng.uniform(-1, 1, 4),
                                       p_cos=rng.uniform(-0.3, 0.3, 4))
    return s, load


SYSTEMS = {"two_node": two_node(), "four_node": four_node()}
REF_BOUNDS = {k: sd.shakedown_bounds(*v) for k, v in SYSTEMS.items()}


# ------------------------------------------------------------------ lam1, lam2, lam_adj
@PENDING_BOUNDS
@pytest.mark.parametrize("name", sorted(SYSTEMS))
@FAST
@given(ek=EXPONENT, ef=EXPONENT)
@example(ek=12.0, ef=-6.0)
@example(ek=-6.0, ef=12.0)
@example(ek=36 * np.log10(2), ef=27 * np.log10(2))  # the exact powers of two
def test_bounds_do_not_depend_on_units(name, ek, ef):
    ref = REF_BOUNDS[name]
    b = sd.shakedown_bounds(*rescaled(*SYSTEMS[name], 10.0**ek, 10.0**ef))
    assert b.status == ref.status
    # LP answers are certified to 1e-9 relative (HiGHS feasibility/optimality tolerances on
    # the nondimensional problem); the two problems differ only by rounding of the data
    for key in ("lam1", "lam2", "lam_adj"):
        assert getattr(b, key) == pytest.approx(getattr(ref, key), rel=1e-7, abs=1e-9), key


# ------------------------------------------------------------------ critical friction (model/)
@SLOW
@given(ek=EXPONENT)
@example(ek=12.0)
@example(ek=-6.0)
def test_critical_friction_does_not_depend_on_units(ek):
    for s, _ in SYSTEMS.values():
        ref = s.critical_friction()
        c = sd.DiscreteSystem(10.0**ek * s.A, 10.0**ek * s.B, 10.0**ek * s.C,
                              s.friction).critical_friction()
        # generalized eigenvalues of the scaled pencils: relative rounding ~1e-14 x cond
        assert c.factor == pytest.approx(ref.factor, rel=1e-10)
        assert (c.method, c.exact, c.well_posed) == (ref.method, ref.exact, ref.well_posed)


# ------------------------------------------------------------------ cycles: W, stuck nodes
def _cycle(system, load, lam):
    return sd.solve_cycles(system, load, lam, initial_slip=None, steps_per_cycle=64,
                           max_cycles=200)


REF_RUNS = {}


def ref_run(name, factor):
    key = (name, factor)
    if key not in REF_RUNS:
        s, load = SYSTEMS[name]
        REF_RUNS[key] = _cycle(s, load, factor * REF_BOUNDS[name].lam2)
    return REF_RUNS[key]


@pytest.mark.parametrize("name", sorted(SYSTEMS))
@pytest.mark.parametrize("factor", [0.3, 1.5])  # below lam1 (shakedown) and above lam2 (slip)
@SLOW
@given(ek=EXPONENT, ef=EXPONENT)
@example(ek=12.0, ef=-6.0)
@example(ek=-6.0, ef=12.0)
def test_cycles_do_not_depend_on_units(name, factor, ek, ef):
    ck, cf = 10.0**ek, 10.0**ef
    ref = ref_run(name, factor)
    run = _cycle(*rescaled(*SYSTEMS[name], ck, cf), factor * REF_BOUNDS[name].lam2)
    assert (run.status, run.period, run.shook_down) == (ref.status, ref.period, ref.shook_down)
    assert np.array_equal(run.stuck_nodes, ref.stuck_nodes)
    # the steady test stops at a relative state change tol = 1e-10 and steps are verified to
    # FEAS_TOL ~1e-9 relative: W / (cf^2 / ck) agrees to that, measured 1e-12 here
    assert run.steady_dissipation * ck / cf**2 == pytest.approx(ref.steady_dissipation,
                                                                rel=1e-7, abs=1e-9)
    assert run.final_slip * ck / cf == pytest.approx(ref.final_slip, rel=1e-7, abs=1e-9)
    assert run.sampling_error / cf == pytest.approx(ref.sampling_error, rel=1e-12)


@pytest.mark.parametrize("ek, ef", [(12.0, -6.0), (np.log10(3.7e9), np.log10(1.3e-5))])
def test_steady_cycle_solver_does_not_depend_on_units(ek, ef):
    from shakedown.evolution import steady_cycle

    s, load = SYSTEMS["two_node"]
    lam = 1.5 * REF_BOUNDS["two_node"].lam2
    ref = steady_cycle(s, load, lam, steps_per_cycle=64)
    ck, cf = 10.0**ek, 10.0**ef
    sc = steady_cycle(*rescaled(s, load, ck, cf), lam, steps_per_cycle=64)
    assert sc.status == ref.status
    # fixed point of the period map, verified by one simulated period to 1e-10 relative
    assert sc.run.steady_dissipation * ck / cf**2 == pytest.approx(
        ref.run.steady_dissipation, rel=1e-7)


# ------------------------------------------------------------------ stability: mu*, growth rates
@FAST
@given(ek=EXPONENT)
@example(ek=12.0)
@example(ek=-6.0)
def test_mu_star_does_not_depend_on_units(ek):
    s, _ = SYSTEMS["four_node"]
    part = stab.NodePartition.all_slip(4, chi=np.array([1.0, -1.0, 1.0, -1.0]))
    ref = stab.mceip_mu(s.K, part)
    for method in ("auto", "enumeration", "linear-dense", "power"):
        r = stab.mceip_mu(10.0**ek * np.asarray(s.K), part, method=method)
        r0 = ref if method == "auto" else stab.mceip_mu(s.K, part, method=method)
        assert r.status == r0.status
        if r.found:
            # eigenvalues of the same pencil times a constant: relative rounding only;
            # the power iteration converges to 1e-10 relative (its own tolerance)
            assert r.mu == pytest.approx(r0.mu, rel=1e-8)
            assert np.array_equal(r.support, r0.support)


K_RP = np.array([  # tests/stability/test_stability_fe.py: returning point, two growth rates
    [4.9, 4.54, 0.02, 2.95, -0.78, -1.13], [4.54, 6.54, -1.45, 3.06, -0.67, -3.23],
    [0.02, -1.45, 4.59, -0.45, 0.15, 1.92], [2.95, 3.06, -0.45, 8.54, -0.02, -0.54],
    [-0.78, -0.67, 0.15, -0.02, 0.67, 0.23], [-1.13, -3.23, 1.92, -0.54, 0.23, 3.88]])
M_RP = np.array([
    [0.76, 0.59, -0.3, 0.07, 0.15, 0.61], [0.59, 2.89, -0.58, 0.58, -0.68, -0.17],
    [-0.3, -0.58, 1.13, -0.2, -0.45, -0.76], [0.07, 0.58, -0.2, 2.19, 0.5, -0.93],
    [0.15, -0.68, -0.45, 0.5, 3.48, -0.07], [0.61, -0.17, -0.76, -0.93, -0.07, 1.82]])
PART_RP = stab.NodePartition.from_states(["slip", "slip", "free"], -1.0)


def _rates(ck, cm):
    unit = np.sqrt(ck / cm)  # growth rates carry 1 / time = sqrt(stiffness / mass)
    # mu = 2.075: 0.1 below the returning point mu_m = 2.1754 (lam_m = 2.255), two rates
    return stab.growth_rates(ck * K_RP, PART_RP, 2.075, lams=unit * np.linspace(0, 4, 21),
                             mass=cm * M_RP), unit


@SLOW
@given(ek=EXPONENT, em=EXPONENT)
@example(ek=10.3, em=3.4)   # SI: GPa-range stiffness, kg-range mass
@example(ek=-6.0, em=12.0)
def test_growth_rates_scale_as_sqrt_stiffness_over_mass(ek, em):
    ref, _ = _rates(1.0, 1.0)
    assert ref.status == "found" and ref.lam.size == 2
    g, unit = _rates(10.0**ek, 10.0**em)
    assert g.status == ref.status
    # Brent's method to rtol 1e-12 on the support eigenvalue, xtol relative to the range
    np.testing.assert_allclose(g.lam / unit, ref.lam, rtol=1e-8)


def test_layer_growth_rates_scale_with_modulus_height_density():
    D = np.array([[8.6, 1.1, 0.9], [1.1, 1.3, 0.35], [0.9, 0.35, 0.45]])  # anisotropic, D24 != 0
    mu_cr, _ = stab.layer_critical_friction(D)
    mu = 1.2 * mu_cr
    ref = stab.layer_growth_rates(D, mu)
    assert ref.size >= 1
    E, h, rho = 7.3e10, 2.5e-3, 2.7e3  # SI: Pa, m, kg / m^3
    got = stab.layer_growth_rates(E * D, mu, height=h, density=rho)
    assert stab.layer_critical_friction(E * D)[0] == pytest.approx(mu_cr, rel=1e-14)
    # Brent to rtol 1e-14 on both: the scaled roots agree to rounding of the scan
    np.testing.assert_allclose(got * h * np.sqrt(rho / E), ref, rtol=1e-9)


# ------------------------------------------------------------------ FE in SI units
def _fe_block(E, width, thickness):
    from shakedown import fe

    mesh = fe.rectangle(width, 0.5 * width, 6, 3)
    loads = {"dead": fe.Pressure("top", 1e-3 * E), "shake": fe.Traction("left", (5e-4 * E, 0.0))}
    model = fe.FEModel(mesh, fe.isotropic(E, 0.3), dirichlet={"right": "xy"},
                       contact=["bottom"], loads=loads, friction=0.5, thickness=thickness)
    cm = model.condense()
    return cm, cm.load_cycle(static="dead", cyclic="shake")


@pytest.fixture(scope="module")
def fe_pair():
    return _fe_block(1.0, 1.0, 1.0), _fe_block(2.1e11, 3.7e-3, 1e-2)  # steel, mm-size, 1 cm


def test_fe_model_in_si_units_scales_exactly(fe_pair):
    (cm1, load1), (cm2, load2) = fe_pair
    # plane strain 2-D: K ~ E t (no length), reactions ~ stress x length x t
    ck, cf = 2.1e11 * 1e-2, 2.1e11 * 3.7e-3 * 1e-2
    # condensation is exact up to round-off (cond(K_ii) <= 1e5): 1e-9 relative
    np.testing.assert_allclose(cm2.K / ck, cm1.K, rtol=1e-9, atol=1e-12 * np.abs(cm1.K).max())
    np.testing.assert_allclose(load2.q0 / cf, load1.q0, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(load2.q_cos / cf, load1.q_cos, rtol=1e-9, atol=1e-12)
    assert cm2.system.critical_friction().factor == pytest.approx(
        cm1.system.critical_friction().factor, rel=1e-8)
    r1 = sd.solve_cycles(cm1.system, load1, 1.0, steps_per_cycle=32)
    r2 = sd.solve_cycles(cm2.system, load2, 1.0, steps_per_cycle=32)
    assert (r1.status, r1.shook_down) == (r2.status, r2.shook_down)
    assert r2.steady_dissipation * ck / cf**2 == pytest.approx(r1.steady_dissipation,
                                                               rel=1e-7, abs=1e-12)


@PENDING_BOUNDS
def test_fe_bounds_in_si_units(fe_pair):
    (cm1, load1), (cm2, load2) = fe_pair
    b1, b2 = sd.shakedown_bounds(cm1.system, load1), sd.shakedown_bounds(cm2.system, load2)
    for key in ("lam1", "lam2", "lam_adj"):
        assert getattr(b2, key) == pytest.approx(getattr(b1, key), rel=1e-7), key


# ------------------------------------------------------------------ Kachanov in SI units
@pytest.fixture(scope="module")
def cracks():
    return cn.sample_crack_set(30, density=0.1, rng=3)  # the set


def _kachanov(cracks, mu, p0, length):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cn.KachanovAccuracyWarning)
        m = cn.kachanov_model(cracks.scaled(length), shear_modulus=mu, friction=0.6)
    return m, m.load_cycle((-p0, 0.0, -p0), (0.0, p0, 0.0))


SI = [(1.0, 1.0, 1.0), (2.0**36, 2.0**27, 1.0), (1.0, 1e8, 1.0), (3e10, 1e8, 1e-3),
      (3e10, 1e8, 1.0), (1e-6, 1e-6, 1e6)]


@pytest.mark.parametrize("mu, p0, length", SI[1:])
def test_kachanov_model_in_si_units_scales_exactly(cracks, mu, p0, length):
    m1, l1 = _kachanov(cracks, *SI[0])
    m2, l2 = _kachanov(cracks, mu, p0, length)
    # 2-D: K ~ mu (traction x length over mean displacement), reactions ~ stress x length
    np.testing.assert_allclose(m2.system.K / mu, m1.system.K, rtol=1e-12,
                               atol=1e-14 * np.abs(m1.system.K).max())
    cf = p0 * length
    np.testing.assert_allclose(l2.p0 / cf, l1.p0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(l2.q_cos / cf, l1.q_cos, rtol=1e-12, atol=1e-14)
    run1 = sd.solve_cycles(m1.system, l1, 0.9, steps_per_cycle=32)
    run2 = sd.solve_cycles(m2.system, l2, 0.9, steps_per_cycle=32)
    assert run2.status == run1.status == "periodic"
    assert np.array_equal(run2.stuck_nodes, run1.stuck_nodes)
    # W* = W mu / (4 (1 - nu) p0^2 abar^2) is the dimensionless dissipation (MODEL.md s.7)
    assert m2.normalised_dissipation(run2.steady_dissipation, p0) == pytest.approx(
        m1.normalised_dissipation(run1.steady_dissipation, 1.0), rel=1e-7)


@PENDING_BOUNDS
@pytest.mark.parametrize("mu, p0, length", SI[1:])
def test_kachanov_bounds_in_si_units(cracks, mu, p0, length):
    b1 = sd.shakedown_bounds(*(lambda m, lc: (m.system, lc))(*_kachanov(cracks, *SI[0])))
    b2 = sd.shakedown_bounds(*(lambda m, lc: (m.system, lc))(*_kachanov(cracks, mu, p0, length)))
    for key in ("lam1", "lam2", "lam_adj"):
        assert getattr(b2, key) == pytest.approx(getattr(b1, key), rel=1e-7), key
