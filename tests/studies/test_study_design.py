"""The study's load factors, initial states and summaries (issue 13).

* load factors fall where the seed's claims are decided: inside ``(lam1, lam2)`` near both ends,
  inside ``(lam_adj, lam1)``, at the same ``lam / lam2`` in every realisation (property test);
* the ``safe`` state shakes down at once for ``lam <= lam2`` (the bounds' certificate), the
  ``corner`` states are at the static friction limit of every node;
* one step solver shared by the states of a task gives the same steady ``W`` as a fresh solver
  per run (the batched path against the independent one);
* the bands over realisations equal the Student-t interval of scipy.stats (independent code).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shakedown.studies.design import _corner, initial_states, lam_points, refine_points
from shakedown.studies.summary import bands, lam_u

pytest.importorskip("crack_networks")


@settings(max_examples=60, deadline=None)
@given(lam2=st.floats(1e-6, 1e9), r1=st.floats(0.0, 1.0), ra=st.floats(0.0, 1.5),
       n_band=st.integers(0, 6), n_adj=st.integers(0, 3))
def test_load_factors_sample_the_bands(lam2, r1, ra, n_band, n_adj):
    lam1, lam_adj = r1 * lam2, ra * r1 * lam2
    pts = lam_points(lam1, lam2, lam_adj, n_lams=5, lam_span=(0.5, 2.0), n_band=n_band,
                     n_adj=n_adj)
    lam = np.array([p[1] for p in pts])
    assert np.all(np.diff(lam) >= 0)
    names = [p[0] for p in pts]
    assert len(set(names)) == len(names)
    band = lam[[n.startswith("b") for n in names]]
    adj = lam[[n.startswith("a") for n in names]]
    grid = lam[[n.startswith("g") for n in names]]
    np.testing.assert_allclose(grid / lam2, np.linspace(0.5, 2.0, 5), rtol=1e-14)
    # every point strictly inside its band; all of them unless the band is a few ulps wide
    wide = (lam2 - lam1) > 1e-13 * lam2
    if lam1 < lam2:
        assert band.size == n_band or not wide
        assert np.all((band > lam1) & (band < lam2))
        if n_band > 1 and wide:  # near both ends: within 2 % of the band's width
            assert band.min() - lam1 <= 0.0201 * (lam2 - lam1)
            assert lam2 - band.max() <= 0.0201 * (lam2 - lam1)
    else:
        assert band.size == 0
    if lam_adj < lam1:
        assert adj.size == n_adj or lam1 - lam_adj <= 1e-13 * lam1
        assert np.all((adj > lam_adj) & (adj < lam1))
    else:
        assert adj.size == 0


def test_refinement_brackets_lam_u_and_splits_the_widest_spread():
    pts = pd.DataFrame(dict(lam=[1.0, 2.0, 3.0, 4.0], W_star_min=[0, 0.5, 2.0, 5.0],
                            W_star_max=[0, 1.5, 2.1, 5.0], all_slip=[False, False, False, True]))
    out = refine_points(pts, 3)
    assert out[0] == ("u0", 3.5)
    assert out[1][1] in (1.5, 2.5)  # the intervals next to the largest spread (lam = 2)
    assert len(out) == 3


def test_lam_u_and_lam_same_from_a_summary():
    s = pd.DataFrame(dict(realisation=0, lam=[1.0, 2.0, 3.0, 4.0],
                          W_star_min=[0.0, 1.0, 3.0, 5.0], W_star_max=[0.0, 2.0, 3.0, 5.0],
                          all_slip=[False, True, False, True]))
    row = lam_u(s).iloc[0]
    # "from lam_u on": the all-slip point at 2.0 is followed by one that is not
    assert (row.lam_u, row.lam_u_low, row.lam_same) == (4.0, 3.0, 3.0)


def test_bands_equal_student_t_of_scipy_stats():
    from scipy import stats

    rng = np.random.default_rng(0)
    x = rng.uniform(1, 2, 7)
    s = pd.DataFrame(dict(realisation=range(7), point="g0", lam=1.0, x=0.5, W_star_min=x,
                          W_star_max=2 * x, frac_slip_min=0.1, frac_slip_max=0.2,
                          frac_open_min=0.0, frac_open_max=0.0))
    b = bands(s, 0.9).iloc[0]
    lo, hi = stats.t.interval(0.9, 6, loc=x.mean(), scale=x.std(ddof=1) / np.sqrt(7))
    # two implementations of the same quantile: agreement to rounding (1e-12 relative)
    np.testing.assert_allclose([b.W_star_min_lo, b.W_star_min_hi], [lo, hi], rtol=1e-12)
    assert np.isnan(bands(s.iloc[:1], 0.9).iloc[0].W_star_min_lo)  # one realisation: no band


@pytest.fixture(scope="module")
def network():
    import crack_networks as cn
    import shakedown as sd

    cs = cn.sample_crack_set(15, density=0.1, rng=7)
    m = cn.kachanov_model(cs, shear_modulus=3.0e4, friction=0.6)  # not unit modulus on purpose
    load = m.load_cycle(static=(-50.0, 0.0, -50.0), cyclic=(0.0, 50.0, 0.0))
    b = sd.shakedown_bounds(m.system, load, separation=False)
    return m.system, load, b


def test_corner_states_are_at_the_static_friction_limit(network):
    system, load, _ = network
    for signs in (np.ones(15), -np.ones(15), np.where(np.arange(15) % 3, 1.0, -1.0)):
        v = _corner(system, load, signs)
        q = load.q0 + system.A @ v
        p = load.p0 + system.B.T @ v
        # a linear solve with a well-conditioned matrix: residual ~ 1e-12 of the forces
        np.testing.assert_allclose(q, signs * system.friction * p,
                                   atol=1e-10 * np.abs(load.p0).max())


def test_safe_state_shakes_down_at_once_below_lam2(network):
    import shakedown as sd

    system, load, b = network
    states = initial_states(system, load, 2, (0, 0, 1), safe_state=b.state_at_lam2)
    for lam in (0.5 * b.lam1, 0.5 * (b.lam1 + b.lam2), b.lam2 * (1 - 1e-6)):
        run = sd.solve_cycles(system, load, lam, initial_slip=states[1], steps_per_cycle=32)
        assert run.shook_down and run.steady_dissipation == 0.0, lam


def test_batched_states_equal_independent_runs(network):
    """The study's path (all states of a task together through solve_cycles' batched mode, one
    StepSolver) against a fresh solver per independent run: the same steady W to the solver's
    tolerance (1e-9 relative: the steady-state test stops at a 1e-10 relative change per cycle,
    and the shared factors change only the last bits of each step)."""
    import shakedown as sd
    from shakedown.studies.runs import run_row

    system, load, b = network
    states = initial_states(system, load, 6, (0, 0, 1), safe_state=b.state_at_lam2)
    opts = dict(method="implicit", steps_per_cycle=32, max_cycles=100, tol=1e-10)
    for lam in (0.5 * (b.lam1 + b.lam2), 1.3 * b.lam2):
        a = run_row(system, load, lam, states, opts, step_solver=sd.StepSolver(system))
        c = [run_row(system, load, lam, v, opts) for v in states]
        assert isinstance(a, list) and len(a) == len(states)
        for x, y in zip(a, c, strict=True):
            assert x["period"] == y["period"] and x["shook_down"] == y["shook_down"]
            np.testing.assert_allclose(x["W"], y["W"], rtol=1e-9, atol=0)
            assert x["frac_slip"] == y["frac_slip"] or np.isnan(x["frac_slip"])


def test_study_answers_do_not_depend_on_units(tmp_path):
    """The same study in SI-like units (mu = 27 GPa, stresses of 130 MPa, not powers of two):
    the same load factors, W* (dimensionless) and counts as in unit scales."""
    from dataclasses import replace

    from shakedown.studies.sweep import SweepSpec, run_sweep

    unit = SweepSpec(n_cracks=8, density=0.1, n_lams=3, n_band=2, n_adj=1, n_refine=1,
                     n_states=4, steps_per_cycle=16, max_cycles=60, seed=3)
    p0, mu = 1.3e8, 2.7e10
    si = replace(unit, shear_modulus=mu, static=(-p0, 0.0, -p0), cyclic=(0.0, p0, 0.0))
    a = run_sweep(unit, tmp_path / "unit", n_workers=1, progress=False).summary
    b = run_sweep(si, tmp_path / "si", n_workers=1, progress=False).summary
    assert list(a["point"]) == list(b["point"])
    # load factors from the bounds: the LP tolerances are relative, so the bounds agree to
    # the LP's relative optimality tolerance (1e-9); W* to the steady-state tolerance (1e-10
    # relative change per cycle) amplified by the few cycles of the approach: 1e-7
    np.testing.assert_allclose(b["lam"], a["lam"], rtol=1e-8)
    scale = float(a["W_star_max"].max())
    for col in ("W_star_min", "W_star_max"):
        np.testing.assert_allclose(b[col], a[col], rtol=1e-7, atol=1e-9 * scale)
    for col in ("n_shook_down", "n_cyclic_slip", "frac_slip_max", "frac_open_max"):
        np.testing.assert_array_equal(b[col], a[col])


def test_verdict_states_the_band_cyclic_slip_below_lam1_and_lam_u():
    from shakedown.studies.spec import SweepSpec
    from shakedown.studies.summary import regions, verdict

    rel = pd.DataFrame(dict(realisation=[0], lam1=[1.0], lam2=[2.0], lam_adj=[0.5]))
    s = pd.DataFrame(dict(
        realisation=0, point=["g0", "a0", "b0", "g1", "g2"], lam=[0.4, 0.8, 1.5, 3.0, 4.0],
        x=[0.2, 0.4, 0.75, 1.5, 2.0], W_star_min=[0, 0, 0, 1.0, 2.0],
        W_star_max=[0, 0.1, 0.3, 1.2, 2.0], n_states=4, n_cyclic_slip=[0, 1, 3, 4, 4],
        all_slip=[False, False, False, False, True], lam1=1.0, lam2=2.0, lam_adj=0.5))
    lu = lam_u(s)
    text = verdict(SweepSpec(), rel, s, lu, regions(s, lu))
    # 4 significant digits with trailing zeros, ratios 3 (issue 25)
    assert "lam1 = 1.000 < lam < lam2 = 2.000" in text and "max W* up to 0.3000" in text
    assert "from lam = 0.8000 (lam/lam2 = 0.400) to 3.000 (lam/lam2 = 1.50)" in text
    assert "Below lam1, 1 of 8 runs ended in cyclic slip" in text
    assert "between lam_adj = 0.5000 and lam1: 1 of 4" in text
    assert "from lam_u = 4.000 (lam/lam2 = 2.00) on" in text
    assert "for lam >= 4.000 (lam/lam2 = 2.00)" in text
    assert "1 realisation of 100 cracks" in text and "5 load factors x 4 initial states" in text


def test_verdict_uses_the_tables_digits_and_the_options_that_exist():
    # issue 25: W* 54.753536 and 54.753976 (8e-6 relative apart) print as 54.75 and 54.75 in the
    # table; the verdict said "min and max W* differ ... to 2.28" there
    from shakedown.scenes.analyses.sweep import format_table
    from shakedown.studies.spec import SweepSpec
    from shakedown.studies.summary import regions, verdict

    rel = pd.DataFrame(dict(realisation=[0], lam1=[1.0], lam2=[2.0], lam_adj=[1.0]))
    s = pd.DataFrame(dict(
        realisation=0, point=["l0", "l1", "l2"], lam=[0.5, 3.0, 4.56], x=[0.25, 1.5, 2.28],
        W_star_min=[0.0, 1.0, 54.753536], W_star_max=[0.0, 1.2, 54.753976], n_states=4,
        n_cyclic_slip=[0, 4, 4], n_steady=4, n_shook_down=[4, 0, 0], all_slip=False,
        frac_slip_min=0.5, frac_slip_max=0.6, frac_open_min=0.0, frac_open_max=0.0,
        max_from="zero", lam1=1.0, lam2=2.0, lam_adj=1.0))
    lu = lam_u(s)
    spec = SweepSpec(lams=(0.5, 3.0, 4.56))
    text = verdict(spec, rel, s, lu, regions(s, lu))
    table = format_table(s)
    assert table.count("54.75") == 2  # the table shows them equal ...
    assert "to 3.000 (lam/lam2 = 1.50)." in text  # ... so the verdict's "differ" ends at 3.0
    assert "2.28" not in text
    assert "agree to 4 significant digits but not to 1e-06" in text
    # listed load factors: lam_span is unused, so the advice names lams
    assert "raise lam_span" not in text and "add load factors above 4.560 to lams" in text
    one = verdict(SweepSpec(lams=(0.5,)), rel, s.iloc[:1], lam_u(s.iloc[:1]),
                  regions(s.iloc[:1], lam_u(s.iloc[:1])))
    assert "1 load factor x 4 initial states" in one and "load factors)" not in one


def test_study_on_truncated_sparse_networks(tmp_path):
    """interaction_radius in the study: every realisation's system is sparse, and with a radius
    that keeps every pair the rows equal the full-interaction study's."""
    from dataclasses import replace

    import crack_networks as cn
    from shakedown.model.errors import InputError
    from shakedown.studies.crack_study import realisation_model
    from shakedown.studies.sweep import SweepSpec, run_sweep

    full = SweepSpec(n_cracks=8, density=0.1, lams=(0.3, 0.9), n_states=3, steps_per_cycle=16,
                     max_cycles=60, seed=5)
    wide = replace(full, interaction_radius=1e6)  # keeps every pair, but sparse
    _, model, _ = realisation_model(wide, 0)
    assert model.system.is_sparse
    assert isinstance(model, cn.KachanovModel)
    a = run_sweep(full, tmp_path / "full", n_workers=1, progress=False).summary
    b = run_sweep(wide, tmp_path / "wide", n_workers=1, progress=False).summary
    np.testing.assert_allclose(b["lam"], a["lam"], rtol=1e-12)
    scale = float(a["W_star_max"].max())
    for col in ("W_star_min", "W_star_max"):
        np.testing.assert_allclose(b[col], a[col], rtol=1e-7, atol=1e-9 * scale)
    for col in ("n_shook_down", "n_cyclic_slip"):
        np.testing.assert_array_equal(b[col], a[col])
    with pytest.raises(InputError, match="interaction_radius"):
        replace(full, interaction_radius=-1.0)
