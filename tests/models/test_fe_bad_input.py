"""Bad input to the FE condensation: clear errors whose messages name the problem."""

import numpy as np
import pytest

from shakedown import InputError, fe


@pytest.fixture
def mesh():
    return fe.rectangle(1.0, 1.0, 4, 4)


@pytest.fixture
def mat():
    return fe.isotropic(1.0, 0.3)


def test_no_contact_boundary(mesh, mat):
    with pytest.raises(InputError, match="no contact boundary"):
        fe.FEModel(mesh, mat, dirichlet=["top"])


def test_unknown_boundary_names(mesh, mat):
    with pytest.raises(InputError, match=r"unknown boundary name 'bottm'.*'bottom'"):
        fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottm"])
    with pytest.raises(InputError, match="unknown boundary name 'roof'"):
        fe.FEModel(mesh, mat, dirichlet=["roof"], contact=["bottom"])
    with pytest.raises(InputError, match="unknown boundary name 'side'"):
        fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"],
                   loads={"a": fe.Traction("side", (1, 0))})


def test_rigid_body_modes_held_by_contact_only(mesh, mat):
    model = fe.FEModel(mesh, mat, contact=["bottom"])
    with pytest.raises(InputError, match="condensed K is singular.*held only by its contact"):
        model.condense()
    cm = model.condense(allow_rigid_body_modes=True)
    with pytest.raises(InputError, match="positive definite"):
        _ = cm.system


def test_floating_body_is_detected(mat):
    top = fe.Body(fe.rectangle(1, 1, 3, 3), mat, dirichlet=["top"])
    loose = fe.Body(fe.rectangle(1, 1, 3, 3, origin=(2, 0)), mat)
    model = fe.FEModel(bodies=[top, loose], contact=[(0, "bottom")])
    with pytest.raises(InputError, match="body 1 .*rigid-body modes"):
        model.condense()


def test_roller_leaves_a_rigid_body_mode(mesh, mat):
    # a roller (x held) on the right and contact on the top: welded, the body is held (K_ii
    # regular) but a vertical translation moves the contact nodes at no energy: K singular
    model = fe.FEModel(mesh, mat, dirichlet={"right": "x"}, contact=["top"])
    with pytest.raises(InputError, match="singular"):
        model.condense()


@pytest.mark.parametrize("nu", [0.5, 0.7, -1.0, -3.0])
def test_isotropic_poisson_ratio_out_of_range(nu):
    with pytest.raises(InputError, match=r"nu must satisfy -1 < nu < 0.5"):
        fe.isotropic(1.0, nu)


@pytest.mark.parametrize("E", [0.0, -1.0, np.nan, "a"])
def test_non_positive_modulus(E):
    with pytest.raises(InputError, match="E must be"):
        fe.isotropic(E, 0.3)


def test_orthotropic_compliance_not_positive_definite():
    with pytest.raises(InputError, match="compliance .* not positive definite"):
        fe.transversely_isotropic(1.0, 1.0, 0.9, 0.3, 0.1, 0.0)
    with pytest.raises(InputError, match="nu23"):
        fe.transversely_isotropic(8.0, 1.0, 0.4, 1.0, 0.1, 0.0)
    with pytest.raises(InputError, match="G12 must be > 0"):
        fe.transversely_isotropic(8.0, 1.0, 0.4, 0.3, -0.1, 0.0)


def test_bad_plane_element_pattern():
    with pytest.raises(InputError, match="plane must be 'strain' or 'stress'"):
        fe.isotropic(1.0, 0.3, plane="axisymmetric")
    with pytest.raises(InputError, match="element must be one of"):
        fe.rectangle(1, 1, 2, 2, element="P3")
    with pytest.raises(InputError, match="pattern must be one of"):
        fe.rectangle(1, 1, 2, 2, pattern="zigzag")
    with pytest.raises(InputError, match="nx .* integer >= 1"):
        fe.rectangle(1, 1, 0, 2)
    with pytest.raises(InputError, match="'Q1' on quadrilateral"):
        fe.FEMesh(fe.rectangle(1, 1, 2, 2).mesh, "Q1")


def test_self_intersecting_polygon():
    with pytest.raises(InputError, match="simple"):
        fe.polygon([[0, 0], [1, 1], [1, 0], [0, 1]])


def test_periodic_sides_must_match():
    mesh = fe.trapezoid(2.0, 1.0, 1.0, 4, 4)
    model = fe.FEModel(mesh, fe.isotropic(1, 0.3), dirichlet=["top"], contact=["bottom"],
                       periodic=("left", "right"))
    with pytest.raises(InputError, match="periodic sides .* no partner"):
        model.condense()


def test_interface_nodes_must_match(mat):
    a = fe.Body(fe.rectangle(1, 1, 4, 4), mat, dirichlet=["top"])
    b = fe.Body(fe.rectangle(1, 1, 5, 4, origin=(0, -1)), mat, dirichlet=["bottom"])
    with pytest.raises(InputError, match="interface .* must match"):
        fe.FEModel(bodies=[a, b], interfaces=[(0, "bottom", 1, "top")]).condense()


def test_displacement_load_needs_dirichlet(mesh, mat):
    with pytest.raises(InputError, match="not a Dirichlet boundary"):
        fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"],
                   loads={"d": fe.Displacement("left", (0.1, 0))})


def test_bad_load_values(mesh, mat):
    with pytest.raises(InputError, match="Traction.value must be a finite pair"):
        fe.Traction("top", (1, 2, 3, 4))
    with pytest.raises(InputError, match=r"Traction.value = \(1.0, 2.0, 3.0\) has 3 components "
                                         "but the mesh is 2-D"):
        fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"],
                   loads={"a": fe.Traction("top", (1, 2, 3))})
    with pytest.raises(InputError, match="not one of Traction"):
        fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"], loads={"a": [3.0]})


def test_products_need_what_they_use(mesh, mat):
    cm = fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"],
                    loads={"dead": fe.Pressure("top", 1.0)}).condense()
    with pytest.raises(InputError, match="mass=True"):
        cm.dynamic_stiffness(1.0)
    with pytest.raises(InputError, match="unknown load case 'live'.*'dead'"):
        cm.load_cycle(static="live")


def test_callable_loads_are_not_cached(tmp_path, mesh, mat):
    model = fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"],
                       loads={"f": fe.BodyForce(lambda x: (0 * x[0], -1 + 0 * x[0]))})
    with pytest.raises(InputError, match="callables, which cannot be cached"):
        model.condense(cache_dir=tmp_path)
    assert model.condense().welded["f"][1].sum() > 0


def test_missing_mesh_file(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        fe.from_file(tmp_path / "nothing.msh")
