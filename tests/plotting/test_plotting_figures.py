"""Plots of cycles read from their artists (issue 25): one legend entry per drawn curve on the
half-plane's steady cycle (mirror nodes drew over each other), initial states numbered from 1,
units in brackets."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from figure_checks import check_legend_matches_drawn, check_units, legend_entries  # noqa: E402

import shakedown as sd  # noqa: E402
from shakedown import gallery  # noqa: E402
from shakedown.plotting.cycles import plot_dissipation, plot_steady_cycle, plot_uniqueness  # noqa: E402

UNITS = {"force": "N", "length": "mm", "energy": "N mm"}


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _distinct_curves(ax) -> int:
    ys = [np.asarray(ln.get_ydata(), float) for ln in ax.lines]
    out = []
    for y in ys:
        if not any(y.shape == z.shape and np.allclose(y, z, rtol=0, atol=1e-12 * np.abs(y).max())
                   for z in out):
            out.append(y)
    return len(out)


def _check_steady_cycle(axs):
    top, bottom = axs
    entries = legend_entries(top)
    assert len(entries) == len(top.lines) == _distinct_curves(top), (entries, len(top.lines))
    check_legend_matches_drawn(top)
    assert len(bottom.lines) == 2 * len(top.lines)
    check_units(top, bottom)


def test_half_plane_steady_cycle_names_each_drawn_curve_once():
    """The symmetric Hertz contact: mirror nodes slip alike; each curve is drawn once, named
    after every node it stands for (the legend listed 10 nodes over 5 visible curves)."""
    m = sd.half_plane_model(radius=1.0, n_nodes=41, friction=0.5,
                            width=2.4 * 0.0413, materials=((1.0, 0.3), (1.0, 0.3)))
    load = m.load_cycle(P0=1e-3, P1=0.3e-3, Q1=0.3e-3, phase=0.6)
    run = sd.solve_cycles(m.system, load, 1.0, steps_per_cycle=40, max_cycles=10)
    axs = plot_steady_cycle(run, units=UNITS)
    _check_steady_cycle(axs)
    entries = legend_entries(axs[0])
    assert any(e.startswith("nodes ") for e in entries), entries  # mirror pairs named together
    assert axs[0].get_ylabel() == "slip v [mm]"


def test_steady_cycle_groups_identical_nodes_of_a_table():
    t = np.linspace(0, 1, 5)
    rows = []
    for node, amp in ((0, 1.0), (1, 2.0), (2, 1.0), (3, 3.0)):  # nodes 1 and 3 identical
        rows += [dict(t=ti, node=node, slip=amp * np.sin(6 * ti), q=amp * ti, p=1.0 + ti,
                      state="forward") for ti in t]
    axs = plot_steady_cycle(pd.DataFrame(rows))
    assert legend_entries(axs[0]) == ["nodes 1, 3", "node 2", "node 4"]
    _check_steady_cycle(axs)


def test_uniqueness_numbers_initial_states_from_1():
    p = gallery.fig5_uncoupled_stuck()
    study = sd.uniqueness_study(p.system, p.load, p.lam, 3, rng=1, n_jobs=1,
                                steps_per_cycle=16, max_cycles=50)
    ax = plot_uniqueness(study, units=UNITS)
    xs = np.sort(np.concatenate([ln.get_xdata() for ln in ax.lines]))
    np.testing.assert_array_equal(xs, [1, 2, 3])
    assert "(1: zero slip)" in ax.get_xlabel()
    assert ax.get_ylabel().endswith("[N mm]")
    check_legend_matches_drawn(ax)


def test_dissipation_axis_units_keep_their_brackets():
    ax = plot_dissipation(np.array([1.0, 0.5, 0.4, 0.4]), units=UNITS)
    assert ax.get_ylabel() == "W per cycle [N mm]"
    ax = plot_dissipation(np.array([1.0, 0.5, 0.4, 0.4]))
    assert ax.get_ylabel() == "W per cycle [force x length]"


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory):
    from shakedown.studies.sweep import SweepSpec, run_sweep

    spec = SweepSpec(n_cracks=8, density=0.1, n_lams=5, n_band=2, n_adj=1, n_refine=1,
                     n_states=3, steps_per_cycle=16, max_cycles=60, seed=11)
    return run_sweep(spec, tmp_path_factory.mktemp("sweep") / "s", n_workers=1, progress=False)


def test_dissipation_vs_lam_marks_every_bound_with_its_value(small_sweep):
    """lam1, lam2 (not only lam_adj, lam_u) in the legend with their values; 1 realisation is
    not "1 realisation(s)"; units in brackets; legend entries match what is drawn."""
    from shakedown.plotting.sweep import plot_fractions, plot_sweep

    r = small_sweep.realisations.iloc[0]
    for axis in ("lam", "x"):
        ax = plot_sweep(small_sweep, axis=axis)
        entries = legend_entries(ax)
        for name, col in (("lambda_1", "lam1"), ("lambda_2", "lam2"), ("lambda_{adj}", "lam_adj"),
                          ("lambda_u", "lam_u")):
            if np.isfinite(r[col]) and not (col == "lam_adj" and r.lam_adj >= r.lam1):
                assert any(name in e and f"{r[col]:.4g}" in e for e in entries), (name, entries)
        assert "realisation(s)" not in ax.get_title() and "realisation" not in ax.get_title()
        check_legend_matches_drawn(ax)
        check_units(ax)
        ax = plot_fractions(small_sweep, axis=axis)
        check_legend_matches_drawn(ax)
        check_units(ax)
