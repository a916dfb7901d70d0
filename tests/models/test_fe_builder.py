"""Scene model kind "fe" (shakedown/builders/fe.py): scenes build condensed FE systems."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from shakedown import SceneError, fe, scenes
from shakedown.scenes.builders import fe as fe_builder

SCENES = Path(__file__).resolve().parents[2] / "data" / "scenes"

SQUARE = {
    "geometry": "rectangle", "width": 1.0, "height": 1.0, "nx": 6, "ny": 6,
    "element": "P1", "pattern": "union-jack",
    "material": {"type": "isotropic", "E": 1.0, "nu": 0.3},
    "dirichlet": ["top"], "contact": ["bottom"], "friction": 0.5,
}


def test_builder_matches_the_python_api(tmp_path):
    load = {"static": {"displacement": {"top": [0.0, -0.01]}},
            "cyclic": {"traction": {"left": [0.002, 0.0]}}}
    system, cycle, cm = fe_builder.build(dict(SQUARE), load, tmp_path)
    model = fe.FEModel(fe.rectangle(1, 1, 6, 6, pattern="union-jack"), fe.isotropic(1.0, 0.3),
                       dirichlet=["top"], contact=["bottom"], friction=0.5,
                       loads={"static": fe.Displacement("top", (0.0, -0.01)),
                              "cyclic": fe.Traction("left", (0.002, 0.0))})
    ref = model.condense()
    np.testing.assert_allclose(system.K, ref.K, rtol=1e-12)
    np.testing.assert_allclose(system.friction, 0.5)
    np.testing.assert_allclose(cycle.q0, ref.welded["static"][0], rtol=1e-12)
    q, _ = cycle.evaluate(np.array([0.0]), 1.0)
    np.testing.assert_allclose(q[0], ref.welded["static"][0] + ref.welded["cyclic"][0],
                               rtol=1e-12, atol=1e-15)
    assert np.all(cycle.p0 > 0)  # the top pushed down presses the bottom: compression
    assert cm.n_nodes == system.n_nodes == 7


def test_builder_cache_lives_in_the_output_folder(tmp_path):
    model = dict(SQUARE, cache_dir="cache")
    scene_dir, out = tmp_path / "scene", tmp_path / "out"
    scene_dir.mkdir()
    _, _, cm1 = fe_builder.build(model, {}, scene_dir, cache_root=out)
    _, _, cm2 = fe_builder.build(dict(model), {}, scene_dir, cache_root=out)
    assert not cm1.from_cache and cm2.from_cache
    assert any((out / "cache").glob("fe-*.npz"))
    assert not any(scene_dir.iterdir())  # nothing written beside the scene
    _, _, cm3 = fe_builder.build(dict(model), {}, scene_dir)  # no output folder: no cache
    assert not cm3.from_cache and not any(scene_dir.iterdir())


def test_builder_geometries(tmp_path):
    trap = dict(SQUARE, geometry="trapezoid", bottom_width=2.0, top_width=1.0)
    del trap["width"]
    assert fe_builder.build(trap, {}, tmp_path)[0].n_nodes == 7
    poly = {"geometry": "polygon", "vertices": [[0, 0], [2, 0], [2, 1], [0, 1.5]],
            "side_names": ["base", "right", "roof", "left"], "refine": 2, "element": "P2",
            "material": {"type": "transversely_isotropic", "E1": 8, "E2": 1, "nu12": 0.4,
                         "nu23": 0.3, "G12": 0.1, "theta_deg": 30},
            "dirichlet": ["roof"], "contact": ["base"]}
    system, _, cm = fe_builder.build(poly, {"static": {"body_force": [0.0, -1.0]}}, tmp_path)
    assert system.n_nodes == 9 and system.is_coupled
    np.testing.assert_allclose(cm.tangents, np.tile([1.0, 0.0], (9, 1)), atol=1e-14)


def test_builder_mesh_file(tmp_path):
    # a mesh written by meshio and read back, boundaries given as segments
    import meshio

    m = fe.rectangle(1.0, 0.5, 4, 2).mesh
    meshio.write(tmp_path / "block.vtk", meshio.Mesh(
        np.c_[m.p.T, np.zeros(m.p.shape[1])], [("triangle", m.t.T)]))
    model = {"geometry": "mesh_file", "file": "block.vtk",
             "boundaries": {"base": [[0, 0], [1, 0]], "lid": [[0, 0.5], [1, 0.5]]},
             "material": {"type": "isotropic", "E": 1.0, "nu": 0.3},
             "dirichlet": ["lid"], "contact": ["base"]}
    system, _, _ = fe_builder.build(model, {}, tmp_path)
    ref = fe.FEModel(fe.rectangle(1.0, 0.5, 4, 2), fe.isotropic(1.0, 0.3),
                     dirichlet=["top"], contact=["bottom"]).condense()
    np.testing.assert_allclose(system.K, ref.K, rtol=1e-10)


@pytest.mark.parametrize("change,match", [
    ({"geometry": "circle"}, "'geometry' = 'circle' is not allowed"),
    ({"material": {"type": "isotropic", "E": 1.0, "nu": 0.6}}, "nu must satisfy"),
    ({"material": {"type": "rubber"}}, "'type' = 'rubber' is not allowed"),
    ({"material": {"type": "isotropic", "E": 1.0, "nu": 0.3, "G": 1}}, "'G' is not allowed"),
    ({"contact": ["floor"]}, "unknown boundary name 'floor'"),
    ({"colour": "red"}, "'colour' is not allowed"),
    ({"width": None}, "must be"),
])
def test_builder_bad_scenes(tmp_path, change, match):
    model = dict(SQUARE, **change)
    if model.get("width", 0) is None:
        del model["width"]
        match = "'width' is missing"
    with pytest.raises(SceneError, match=match):
        fe_builder.build(model, {}, tmp_path)


def test_builder_bad_loads(tmp_path):
    with pytest.raises(SceneError, match="'wind' is not allowed"):
        fe_builder.build(dict(SQUARE), {"static": {"wind": 1}}, tmp_path)
    with pytest.raises(SceneError, match="'dynamic' is not allowed"):
        fe_builder.build(dict(SQUARE), {"dynamic": {}}, tmp_path)
    with pytest.raises(SceneError, match="unknown boundary name 'lid'"):
        fe_builder.build(dict(SQUARE), {"static": {"pressure": {"lid": 1.0}}}, tmp_path)


@pytest.mark.parametrize("name", ["fe_unit_square", "fe_orthotropic_layer"])
def test_shipped_fe_scenes_build(tmp_path, name):
    shutil.copy(SCENES / f"{name}.toml", tmp_path)
    scene = scenes.load_scene(tmp_path / f"{name}.toml")
    system, cycle, cm = scenes.build(scene)
    assert cycle.n_nodes == system.n_nodes == cm.n_nodes
    if name == "fe_orthotropic_layer":
        o = np.ones(system.n_nodes)
        mu = (o @ system.A @ o) / abs(o @ system.B @ o)
        assert mu == pytest.approx(0.2629238, abs=5e-8)  # seed 001
        assert cm.M is not None


def test_sparse_fe_scene_equals_condensed(tmp_path):
    """``sparse = true``: the uncondensed model (``FEModel.uncondensed()``), the same load cycle
    and bounds as the condensed one; not with ``mass`` or ``cache_dir``."""
    import shakedown as sd
    from shakedown.model.uncondensed import UncondensedSystem

    load = {"static": {"displacement": {"top": [0.0, -0.01]}},
            "cyclic": {"traction": {"left": [0.002, 0.0]}}}
    s1, c1, _ = fe_builder.build(dict(SQUARE), load, tmp_path)
    s2, c2, m2 = fe_builder.build(dict(SQUARE, sparse=True), load, tmp_path)
    assert isinstance(s2, UncondensedSystem) and m2.K is None
    np.testing.assert_allclose(c2.q0, c1.q0, rtol=0, atol=1e-12 * np.abs(c1.q0).max())
    np.testing.assert_allclose(c2.p0, c1.p0, rtol=0, atol=1e-12 * np.abs(c1.p0).max())
    b1, b2 = sd.shakedown_bounds(s1, c1), sd.shakedown_bounds(s2, c2)
    assert b2.lam2 == pytest.approx(b1.lam2, rel=1e-9)
    assert b2.lam1 == pytest.approx(b1.lam1, rel=1e-9)
    with pytest.raises(SceneError, match="'sparse'"):
        fe_builder.build(dict(SQUARE, sparse=True, mass=True), load, tmp_path)
    with pytest.raises(SceneError, match="'sparse'"):
        fe_builder.build(dict(SQUARE, sparse=True, cache_dir="c"), load, tmp_path)
    with pytest.raises(SceneError, match="'sparse'"):
        fe_builder.build(dict(SQUARE, sparse="yes"), load, tmp_path)
