"""Half-space influence coefficients (issue 23): closed forms against brute force and the 2-D limit.

References: Boussinesq and Cerruti point loads (Johnson, *Contact Mechanics*, 1985, eqs. 3.19,
3.22); Dundurs' ``beta``; the plane-strain half-plane coefficients of
:mod:`shakedown.models.half_plane.influence` (a strip of 3-D cells loaded uniformly along ``y``
is a 2-D line load).  Tolerances are relative to each coefficient and justified where used.
"""

import numpy as np
import pytest
from scipy import integrate

from shakedown.models.half_plane.influence import cell_kernels as half_plane_kernels
from shakedown.models.half_space.influence import (
    _KERNEL,
    FAR,
    KERNELS,
    cell_kernel,
    dense_compliance,
    material_constants,
    offset_kernels,
)


def brute(name, dx, dy):
    """``int k(d + u) (1 - |u_x|)(1 - |u_y|) du`` by adaptive quadrature, split at the kinks."""
    k = _KERNEL[name]

    def f(uy, ux):
        return k(dx + ux, dy + uy) * (1 - abs(ux)) * (1 - abs(uy))

    tot = 0.0
    for ax in ((-1, 0), (0, 1)):
        for ay in ((-1, 0), (0, 1)):
            tot += integrate.dblquad(f, *ax, *ay, epsabs=1e-13, epsrel=1e-11)[0]
    return tot


@pytest.mark.parametrize("name", ["inv_r", "xx", "xy", "x_r2"])
@pytest.mark.parametrize("d", [(0, 0), (1, 0), (0, 1), (1, 1), (2, -1), (-3, 2), (5, 7)])
def test_closed_form_matches_brute_force(name, d):
    if d == (0, 0) and name in ("xy", "x_r2", "y_r2"):
        assert cell_kernel(name, 0, 0) == 0.0  # odd kernels vanish on their own cell
        return
    # dblquad reaches ~1e-13 absolute on these weakly singular integrands (measured)
    assert float(cell_kernel(name, *d)) == pytest.approx(brute(name, *d), rel=1e-11, abs=1e-12)


def test_swapped_kernels_are_transposes():
    d = np.arange(-FAR - 2, FAR + 3, dtype=float)
    dx, dy = np.meshgrid(d, d, indexing="ij")
    # the same terms summed in another order: equal to the closed form's cancellation error,
    # ~eps d^4 (d < FAR cells) against the largest coefficient (~3): measured 1.1e-13
    for a, b in (("yy", "xx"), ("y_r2", "x_r2")):
        np.testing.assert_allclose(cell_kernel(a, dx, dy), cell_kernel(b, dy, dx), rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["inv_r", "xx", "xy", "x_r2"])
def test_far_quadrature_continues_the_closed_form(name):
    # at FAR - 1 the closed form is used, at FAR the quadrature: both against brute force
    for d in [(FAR - 1, 3), (FAR, 3), (FAR + 5, -7)]:
        assert float(cell_kernel(name, *d)) == pytest.approx(brute(name, *d), rel=1e-10)


def test_point_load_far_field():
    # far from the cell the mean is the point-load value, error O((h/r)^2)
    for name in KERNELS:
        d = (40.0, 25.0)
        r = np.hypot(*d)
        assert float(cell_kernel(name, *d)) == pytest.approx(float(_KERNEL[name](*d)), rel=1 / r**2)


def test_strip_of_cells_is_the_half_plane_line_load():
    # a strip of cells along y, each carrying force h (unit force per unit length), is a 2-D line
    # load: the 3-D means summed along y converge to the plane-strain coefficients of the
    # half-plane model (differences in x for the log kernels; the tail beyond M cells is
    # O(x^2 / M^2) for 1/r and O(x / M) for x/r^2)
    mats = ((1.0, 0.3), (np.inf, 0.0))
    e_star, beta, b = material_constants(mats)
    M = 4000
    dy = np.arange(-M, M + 1, dtype=float)
    G, S = half_plane_kernels(8, 1.0)
    h = 1.0
    for di in (1, 2, 3):
        zz = [np.sum(cell_kernel("inv_r", d, dy)) / (np.pi * e_star) for d in (0, di)]
        xx = [np.sum(cell_kernel("inv_r", d, dy) / (np.pi * e_star)
                     + b / (2 * np.pi) * cell_kernel("xx", d, dy)) for d in (0, di)]
        ref_log = -(2 / (np.pi * e_star)) * (G[di, 0] - G[0, 0])
        assert (zz[1] - zz[0]) * h == pytest.approx(ref_log, rel=1e-5)
        assert (xx[1] - xx[0]) * h == pytest.approx(ref_log, rel=1e-5)
        zx = beta / (np.pi * e_star) * np.sum(cell_kernel("x_r2", di, dy))
        assert zx * h == pytest.approx(beta / e_star * S[di, 0], rel=3 * di / M)


def test_dundurs_beta_and_material_constants():
    # rigid body 2: beta = (1 - 2 nu) / (2 (1 - nu)); similar materials: beta = 0
    for nu in (0.0, 0.25, 0.3, 0.49):
        e_star, beta, b = material_constants(((2.0, nu), (np.inf, 0.0)))
        assert beta == pytest.approx((1 - 2 * nu) / (2 * (1 - nu)))
        assert e_star == pytest.approx(2.0 / (1 - nu**2))
        assert b == pytest.approx(2 * nu * (1 + nu) / 2.0)
    assert material_constants(((3.0, 0.2), (3.0, 0.2)))[1] == 0.0
    # textbook form: [G2 (k1 - 1) - G1 (k2 - 1)] / [G2 (k1 + 1) + G1 (k2 + 1)], k = 3 - 4 nu
    E1, n1, E2, n2 = 1.0, 0.3, 3.0, 0.1
    G1, G2, k1, k2 = E1 / (2 + 2 * n1), E2 / (2 + 2 * n2), 3 - 4 * n1, 3 - 4 * n2
    beta = (G2 * (k1 - 1) - G1 * (k2 - 1)) / (G2 * (k1 + 1) + G1 * (k2 + 1))
    assert material_constants(((E1, n1), (E2, n2)))[1] == pytest.approx(beta)


@pytest.mark.parametrize("mats", [((1.0, 0.3), (1.0, 0.3)), ((1.0, 0.3), (np.inf, 0.0)),
                                  ((1.0, 0.0), (1.0, 0.0))])
def test_dense_compliance_symmetric_positive_definite(mats):
    n = 6
    F = dense_compliance(offset_kernels(n, 0.1, *material_constants(mats)), n)
    assert np.array_equal(F, F.T)
    ev = np.linalg.eigvalsh(F)
    assert ev[0] > 1e-3 * ev[-1]  # well conditioned at this size (measured ~0.04)
    coupled = np.any(F[2 * n * n:, : 2 * n * n])
    assert coupled == (material_constants(mats)[1] != 0)
