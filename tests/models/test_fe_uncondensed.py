"""An FE interface kept uncondensed (``FEModel.uncondensed()``, issue 14): the same welded
reactions, stiffness, displacements, runs, bounds and certificates as the condensed model
(``FEModel.condense()``, the boundary-layer Schur complement), without forming ``K``."""

import pickle

import numpy as np
import pytest

import shakedown as sd
from shakedown import fe
from shakedown.model.schur import SchurStiffness
from shakedown.model.uncondensed import UncondensedSystem


def strip(nx=39, E=1.0, traction=1.0, friction=0.5):
    """The strip of ``benchmarks/bench_fe_uncondensed.py``: held at its left end, bottom on a
    rigid obstacle (``nx`` contact nodes: the corner on the left end is held)."""
    loads = {"dead": fe.Traction("top", (0.0, -traction)),
             "shake": fe.Traction("top", (0.4 * traction, 0.0))}
    return fe.FEModel(fe.rectangle(nx / 100, 0.1, nx, 4), fe.isotropic(E, 0.3),
                      dirichlet={"left": "xy"}, contact=["bottom"], loads=loads,
                      friction=friction)


@pytest.fixture(scope="module")
def models():
    m = strip()
    return m.condense(), m.uncondensed()


def test_stiffness_welded_and_displacements_equal_condensed(models):
    c, u = models
    assert isinstance(u.system, UncondensedSystem) and isinstance(u.system.K, SchurStiffness)
    assert u.K is None and u.n_nodes == c.n_nodes == 39
    kmax = np.abs(c.K).max()
    np.testing.assert_allclose(u.system.K.toarray(), c.K, rtol=0, atol=1e-11 * kmax)
    for case in ("dead", "shake"):
        for a, b in zip(u.welded[case], c.welded[case], strict=True):  # (q, p)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(np.abs(b).max(), 1e-300))
    rng = np.random.default_rng(0)
    v, w = 1e-3 * rng.standard_normal(39), 1e-3 * rng.standard_normal(39)
    for load in (None, "dead"):
        du, dc = u.displacements(v, w, load), c.displacements(v, w, load)
        np.testing.assert_allclose(du, dc, rtol=0, atol=1e-11 * np.abs(dc).max())
    np.testing.assert_allclose(u.condensed().K, c.K, rtol=0, atol=1e-11 * kmax)
    assert "UncondensedModel(N=39" in repr(u)
    with pytest.raises(sd.InputError, match="unknown load case"):
        u.displacements(v, w, "nope")


@pytest.mark.parametrize("lam", [0.5, 0.86, 1.2])
def test_runs_equal_condensed(models, lam):
    c, u = models
    lc, lu = (m.load_cycle(static="dead", cyclic="shake") for m in (c, u))
    a = sd.solve_cycles(u.system, lu, lam, steps_per_cycle=24, max_cycles=30)
    b = sd.solve_cycles(c.system, lc, lam, steps_per_cycle=24, max_cycles=30)
    assert a.status == b.status and a.n_cycles == b.n_cycles
    scale = np.abs(b.final_slip).max() + 1e-300
    np.testing.assert_allclose(a.final_slip, b.final_slip, rtol=0, atol=1e-9 * scale)
    W = abs(b.dissipation).max() + 1e-300
    np.testing.assert_allclose(a.dissipation, b.dissipation, rtol=0, atol=1e-9 * W)
    np.testing.assert_array_equal(a.stuck_nodes, b.stuck_nodes)


def test_bounds_and_critical_friction_equal_condensed(models):
    c, u = models
    lc, lu = (m.load_cycle(static="dead", cyclic="shake") for m in (c, u))
    a, b = sd.shakedown_bounds(u.system, lu), sd.shakedown_bounds(c.system, lc)
    assert a.lam1 == pytest.approx(b.lam1, rel=1e-9)
    assert a.lam2 == pytest.approx(b.lam2, rel=1e-9)
    assert a.lam_separation == pytest.approx(b.lam_separation, rel=1e-9)
    ca, cb = u.system.critical_friction(), c.system.critical_friction()
    assert ca.factor == pytest.approx(cb.factor, rel=1e-8)


@pytest.mark.parametrize("E, t", [(2.1e11, 1e6), (3.0e9, 1.0)])
def test_units_of_the_uncondensed_model(E, t):
    """Young's modulus x E, tractions x t: K x E, slips x t / E, load factors unchanged."""
    ref, big = strip(19).uncondensed(), strip(19, E=E, traction=t).uncondensed()
    x = np.random.default_rng(1).standard_normal(2 * ref.n_nodes)
    np.testing.assert_allclose(big.system.K @ x, E * (ref.system.K @ x), rtol=1e-9,
                               atol=1e-12 * E * np.abs(ref.system.K @ x).max())
    la, lb = (m.load_cycle(static="dead", cyclic="shake") for m in (ref, big))
    a = sd.solve_cycles(ref.system, la, 0.86, steps_per_cycle=16, max_cycles=20)
    b = sd.solve_cycles(big.system, lb, 0.86, steps_per_cycle=16, max_cycles=20)
    assert a.status == b.status and a.n_cycles == b.n_cycles
    np.testing.assert_allclose(b.final_slip, a.final_slip * t / E, rtol=0,
                               atol=1e-8 * np.abs(a.final_slip).max() * t / E)
    ba, bb = sd.shakedown_bounds(ref.system, la), sd.shakedown_bounds(big.system, lb)
    assert bb.lam1 == pytest.approx(ba.lam1, rel=1e-9)


def test_pickle_and_friction(models):
    _, u = models
    s = pickle.loads(pickle.dumps(u.system))
    x = np.arange(78.0)
    np.testing.assert_allclose(s.K @ x, u.system.K @ x, rtol=1e-12)
    v = u.with_friction(0.2)
    assert v.K is u.system.K and np.all(v.friction == 0.2)


def test_no_support_is_named():
    """A body the Dirichlet conditions and the contact nodes do not hold: a clear error."""
    m = fe.FEModel(fe.rectangle(1.0, 0.2, 6, 2), fe.isotropic(1.0, 0.3), dirichlet={},
                   contact=["bottom"], friction=0.3)
    with pytest.raises(sd.InputError):
        m.uncondensed()
