"""Matrix-free Melan ``lam2`` of a fretting load (similar materials) against the dense cone engine.

The dense side builds the system of the contact cells from the dense cell compliance (its own
reduction and inversion), the welded loads by dense solves, and asks
:func:`shakedown.shakedown_bounds` (the 3-D cone engine, cutting planes with a certified bracket);
the matrix-free side uses FFT products, CG and the per-node enclosing circle only.
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.models.half_space.bounds import bonded_tractions, contact_system_dense, fretting_lam2
from shakedown.models.half_space.normal import normal_contact

E, R, P, F = 1.0, 1.0, 1e-3, 0.5


def _model(n, nu=0.3):
    a = float(cont.hertz_radius(P, R, E / (2 * (1 - nu**2))))
    return sd.half_space_model(radius=R, n_cells=n, width=2.4 * a, friction=F,
                               materials=((E, nu), (E, nu)))


@pytest.mark.parametrize("Qy", [0.0, 0.5])  # oscillating, elliptical
def test_lam2_matches_the_dense_cone_engine(Qy):
    m = _model(9)
    Qx, Qy = 0.3 * F * P, Qy * 0.3 * F * P
    mf = fretting_lam2(m, P, Qx, Qy)
    system, welded, nodes = contact_system_dense(m, mf.contact)
    q0, p0 = welded(0.0, 0.0, P)
    ux = welded(1.0, 0.0, P)[0] - q0
    uy = welded(0.0, 1.0, P)[0] - q0
    # the welded pressure of the contact cells is the frictionless contact pressure
    np.testing.assert_allclose(p0, mf.p[nodes], rtol=0, atol=1e-9 * P)
    np.testing.assert_allclose(ux, mf.U[nodes], rtol=0, atol=1e-9)
    load = sd.LoadCycle.from_harmonics(q0, p0, q_cos=Qx * ux, q_sin=Qy * uy)
    dense = sd.shakedown_bounds(system, load, only=["lam2"])
    assert dense.lam2_lower <= mf.lam2 * (1 + 1e-9) and mf.lam2 <= dense.lam2_upper * (1 + 1e-9)
    assert mf.lam2 == pytest.approx(dense.lam2, rel=1e-5)
    assert mf.residual < 1e-9


def test_lam2_is_set_by_the_contact_edge():
    # continuum: the bonded shear is singular at the contact edge where p -> 0 (every oscillating
    # Q dissipates); the discrete lam2 is set by the edge cells, far below gross slip (f P / Q*),
    # and jumps as the edge crosses cells (measured 0.43, 0.057, 0.12 at n = 9, 17, 33)
    gross = F * P / (0.3 * F * P)
    for n in (9, 17):
        r = fretting_lam2(_model(n), P, 0.3 * F * P)
        assert 0 < r.lam2 < 0.2 * gross
        i = r.critical_cell
        assert r.p[i] < 0.5 * r.p.max()  # an edge cell, not the centre


def test_bonded_tractions_are_a_rigid_shift_and_carry_the_resultant():
    m = _model(11)
    contact = normal_contact(m, P).p > 0
    U, V, _, res = bonded_tractions(m, contact)
    assert res < 1e-9
    np.testing.assert_allclose(U.sum(axis=0), [1, 0], atol=1e-12)
    np.testing.assert_allclose(V.sum(axis=0), [0, 1], atol=1e-12)
    assert np.all(U[~contact] == 0)
    # symmetry: U_x even in x and y, U_y odd in both
    Ux = U[:, 0].reshape(11, 11)
    np.testing.assert_allclose(Ux, Ux[::-1, :], atol=1e-12 * Ux.max())


def test_refuses_coupled_materials_and_no_load():
    m = sd.half_space_model(radius=R, n_cells=5, width=0.3, materials=((E, 0.3), (np.inf, 0.0)))
    with pytest.raises(sd.InputError, match="beta"):
        fretting_lam2(m, P, 0.1 * P)
    with pytest.raises(sd.InputError, match="Qx"):
        fretting_lam2(_model(5), P, 0.0, 0.0)
