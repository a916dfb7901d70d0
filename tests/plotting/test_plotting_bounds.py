"""The two-node pictures: safe regions (``plot_constraints_2d``), trajectories
(``plot_trajectory``) and ``plot_region_vs_lam``, checked from their artists (issue 25: the
constraint colours and names differed between the safe-region and trajectory plots, II_1 was in
a legend but off the axes, units lost their brackets, the area had no unit, the safe state was
not marked)."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from figure_checks import check_legend_matches_drawn, check_units, legend_entries  # noqa: E402

import shakedown as sd  # noqa: E402
from shakedown.plotting.axes import OUTSIDE  # noqa: E402
from shakedown.plotting.bounds import plot_constraints_2d, plot_region_vs_lam  # noqa: E402
from shakedown.plotting.cycles import plot_trajectory  # noqa: E402

UNITS = {"force": "N", "length": "mm", "energy": "N mm"}


@pytest.fixture(scope="module")
def coupled():
    system = sd.DiscreteSystem(A=[[1.0, -0.3], [-0.3, 1.0]], B=[[-0.3, 0.9], [0.4, -0.1]],
                               C=[[1.5, 0.2], [0.2, 1.5]], friction=0.7)
    load = sd.LoadCycle.from_harmonics(q0=[0.1, -0.1], p0=[1.0, 1.0], q_cos=[0.5, 0.0],
                                       q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
    return system, load, sd.shakedown_bounds(system, load, adjacency=True)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _constraint_lines(ax) -> dict:
    """Constraint name (I_1, II_1, I_2, II_2) -> colour of its dashed extreme line."""
    out = {}
    for line in ax.lines:
        lab = line.get_label()
        for name in ("II_1", "II_2", "I_1", "I_2"):
            if f"{name} " in lab or lab.startswith(name):
                out[name] = matplotlib.colors.to_hex(line.get_color())
                break
    return out


def test_safe_region_and_trajectory_name_and_colour_the_constraints_alike(coupled):
    system, load, b = coupled
    for lam in (0.0, b.safe_lam, 0.5 * (b.lam1 + b.lam2), 0.9, 0.98 * b.lam2):
        ax1 = plot_constraints_2d(system, load, lam, units=UNITS)
        run = sd.solve_cycles(system, load, lam, steps_per_cycle=16, max_cycles=50)
        _, ax2 = plt.subplots()
        plot_trajectory(system, load, lam, run, ax2, units=UNITS)
        c1, c2 = _constraint_lines(ax1), _constraint_lines(ax2)
        assert set(c1) == set(c2) == {"I_1", "II_1", "I_2", "II_2"}, (c1, c2)
        assert c1 == c2, f"colours differ at lam = {lam}: {c1} vs {c2}"
        names = lambda ax: [e.removesuffix(OUTSIDE) for e in legend_entries(ax)  # noqa: E731
                            if "extreme" in e]
        assert names(ax1) == names(ax2), (names(ax1), names(ax2))  # same words, same order
        for ax in (ax1, ax2):
            check_legend_matches_drawn(ax)
            check_units(ax)
            assert ax.get_xlabel().endswith("[mm]") and ax.get_ylabel().endswith("[mm]")


def test_trajectory_in_tau_space_frames_every_constraint(coupled):
    system, load, _ = coupled
    run = sd.solve_cycles(system, load, 0.9, steps_per_cycle=16, max_cycles=50)
    ax = plot_trajectory(system, load, 0.9, run, space="tau", units=UNITS)
    check_legend_matches_drawn(ax)
    assert ax.get_xlabel().endswith("[N]")


def test_safe_state_is_marked_with_its_value(coupled):
    system, load, b = coupled
    ax = plot_constraints_2d(system, load, b.safe_lam, state=b.safe_state,
                             state_label="safe state", units=UNITS)
    entry = [e for e in legend_entries(ax) if "safe state" in e]
    assert len(entry) == 1, legend_entries(ax)
    marker = [ln for ln in ax.lines if ln.get_label() == entry[0]][0]
    np.testing.assert_allclose(np.ravel(marker.get_xydata()), b.safe_state)
    assert f"{b.safe_state[0]:.3g}" in entry[0]
    check_legend_matches_drawn(ax)


def test_region_vs_lam_marks_the_bounds_and_gives_the_area_a_unit(coupled):
    system, load, b = coupled
    ax = plot_region_vs_lam(b, system=system, load=load, units=UNITS)
    check_units(ax, ax.right_ax)
    assert ax.right_ax.get_ylabel().endswith("[mm²]")
    entries = legend_entries(ax)
    for name, value in (("lambda_1", b.lam1), ("lambda_2", b.lam2)):
        assert any(name in e and f"{value:.4g}" in e for e in entries), (name, entries)


def test_a_marked_state_must_be_two_slips(coupled):
    system, load, b = coupled
    with pytest.raises(ValueError, match=r"state must be the slips \(v_1, v_2\).*got shape \(0,\)"):
        plot_constraints_2d(system, load, b.safe_lam, state=np.zeros(0))


def test_a_far_constraint_is_named_outside_instead_of_shrinking_the_region(coupled):
    """Near lam2 the region is small and II_1 far away: framing it would flatten the picture,
    so its entry says it is outside; the region keeps most of the view."""
    system, load, b = coupled
    ax = plot_constraints_2d(system, load, 0.98 * b.lam2)
    entries = legend_entries(ax)
    assert [e for e in entries if e.endswith(OUTSIDE)] == ["II_1 extreme (seed II)" + OUTSIDE]
    check_legend_matches_drawn(ax)
    verts = sd.safe_region(system, load, 0.98 * b.lam2).vertices_2d()
    width = np.ptp(verts[:, 0]) / np.ptp(ax.get_xlim())
    assert width > 0.25, width  # the region fills a fair part of the picture


def test_legend_placement_is_checked(coupled):
    system, load, b = coupled
    ax = plot_constraints_2d(system, load, b.safe_lam, legend="inside")
    check_legend_matches_drawn(ax)
    assert plot_constraints_2d(system, load, b.safe_lam, legend="none").get_legend() is None
    with pytest.raises(ValueError, match="legend must be 'outside', 'inside' or 'none'; got 'left'"):
        plot_constraints_2d(system, load, b.safe_lam, legend="left")


def test_the_bounds_analysis_marks_the_safe_state_on_its_own_picture(tmp_path, monkeypatch):
    """safe_region_*.png at the safe state's lam shows that state (it was drawn unmarked)."""
    import json

    import shakedown.plotting.bounds as pb
    from shakedown.scenes.cli import main

    calls = []
    real = pb.plot_constraints_2d

    def spy(system, load, lam, **kw):
        calls.append((lam, kw))
        return real(system, load, lam, **kw)

    monkeypatch.setattr(pb, "plot_constraints_2d", spy)
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(tmp_path / "b")]) == 0
    res = json.loads((tmp_path / "b" / "bounds.json").read_text())
    marked = [(lam, kw) for lam, kw in calls if kw.get("state") is not None]
    assert len(marked) == 1 and len(calls) >= 2, calls
    lam, kw = marked[0]
    assert lam == pytest.approx(res["safe_lam"]) and kw["state_label"] == "safe state"
    np.testing.assert_allclose(kw["state"], res["safe_state"])
