"""FE condensation: reference problems (seeds 000 s.7.1 and 001), frame/sign conventions,
interfaces, cross-checks against the full model, mass, cache.

Tolerances: condensation of these small models is exact up to round-off; with
``cond(K_ii) <= 1e5`` and double precision the Schur complement is good to ~1e-11 relative,
so "exact" identities use ``rtol = 1e-9``.
"""

import numpy as np
import pytest
import scipy.linalg as sla

from shakedown import fe
from shakedown.models.fe.analytic import layer_uniform_stiffness

EXACT = 1e-9  # relative tolerance of identities that hold up to round-off (see module doc)


def seed001_material(theta_deg=80.0, E1=8.0, plane="strain"):
    # seed 001 (Agwa & Pinto da Costa 2007), Fig. 2: E1 = 8, E2 = 1, nu12 = 0.4, nu23 = 0.3,
    # G12 / E2 = 0.1
    return fe.transversely_isotropic(E1, 1.0, 0.4, 0.3, 0.1, np.deg2rad(theta_deg), plane=plane)


def square(n_nodes=11, pattern="union-jack", element="P1", nu=0.3, **kw):
    # seed 000 s.7.1: unit square, plane strain, nu = 0.3, contact bottom, top fixed, sides free
    mesh = fe.rectangle(1.0, 1.0, n_nodes - 1, n_nodes - 1, element=element, pattern=pattern)
    return fe.FEModel(mesh, fe.isotropic(1.0, nu), dirichlet=["top"], contact=["bottom"], **kw)


def layer(mat, nx=6, ny=4, element="P1", pattern="diagonal", width=1.0, height=0.5):
    mesh = fe.rectangle(width, height, nx, ny, element=element, pattern=pattern)
    return fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"], periodic=("left", "right"))


def uniform_blocks(cm):
    N = cm.n_nodes
    o = np.ones(N)
    return o @ cm.A @ o, o @ cm.B.T @ o


# ----------------------------------------------------------------- seed 001: orthotropic layer
def test_seed001_material_critical_friction():
    # seed 001 s.3: mu_cr = D44 / |D24| = 0.2629238 (7 digits given: half an ulp of the last)
    m = seed001_material()
    assert m.layer_critical_friction() == pytest.approx(0.2629238, abs=5e-8)
    assert m.D44 == m.D[2, 2] and m.D24 == m.D[1, 2]


@pytest.mark.parametrize("element,pattern", [("P1", "diagonal"), ("P1", "union-jack"),
                                             ("P2", "crossed"), ("Q1", "diagonal")])
def test_seed001_layer_uniform_mode_gives_D44_over_D24(element, pattern):
    # the uniform slip of the bottom produces the linear field u = (1 - y/h) e_x, which every
    # element reproduces exactly: (1^T A 1) / |1^T B^T 1| = D44 / |D24| on any mesh
    mat = seed001_material()
    cm = layer(mat, element=element, pattern=pattern).condense()
    a, b = uniform_blocks(cm)
    assert a / abs(b) == pytest.approx(mat.layer_critical_friction(), rel=EXACT)
    # totals are the uniform tractions D44 / h, D24 / h times the width (signs: MODEL.md s.1)
    assert a == pytest.approx(mat.D44 / 0.5, rel=EXACT)
    assert b == pytest.approx(mat.D24 / 0.5, rel=EXACT)
    # x = 1 solves the MCEIP-mu equations y = (X A X + mu B^T X) x = 0 at mu = mu_cr
    chi = -np.sign(b)
    X = chi * np.eye(cm.n_nodes)
    y = (X @ cm.A @ X + mat.layer_critical_friction() * cm.B.T @ X) @ np.ones(cm.n_nodes)
    assert np.abs(y).max() <= EXACT * np.abs(cm.A).max()


def test_periodic_layer_drops_the_copied_corner():
    cm = layer(seed001_material(), nx=6).condense()
    assert cm.n_nodes == 6  # 7 bottom vertices, the right corner is a copy of the left one
    assert np.all(cm.node_coordinates[:, 0] < 1.0 - 1e-12)


def test_isotropic_layer_is_uncoupled_for_uniform_mode():
    # seed 001: an isotropic layer is never directionally unstable (D24 = 0)
    mat = fe.isotropic(1.0, 0.3)
    assert mat.layer_critical_friction() == np.inf
    a, b = uniform_blocks(layer(mat).condense())
    assert abs(b) <= EXACT * a


def test_layer_dynamic_stiffness_converges_to_analytic():
    # uniform modes of the layer obey Dt u'' = rho s u (fe.analytic); P1 error ~ h^2
    mat = seed001_material()
    s, W = 30.0, 0.25
    Z = layer_uniform_stiffness(mat, 1.0, s)
    errs = []
    for ny in (8, 16, 32):
        cm = layer(mat, nx=2, ny=ny, width=W, height=1.0).condense(mass=True)
        Ks = cm.dynamic_stiffness(s)
        N = cm.n_nodes
        o = np.ones(N)
        Zh = np.array([[o @ Ks[:N, :N] @ o, o @ Ks[:N, N:] @ o],
                       [o @ Ks[N:, :N] @ o, o @ Ks[N:, N:] @ o]]) / W
        errs.append(np.abs(Zh - Z).max())
    rates = np.log2(np.array(errs[:-1]) / errs[1:])
    assert np.all(rates > 1.8), (errs, rates)  # second order (P1 consistent mass)
    np.testing.assert_allclose(layer_uniform_stiffness(mat, 2.0, 0.0), Z0 := np.array(
        [[mat.D44, mat.D24], [mat.D24, mat.D[1, 1]]]) / 2.0, rtol=1e-14)
    assert Z0.shape == (2, 2)


# ----------------------------------------------------------------- seed 000 s.7.1: unit square
def test_square_K_symmetric_positive_definite_and_frame():
    cm = square(11).condense()
    assert cm.K.shape == (22, 22)
    assert np.array_equal(cm.K, cm.K.T)
    assert np.linalg.eigvalsh(cm.K)[0] > 0
    np.testing.assert_array_equal(cm.system.K, cm.K)
    assert cm._assembled().lu.symmetric  # the trailing-block Schur path was used
    # bottom side: outward normal -y, tangent +x; nodes ordered by increasing x
    np.testing.assert_allclose(cm.normals, np.tile([0.0, -1.0], (11, 1)))
    np.testing.assert_allclose(cm.tangents, np.tile([1.0, 0.0], (11, 1)))
    assert np.all(np.diff(cm.node_coordinates[:, 0]) > 0)
    # pushing a node up into the body (opening w > 0) needs compression p > 0: C_jj > 0;
    # sliding a node along +t needs q along +t: A_jj > 0
    assert np.all(np.diag(cm.C) > 0) and np.all(np.diag(cm.A) > 0)


def test_square_mirror_symmetry():
    # the union-jack mesh with an even number of cells is mirror-symmetric about x = 1/2:
    # mirroring reverses the node order and the slip sign, keeps the gap
    cm = square(11).condense()
    R = np.eye(11)[::-1]
    np.testing.assert_allclose(R @ cm.A @ R, cm.A, atol=EXACT * np.abs(cm.K).max())
    np.testing.assert_allclose(R @ cm.C @ R, cm.C, atol=EXACT * np.abs(cm.K).max())
    np.testing.assert_allclose(-R @ cm.B @ R, cm.B, atol=EXACT * np.abs(cm.K).max())


@pytest.mark.parametrize("n_nodes", [21, 41])
def test_square_linear_eigenvalue_near_seed000(n_nodes):
    # seed 000 s.7.1, Fig. 6: mu*_h in [1.944, 1.950] for 1/h = 10..100 (linear case, all
    # nodes slipping, positive mode).  Direct dense eigen-solve of A x = mu (-chi B^T) x.
    cm = square(n_nodes).condense()
    ev, V = sla.eig(cm.A, -cm.B.T)  # chi = +1 (slip along +x); chi = -1 is the mirror image
    ok = np.isfinite(ev) & (np.abs(ev.imag) < 1e-9) & (ev.real > 0)
    k = np.argmin(ev.real[ok])
    mu, x = ev.real[ok][k], V[:, ok][:, k].real
    x *= np.sign(x.sum())
    assert abs(mu - 1.945) < 0.006
    assert np.all(x > 0)  # the eigenvector is positive (the linear case)


@pytest.mark.slow
@pytest.mark.parametrize("n_nodes", [61, 101])
def test_square_linear_eigenvalue_converged_seed000(n_nodes):
    cm = square(n_nodes).condense()
    ev = sla.eigvals(cm.A, -cm.B.T)
    ok = np.isfinite(ev) & (np.abs(ev.imag) < 1e-9) & (ev.real > 0)
    # seed 000: converged to 1.945 for more than 60 nodes per edge (3 digits)
    assert abs(ev.real[ok].min() - 1.945) < 1e-3


def test_tangential_push_sign_sanity():
    # MODEL.md s.1: a tangential push F gives q_w = -F (the obstacle resists it), a weight
    # gives p_w > 0 (compression).  Block welded to the obstacle along its bottom only.
    b = np.array([0.3, -1.0])
    model = fe.FEModel(fe.rectangle(2.0, 1.0, 8, 4), fe.isotropic(1.0, 0.25),
                       contact=["bottom"], loads={"push": fe.BodyForce(tuple(b))})
    cm = model.condense(allow_rigid_body_modes=True)  # held by the contact only: K singular
    q, p = cm.welded["push"]
    assert q.sum() == pytest.approx(-b[0] * 2.0, rel=EXACT)  # t = +x on the bottom
    assert p.sum() == pytest.approx(-b[1] * 2.0, rel=EXACT)  # compression positive
    # and q rises as v grows (MODEL.md s.1): A has a positive diagonal
    assert np.all(np.diag(cm.A) > 0)
    with pytest.raises(ValueError, match="held only by its contact nodes"):
        model.condense()


def test_welded_reactions_balance_the_load_on_two_sides():
    # bottom and left sides on the obstacle, no Dirichlet part: the welded reaction vectors
    # R = q t - p n balance the body force exactly (global equilibrium)
    b = np.array([0.3, -1.0])
    model = fe.FEModel(fe.rectangle(2.0, 1.0, 8, 4, element="P2"), fe.isotropic(1.0, 0.25),
                       contact=["bottom", "left"], loads={"push": fe.BodyForce(tuple(b))})
    cm = model.condense(allow_rigid_body_modes=True)
    q, p = cm.welded["push"]
    R = q[:, None] * cm.tangents - p[:, None] * cm.normals
    np.testing.assert_allclose(R.sum(axis=0), -b * 2.0, rtol=EXACT)
    left = cm.normals[:, 0] < -0.5
    np.testing.assert_allclose(cm.tangents[left], np.tile([0.0, -1.0], (left.sum(), 1)))


# ----------------------------------------------------------------- interfaces
def two_bodies(mat_top, mat_bottom, n=6, pattern="diagonal"):
    mirrored = {"diagonal": "anti-diagonal", "anti-diagonal": "diagonal"}.get(pattern, pattern)
    top = fe.Body(fe.rectangle(1, 1, n, n, pattern=pattern), mat_top, dirichlet=["top"])
    bot = fe.Body(fe.rectangle(1, 1, n, n, pattern=mirrored, origin=(0, -1)), mat_bottom,
                  dirichlet=["bottom"])
    return fe.FEModel(bodies=[top, bot], interfaces=[(0, "bottom", 1, "top")])


def test_symmetric_interface_is_uncoupled():
    # MODEL.md s.6: two symmetric bodies of the same material give B = 0
    mat = fe.isotropic(1.0, 0.3)
    cm = two_bodies(mat, mat).condense()
    assert cm.node_kind == ("interface",) * 7
    assert np.abs(cm.B).max() <= EXACT * np.abs(cm.K).max()
    assert not cm.system.is_coupled or np.abs(cm.B).max() < 1e-12 * np.abs(cm.K).max()
    assert np.linalg.eigvalsh(cm.K)[0] > 0


def test_dissimilar_interface_is_coupled():
    # Dundurs' beta != 0 for different materials: B != 0 (the check above can fail)
    cm = two_bodies(fe.isotropic(1.0, 0.3), fe.isotropic(10.0, 0.1)).condense()
    assert np.abs(cm.B).max() > 1e-3 * np.abs(cm.K).max()


def test_interface_with_rigid_like_body_approaches_rigid_contact():
    # a very stiff lower body behaves as the rigid obstacle (relative = absolute displacement)
    mat = fe.isotropic(1.0, 0.3)
    cm_if = two_bodies(mat, fe.isotropic(1e7, 0.3)).condense()
    cm_rigid = fe.FEModel(fe.rectangle(1, 1, 6, 6), mat, dirichlet=["top"],
                          contact=["bottom"]).condense()
    # the lower body's compliance is 1e-7 of the upper one's: measured difference 1.4e-7 of
    # max|K| (first order in the stiffness ratio); 1e-6 is 7x that
    np.testing.assert_allclose(cm_if.K, cm_rigid.K, atol=1e-6 * np.abs(cm_rigid.K).max())


# ----------------------------------------------------------------- condensation == full model
def full_solve(model, values, case):
    """Solve the full (uncondensed) single-body model with the contact DOFs prescribed."""
    import scipy.sparse.linalg as spla

    body = model.bodies[0]
    cm = model.condense()
    K = body.stiffness()
    f, pres = body.load_vector(body.loads[case])
    u = np.zeros(body.n_dofs)
    fixed = dict(pres)
    for d in body.held_dofs():
        fixed.setdefault(d, 0.0)
    N = cm.n_nodes
    v, w = values[:N], values[N:]
    for j in range(N):
        uj = v[j] * cm.tangents[j] - w[j] * cm.normals[j]
        for c in range(2):
            fixed[int(body.node_dofs[cm.node_index[j], c])] = uj[c]
    D = np.array(sorted(fixed))
    u[D] = [fixed[d] for d in D]
    I = np.setdiff1d(np.arange(body.n_dofs), D)
    u[I] = spla.spsolve(K[I][:, I].tocsc(), f[I] - K[I][:, D] @ u[D])
    R = K @ u - f  # reactions at the prescribed DOFs
    nd = body.node_dofs[cm.node_index]
    Rc = R[nd]  # (N, 2)
    q = np.sum(Rc * cm.tangents, axis=1)
    p = -np.sum(Rc * cm.normals, axis=1)
    return cm, u, q, p


@pytest.mark.parametrize("element", ["P1", "P2", "Q1"])
def test_condensation_equals_full_solve(element):
    rng = np.random.default_rng(5)
    mesh = fe.trapezoid(1.5, 1.0, 1.0, 5, 4, element=element)
    loads = {"mixed": [fe.Traction("right", (0.2, -0.1)), fe.BodyForce((0.0, -1.0)),
                       fe.Pressure("left", 0.3), fe.Displacement("top", (0.01, -0.02))]}
    model = fe.FEModel(mesh, seed001_material(35.0), dirichlet=["top"], contact=["bottom"],
                       loads=loads)
    N = model.condense().n_nodes
    z = rng.normal(size=2 * N) * 1e-2
    cm, u, q, p = full_solve(model, z, "mixed")
    qw, pw = cm.welded["mixed"]
    scale = np.abs(np.concatenate([q, p])).max()
    np.testing.assert_allclose(qw + cm.A @ z[:N] + cm.B @ z[N:], q, atol=EXACT * scale)
    np.testing.assert_allclose(pw + cm.B.T @ z[:N] + cm.C @ z[N:], p, atol=EXACT * scale)
    u_rec = cm.displacements(z[:N], z[N:], load="mixed")[0]
    np.testing.assert_allclose(u_rec, u, atol=EXACT * np.abs(u).max())
    # the trailing-block Schur complement equals the plain one (solves with every column)
    a = cm._assembled()
    plain = a.Kcc - a.Kci @ np.linalg.solve(a.Kii.toarray(), a.Kci.T.toarray())
    np.testing.assert_allclose(cm.K, plain, atol=EXACT * np.abs(plain).max())


# ----------------------------------------------------------------- mass
def test_guyan_mass_properties():
    model = fe.FEModel(fe.rectangle(2.0, 1.0, 6, 3, element="P2"),
                       fe.isotropic(1.0, 0.3, density=2.5),
                       contact=["bottom", "left", "right", "top"])
    cm = model.condense(mass=True, allow_rigid_body_modes=True)
    assert np.array_equal(cm.M, cm.M.T) and np.linalg.eigvalsh(cm.M)[0] > 0
    # a rigid translation (interior follows exactly): z^T M z = total mass = rho * area
    for e in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
        z = np.concatenate([cm.tangents @ e, -(cm.normals @ e)])
        assert z @ cm.M @ z == pytest.approx(2.5 * 2.0, rel=EXACT)
        assert np.abs(cm.K @ z).max() <= 1e-9 * np.abs(cm.K).max()


def test_dynamic_stiffness_identities():
    cm = square(7, element="P2").condense(mass=True)
    np.testing.assert_array_equal(cm.dynamic_stiffness(0.0), cm.K)
    h = 1e-3
    dK = (cm.dynamic_stiffness(h) - cm.dynamic_stiffness(-h)) / (2 * h)
    # d/ds S(K + s M) at s = 0 is the Guyan mass; central difference error O(h^2)
    np.testing.assert_allclose(dK, cm.M, atol=1e-5 * np.abs(cm.M).max())
    # exact formula against a dense evaluation
    a = cm._assembled()
    s = 7.0
    Kii = (a.Kii + s * a.Mii).toarray()
    Kci = (a.Kci + s * a.Mci).toarray()
    dense = a.Kcc + s * a.Mcc - Kci @ np.linalg.solve(Kii, Kci.T)
    np.testing.assert_allclose(cm.dynamic_stiffness(s), dense, atol=EXACT * np.abs(dense).max())


# ----------------------------------------------------------------- loads and cycles
def test_load_cycle_from_cases():
    loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shake": fe.Traction("left", (0.5, 0.0))}
    model = fe.FEModel(fe.rectangle(1, 1, 4, 4), fe.isotropic(1.0, 0.3),
                       dirichlet={"right": "xy"}, contact=["bottom"], loads=loads,
                       friction=0.4)
    cm = model.condense()
    lc = cm.load_cycle(static="dead", cyclic="shake")
    qd, pd = cm.welded["dead"]
    qs, ps = cm.welded["shake"]
    q, p = lc.evaluate(np.array([0.0, 0.5]), 2.0)
    np.testing.assert_allclose(q[0], qd + 2 * qs, rtol=1e-12)
    np.testing.assert_allclose(p[1], pd - 2 * ps, rtol=1e-12)
    assert np.all(pd > 0)  # dead load presses the block on the obstacle: compression
    assert cm.system.friction[0] == 0.4
    ls = cm.load_cycle(static={"dead": 1.0}, samples=["shake", {"shake": -1.0}])
    assert ls.kind == "samples"
    assert cm.load_cycle(static="dead").has_periodic_part is False


# ----------------------------------------------------------------- cache
def test_cache_second_build_is_read_from_disk(tmp_path, monkeypatch):
    calls = []
    original = fe.Body.stiffness
    monkeypatch.setattr(fe.Body, "stiffness", lambda self: calls.append(1) or original(self))
    loads = {"dead": fe.Traction("top", (0.0, -1.0))}
    make = lambda E: fe.FEModel(fe.rectangle(1, 1, 6, 6), fe.isotropic(E, 0.3),
                                dirichlet={"left": "xy"}, contact=["bottom"], loads=loads)
    cm1 = make(1.0).condense(mass=True, cache_dir=tmp_path)
    assert not cm1.from_cache and len(calls) == 1
    cm2 = make(1.0).condense(mass=True, cache_dir=tmp_path)
    assert cm2.from_cache and len(calls) == 1  # no assembly
    np.testing.assert_array_equal(cm1.K, cm2.K)
    np.testing.assert_array_equal(cm1.M, cm2.M)
    np.testing.assert_array_equal(cm1.welded["dead"][1], cm2.welded["dead"][1])
    np.testing.assert_array_equal(cm1.node_coordinates, cm2.node_coordinates)
    assert make(1.0).condense(cache_dir=tmp_path).from_cache  # mass not needed: still a hit
    cm3 = make(2.0).condense(cache_dir=tmp_path)  # another material: another key
    assert not cm3.from_cache and len(calls) == 2
    np.testing.assert_allclose(cm3.K, 2 * cm1.K, rtol=1e-12)
    # the cached model still recovers fields (assembling lazily)
    assert cm2.displacements(load="dead")[0].shape == (2 * 49,)
