"""Scenes of 3-D FE bodies (issue 23): the ``fe`` builder with boxes, several bodies and
interfaces, a small bolted lap joint run end to end (the grip's work balances the dissipation),
the contact patch maps, the built-in ``lap_joint`` scene, and bad scene input."""

import numpy as np
import pytest

import shakedown as sd
from shakedown import fe
from shakedown.model.errors import SceneError
from shakedown.scenes.files import build, load_scene, scene_from_string

LAP = """
[scene]
force_unit = "N"
length_unit = "mm"
[model]
kind = "fe"
friction = 0.3
interfaces = [[1, "lap", 0, "lap"]]
[[model.bodies]]
geometry = "box"
size = [30.0, 20.0, 3.0]
cells = [6, 4, 1]
origin = [-10.0, 0.0, 0.0]
material = { type = "isotropic", E = 210000.0, nu = 0.3 }
dirichlet = ["left"]
boundaries = { lap = [[0.0, 0.0, 3.0], [20.0, 20.0, 3.0]], washer = [[5.0, 5.0, 0.0], [15.0, 15.0, 0.0]] }
[[model.bodies]]
geometry = "box"
size = [30.0, 20.0, 3.0]
cells = [6, 4, 1]
origin = [0.0, 0.0, 3.0]
material = { type = "isotropic", E = 210000.0, nu = 0.3 }
dirichlet = ["right"]
boundaries = { lap = [[0.0, 0.0, 3.0], [20.0, 20.0, 3.0]], washer = [[5.0, 5.0, 6.0], [15.0, 15.0, 6.0]] }
[load.static]
pressure = { washer = 50.0 }
[load.cyclic]
displacement = { "1:right" = [0.002, 0.0, 0.0] }
[analyses.cycles]
steps_per_cycle = 40
max_cycles = 30
"""
GRIP = 0.002  # mm


@pytest.fixture(scope="module")
def lap():
    return build(scene_from_string(LAP))


def plates():
    """The same two plates through the Python API."""
    mat = fe.isotropic(210000.0, 0.3, plane="3d")
    lower = fe.box(30.0, 20.0, 3.0, 6, 4, 1, origin=(-10.0, 0.0, 0.0)).with_boundaries(
        {"lap": ((0.0, 0.0, 3.0), (20.0, 20.0, 3.0)), "washer": ((5, 5, 0), (15, 15, 0))})
    upper = fe.box(30.0, 20.0, 3.0, 6, 4, 1, origin=(0.0, 0.0, 3.0)).with_boundaries(
        {"lap": ((0.0, 0.0, 3.0), (20.0, 20.0, 3.0)), "washer": ((5, 5, 6), (15, 15, 6))})
    bodies = [fe.Body(lower, mat, ["left"], {"static": fe.Pressure("washer", 50.0)}),
              fe.Body(upper, mat, ["right"], {"static": fe.Pressure("washer", 50.0),
                                              "cyclic": fe.Displacement("right", (GRIP, 0, 0))})]
    return fe.FEModel(bodies=bodies, interfaces=[(1, "lap", 0, "lap")], friction=0.3)


def test_scene_builds_the_python_model(lap):
    system, load, cm = lap
    ref = plates().condense()
    assert system.dim == 3 and load.dim == 3 and system.n_nodes == 25
    assert set(cm.node_kind) == {"interface"}
    np.testing.assert_array_equal(system.K, ref.K)
    for case in ("static", "cyclic"):
        for a, b in zip(cm.welded[case], ref.welded[case], strict=True):
            np.testing.assert_array_equal(a, b)
    # the bolt load (50 MPa on 10 mm x 10 mm washers: 5 kN) crosses the interface, compressing
    # its middle; the plates' clamped ends carry what the plates' bending leaves (< 1 %)
    p = cm.welded["static"][1]
    assert p.sum() == pytest.approx(5000.0, rel=0.01) and p.max() > 0 > p.min()
    # upper plate's frame: t_x = +x, t_y = +y, n = +z (outward normal -z)
    np.testing.assert_allclose(cm.normals, np.broadcast_to([0, 0, -1.0], (25, 3)))


def test_lap_joint_grip_work_balances_dissipation(lap):
    """Steady cyclic microslip: the work of the grip over the cycle, ``-oint sum q_x du``
    (grip force = -sum q_x, the only x force on the upper plate), is the dissipation ``W`` of
    the run (up to the trapezoidal rule over the 40 steps)."""
    system, load, cm = lap
    run = sd.solve_cycles(system, load, 1.0, steps_per_cycle=40, max_cycles=30)
    assert run.status == "periodic" and not run.shook_down and run.steady_dissipation > 0
    tot = run.steady_table.groupby("t")["q_x"].sum().sort_index()
    u = GRIP * np.cos(2 * np.pi * tot.index.to_numpy(float))
    F = -tot.to_numpy(float)
    u, F = np.r_[u, u[:1]], np.r_[F, F[:1]]
    work = float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u)))
    assert work == pytest.approx(run.steady_dissipation, rel=0.02)
    # a stuck core under the washer, slipping rim, open corners
    states = run.steady_table.pivot_table(index="node", columns="t", values="state",
                                          aggfunc="first").to_numpy(str)
    assert np.all(states == "stick", axis=1).any() and (states == "slip").any()


def test_cycles_analysis_writes_contact_patch_maps(tmp_path):
    from shakedown.scenes.cli import main

    scene = tmp_path / "tiny.toml"
    scene.write_text("""
[model]
kind = "fe"
geometry = "box"
size = [1.0, 1.0, 0.5]
cells = [2, 2, 1]
material = { type = "isotropic", E = 1.0, nu = 0.3 }
dirichlet = ["top"]
contact = ["bottom"]
friction = 0.3
[load.static]
displacement = { top = [0.0, 0.0, -0.01] }
[load.cyclic]
displacement = { top = [0.01, 0.005, 0.0] }
[analyses.cycles]
steps_per_cycle = 16
max_cycles = 6
""")
    out = tmp_path / "out"
    assert main(["cycles", str(scene), "-o", str(out), "-q"]) == 0
    for name in ("contact_patch.png", "stuck_zone.png", "force_loop.png", "node_states.png",
                 "dissipation.png", "cycles.json", "steady_cycle.csv"):
        assert (out / name).stat().st_size > 1000, name
    assert not (out / "steady_cycle.png").exists()


def test_builtin_lap_joint_scene_loads():
    sc = load_scene("lap_joint")
    assert sc.model["kind"] == "fe" and len(sc.model["bodies"]) == 2
    assert sc.units == {"force": "N", "length": "mm", "energy": "N mm"}


@pytest.mark.slow
def test_builtin_lap_joint_runs(tmp_path):
    from shakedown.scenes.cli import main

    out = tmp_path / "lap"
    assert main(["cycles", "lap_joint", "-o", str(out), "-q"]) == 0
    assert (out / "contact_patch.png").is_file() and (out / "stuck_zone.png").is_file()


@pytest.mark.parametrize("edit, match", [
    (('geometry = "box"\nsize = [30.0, 20.0, 3.0]\ncells = [6, 4, 1]\norigin = [-10',
      'geometry = "box"\nsize = [30.0, 20.0]\ncells = [6, 4, 1]\norigin = [-10'),
     r"key 'size' = \[30.0, 20.0\] must be a list of three numbers"),
    (('"1:right"', '"5:right"'), "'5' is not a body index 0..1"),
    (("pressure = { washer = 50.0 }", "pressure = { bolt = 50.0 }"),
     "boundary 'bolt' belongs to no body"),
    (('interfaces = [[1, "lap", 0, "lap"]]', 'interfaces = [[1, "lap", 0, "lap"]]\n'
      'geometry = "box"'), "key 'geometry' goes inside each"),
    (('dirichlet = ["left"]', 'dirichlet = ["left"]\nthickness = 2.0'),
     r"\[model.bodies\[0\]\] key 'thickness' is not allowed"),
    (('dirichlet = ["left"]', 'dirichlet = ["clamp"]'), "unknown boundary name 'clamp'"),
])
def test_bad_3d_scenes_named(edit, match):
    text = LAP.replace(*edit)
    assert text != LAP
    with pytest.raises(SceneError, match=match):
        build(scene_from_string(text))


@pytest.mark.slow  # ~19 s: two bounds and a 40-cycle run
def test_lap_joint_bounds_on_the_closed_nodes(tmp_path):
    """``contact = "static"``: the bolt opens the rim of the overlap, so the bounds are those of
    the nodes closed under the preload (the others condensed out as free).  ``lam2`` is then
    certified for that system; above it a run of that system cannot shake down (Melan), below it
    a safe state exists (checked by its cone margins), and the verdict names the reduction."""
    import json

    from shakedown.model.open_nodes import condense_open
    from shakedown.scenes.cli import main

    scene = tmp_path / "lap.toml"
    scene.write_text(LAP.replace("[analyses.cycles]", '[analyses.bounds]\ncontact = "static"\n'
                                 "adjacency = false\n[analyses.cycles]"))
    out = tmp_path / "out"
    assert main(["bounds", str(scene), "-o", str(out), "-q"]) == 0
    d = json.loads((out / "bounds.json").read_text())
    assert d["status"] == "bounded" and 0 < d["n_closed"] < d["n_nodes_full"] == 25
    assert f"Bounds of the {d['n_closed']} of 25 nodes" in d["verdict"]
    lam2 = d["lam2"]
    system, load, _ = build(scene_from_string(LAP))
    cs = condense_open(system, load, np.asarray(d["closed_nodes"]) - 1)
    b = sd.shakedown_bounds(cs.system, cs.load)
    assert b.lam2 == pytest.approx(lam2, rel=1e-6)
    run = sd.solve_cycles(cs.system, cs.load, 1.2 * lam2, steps_per_cycle=32, max_cycles=40)
    assert not run.shook_down


def test_bounds_contact_option_is_checked(tmp_path):
    from shakedown.scenes.cli import main

    scene = tmp_path / "lap.toml"
    scene.write_text(LAP.replace("[analyses.cycles]", '[analyses.bounds]\ncontact = "closed"\n'
                                 "[analyses.cycles]"))
    assert main(["bounds", str(scene), "-o", str(tmp_path / "o"), "-q"]) != 0
