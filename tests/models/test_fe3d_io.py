"""3-D meshes from Gmsh files (physical groups name the contact, held and loaded surfaces) and
the bad inputs of 3-D FE models, each refused with an error naming the field (issue 23)."""

from pathlib import Path

import numpy as np
import pytest

from shakedown import fe
from shakedown.model.errors import InputError

DATA = Path(__file__).resolve().parents[2] / "data" / "models"
MAT = fe.isotropic(1.0, 0.3, plane="3d")


def pad(name, element=None, **kw):
    mesh = fe.from_file(DATA / name, element=element)
    return fe.FEModel(mesh, MAT, dirichlet=["clamped"], contact=["contact"],
                      loads={"side": fe.Traction("loaded", (0.0, 0.1, 0.0))}, **kw)


@pytest.mark.parametrize("name, kind, element, n_contact",
                         [("pad_tet.msh", "MeshTet1", "P1", None),
                          ("pad_hex.msh", "MeshHex1", "Q1", 25)])
def test_gmsh_physical_groups_become_boundaries(name, kind, element, n_contact):
    mesh = fe.from_file(DATA / name)
    assert type(mesh.mesh).__name__ == kind and mesh.element == element and mesh.dim == 3
    assert set(mesh.boundary_names) == {"contact", "clamped", "loaded"}
    p = mesh.mesh.p
    for face, axis, value in (("contact", 2, 0.0), ("clamped", 2, 0.5), ("loaded", 0, 1.0)):
        verts = np.unique(mesh.mesh.facets[:, mesh.facets(face)])
        np.testing.assert_allclose(p[axis, verts], value, atol=1e-12)
        # every boundary facet on that plane is in the group
        bf = mesh.mesh.boundary_facets()
        on = np.all(np.abs(p[axis, mesh.mesh.facets[:, bf]] - value) < 1e-12, axis=0)
        assert set(bf[on]) == set(mesh.facets(face))
    cm = pad(name).condense()
    # the contact nodes: the bottom face's vertices less those on the clamped top (none)
    bottom = np.unique(mesh.mesh.facets[:, mesh.facets("contact")])
    assert cm.n_nodes == bottom.size == (n_contact or bottom.size)
    np.testing.assert_allclose(cm.normals, np.broadcast_to([0, 0, -1.0], (cm.n_nodes, 3)),
                               atol=1e-12)
    q, p_w = cm.welded["side"]
    # the side load +y (total 0.05) is shared by the clamped top and the welded bottom
    assert -0.05 < q[:, 1].sum() < 0 and np.all(np.isfinite(p_w))
    ev = np.linalg.eigvalsh(cm.K)
    assert ev[0] > 0


@pytest.mark.slow  # ~25 s: 270 contact nodes of quadratic tetrahedra (P2 on boxes: test_fe3d.py)
def test_quadratic_tetrahedra_on_a_linear_gmsh_mesh():
    """``element='P2'`` on the linear tetrahedra of the file: mid-edge nodes join the contact,
    and the stiffer quadratic field gives the same total welded reaction within 5 %."""
    c1, c2 = pad("pad_tet.msh").condense(), pad("pad_tet.msh", "P2").condense()
    assert c2.n_nodes > 3 * c1.n_nodes
    s1, s2 = c1.welded["side"][0][:, 1].sum(), c2.welded["side"][0][:, 1].sum()
    assert abs(s2 - s1) < 0.05 * abs(s1)


def test_missing_physical_group_named():
    mesh = fe.from_file(DATA / "pad_tet.msh")
    with pytest.raises(InputError, match=r"unknown boundary name 'bottom'.*'clamped', "
                                         r"'contact', 'loaded'"):
        fe.FEModel(mesh, MAT, dirichlet=["clamped"], contact=["bottom"])
    with pytest.raises(InputError, match="unknown boundary name 'top'"):
        fe.FEModel(mesh, MAT, dirichlet=["top"], contact=["contact"])
    with pytest.raises(InputError, match="unknown boundary name 'side'"):
        fe.FEModel(mesh, MAT, dirichlet=["clamped"], contact=["contact"],
                   loads={"x": fe.Pressure("side", 1.0)})


def test_wrong_element_type_refused(tmp_path):
    with pytest.raises(InputError, match="element 'Q1' does not fit a MeshTet1"):
        fe.from_file(DATA / "pad_tet.msh", element="Q1")
    with pytest.raises(InputError, match="element 'P1' does not fit a MeshHex1"):
        fe.from_file(DATA / "pad_hex.msh", element="P1")
    meshio = pytest.importorskip("meshio")
    # a quadratic (tetra10) file: store linear elements and ask for P2 instead
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [.5, 0, 0], [.5, .5, 0],
                    [0, .5, 0], [0, 0, .5], [.5, 0, .5], [0, .5, .5]], float)
    path = tmp_path / "quadratic.msh"
    meshio.write(path, meshio.Mesh(pts, [("tetra10", np.arange(10)[None])]), file_format="gmsh")
    with pytest.raises(InputError, match="holds a MeshTet2; only linear .* element='P2'"):
        fe.from_file(path)


def test_dimension_mismatches_named():
    mesh = fe.box(1, 1, 1, 1, 1, 1, element="P1")
    with pytest.raises(InputError, match=r"material is 2-D \(plane = 'strain'\) but the mesh is "
                                         "3-D: use fe.isotropic"):
        fe.FEModel(mesh, fe.isotropic(1.0, 0.3), dirichlet=["top"], contact=["bottom"])
    with pytest.raises(InputError, match="material is 3-D"):
        fe.FEModel(fe.rectangle(1, 1, 2, 2), MAT, dirichlet=["top"], contact=["bottom"])
    with pytest.raises(InputError, match=r"Traction.value = \(1.0, 0.0\) has 2 components but "
                                         "the mesh is 3-D"):
        fe.FEModel(mesh, MAT, dirichlet=["top"], contact=["bottom"],
                   loads={"a": fe.Traction("right", (1.0, 0.0))})
    with pytest.raises(InputError, match=r"dirichlet\['top'\] must be 'x', 'y', 'z' or a "
                                         "combination"):
        fe.FEModel(mesh, MAT, dirichlet={"top": "xw"}, contact=["bottom"])
    with pytest.raises(InputError, match=r"dirichlet\['top'\] must be 'x', 'y' or 'xy'"):
        fe.FEModel(fe.rectangle(1, 1, 2, 2), fe.isotropic(1.0, 0.3), dirichlet={"top": "z"},
                   contact=["bottom"])
    with pytest.raises(InputError, match="thickness = 2.0 applies to 2-D bodies only"):
        fe.FEModel(mesh, MAT, dirichlet=["top"], contact=["bottom"], thickness=2.0)
    with pytest.raises(InputError, match="bodies\\[1\\] is 2-D but bodies\\[0\\] is 3-D"):
        fe.FEModel(bodies=[fe.Body(mesh, MAT, dirichlet=["top"]),
                           fe.Body(fe.rectangle(1, 1, 1, 1), fe.isotropic(1, 0.3),
                                   dirichlet=["top"])],
                   interfaces=[(0, "bottom", 1, "bottom")]).condense()


def test_box_and_extrude_bad_input():
    with pytest.raises(InputError, match=r"lz must be a finite number > 0 \[length\]; got 0.0"):
        fe.box(1, 1, 0, 1, 1, 1)
    with pytest.raises(InputError, match="element must be 'Q1' .* got 'P3'"):
        fe.box(1, 1, 1, 1, 1, 1, element="P3")
    with pytest.raises(InputError, match="origin must be three finite numbers"):
        fe.box(1, 1, 1, 1, 1, 1, origin=(0, 0))
    with pytest.raises(InputError, match="mesh2d must be a 2-D Q1"):
        fe.extrude(fe.rectangle(1, 1, 2, 2), 1.0, 1)
    with pytest.raises(InputError, match=r"box \(\(x0, y0, z0\), \(x1, y1, z1\)\)"):
        fe.box(1, 1, 1, 1, 1, 1).with_boundaries({"patch": ((0, 0), (1, 1))})
    with pytest.raises(InputError, match="plane must be 'strain' or 'stress' .* or '3d'"):
        fe.isotropic(1.0, 0.3, plane="3D")


def test_box_patch_selection_and_transversely_isotropic_3d():
    """A flat box selects a patch of the bottom face; a transversely isotropic 3-D material
    turned about z has the rotated 6 x 6 stiffness (positive definite, symmetric)."""
    mesh = fe.box(2, 2, 1, 4, 4, 1, element="Q1").with_boundaries(
        {"patch": ((0.5, 0.5, 0.0), (1.5, 1.5, 0.0))})
    assert len(mesh.facets("patch")) == 4
    m = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.5, np.deg2rad(30), plane="3d")
    assert m.D.shape == (6, 6) and np.linalg.eigvalsh(m.D)[0] > 0
    m0 = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.5, 0.0, plane="3d")
    assert m0.D[0, 0] > 5 * m0.D[1, 1]
    # turning by 90 degrees swaps x and y
    m90 = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.5, np.pi / 2, plane="3d")
    np.testing.assert_allclose(m90.D[1, 1], m0.D[0, 0], rtol=1e-12)
    np.testing.assert_allclose(m90.D[4, 4], m0.D[3, 3], rtol=1e-12)
    # the 2-D plane-strain material is the (xx, yy, xy) block of the 3-D one
    m2 = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.5, np.deg2rad(30))
    np.testing.assert_allclose(m2.D, m.D[np.ix_([0, 1, 5], [0, 1, 5])], rtol=1e-12)
