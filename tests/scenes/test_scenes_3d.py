"""3-D scenes (MODEL.md s.8): ``[model] dim = 3`` for the matrices kind, the (N, 2) tangential
load arrays, the cycles analysis with its verdict in words and its 3-D pictures, and the
built-in 3-D scene.

What these tests prove: a scene builds the same 3-D system and load as Python; bad 3-D input is
refused naming the key and the fix; the cycles analysis of a 3-D scene writes its verdict, the
steady table with (x, y) columns and the cone / trajectory pictures.
"""

import json

import numpy as np
import pytest

import shakedown as sd
from shakedown.model.errors import SceneError
from shakedown.scenes.files import build, builtin_scenes, load_scene

SCENE = """
[scene]
name = "one node, rotating load"

[model]
kind = "matrices"
dim = 3
A = [[2.0, 0.0], [0.0, 2.0]]
B = [[0.0], [0.0]]
C = [[1.0]]
friction = 0.5

[load]
q0 = [[0.0, 0.0]]
p0 = [1.0]
q_cos = [[1.3, 0.0]]
q_sin = [[0.0, 1.3]]

[analyses.cycles]
lam = 1.0
steps_per_cycle = 16
"""


def write(tmp_path, text):
    p = tmp_path / "scene.toml"
    p.write_text(text)
    return p


def test_3d_scene_builds_the_python_system_and_load(tmp_path):
    system, load, _ = build(load_scene(write(tmp_path, SCENE)))
    assert system.dim == 3 and load.dim == 3 and system.n_nodes == 1
    np.testing.assert_array_equal(system.A, 2 * np.eye(2))
    q, p = load.evaluate(np.array([0.25]), 1.0)
    np.testing.assert_allclose(q[0, 0], [0.0, 1.3], atol=1e-12)


@pytest.mark.parametrize("old,new,match", [
    ("dim = 3", "dim = 4", "dim"),
    ("q0 = [[0.0, 0.0]]", "q0 = [0.0]", "q0"),
    ('kind = "matrices"\ndim = 3', 'kind = "matrices"\ndim = 3\nstiffness_file = "k.mtx"',
     "2-D only"),
])
def test_bad_3d_scene_input_is_refused_by_key(tmp_path, old, new, match):
    with pytest.raises(SceneError, match=match):
        build(load_scene(write(tmp_path, SCENE.replace(old, new))))


def test_3d_cycles_analysis_writes_verdict_tables_and_cone_pictures(tmp_path):
    from shakedown.scenes.cli import main

    out = tmp_path / "out"
    assert main(["run", str(write(tmp_path, SCENE)), "-o", str(out), "-q"]) == 0
    data = json.loads((out / "cycles.json").read_text())
    assert data["verdict"].startswith("At lam = 1.000, cyclic slip: W = ")
    assert "node 1 slip" in data["verdict"]
    # the discrete closed form of the rotating node (tests/evolution/test_cone_cycles.py)
    a = 2 * np.pi / 16
    kr = -0.5 * np.sin(a / 2) + np.sqrt(1.3**2 - (0.5 * np.cos(a / 2)) ** 2)
    assert data["steady_dissipation"] == pytest.approx(16 * 0.5 * 2 * kr / 2 * np.sin(a / 2),
                                                       rel=1e-9)
    header = (out / "steady_cycle.csv").read_text().splitlines()[0]
    assert "slip_x" in header and "q_y" in header
    for name in ("cone_paths.png", "slip_trajectories.png", "steady_cycle.png",
                 "node_states.png", "dissipation.png"):
        assert (out / name).stat().st_size > 1000, name


def test_builtin_3d_scene_is_listed_and_builds():
    assert "rotating_3d" in builtin_scenes()
    system, load, _ = build(load_scene("rotating_3d"))
    assert system.dim == 3 and system.is_coupled and load.dim == 3
    assert isinstance(system, sd.DiscreteSystem)


@pytest.mark.parametrize("arrays", ["blocks", "K"])
def test_3d_matrices_from_an_npz_file(tmp_path, arrays):
    """``file = "system.npz"`` with A, B, C or with the 3N x 3N K (order v_1x, v_1y, ..., w_1, ...)."""
    rng = np.random.default_rng(0)
    n = 2
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    if arrays == "K":
        np.savez(tmp_path / "system.npz", K=K)
    else:
        np.savez(tmp_path / "system.npz", A=K[:2 * n, :2 * n], B=K[:2 * n, 2 * n:],
                 C=K[2 * n:, 2 * n:])
    text = SCENE.replace("A = [[2.0, 0.0], [0.0, 2.0]]\nB = [[0.0], [0.0]]\nC = [[1.0]]",
                         'file = "system.npz"').replace("q0 = [[0.0, 0.0]]",
                                                        "q0 = [[0.0, 0.0], [0.1, 0.0]]")
    text = text.replace("p0 = [1.0]", "p0 = [1.0, 1.0]").replace(
        "q_cos = [[1.3, 0.0]]", "q_cos = [[1.3, 0.0], [0.0, 0.5]]").replace(
        "q_sin = [[0.0, 1.3]]", "q_sin = [[0.0, 1.3], [0.5, 0.0]]")
    system, load, _ = build(load_scene(write(tmp_path, text)))
    assert system.dim == 3 and system.n_nodes == 2 and load.n_nodes == 2
    np.testing.assert_allclose(system.K, K, rtol=0, atol=1e-12 * np.abs(K).max())
