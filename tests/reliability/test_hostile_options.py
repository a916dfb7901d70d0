"""Every option of every analysis, given a value of the wrong type on the command line
(``--set``): refused with exit status 2 and the key named, never a traceback (issue 24)."""

from __future__ import annotations

import pytest
from hostile_common import CRACK_SCENE, run_cli, scene_text

from shakedown.scenes.files import ANALYSES, analysis_module


def wrong_value(types) -> str:
    """A TOML value of a type the option does not take."""
    if float in types or int in types:
        return '"text"'
    if bool in types:
        return "3"
    if str in types and list not in types:
        return "[1, 2]"
    return "{a = 1}"


def cases():
    out = []
    for name in ANALYSES:
        for key, (typ, _, _) in analysis_module(name).OPTIONS.items():
            out.append((name, key, wrong_value(typ if isinstance(typ, tuple) else (typ,))))
    return out


@pytest.mark.parametrize("name, key, bad", cases())
def test_an_option_of_the_wrong_type_is_refused(tmp_path, name, key, bad):
    p = tmp_path / "s.toml"
    p.write_text(CRACK_SCENE.format(seed=1, fmt="csv") if name == "sweep" else scene_text())
    code, _, err = run_cli([name, str(p), "-q", "-o", str(tmp_path / "o"), "--set",
                            f"{name}.{key}={bad}"])
    assert code == 2 and key in err and "Traceback" not in err


@pytest.mark.slow
@pytest.mark.parametrize("steps", [65536])
def test_many_steps_per_cycle_in_a_scene(tmp_path, steps):
    p = tmp_path / "s.toml"
    p.write_text(scene_text().replace("[analyses.bounds]\nplots = false",
                                      f"[analyses.cycles]\nlam = 1.5\nsteps_per_cycle = {steps}"
                                      "\nmax_cycles = 3\nplots = false"))
    code, text, err = run_cli(["cycles", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 0 and "cycles:" in text, err
