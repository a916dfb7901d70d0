"""Provenance: manifest.json, scene.resolved.toml, CITATIONS.bib; `shakedown --version`."""

import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shakedown
from shakedown.scenes.cli import main
from shakedown.scenes.files import tomllib
from shakedown.scenes.manifest import to_toml

ROOT = Path(__file__).resolve().parents[2]
#: the default scene at reduced size (same methods, fewer load factors and states)
SMALL = ["--set", "sweep.n_lams=2", "--set", "sweep.n_states=2"]
#: the methods the default scene uses: Kachanov's crack model; the shakedown bounds (Melan /
#: Klarbring-Ciavarella-Barber lam1, Ahn lam2) with HiGHS; the step solver's uniqueness
#: certificate (Klarbring's critical friction).  Not: FE, stability, uniqueness studies, Lemke.
# HiGHS (huangfu2018) is not among them: the dense interior point and dual simplex answer every
# LP of the default scene (the bounds engine falls back to HiGHS only when they cannot)
DEFAULT_METHODS = {"shakedown", "kachanov1987", "melan1936", "klarbring2007", "ahn2008",
                   "klarbring1990"}


def _bib_keys(path: Path) -> list[str]:
    return re.findall(r"^@\w+\{([^,]+),", path.read_text(), re.M)


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("default") / "out"
    assert main(["run", "-q", "-o", str(out), *SMALL]) == 0
    return out


def test_default_run_cites_exactly_the_methods_it_used(default_run):
    keys = _bib_keys(default_run / "CITATIONS.bib")
    assert len(keys) == len(set(keys))
    assert set(keys) == DEFAULT_METHODS
    cite = json.loads((default_run / "summary.json").read_text())["cite"]
    assert all(k in cite for k in DEFAULT_METHODS)
    assert json.loads((default_run / "manifest.json").read_text())["citations"] == keys


def test_a_bounds_run_cites_no_crack_model(tmp_path):
    out = tmp_path / "b"
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(out)]) == 0
    keys = set(_bib_keys(out / "CITATIONS.bib"))
    assert {"melan1936", "klarbring2007", "ahn2008"} <= keys
    assert not keys & {"kachanov1987", "gustafsson2020", "hassani2007", "barber2011"}


def test_manifest_records_versions_scene_seeds_command_times_machine(default_run):
    m = json.loads((default_run / "manifest.json").read_text())
    assert m["shakedown_version"] == shakedown.__version__
    assert m["dependencies"]["numpy"] == np.__version__
    assert m["dependencies"]["pandas"] == pd.__version__
    assert m["command"][:2] == ["shakedown", "run"] and "sweep.n_lams=2" in m["command"]
    assert m["seeds"] == {"model.seed": 2024}
    assert m["start_utc"] <= m["end_utc"]
    assert m["machine"]["cpu_count"] >= 1 and m["machine"]["python"]
    sweep = m["resolved_scene"]["analyses"]["sweep"]
    assert sweep["n_lams"] == 2 and sweep["steps_per_cycle"] == 64  # --set and scene values
    assert sweep["store_format"] == "parquet"  # a default filled in
    assert m["resolved_scene"]["model"]["poisson_ratio"] == 0.25  # a builder default
    from shakedown.scenes.manifest import sha256

    for name, digest in m["output_files"].items():
        assert sha256(default_run / name) == digest


def _tables(folder: Path) -> dict:
    """Result tables with their timing columns dropped (wall times differ between runs)."""
    out = {}
    for p in sorted(folder.glob("*.csv")):
        t = pd.read_csv(p)
        out[p.name] = t.drop(columns=[c for c in t.columns if "second" in c or c.endswith("_s")])
    return out


def _same(first: Path, rerun: Path, files):
    tables, ref = _tables(rerun), _tables(first)
    assert ref and tables.keys() == ref.keys()
    for name, table in ref.items():
        # bit for bit: exact equality of every number, no tolerance
        pd.testing.assert_frame_equal(tables[name], table, check_exact=True)
    for name in files:
        assert (rerun / name).read_bytes() == (first / name).read_bytes(), name


def test_manifest_reproduces_the_default_run_bit_for_bit(default_run, tmp_path):
    again = tmp_path / "again"
    assert main(["run", str(default_run / "manifest.json"), "-q", "-o", str(again)]) == 0
    _same(default_run, again, ("sweep_runs.csv", "sweep_summary.csv", "CITATIONS.bib",
                               "scene.resolved.toml"))
    m = json.loads((again / "manifest.json").read_text())
    assert m["reproduces"] == str((default_run / "manifest.json").resolve())


def test_resolved_scene_reproduces_a_run_bit_for_bit(tmp_path):
    first, again = tmp_path / "first", tmp_path / "again"
    assert main(["run", "two_node_coupled", "-q", "-o", str(first), "--set", "lam=0.3"]) == 0
    assert main(["run", str(first / "scene.resolved.toml"), "-q", "-o", str(again)]) == 0
    _same(first, again, ("constraints.csv", "CITATIONS.bib", "scene.resolved.toml"))
    assert json.loads((again / "bounds.json").read_text())["safe_lam"] == 0.3


def test_resolved_scene_leaves_out_where_the_sweep_ran():
    """A Dask scheduler given with --set is not written into the resolved scene (a scene file
    naming one is refused), so the rerun is possible; results do not depend on it."""
    from dataclasses import replace

    from shakedown.scenes.files import load_scene, resolved_analyses

    scene = load_scene()
    opts = dict(scene.analyses["sweep"], scheduler="tcp://127.0.0.1:8786")
    scene = replace(scene, analyses={**scene.analyses, "sweep": opts})
    assert resolved_analyses(scene, ["sweep"])["sweep"]["scheduler"] == ""


def test_manifest_refuses_a_changed_input_file(tmp_path, capsys):
    (tmp_path / "scenes").mkdir()
    shutil.copytree(ROOT / "data" / "models", tmp_path / "models",
                    ignore=shutil.ignore_patterns("*.py", "*.msh", "square_*"))
    shutil.copy(ROOT / "data" / "scenes" / "two_node_mtx.toml", tmp_path / "scenes")
    out = tmp_path / "out"
    assert main(["bounds", str(tmp_path / "scenes" / "two_node_mtx.toml"), "-q", "-o", str(out)]) == 0
    m = json.loads((out / "manifest.json").read_text())
    mtx = str((tmp_path / "models" / "two_node_K.mtx").resolve())
    assert mtx in m["input_files"] and m["resolved_scene"]["model"]["K_file"] == mtx
    with open(mtx, "a") as f:
        f.write("% edited\n")
    capsys.readouterr()
    assert main(["bounds", str(out / "manifest.json"), "-q", "-o", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err
    assert "two_node_K.mtx has changed since the recorded run" in err


def test_manifest_states_the_resampling_error_of_a_load_record(tmp_path):
    out = tmp_path / "rec"
    scene = ROOT / "data" / "scenes" / "two_node_record.toml"
    assert main(["bounds", str(scene), "-q", "-o", str(out)]) == 0
    notes = json.loads((out / "manifest.json").read_text())["input_notes"]
    assert "resampled to 256 samples" in notes["load_record"]
    assert 0 <= notes["load_record_relative_error"] < 0.01  # the scene's max_error


def test_a_file_that_is_not_a_manifest_is_refused(tmp_path, capsys):
    p = tmp_path / "x.json"
    p.write_text('{"a": 1}')
    assert main(["run", str(p), "-q", "-o", str(tmp_path / "o")]) == 2
    assert "not a shakedown manifest" in capsys.readouterr().err


_scalars = st.one_of(
    st.booleans(), st.integers(-2**63, 2**63 - 1), st.text(max_size=12),
    st.floats(allow_nan=False), st.floats(min_value=-1e-300, max_value=1e-300))
_values = st.one_of(_scalars, st.lists(st.one_of(_scalars, st.lists(_scalars, max_size=4)),
                                      max_size=4))
_tables_st = st.dictionaries(st.text(min_size=1, max_size=8), _values, max_size=5)


@given(st.fixed_dictionaries({"model": _tables_st, "load": st.dictionaries(
    st.text(min_size=1, max_size=8), st.dictionaries(st.text(min_size=1, max_size=5), _values,
                                                     max_size=3), max_size=2)}))
@settings(max_examples=60, deadline=None)
def test_toml_writer_round_trips_every_value_exactly(tables):
    """The resolved scene is the run: every float, string and nesting must read back equal."""
    assert tomllib.loads(to_toml(tables)) == tables


def test_toml_writer_keeps_non_finite_floats():
    back = tomllib.loads(to_toml({"model": {"a": math.inf, "b": -math.inf, "c": math.nan}}))
    assert back["model"]["a"] == math.inf and back["model"]["b"] == -math.inf
    assert math.isnan(back["model"]["c"])


def test_version_everywhere_is_the_same():
    r = subprocess.run([sys.executable, "-m", "shakedown", "--version"], capture_output=True,
                       text=True, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert r.returncode == 0 and r.stdout.strip() == f"shakedown {shakedown.__version__}"
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["version"] == shakedown.__version__
    import yaml

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and str(cff["version"]) == shakedown.__version__
    # py.typed ships with the package (PEP 561)
    assert (ROOT / "shakedown" / "py.typed").is_file()
    assert "py.typed" in project["tool"]["setuptools"]["package-data"]["shakedown"]
