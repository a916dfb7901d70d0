"""A new user's first hour (issue 9): the main job end to end, verdicts first, options that a
person can find (--help, README tables, --set on model keys), the README's Python example.

Each test states what it guards; each was seen to fail on a deliberately broken version (the
report of issue 9 lists the breakages).
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import shakedown as sd
from shakedown.scenes.cli import main
from shakedown.scenes.files import ANALYSES, analysis_module, load_scene

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"


def _run_cli(args, tmp_path, *extra):
    """``python -m shakedown ARGS`` in a subprocess (as a user types it): (stdout, stderr, rc)."""
    r = subprocess.run([sys.executable, "-m", "shakedown", *args, *extra], capture_output=True,
                       text=True, cwd=tmp_path, stdin=subprocess.DEVNULL, timeout=600)
    return r.stdout, r.stderr, r.returncode


def _check_main_job_output(stdout: str, out: Path, names: list[str]):
    """Verdict lines first (one per analysis), then details; files and readable plots written."""
    lines = stdout.splitlines()
    head = lines[: len(names)]
    assert [ln.split(":", 1)[0] for ln in head] == names, stdout[:2000]
    pending = [ln for ln in head if "(no verdict)" in ln]
    for ln in head:
        if ln not in pending:
            assert len(ln.split(":", 1)[1].strip()) > 20, ln  # a sentence, not a number
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary["analyses"]) == names
    files = [p for p in out.iterdir() if p.is_file()]
    assert {p.suffix for p in files} >= {".json", ".png"}, files
    import matplotlib.image as mpimg

    for png in (p for p in files if p.suffix == ".png"):
        img = mpimg.imread(png)
        # a real figure: some hundreds of pixels each way and more than one colour drawn
        assert min(img.shape[:2]) > 200 and np.ptp(img[..., :3]) > 0.5, png.name
    if pending:  # the sweep's verdict is the study branch's item of issue 9
        pytest.xfail(f"analysis without a verdict yet: {pending}")


def _small_overrides(scene) -> list[str]:
    """Shrink the default scene for the default test run, with only keys the scene has."""
    sets = []
    if "n_cracks" in scene.model:
        sets.append("model.n_cracks=16")
    for name in scene.analyses:
        opts = analysis_module(name).OPTIONS
        for key, value in (("n_lams", 4), ("n_states", 2), ("n_workers", 1),
                           ("steps_per_cycle", 32), ("max_cycles", 60)):
            if key in opts:
                sets.append(f"{name}.{key}={value}")
    return sets


def test_main_job_end_to_end_small(tmp_path):
    """`shakedown run` on the built-in default scene (shrunk with --set so the default test run
    stays fast): verdict lines first, summary.json, PNG plots that are real figures."""
    scene = load_scene(None)
    sets = [a for s in _small_overrides(scene) for a in ("--set", s)]
    stdout, stderr, rc = _run_cli(["run", "-o", "out", *sets], tmp_path)
    assert rc == 0, stderr[-3000:]
    names = list(scene.analyses) or ["bounds"]
    _check_main_job_output(stdout, tmp_path / "out", names)


@pytest.mark.slow
def test_main_job_exactly_as_the_readme_says(tmp_path):
    """README quick-start command 1's `shakedown run`, unmodified (about half a minute)."""
    stdout, stderr, rc = _run_cli(["run"], tmp_path)
    assert rc == 0, stderr[-3000:]
    scene = load_scene(None)
    _check_main_job_output(stdout, tmp_path / "shakedown-out" / scene.name,
                           list(scene.analyses) or ["bounds"])


def test_every_command_prints_verdicts_on_stdout_and_progress_on_stderr(tmp_path, capsys):
    for args, name in ((["bounds", "two_node_coupled"], "bounds"),
                       (["cycles", "two_node_coupled", "--set", "lam=2.0"], "cycles"),
                       (["stability", "two_node_coupled", "--set", "chi=[-1]"], "stability")):
        assert main([*args, "-o", str(tmp_path / name)]) == 0
        out, err = capsys.readouterr()
        assert out.startswith(f"{name}: "), out[:300]
        assert "building the" in err  # what it is doing, on stderr
        assert "building the" not in out
        assert main([*args, "-o", str(tmp_path / name), "-q"]) == 0
        quiet, quiet_err = capsys.readouterr()
        assert quiet_err == "" and quiet.splitlines()[0] == out.splitlines()[0]


def test_details_are_rounded_and_json_keeps_full_precision(tmp_path, capsys):
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    data = json.loads((tmp_path / "bounds.json").read_text())
    assert f"lam1: {data['lam1']:.4g}\n" in printed
    assert repr(data["lam1"]) not in printed  # 17 digits only in the JSON
    # lam_adj equal to lam1 within the LP tolerance is said to be equal, not shown as 2 numbers
    if abs(data["lam_adj"] - data["lam1"]) <= 1e-7 * data["lam1"]:
        assert "lam_adj = lam1" in printed


@pytest.mark.parametrize("name", sorted(ANALYSES))
def test_help_lists_every_option_with_type_default_and_meaning(name, capsys):
    from shakedown.scenes.options import default_text, type_name

    with pytest.raises(SystemExit) as info:
        main([name, "--help"])
    assert info.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for key, (typ, default, meaning) in analysis_module(name).OPTIONS.items():
        assert f"{key} {type_name(typ)}, default {default_text(default)}" in text, key
        assert " ".join(meaning.split()) in text, key


def test_readme_option_tables_are_the_generated_ones():
    from shakedown.scenes.options import readme_with_tables

    text = README.read_text()
    assert readme_with_tables(text) == text, (
        "README option tables are stale: run python3 -c \"from shakedown.scenes.options "
        "import update_readme; update_readme()\"")
    for name in ANALYSES:
        for key in analysis_module(name).OPTIONS:
            assert f"| `{key}` |" in text


def test_set_reaches_model_and_load_keys(tmp_path):
    from shakedown.scenes.options import apply_overrides

    scene = load_scene("two_node_coupled")
    changed = apply_overrides(scene, ["bounds"], ["model.friction=0.4", "load.q0=[0.2, -0.1]",
                                                  "lam=0.1"])
    assert changed.model["friction"] == 0.4 and changed.load["q0"] == [0.2, -0.1]
    assert changed.analyses["bounds"]["lam"] == 0.1
    assert scene.model["friction"] == 0.7  # the original scene is untouched
    # a Dask scheduler from --set is not mistaken for one named in the file (refused there)
    dask = apply_overrides(load_scene(None), ["sweep"], ['sweep.scheduler="tcp://h:1"'])
    assert dask.analyses["sweep"]["scheduler"] == "tcp://h:1"
    assert "scheduler" not in dask.raw.get("analyses", {}).get("sweep", {})
    units = apply_overrides(scene, ["bounds"], ['scene.force_unit="N"', 'scene.length_unit="mm"'])
    assert units.units["energy"] == "N mm"
    # the answer is that of the system built by hand with the new values (cross-check)
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(tmp_path),
                 "--set", "model.friction=0.4"]) == 0
    m = scene.model
    ref = sd.shakedown_bounds(sd.DiscreteSystem(m["A"], m["B"], m["C"], friction=0.4),
                              sd.LoadCycle.from_harmonics(**scene.load))
    data = json.loads((tmp_path / "bounds.json").read_text())
    assert data["lam1"] == pytest.approx(ref.lam1, rel=1e-12)  # same LPs, same numbers
    nested = apply_overrides(load_scene(ROOT / "data" / "scenes" / "fe_unit_square.toml"),
                             ["bounds"], ["model.material.E=2.5"])
    assert nested.model["material"] == {"type": "isotropic", "E": 2.5, "nu": 0.3,
                                        "plane": "strain"}


@pytest.mark.parametrize("item, expected", [
    ("nonsense.x=1", ["'nonsense'", "neither an analysis", "model"]),
    ("model.friction", ["expected KEY=VALUE"]),
    ("model.friction=\"0.7\"", ["'friction'", "'0.7'", "not a number"]),
    ("model.friction=true", ["'friction'", "boolean true"]),
])
def test_set_errors_name_the_key(item, expected, tmp_path, capsys):
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(tmp_path), "--set", item]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("shakedown: error:")  # one line, no traceback
    for piece in expected:
        assert piece in err, (piece, err)


def test_tensile_static_load_is_explained(tmp_path, capsys):
    assert main(["bounds", "two_node_coupled", "-q", "-o", str(tmp_path),
                 "--set", "load.p0=[-1.0, 1.0]"]) == 0
    verdict = capsys.readouterr().out.splitlines()[0]
    assert "tensile" in verdict and "node 1" in verdict and "nan" in verdict, verdict


def _readme_python_block() -> str:
    text = README.read_text()
    return re.search(r"```python\n(.*?)```", text, re.S).group(1)


def test_readme_python_example_prints_what_its_comments_say():
    """Every `print(...)` of the README example is followed by comments quoting its output
    (fragments separated by '...'); they must appear in what the example prints, in order."""
    code = _readme_python_block()
    lines = code.splitlines()
    expected = []
    for i, line in enumerate(lines):
        if not line.startswith("print("):
            continue
        quoted = []
        if "#" in line:  # "print(x)  # label: output"
            quoted.append(line.split("#", 1)[1].split(": ", 1)[-1])
        for nxt in lines[i + 1:]:
            if not nxt.startswith("#"):
                break
            quoted.append(nxt[1:].strip())
        assert quoted, f"README: {line!r} has no comment saying what it prints"
        expected.append(" ".join(quoted))
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(compile(code, "README.md", "exec"), {})
    printed = " ".join(buf.getvalue().split())
    pos = 0
    for quote in expected:
        for fragment in (f.strip() for f in quote.split("...")):
            if fragment:
                at = printed.find(fragment, pos)
                assert at >= 0, (fragment, printed)
                pos = at + len(fragment)


def test_ci_script_runs_the_readme_commands_verbatim():
    """.ci/run reads quick-start commands 1 and 2 from the README (so they cannot drift) and
    runs command 1 in a fresh venv outside the repository, without a terminal or stdin."""
    script = (ROOT / ".ci" / "run").read_text()
    func = re.search(r"^readme_command\(\) \{.*?^\}", script, re.S | re.M).group(0)
    lines = README.read_text().splitlines()
    for n in (1, 2):
        r = subprocess.run(["bash", "-c", f"{func}\nreadme_command {n}"], cwd=ROOT,
                           capture_output=True, text=True, timeout=60)
        at = next(i for i, ln in enumerate(lines) if ln.startswith(f"# {n}."))
        assert r.stdout.strip() == lines[at + 1].strip() != "", (n, r.stdout, r.stderr)
    assert 'python3 -m venv "$venv"' in script and "mktemp -d" in script
    assert "exec </dev/null" in script and 'bash -euo pipefail -c "$quick_start"' in script
    assert lines[lines.index("# 2. install and run the tests (this is exactly what .ci/run does)")
                 + 1] == 'python3 -m pip install -q -e ".[test]" && python3 -m pytest'
