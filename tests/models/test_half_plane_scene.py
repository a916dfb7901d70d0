"""Scene kind ``half_plane`` and the built-in scene ``hertz_ellipse``."""

import sys

import numpy as np
import pytest

import shakedown as sd
from shakedown.models.half_plane.scene import HERTZ_ELLIPSE, build_from_scene

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


def test_scene_runs_through_the_registry_when_wired():
    from shakedown import scenes

    kinds = getattr(scenes, "MODEL_KINDS", {})
    if "half_plane" not in kinds:
        pytest.skip("scene kind 'half_plane' is not registered in shakedown.scenes yet")
    scene = scenes.load_scene(HERTZ_ELLIPSE)
    system, load, model = scenes.build(scene)
    assert system.n_nodes == 60
