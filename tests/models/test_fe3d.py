"""Three-dimensional FE bodies condensed onto their contact surfaces (issue 23): the periodic
layer's uniform modes and a frictionless slide against the closed form, SPD stiffness, condensed
against uncondensed, a one-layer extrusion against the 2-D plane-strain model, mirror-symmetric
bodies (B = 0), the frames, unit rescaling."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shakedown import fe
from shakedown.models.fe.meshes import FEMesh

E, NU = 1.0, 0.3
MU = E / (2 * (1 + NU))
M_P = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))  # P-wave (uniaxial strain) modulus


def layer(element, n=3, h=0.5, E=E, nu=NU, length=1.0, top=(0.1, 0.2, -0.01)):
    """A periodic layer ``length x length x h`` held at its top, its bottom on a rigid plane;
    load case ``"push"``: the top displaced by ``top`` [length]."""
    mesh = fe.box(length, length, h, n, n, 2, element=element)
    return fe.FEModel(mesh, fe.isotropic(E, nu, plane="3d"), dirichlet=["top"],
                      contact=["bottom"], periodic=[(0, "left", "right"), (0, "front", "back")],
                      loads={"push": fe.Displacement("top", top)})


@pytest.fixture(scope="module", params=["Q1", "P1", "P2"])
def layers(request):
    model = layer(request.param)
    return request.param, model.condense(), model.uncondensed()


def test_layer_uniform_modes_match_closed_form(layers):
    """Uniform slip and gap of the periodic layer (h = 0.5, area 1): simple shear and uniaxial
    strain, ``sum K u = (mu, mu, M) area / h`` and no coupling; exact for every element (the
    fields are linear)."""
    element, cm, _ = layers
    N = cm.n_nodes
    assert cm.K.shape == (3 * N, 3 * N) and cm.dim == 3
    area, h = 1.0, 0.5
    for comp, modulus in ((0, MU), (1, MU), (2, M_P)):
        u = np.zeros((N, 3))
        u[:, comp] = 1.0
        z = np.concatenate([u[:, :2].ravel(), u[:, 2]])
        r = cm.K @ z
        q, p = r[:2 * N].reshape(N, 2), r[2 * N:]
        total = np.r_[q.sum(axis=0), p.sum()]
        expect = np.zeros(3)
        expect[comp] = modulus * area / h
        np.testing.assert_allclose(total, expect, rtol=0, atol=1e-12 * M_P)


def test_layer_welded_reactions_and_frictionless_slide(layers):
    """Top displaced by (a, b, -c): welded reactions ``q = -mu (a, b) area / h`` and
    ``p = M c area / h`` (compression); on a frictionless base (``q = 0``, ``w = 0``) every node
    slides by exactly ``(a, b)`` and keeps the pressure (Q1: ``M c / h`` times each node's
    area ``dx dy``, the consistent nodal forces of a uniform stress)."""
    element, cm, _ = layers
    a, b, c, h = 0.1, 0.2, 0.01, 0.5
    q, p = cm.welded["push"]
    assert q.shape == (cm.n_nodes, 2) and p.shape == (cm.n_nodes,)
    np.testing.assert_allclose(q.sum(axis=0), [-MU * a / h, -MU * b / h], rtol=1e-12)
    np.testing.assert_allclose(p.sum(), M_P * c / h, rtol=1e-12)
    if element == "Q1":
        np.testing.assert_allclose(p, M_P * c / h / cm.n_nodes, rtol=1e-12)
    v = -np.linalg.solve(cm.A, q.ravel())
    np.testing.assert_allclose(v.reshape(-1, 2), np.broadcast_to([a, b], (cm.n_nodes, 2)),
                               rtol=0, atol=1e-12 * a)
    p_slid = p + cm.B.T @ v
    np.testing.assert_allclose(p_slid.sum(), M_P * c / h, rtol=1e-12)


def test_stiffness_symmetric_positive_definite(layers):
    _, cm, _ = layers
    K = cm.K
    assert np.array_equal(K, K.T)
    ev = np.linalg.eigvalsh(K)
    assert ev[0] > 1e-6 * ev[-1]


def test_condensed_and_uncondensed_agree(layers):
    _, cm, um = layers
    Ku = um.system.K.toarray()
    np.testing.assert_allclose(Ku, cm.K, rtol=0, atol=1e-12 * np.abs(cm.K).max())
    for x, y in zip(um.welded["push"], cm.welded["push"], strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12 * np.abs(y).max())
    assert um.system.n_nodes == cm.n_nodes
    assert um.system.A.shape == (2 * cm.n_nodes, 2 * cm.n_nodes)
    assert um.system.B.shape == (2 * cm.n_nodes, cm.n_nodes)
    np.testing.assert_allclose(um.system.diagonal(), np.diag(cm.K), rtol=1e-11)
    slip = np.random.default_rng(1).standard_normal((cm.n_nodes, 2))
    for du, dc in zip(um.displacements(slip=slip, load="push"),
                      cm.displacements(slip=slip, load="push"), strict=True):
        np.testing.assert_allclose(du, dc, rtol=0, atol=1e-11 * np.abs(dc).max())


def test_displacements_reproduce_contact_values():
    """The recovered field has the given slip and gap at the contact nodes, in the frames."""
    model = fe.FEModel(fe.box(1, 1, 0.5, 2, 2, 2, element="P1"), fe.isotropic(E, NU, plane="3d"),
                       dirichlet=["top"], contact=["bottom"])
    cm = model.condense()
    rng = np.random.default_rng(2)
    v, w = rng.standard_normal((cm.n_nodes, 2)), rng.random(cm.n_nodes)
    (u,) = cm.displacements(slip=v, gap=w)
    body = model.bodies[0]
    un = u[body.node_dofs[cm.node_index]]  # (N, 3)
    np.testing.assert_allclose(np.einsum("nac,nc->na", cm.tangents, un), v, atol=1e-14)
    np.testing.assert_allclose(un @ np.array([0, 0, 1.0]), w, atol=1e-14)


def test_extruded_rectangle_equals_plane_strain_model():
    """One layer of hexahedra of depth d, periodic front/back: the in-plane field is independent
    of z with eps_zz = 0 (plane strain) and u_z is an anti-plane field decoupled from it (isotropic).
    Hence the (v_x, w) block of the 3-D K is exactly d times the 2-D Q1 plane-strain K, and v_y
    (= -u_z) is uncoupled from it; the same for the welded reactions of an in-plane load."""
    rect = fe.rectangle(1.0, 0.4, 6, 3, element="Q1")
    load2 = {"shake": fe.BodyForce((0.3, -1.0))}
    cm2 = fe.FEModel(rect, fe.isotropic(E, NU), dirichlet=["top"], contact=["bottom"],
                     loads=load2).condense()
    d = 0.25
    model3 = fe.FEModel(fe.extrude(rect, d, 1), fe.isotropic(E, NU, plane="3d"),
                        dirichlet=["top"], contact=["bottom"], periodic=("front", "back"),
                        loads={"shake": fe.BodyForce((0.3, -1.0, 0.0))})
    cm3 = model3.condense()
    N = cm2.n_nodes
    assert cm3.n_nodes == N
    np.testing.assert_allclose(cm3.node_coordinates[:, :2], cm2.node_coordinates, atol=1e-15)
    idx = np.concatenate([2 * np.arange(N), 2 * N + np.arange(N)])  # (v_x, w)
    ivy = 2 * np.arange(N) + 1
    scale = np.abs(cm2.K).max() * d
    np.testing.assert_allclose(cm3.K[np.ix_(idx, idx)], d * cm2.K, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(cm3.K[np.ix_(ivy, idx)], 0.0, atol=1e-12 * scale)
    q3, p3 = cm3.welded["shake"]
    q2, p2 = cm2.welded["shake"]
    assert np.abs(q2).min() > 1e-3 * np.abs(p2).max()
    np.testing.assert_allclose(q3[:, 0], d * q2, rtol=0, atol=1e-12 * np.abs(p2).max() * d)
    np.testing.assert_allclose(p3, d * p2, rtol=0, atol=1e-12 * np.abs(p2).max() * d)
    np.testing.assert_allclose(q3[:, 1], 0.0, atol=1e-12 * np.abs(p2).max() * d)


def mirrored(mesh: FEMesh) -> FEMesh:
    """The mirror image of a box mesh in the plane z = 0 (its "top" and "bottom" swap places)."""
    return FEMesh(replace(mesh.mesh, doflocs=mesh.mesh.p * np.array([[1.0], [1.0], [-1.0]])),
                  mesh.element)


@pytest.mark.parametrize("element", ["P1", "Q1", "P2"])
def test_mirror_symmetric_bodies_are_uncoupled(element):
    """Two mirror-image bodies of the same material joined at z = 0 give B = 0 (relative slip
    does not change the normal reactions); a dissimilar lower body couples them."""
    a = fe.box(1.0, 0.8, 0.5, 3, 2, 2, element=element)
    b = mirrored(a)  # its facet set "bottom" lies on z = 0, "top" on z = -0.5
    mat = fe.isotropic(E, NU, plane="3d")

    def model(mat_b):
        return fe.FEModel(bodies=[fe.Body(a, mat, dirichlet=["top"]),
                                  fe.Body(b, mat_b, dirichlet=["top"])],
                          interfaces=[(0, "bottom", 1, "bottom")], friction=0.3).condense()

    cm = model(mat)
    assert set(cm.node_kind) == {"interface"}
    assert np.abs(cm.B).max() <= 1e-13 * np.abs(cm.K).max()
    # two springs in series: the relative displacement's compliance is body a's compliance on a
    # rigid obstacle plus its mirror image's, whose normal component changes sign (E)
    Ka = fe.FEModel(a, mat, dirichlet=["top"], contact=["bottom"]).condense().K
    Ea = np.diag(np.r_[np.ones(2 * cm.n_nodes), -np.ones(cm.n_nodes)])
    Ca = np.linalg.inv(Ka)
    np.testing.assert_allclose(np.linalg.inv(Ca + Ea @ Ca @ Ea), cm.K, rtol=0,
                               atol=1e-11 * np.abs(cm.K).max())
    coupled = model(fe.isotropic(3 * E, 0.1, plane="3d"))
    assert np.abs(coupled.B).max() > 1e-3 * np.abs(coupled.K).max()


@settings(max_examples=25)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
    lambda v: np.linalg.norm(v) > 1e-3))
def test_tangent_frames_orthonormal_right_handed(normal):
    nrm = np.array(normal) / np.linalg.norm(normal)
    tx, ty, n = fe.tangent_frames(nrm[None])
    F = np.vstack([tx, ty, n])
    np.testing.assert_allclose(F @ F.T, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(n[0], -nrm, atol=1e-15)
    np.testing.assert_allclose(np.cross(tx[0], ty[0]), n[0], atol=1e-14)


def test_bottom_face_frame_and_welded_sign():
    """Bottom face: t_x = +x, t_y = +y, n = +z; a tangential push F on the top gives welded
    reactions against it, ``q_w . F < 0``, and a downward push a compressive ``p_w``
    (MODEL.md s.1 sanity check; the clamped left face carries the rest of the load)."""
    F = np.array([0.2, -0.1, -1.0])
    model = fe.FEModel(fe.box(1, 1, 0.3, 2, 2, 1, element="P1"), fe.isotropic(E, NU, plane="3d"),
                       dirichlet=["left"], contact=["bottom"],
                       loads={"f": fe.Traction("top", F)})
    cm = model.condense()
    np.testing.assert_allclose(cm.tangents[:, 0], np.broadcast_to([1, 0, 0], (cm.n_nodes, 3)))
    np.testing.assert_allclose(cm.tangents[:, 1], np.broadcast_to([0, 1, 0], (cm.n_nodes, 3)))
    np.testing.assert_allclose(cm.normals, np.broadcast_to([0, 0, -1], (cm.n_nodes, 3)))
    q, p = cm.welded["f"]
    assert cm.n_nodes == 6  # the 3 x 3 bottom nodes less the 3 on the clamped face
    assert 0 < p.sum() < -F[2] and np.all(p > 0)
    assert q[:, 0].sum() < 0 and q[:, 1].sum() > 0


@settings(max_examples=12)
@given(st.floats(-6, 12), st.floats(-6, 6))
def test_unit_rescaling(log_e, log_l):
    """Stress unit x s_E and length unit x s_L: K scales by s_E s_L, the welded reactions of a
    traction (stress) by s_E s_L^2 (force)."""
    sE, sL = 10.0**log_e, 10.0**log_l

    def cm(sE, sL):
        mesh = fe.box(sL, sL, 0.5 * sL, 2, 2, 1, element="P1")
        return fe.FEModel(mesh, fe.isotropic(sE * E, NU, plane="3d"), dirichlet=["top"],
                          contact=["bottom"],
                          loads={"t": fe.Traction("top", (0.1 * sE, 0.0, -sE))}).condense()

    ref, big = cm(1.0, 1.0), cm(sE, sL)
    np.testing.assert_allclose(big.K / (sE * sL), ref.K, rtol=1e-10,
                               atol=1e-12 * np.abs(ref.K).max())
    np.testing.assert_allclose(big.welded["t"][1] / (sE * sL**2), ref.welded["t"][1], rtol=1e-10,
                               atol=1e-12)


def test_system_and_load_cycle_are_three_dimensional(layers):
    """``cm.system`` is a ``dim = 3`` DiscreteSystem over the same K (dense or uncondensed);
    ``load_cycle`` gives ``q0`` of shape (N, 2), harmonics or samples."""
    _, cm, um = layers
    N = cm.n_nodes
    s = cm.system
    assert s.dim == 3 and s.n_nodes == N and s.n_tangential == 2 * N
    np.testing.assert_array_equal(s.K, cm.K)
    su = um.system
    assert su.dim == 3 and su.n_nodes == N and su.n_tangential == 2 * N
    np.testing.assert_allclose(su.to_dense().K, cm.K, rtol=0, atol=1e-12 * np.abs(cm.K).max())
    sub = su.subsystem([0, 2])
    assert sub.dim == 3
    keep = np.r_[0, 1, 4, 5, 2 * N, 2 * N + 2]
    np.testing.assert_allclose(sub.K, cm.K[np.ix_(keep, keep)], rtol=0,
                               atol=1e-12 * np.abs(cm.K).max())
    assert su.with_friction(0.2).friction_xy.shape == (N, 2)
    assert su.is_coupled == s.is_coupled
    q, p = cm.welded["push"]
    lc = cm.load_cycle(static={"push": 2.0}, cyclic="push")
    assert lc.dim == 3 and lc.q0.shape == (N, 2)
    np.testing.assert_allclose(lc.q0, 2 * q)
    qt, pt = lc.evaluate(np.array([0.0, 0.5]), 1.0)
    np.testing.assert_allclose(qt[0], 3 * q, atol=1e-15)
    np.testing.assert_allclose(pt[1], p, atol=1e-15)
    ls = cm.load_cycle(samples=["push", {"push": -1.0}])
    assert ls.dim == 3 and ls.q1.shape == (2, N, 2)
    assert um.load_cycle(static="push").dim == 3


@pytest.mark.parametrize("element", ["Q1", "P1", "P2"])
def test_vectorised_stiffness_equals_scikit_fem_form(element):
    """The 3-D stiffness (strains of each local function once per element block) is
    scikit-fem's assembly of the form ``eps(u) . D eps(v)`` to round-off, for an anisotropic
    material turned about z (every entry of the 6 x 6 D non-zero in its block)."""
    from skfem import BilinearForm, asm
    from skfem.helpers import sym_grad

    mat = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.5, 0.4, plane="3d")
    body = fe.Body(fe.box(1.0, 0.7, 0.5, 3, 2, 2, element=element), mat)
    D = mat.D
    pairs = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))

    @BilinearForm
    def form(u, v, w):
        e, f = sym_grad(u), sym_grad(v)
        eu = [e[i, j] * (1 if i == j else 2) for i, j in pairs]
        ev = [f[i, j] * (1 if i == j else 2) for i, j in pairs]
        return sum(D[i, j] * eu[j] * ev[i] for i in range(6) for j in range(6))

    K, ref = body.stiffness(), asm(form, body.basis).tocsr()
    assert abs(K - ref).max() <= 1e-14 * abs(ref).max()


def test_mass_dynamic_stiffness_and_cache(tmp_path):
    """``condense(mass=True)`` in 3-D: the Guyan mass is symmetric positive semi-definite and
    ``dynamic_stiffness(s)`` is the Schur complement of ``K_z + s M_z`` (dense, independent);
    the on-disk cache gives back the same 3-D model."""
    model = fe.FEModel(fe.box(1, 1, 0.5, 2, 2, 1, element="P1"),
                       fe.isotropic(E, NU, plane="3d", density=2.0), dirichlet=["top"],
                       contact=["bottom"], loads={"push": fe.Displacement("top", (0.1, 0, -0.1))})
    # one layer: no interior DOF, the Guyan mass is the contact block itself
    thin = model.condense(mass=True)
    assert thin.counts["n_interior_dofs"] == 0
    np.testing.assert_array_equal(thin.M, thin._assembled().Mcc)
    model = fe.FEModel(fe.box(1, 1, 0.5, 2, 2, 2, element="P1"),
                       fe.isotropic(E, NU, plane="3d", density=2.0), dirichlet=["top"],
                       contact=["bottom"], loads={"push": fe.Displacement("top", (0.1, 0, -0.1))})
    cm = model.condense(mass=True)
    M = cm.M
    assert M.shape == cm.K.shape and np.array_equal(M, M.T)
    assert np.linalg.eigvalsh(M)[0] > -1e-14 * np.abs(M).max()
    a = cm._assembled()
    nc = 3 * cm.n_nodes
    s = 0.7
    Mz = np.block([[a.Mcc, a.Mci.toarray()], [a.Mci.T.toarray(), a.Mii.toarray()]])
    Z = a.Kz.toarray() + s * Mz
    ref = Z[:nc, :nc] - Z[:nc, nc:] @ np.linalg.solve(Z[nc:, nc:], Z[nc:, :nc])
    np.testing.assert_allclose(cm.dynamic_stiffness(s), ref, rtol=0,
                               atol=1e-12 * np.abs(ref).max())
    first = model.condense(cache_dir=tmp_path)
    again = model.condense(cache_dir=tmp_path)
    assert again.from_cache and again.dim == 3 and again.n_nodes == first.n_nodes
    np.testing.assert_array_equal(again.K, first.K)
    np.testing.assert_array_equal(again.tangents, first.tangents)
    for x, y in zip(again.welded["push"], first.welded["push"], strict=True):
        np.testing.assert_array_equal(x, y)
    assert again.load_cycle(static="push").q0.shape == (cm.n_nodes, 2)
