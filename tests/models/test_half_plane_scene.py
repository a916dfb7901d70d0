"""Scene kind ``half_plane`` and the built-in scene ``hertz_ellipse``."""

import sys

import numpy as np
import pytest

import shakedown as sd
from shakedown.scenes.builders.half_plane import HERTZ_ELLIPSE, build_from_scene

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def test_hertz_ellipse_scene_builds_and_runs():
    raw = tomllib.loads(HERTZ_ELLIPSE.read_text())
    assert raw["model"]["kind"] == "half_plane"
    system, load, model = build_from_scene(raw["model"], raw["load"], HERTZ_ELLIPSE.parent)
    assert system.n_nodes == raw["model"]["n_nodes"] - 1 and not system.is_coupled
    run = sd.solve_cycles(system, load, 1.0, steps_per_cycle=50, max_cycles=10)
    assert run.status == "periodic" and run.steady_dissipation > 0
    assert np.allclose(model.x, np.delete(model.x_cells, model.reference))


@pytest.mark.parametrize("model,load,match", [
    ({"radius": 1.0, "colour": 1}, {"P0": 1.0}, "colour"),
    ({"radius": 1.0}, {"P1": 1.0}, "P0"),
    ({"radius": "big"}, {"P0": 1.0}, "radius"),
    ({"profile": "power", "exponent": 3}, {"P0": 1.0}, "width"),
    ({"radius": 1.0}, {"P0": 1.0, "phase": 1, "phase_deg": 2}, "phase"),
])
def test_bad_scene_tables_name_the_key(model, load, match):
    with pytest.raises(sd.InputError, match=match):
        build_from_scene(model, load, None)


def test_builtin_scene_runs_through_the_registry():
    from shakedown import scenes

    assert scenes.MODEL_KINDS["half_plane"] == "shakedown.scenes.builders.half_plane"
    assert "hertz_ellipse" in scenes.builtin_scenes()
    scene = scenes.load_scene("hertz_ellipse")
    system, load, model = scenes.build(scene)
    assert system.n_nodes == 60 and model.reference == 30


def test_bad_scene_through_the_registry_names_file_and_key():
    from shakedown import scenes

    text = HERTZ_ELLIPSE.read_text().replace("radius = 1.0", "radius = -1.0")
    scene = scenes.scene_from_string(text)
    with pytest.raises(sd.SceneError, match="radius"):
        scenes.build(scene)
