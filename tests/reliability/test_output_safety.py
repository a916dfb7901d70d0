"""Nothing is written outside the output folder or through a link (issue 10, items 3, 4).

Before: ``[scene] name = "../../escaped"`` wrote ``shakedown-out/../../escaped/summary.json``,
and a link ``out/summary.json -> elsewhere`` had its target overwritten.
"""

from __future__ import annotations

import json
import os

import pytest

import shakedown as sd
from shakedown.scenes.cli import main
from shakedown.scenes.files import scene_from_string
from shakedown.scenes.output import OutputFolder

SCENE = """
[scene]
name = {name}
[model]
kind = "matrices"
A = [[2.0]]
B = [[0.2]]
C = [[3.0]]
friction = 0.4
[load]
q0 = [0.0]
p0 = [1.0]
q_cos = [1.0]
[analyses.bounds]
plots = false
"""


def files_under(root):
    return {os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs}


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/abs", "..", ".", "a/b", "a\\b", "c:x",
                                  "", " x", "~user", "x\x00y", "n" * 300])
def test_scene_name_must_be_plain(name):
    with pytest.raises(sd.SceneError, match="must be a plain name"):
        scene_from_string(SCENE.format(name=json.dumps(name)))


@pytest.mark.parametrize("name", ["two-node coupled", "Kachanov_100", "été.v2"])
def test_plain_names_pass(name):
    from shakedown.scenes.output import check_plain_name

    assert check_plain_name(name) == name


def test_cli_escape_attempt_writes_nothing(tmp_path, monkeypatch):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    (work / "s.toml").write_text(SCENE.format(name='"../../escaped"'))
    monkeypatch.chdir(work)
    assert main(["bounds", "s.toml", "-q"]) == 2
    assert files_under(tmp_path) == {"a/b/s.toml"}


def test_symlinked_output_file_is_refused(tmp_path, monkeypatch):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").symlink_to(victim)
    (tmp_path / "s.toml").write_text(SCENE.format(name='"s"'))
    monkeypatch.chdir(tmp_path)
    assert main(["bounds", "s.toml", "-q", "-o", str(out)]) == 2
    assert victim.read_text() == "precious\n"
    assert (out / "summary.json").is_symlink()


def test_write_atomically_keeps_old_file_on_failure(tmp_path):
    from shakedown.scenes.output import write_atomically

    target = tmp_path / "r.json"
    target.write_text("old")

    def boom(p):
        p.write_text("half")
        raise RuntimeError("interrupted")

    with pytest.raises(RuntimeError):
        write_atomically(target, boom)
    assert target.read_text() == "old"
    assert files_under(tmp_path) == {"r.json"}  # no temporary file left behind
    write_atomically(target, lambda p: p.write_text("new"))
    assert target.read_text() == "new" and not target.is_symlink()


def test_output_folder_file_names(tmp_path):
    out = OutputFolder(tmp_path / "o")
    for bad in ("../x.json", "/etc/x", "..", "a/b.csv"):
        with pytest.raises(sd.UnsafePathError, match="plain file name"):
            out.write_json(bad, {})
    assert out.write_json("ok.json", {"x": float("nan")}).read_text().strip().endswith("}")


def test_cli_overflow_is_an_error_not_a_traceback(tmp_path, monkeypatch, capsys):
    # issue 10 item 6: `shakedown cycles ... --set lam=1e300` ended in a matplotlib traceback
    (tmp_path / "s.toml").write_text(SCENE.format(name='"s"') + "[analyses.cycles]\n")
    monkeypatch.chdir(tmp_path)
    assert main(["cycles", "s.toml", "-q", "--set", "lam=1e300", "--set", "max_cycles=3"]) == 2
    assert "not finite" in capsys.readouterr().err
