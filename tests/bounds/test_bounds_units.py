"""The shakedown bounds do not depend on the unit system (issue 10 item 1).

Stiffness and loads are rescaled independently by factors from 1e-6 to 1e12 (not only powers of
two).  Load factors are unit-free; slips scale as force / stiffness; the ``lam2`` certificate (the
multipliers of an LP whose objective is ``lam``) as 1 / force.  The LPs are solved in
nondimensional units (``shakedown.bounds.constraints.Scales``), so a rescaled problem differs from
the reference only by the rounding of the scaling itself (1e-16 relative): measured differences
are below 1e-13 on the dense path and 1e-11 with HiGHS (whose pivoting tolerances act on the
rounded data), so the tolerance 1e-9 (the issue's target) has two orders of margin.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_bounds import check_certificate, random_problem

import crack_networks as cn
import shakedown as sd
from shakedown.bounds import shakedown_bounds

RTOL = 1e-9
factors = st.floats(1e-6, 1e12)


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = np.maximum(np.abs(b), np.nanmax(np.abs(b), initial=0.0) * 1e-9 + 1e-300)
    both_nan = np.isnan(a) & np.isnan(b)
    d = np.where(both_nan, 0.0, np.abs(a - b) / scale)
    return float(np.max(np.where(np.isinf(a) & (a == b), 0.0, d), initial=0.0))


def assert_same_bounds(b, ref, stiffness, force, load_factor=1.0):
    """``b`` (rescaled problem) equals ``ref`` in the reference units."""
    for name in ("lam1", "lam2", "lam_adj", "lam_separation", "safe_lam"):
        assert _rel(getattr(b, name) * load_factor, getattr(ref, name)) <= RTOL, name
    for name in ("lam_low", "lam_high"):
        assert _rel(getattr(b, name) * load_factor, getattr(ref, name)) <= RTOL, name
    assert b.adjacency_node == ref.adjacency_node
    assert b.limiting_constraint == ref.limiting_constraint
    assert b.status == ref.status
    slip = force / stiffness
    assert _rel(b.state_at_lam2 / slip, ref.state_at_lam2) <= RTOL
    assert _rel(b.safe_margin / slip, ref.safe_margin) <= RTOL
    assert _rel(b.safe_state / slip, ref.safe_state) <= 1e-7  # a vertex of the centre LP
    assert _rel(b.certificate * force * load_factor, ref.certificate) <= RTOL
    check_certificate(b)


@pytest.mark.parametrize("solver", ["auto", "highs"])
def test_issue_example_kachanov_in_other_units(solver):
    """The issue's example: 30 cracks in units (1, 1), (2^36, 2^27), (1, 1e8) and SI-like
    (3e10, 1e8); before the fix lam1 was 0.5974 / 0.5883 / 0.0 on both paths."""
    cracks = cn.sample_crack_set(30, density=0.1, rng=3)
    out = []
    for mu, p0 in [(1.0, 1.0), (2.0**36, 2.0**27), (1.0, 1e8), (3e10, 1e8)]:
        m = cn.kachanov_model(cracks, shear_modulus=mu, friction=0.6)
        b = shakedown_bounds(m.system, m.load_cycle((-p0, 0, -p0), (0, p0, 0)), solver=solver,
                             adjacency=True)
        out.append((b.lam1, b.lam2, b.lam_adj, b.lam_separation))
    out = np.array(out)
    np.testing.assert_allclose(out, np.broadcast_to(out[0], out.shape), rtol=RTOL)
    assert 0.5 < out[0, 0] < out[0, 1] < 0.65


@settings(max_examples=12, deadline=None)
@given(stiffness=factors, force=factors, seed=st.integers(0, 20))
def test_bounds_do_not_depend_on_units(stiffness, force, seed):
    system, load = random_problem(5, seed, coupling=0.5)
    ref = shakedown_bounds(system, load, adjacency=True, intervals=True)
    scaled = sd.DiscreteSystem(stiffness * system.A, stiffness * system.B, stiffness * system.C,
                               system.friction)
    b = shakedown_bounds(scaled, load.scaled(force), adjacency=True, intervals=True)
    assert_same_bounds(b, ref, stiffness, force)
    # the safe state at a given lam is the same point in the new units
    lam = 0.3 * ref.lam2
    c1 = shakedown_bounds(system, load, lam=lam, intervals=False)
    c2 = shakedown_bounds(scaled, load.scaled(force), lam=lam, intervals=False)
    assert _rel(c2.safe_state * stiffness / force, c1.safe_state) <= 1e-7


@settings(max_examples=6, deadline=None)
@given(stiffness=factors, force=factors, periodic=factors)
def test_highs_path_does_not_depend_on_units(stiffness, force, periodic):
    """The reference path too, and a periodic part in its own units (lam scales inversely)."""
    system, load = random_problem(4, 11, coupling=0.5)
    ref = shakedown_bounds(system, load, adjacency=True, solver="highs")
    scaled = sd.DiscreteSystem(stiffness * system.A, stiffness * system.B, stiffness * system.C,
                               system.friction)
    lo = load.scaled(force)
    lo = sd.LoadCycle.from_harmonics(lo.q0, lo.p0, q_cos=periodic * lo.q_cos,
                                     q_sin=periodic * lo.q_sin, p_cos=periodic * lo.p_cos)
    b = shakedown_bounds(scaled, lo, adjacency=True, solver="highs")
    assert_same_bounds(b, ref, stiffness, force, load_factor=periodic)


def test_frictionless_separation_limit_in_other_units():
    """``lam_separation`` and its nodes (the no-separation LP) in SI-like units."""
    A = np.array([[2.0, 0.5], [0.5, 2.0]])
    B = np.array([[0.0, 0.3], [0.8, 0.0]])
    load = sd.LoadCycle.from_harmonics([0.2, 0.0], [0.3, 2.0], q_cos=[0.0, 1.0], p_cos=[1.0, 0])
    ref = sd.shakedown_bounds(sd.DiscreteSystem(A, B, 3 * np.eye(2), [0.0, 0.5]), load)
    for k, f in [(3.7e10, 2.3e8), (1e-6, 1e12)]:
        s = sd.DiscreteSystem(k * A, k * B, 3 * k * np.eye(2), [0.0, 0.5])
        for solver in ("auto", "highs"):
            b = sd.shakedown_bounds(s, load.scaled(f), solver=solver)
            assert b.separation_nodes == ref.separation_nodes == (0,)
            assert b.lam_separation == pytest.approx(ref.lam_separation, rel=RTOL)
