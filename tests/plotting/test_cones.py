"""3-D pictures (shakedown/plotting/cones.py): the normalised reaction path inside the friction
cone and the slip trajectories, on the rotating-load node whose steady path is the cone's
boundary (MODEL.md s.8.1)."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

import shakedown as sd
from shakedown.model.errors import InputError
from shakedown.plotting.cones import busiest_nodes, plot_cone_paths, plot_slip_trajectories


def test_cone_paths_lie_on_the_ellipse_of_a_fully_slipping_node_and_trajectory_closes():
    fxy = [[0.3, 0.6]]
    s = sd.DiscreteSystem(2 * np.eye(2), np.zeros((2, 1)), [[1.0]], friction=fxy, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=np.zeros((1, 2)), p0=[1.0], q_cos=[[1.5, 0.0]],
                                       q_sin=[[0.0, 1.5]])
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=32)
    axs = plot_cone_paths(run, s)
    pts = axs[0].collections[1].get_offsets()  # the slip points (red)
    assert len(pts) > 10
    np.testing.assert_allclose(np.hypot(pts[:, 0] / 0.3, pts[:, 1] / 0.6), 1.0, rtol=1e-9)
    ax = plot_slip_trajectories(run)
    xy = ax.lines[0].get_xydata()
    np.testing.assert_allclose(xy[0], xy[-1], atol=1e-9)  # a closed steady orbit
    assert list(busiest_nodes(run, 3)) == [0]


def test_a_2d_run_is_refused():
    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    load = sd.LoadCycle.from_harmonics(q0=[0.0], p0=[1.0], q_cos=[1.0])
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=8)
    with pytest.raises(InputError, match="3-D"):
        plot_cone_paths(run, s)
