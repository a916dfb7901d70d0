"""Kachanov's stiffness blocks against an independent method (issue 15).

The coupling block ``B`` (``q = ... + B w``: shear reaction of crack i from the opening of crack
j) of Kachanov's system is compared with the one read, by the documented layout of
``stiffness_raw`` (rows ``(P, Q)``, columns ``(opening, slip)`` interleaved per crack), from the
Galerkin BEM (crack_networks.bem: Chebyshev modes, Galerkin test functions, reciprocal), not
from the same formula.  On these sets ``B`` is far from symmetric, so the two blocks ``B`` and
``B^T`` are told apart: exchanging them moves Kachanov's ``B`` 120-150% away from the BEM,
while Kachanov's own approximation error is 8-20% (measured; line averages instead of the exact
traction profile, MODEL.md s.6).
"""

import numpy as np
import pytest

import crack_networks as cn


def bem_blocks(model):
    """(A, B, C) of a model's symmetrised raw stiffness, by the documented layout."""
    R = 0.5 * (model.stiffness_raw + model.stiffness_raw.T)
    return R[1::2, 1::2], R[1::2, 0::2], R[0::2, 0::2]


@pytest.mark.parametrize("seed", [0, 2])
def test_kachanov_blocks_match_the_bem_and_not_their_transposes(seed):
    cs = cn.sample_crack_set(4, density=0.15, half_length=(0.5, 1.5), rng=seed)
    km = cn.kachanov_model(cs)
    Ab, Bb, Cb = bem_blocks(cn.bem_model(cs, n_modes=16))
    s = km.system
    off = ~np.eye(4, dtype=bool)

    def err(X, ref):
        return np.linalg.norm((X - ref)[off]) / np.linalg.norm(ref[off])

    # measured 0.085 (seed 0) and 0.195 (seed 2) for B; 0.069, 0.067 for A; 0.070, 0.208 for C
    # (off-diagonal entries; the diagonal differs too, by the BEM's neighbour effect on close
    # pairs, up to 19% for A on seed 2, so it is not compared)
    assert err(s.B, Bb) < 0.25
    assert err(s.A, Ab) < 0.1 and err(s.C, Cb) < 0.25
    # premise: the transposed block is far off (measured 1.19, 1.51)
    assert err(s.B.T, Bb) > 1.0


def test_kachanov_system_blocks_follow_the_raw_layout_in_other_units():
    """Units: stiffness ~ mu (any unit), blocks scale with it, nothing else changes."""
    cs = cn.sample_crack_set(4, density=0.15, half_length=(0.5, 1.5), rng=0)
    for mu in (1e-6, 1.0, 7.3e10):
        km = cn.kachanov_model(cs, shear_modulus=mu)
        A, B, C = bem_blocks(km)
        # exact reads of the same (symmetrised) numbers
        np.testing.assert_array_equal(km.system.A, A)
        np.testing.assert_array_equal(km.system.B, B)
        np.testing.assert_array_equal(km.system.C, C)
        k1 = cn.kachanov_model(cs, shear_modulus=1.0)
        np.testing.assert_allclose(km.system.K, mu * k1.system.K, rtol=1e-13)
