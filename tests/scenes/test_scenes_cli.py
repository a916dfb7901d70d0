"""Scene files and the `shakedown` command: built-in scenes, outputs, and bad input messages."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import shakedown as sd
from shakedown.scenes.cli import main
from shakedown.scenes.files import builtin_scenes, load_scene, scene_from_string

GOOD = """
[scene]
name = "t"
[model]
kind = "matrices"
A = [[2.0, 0.5], [0.5, 2.0]]
B = [[0.2, 0.1], [-0.1, 0.3]]
C = [[3.0, 0.0], [0.0, 3.0]]
friction = 0.4
[load]
q0 = [0.0, 0.1]
p0 = [1.0, 1.0]
q_cos = [1.0, 0.0]
q_sin = [0.0, 1.0]
[analyses.bounds]
plots = false
"""


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_builtin_scenes_load_and_build():
    names = builtin_scenes()
    assert "default" in names
    for name in names:
        sc = load_scene(name)
        assert sc.model["kind"] in ("matrices", "crack_network", "fe", "half_plane", "half_space")


def test_scene_builds_the_same_system_as_python(tmp_path):
    from shakedown.scenes.files import build

    sc = load_scene(write(tmp_path, GOOD))
    system, load, extra = build(sc)
    ref = sd.DiscreteSystem([[2, 0.5], [0.5, 2]], [[0.2, 0.1], [-0.1, 0.3]], [[3, 0], [0, 3]], 0.4)
    np.testing.assert_array_equal(system.K, ref.K)
    b1 = sd.shakedown_bounds(system, load)
    b2 = sd.shakedown_bounds(ref, sd.LoadCycle.from_harmonics([0, 0.1], [1, 1], q_cos=[1, 0], q_sin=[0, 1]))
    # the same LPs on the same numbers: identical up to round-off
    assert b1.lam2 == pytest.approx(b2.lam2, rel=1e-12)
    assert extra is None


def test_matrices_from_npz_beside_the_scene(tmp_path):
    np.savez(tmp_path / "k.npz", A=np.eye(2) * 2, B=np.zeros((2, 2)), C=np.eye(2) * 3)
    text = GOOD.replace('A = [[2.0, 0.5], [0.5, 2.0]]\nB = [[0.2, 0.1], [-0.1, 0.3]]\nC = [[3.0, 0.0], [0.0, 3.0]]', 'file = "k.npz"')
    from shakedown.scenes.files import build

    system, _, _ = build(load_scene(write(tmp_path, text)))
    assert not system.is_coupled and system.n_nodes == 2


def test_cli_bounds_writes_json_csv_and_plots(tmp_path, capsys):
    scene = write(tmp_path, GOOD.replace("plots = false", "plots = true"))
    out = tmp_path / "out"
    assert main(["bounds", str(scene), "-o", str(out), "-q"]) == 0
    printed = capsys.readouterr().out
    assert "lam1" in printed and "lam2" in printed
    data = json.loads((out / "bounds.json").read_text())
    b = sd.shakedown_bounds(*__import__("shakedown.scenes", fromlist=["build"]).build(load_scene(scene))[:2])
    # JSON keeps 17 digits: the same number up to round-off
    assert data["lam2"] == pytest.approx(b.lam2, rel=1e-12)
    assert (out / "constraints.csv").exists()
    assert (out / "bounds_vs_lam.png").stat().st_size > 1000
    assert (out / "safe_region_0.png").exists()
    assert json.loads((out / "summary.json").read_text())["analyses"]["bounds"]["status"] == "bounded"


def test_cli_set_override(tmp_path, capsys):
    scene = write(tmp_path, GOOD)
    assert main(["bounds", str(scene), "-o", str(tmp_path / "o"), "-q", "--set", "lam=0.1"]) == 0
    data = json.loads((tmp_path / "o" / "bounds.json").read_text())
    assert data["safe_lam"] == pytest.approx(0.1)


def test_console_script_runs_default_scene(tmp_path):
    # the README's main job: `shakedown run` on the built-in default scene
    r = subprocess.run([sys.executable, "-m", "shakedown", "scenes"], capture_output=True, text=True)
    assert r.returncode == 0 and "default" in r.stdout


@pytest.mark.parametrize(
    "edit, expected",
    [
        (("kind = \"matrices\"", "kind = \"beams\""), ["[model]", "'kind'", "'beams'", "'matrices'"]),
        (("friction = 0.4", "friction = -0.4"), ["friction", ">= 0"]),
        (("friction = 0.4", "friction = \"high\""), ["friction", "'high'"]),
        (("A = [[2.0, 0.5], [0.5, 2.0]]", "A = [[2.0, 0.5], [0.7, 2.0]]"), ["symmetric", "A row 1, column 2"]),
        (("A = [[2.0, 0.5], [0.5, 2.0]]", "A = [[2.0, 0.5, 1.0], [0.5, 2.0, 1.0]]"), ["A", "shape"]),
        (("A = [[2.0, 0.5], [0.5, 2.0]]", "A = [[-2.0, 0.5], [0.5, 2.0]]"), ["positive definite"]),
        (("q0 = [0.0, 0.1]", "q0 = [0.0, 0.1, 3.0]"), ["[load]", "'q0'", "one value per node (2 nodes)", "[0.0, 0.1, 3.0]"]),
        (("p0 = [1.0, 1.0]", "p0 = [1.0]"), ["[load]", "'p0'", "one value per node (2 nodes)"]),
        (("friction = 0.4", "friction = \"0.7\""), ["[model]", "'friction'", "'0.7'", "not a number", "without quotes"]),
        (("friction = 0.4", "friction = true"), ["[model]", "'friction'", "boolean true", "not a number"]),
        (("friction = 0.4", "friction = [0.4, \"0.7\"]"), ["[model]", "'friction'", "'0.7'", "not a number"]),
        (("q0 = [0.0, 0.1]", "q00 = [0.0, 0.1]"), ["[load]", "'q00'", "allowed"]),
        (("q_cos = [1.0, 0.0]", "q1 = [[1.0, 0.0], [0.0, 1.0]]"), ["either harmonics", "samples"]),
        (("plots = false", "plots = 3"), ["[analyses.bounds]", "'plots'", "3", "bool"]),
        (("plots = false", "colour = 3"), ["[analyses.bounds]", "'colour'", "allowed"]),
        (("[analyses.bounds]", "[analyses.nonsense]"), ["nonsense", "not a known analysis"]),
        (("[scene]", "[scenery]"), ["[scenery]", "allowed"]),
        (("p0 = [1.0, 1.0]", "p0 = [1.0, nan]"), ["p0", "finite"]),
    ],
)
def test_bad_scene_errors_name_file_key_value(tmp_path, edit, expected):
    from shakedown.scenes.files import build

    old, new = edit
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(sd.SceneError) as info:
        build(load_scene(path))
    msg = str(info.value)
    assert str(path) in msg
    for piece in expected:
        assert piece in msg, (piece, msg)


def test_scene_errors_are_value_errors_and_cli_exit_code(tmp_path, capsys):
    path = write(tmp_path, GOOD.replace('kind = "matrices"', 'kind = "x"'))
    with pytest.raises(ValueError):
        load_scene(path)
    assert main(["bounds", str(path), "-q", "-o", str(tmp_path / "o")]) == 2
    assert "error" in capsys.readouterr().err


def test_missing_scene_and_bad_toml(tmp_path):
    with pytest.raises(sd.SceneError, match="neither a file nor a built-in scene"):
        load_scene(tmp_path / "nope.toml")
    p = write(tmp_path, "[model\nkind=1")
    with pytest.raises(sd.SceneError, match="not valid TOML"):
        load_scene(p)


def test_output_folder_refuses_paths_outside(tmp_path):
    from shakedown.scenes.output import OutputFolder

    out = OutputFolder(tmp_path / "o")
    for bad in ("../x.json", "/etc/passwd", "a/b.csv", ".."):
        with pytest.raises(ValueError, match="plain file name"):
            out.file(bad)


def test_scene_from_string_without_file():
    sc = scene_from_string(GOOD)
    assert sc.name == "t" and sc.analyses["bounds"]["plots"] is False
    assert Path.cwd() == sc.directory


EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "data" / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_scenes_build(path, tmp_path):
    from shakedown.scenes.files import build
    from shakedown.scenes.output import OutputFolder

    sc = load_scene(path)
    system, load, _ = build(sc, OutputFolder(tmp_path))
    assert system.n_nodes == load.n_nodes > 0
    assert not any(p.name.startswith(".") for p in path.parent.iterdir() if p.is_dir())


def test_cli_several_set_options_accumulate(tmp_path):
    scene = write(tmp_path, GOOD.replace("[analyses.bounds]\nplots = false\n", ""))
    from shakedown.scenes.cli import _apply_overrides

    sc = _apply_overrides(load_scene(scene), ["bounds"], ["lam=0.2", "bounds.plots=false", "adjacency=false"])
    assert sc.analyses["bounds"]["lam"] == 0.2
    assert sc.analyses["bounds"]["plots"] is False and sc.analyses["bounds"]["adjacency"] is False
    with pytest.raises(sd.SceneError, match="--set"):
        _apply_overrides(load_scene(scene), ["bounds"], ["plots=maybe"])


def test_every_analysis_writes_named_files(tmp_path):
    """bounds, cycles and stability on small scenes: every file has a proper name and extension."""
    fe_scene = Path(__file__).resolve().parents[2] / "data" / "scenes" / "fe_unit_square.toml"
    runs = [
        (["bounds", "two_node_coupled"], {"bounds.json", "constraints.csv", "bounds_vs_lam.png"}),
        (["cycles", "two_node_coupled", "--set", "lam=1.0", "--set", "max_cycles=20"],
         {"cycles.json", "dissipation.csv", "steady_cycle.csv", "dissipation.png"}),
        (["stability", str(fe_scene)], {"stability.json", "partition.csv"}),
    ]
    for args, expected in runs:
        out = tmp_path / args[0]
        assert main([*args, "-q", "-o", str(out)]) == 0
        names = {p.name for p in out.iterdir() if p.is_file()}
        assert expected <= names, (args[0], names)
        assert all("." in n for n in names), names
        json.loads((out / "summary.json").read_text())


def test_sparse_matrix_market_scene_keeps_K_sparse(tmp_path, capsys):
    """sparse = true: a Matrix Market K read as scipy.sparse; the system is sparse, equal to the
    dense build, and the bounds and cycles analyses run on it (CLI) with the dense answers."""
    import shutil

    import scipy.sparse as sp

    from shakedown.scenes.files import build

    root = Path(__file__).resolve().parents[2]
    src = root / "data" / "scenes" / "two_node_mtx.toml"
    shutil.copy(root / "data" / "models" / "two_node_K.mtx", tmp_path / "K.mtx")
    text = src.read_text().replace("../models/two_node_K.mtx", "K.mtx")
    dense_scene = write(tmp_path, text)
    sparse_scene = tmp_path / "sparse.toml"
    sparse_scene.write_text(text.replace('K_file = "K.mtx"', 'K_file = "K.mtx"\nsparse = true'))
    sd_sys, load, _ = build(load_scene(dense_scene))
    ss_sys, _, _ = build(load_scene(sparse_scene))
    assert ss_sys.is_sparse and not sd_sys.is_sparse and sp.issparse(ss_sys.K)
    np.testing.assert_array_equal(ss_sys.K.toarray(), sd_sys.K)
    out = tmp_path / "out"
    assert main(["run", str(sparse_scene), "-o", str(out), "-q"]) == 0
    data = json.loads((out / "bounds.json").read_text())
    assert data["lam2"] == pytest.approx(sd.shakedown_bounds(sd_sys, load).lam2, rel=1e-7)
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('K_file = "K.mtx"', 'K_file = "K.mtx"\nsparse = "yes"'))
    with pytest.raises(sd.SceneError, match="sparse"):
        build(load_scene(bad))
