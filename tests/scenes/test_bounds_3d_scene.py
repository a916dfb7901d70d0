"""The ``bounds`` analysis of a 3-D scene (issue 23): ``shakedown bounds`` answers with the cone
bounds (it raised AttributeError on a ``ConeBounds`` before), and ``contact = "static"`` on a
scene whose static load opens no node changes nothing."""

import json

import pytest

import shakedown as sd
from shakedown.scenes.cli import main
from shakedown.scenes.files import build, load_scene


@pytest.fixture(scope="module")
def rotating():
    system, load, _ = build(load_scene("rotating_3d"))
    return sd.shakedown_bounds(system, load, adjacency=True, intervals=False)


@pytest.mark.parametrize("contact", ["all", "static"])
def test_bounds_of_a_3d_scene(tmp_path, rotating, contact):
    out = tmp_path / "out"
    assert main(["bounds", "rotating_3d", "-o", str(out), "-q", "--set",
                 f"bounds.contact={contact}"]) == 0
    d = json.loads((out / "bounds.json").read_text())
    assert d["dim"] == 3 and d["status"] == "bounded"
    assert d["lam2"] == pytest.approx(rotating.lam2, rel=1e-6)
    assert d["lam_adj_cone"] == pytest.approx(rotating.lam_adj_cone, rel=1e-6)
    assert d["verdict"].startswith(f"No safe state above lam2 = {d['lam2']:.4f}")
    if contact == "static":  # every node closed under the static load: nothing condensed
        assert d["n_closed"] == d["n_nodes_full"] == 3
        assert "Every node is in contact under the static load" in d["verdict"]
    assert (out / "constraints.csv").read_text().startswith("node,")
