"""Plots of cyclic evolutions and the ``cycles`` command-line analysis (Agg backend)."""

import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

import shakedown as sd  # noqa: E402
from shakedown import gallery  # noqa: E402
from shakedown.plotting.cycles import (  # noqa: E402
    plot_dissipation,
    plot_node_states,
    plot_steady_cycle,
    plot_trajectory,
    plot_uniqueness,
)


@pytest.fixture(scope="module")
def runs():
    p = gallery.fig8_coupled_one_at_a_time()
    a = sd.solve_cycles(p.system, p.load, p.lam, steps_per_cycle=8, max_cycles=300)
    b = sd.solve_cycles(p.system, p.load, p.lam, initial_slip=[-0.3, 0.3], steps_per_cycle=8,
                        max_cycles=300)
    return p, a, b


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_plot_dissipation_draws_one_line_per_call(runs):
    p, a, _ = runs
    ax = plot_dissipation(a)
    assert len(ax.lines) == 1
    np.testing.assert_allclose(ax.lines[0].get_ydata(), a.dissipation)
    ax = plot_dissipation(a, relative=True)
    assert ax.get_yscale() == "log"
    ax = plot_dissipation(np.array([1.0, 0.5, 0.0]), log=True)
    assert np.isnan(ax.lines[0].get_ydata()[-1])  # W = 0 is not drawn on a log axis


def test_plot_steady_cycle_draws_slips_and_both_reactions(runs):
    p, a, _ = runs
    axs = plot_steady_cycle(a)
    n = p.system.n_nodes
    assert len(axs) == 2
    assert len(axs[0].lines) == n
    assert len(axs[1].lines) == 2 * n
    dashed = [ln for ln in axs[1].lines if ln.get_linestyle() == "--"]
    assert len(dashed) == n  # p dashed


def test_plot_node_states_is_a_node_by_time_image(runs):
    p, a, _ = runs
    ax = plot_node_states(a)
    assert len(ax.images) == 1
    img = ax.images[0].get_array()
    times = a.steady_table["t"].nunique()
    assert img.shape == (p.system.n_nodes, times)


@pytest.mark.parametrize("space", ["v", "tau"])
def test_plot_trajectory_draws_extreme_lines_dashed_and_the_paths(runs, space):
    p, a, b = runs
    ax = plot_trajectory(p.system, p.load, p.lam, [a, b], space=space, labels=["A", "B"])
    dashed = [ln for ln in ax.lines if ln.get_linestyle() == "--"]
    assert len(dashed) == 4  # I, II, III, IV extremes
    assert len(ax.lines) == 4 + 2 * 2  # + per run: cycle starts and steady loop
    ax = plot_trajectory(p.system, p.load, p.lam, a, space=space, times=[0.125, 0.375])
    solid_thin = [ln for ln in ax.lines if ln.get_linestyle() == "-" and ln.get_linewidth() < 1]
    assert len(solid_thin) >= 2 * 4  # instantaneous positions at two times (+ start path)
    assert len(ax.lines) == 4 + 2 * 4 + 2


def test_plot_trajectory_tau_space_maps_points_by_A(runs):
    p, a, _ = runs
    ax = plot_trajectory(p.system, p.load, p.lam, [np.array([[0.1, 0.2], [0.3, -0.1]])],
                         space="tau", extremes=False)
    xy = np.column_stack([ax.lines[0].get_xdata(), ax.lines[0].get_ydata()])
    np.testing.assert_allclose(xy, np.array([[0.1, 0.2], [0.3, -0.1]]) @ p.system.A.T)


def test_plot_uniqueness_and_ax_passthrough():
    p = gallery.fig5_uncoupled_stuck()
    study = sd.uniqueness_study(p.system, p.load, p.lam, 3, rng=1, n_jobs=1,
                                steps_per_cycle=16, max_cycles=50)
    fig, ax = plt.subplots()
    assert plot_uniqueness(study, ax) is ax
    assert sum(len(ln.get_xdata()) for ln in ax.lines) == 3


def test_plot_bad_input(runs):
    p, a, _ = runs
    three = sd.DiscreteSystem(np.eye(3), np.zeros((3, 3)), np.eye(3), 0.3)
    load3 = sd.LoadCycle.from_harmonics([0, 0, 0], [1, 1, 1], q_cos=[1, 0, 0])
    with pytest.raises(ValueError, match="two-node systems; got N = 3"):
        plot_trajectory(three, load3, 1.0)
    with pytest.raises(ValueError, match="space must be 'v' or 'tau'"):
        plot_trajectory(p.system, p.load, p.lam, a, space="w")
    with pytest.raises(ValueError, match="steady table is empty"):
        plot_steady_cycle(pd.DataFrame(columns=["t", "node", "slip", "q", "p", "state"]))
    with pytest.raises(ValueError, match="needs a CycleRun or an array"):
        plot_dissipation(object())
    with pytest.raises(ValueError, match=r"shape \(n_points, 2\)"):
        plot_trajectory(p.system, p.load, p.lam, [np.zeros((3, 3))])


# ------------------------------------------------------------------ the command-line analysis
SCENE = """
[scene]
name = "fig8"
[model]
kind = "matrices"
A = [[1.0, 0.9], [0.9, 1.0]]
B = [[0.3, 0.0], [0.0, 0.3]]
C = [[1.0, 0.0], [0.0, 1.0]]
friction = 0.3
[load]
q0 = [0.0, 0.0]
p0 = [1.0, 1.0]
q1 = [[0, 0], [1, 0], [0, 0], [0, 1], [0, 0], [-1, 0], [0, 0], [0, -1]]
p1 = [[0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0]]
[analyses.cycles]
lam = 0.4
steps_per_cycle = 8
max_cycles = 300
"""


def _run_scene(text, tmp_path, **override):
    from shakedown.scenes.files import run_scene, scene_from_string, validate_options
    from shakedown.scenes.output import OutputFolder, Progress

    scene = scene_from_string(text, tmp_path)
    if override:
        opts = dict(scene.raw["analyses"]["cycles"], **override)
        scene.analyses["cycles"] = validate_options("test", "cycles", opts)
    out = OutputFolder(tmp_path / "out")
    return run_scene(scene, out, Progress(enabled=False), only=["cycles"]), out.path


def test_cycles_analysis_writes_its_files(tmp_path):
    summary, out = _run_scene(SCENE, tmp_path)
    s = summary["cycles"]
    assert s["period"] == 1 and not s["shook_down"] and s["steady_dissipation"] > 0
    for name in ("cycles.json", "dissipation.csv", "steady_cycle.csv", "dissipation.png",
                 "steady_cycle.png", "node_states.png", "trajectory.png"):
        assert (out / name).is_file(), name
    data = json.loads((out / "cycles.json").read_text())
    assert data["steady_dissipation"] == pytest.approx(s["steady_dissipation"])
    W = pd.read_csv(out / "dissipation.csv")
    assert len(W) == s["n_cycles"]
    json.dumps(s)  # the CLI prints it: must be JSON-serialisable


def test_cycles_analysis_uniqueness_and_steady_solver(tmp_path):
    summary, out = _run_scene(SCENE, tmp_path, n_initial_states=3, steady_solver=True)
    s = summary["cycles"]
    assert s["unique_dissipation"] is True
    tab = pd.read_csv(out / "uniqueness.csv")
    assert len(tab) == 3
    data = json.loads((out / "cycles.json").read_text())
    assert data["steady_solver"]["status"] == "converged"
    assert (out / "uniqueness.png").is_file()


def test_cycles_analysis_bad_options(tmp_path):
    from shakedown.model.errors import SceneError

    with pytest.raises(SceneError, match="'initial_slip' must list one slip per node"):
        _run_scene(SCENE, tmp_path, initial_slip=[0.0, 1.0, 2.0])
    with pytest.raises(SceneError, match="'method' must be 'implicit' or 'events'"):
        _run_scene(SCENE, tmp_path, method="rk4")
    with pytest.raises(SceneError, match="'steps_per_cycle' must be >= 2"):
        _run_scene(SCENE, tmp_path, steps_per_cycle=1)
