"""Higher-fidelity Galerkin DD model (crack_networks.bem): convergence to exact solutions and
cross-method agreement with Kachanov's model.

Reference: exact two-collinear-crack mean opening from the Westergaard function with elliptic
integrals (:func:`collinear_exact_amplification`, checked independently in test_kachanov.py).
"""

import numpy as np
import pytest

import crack_networks as cn
import shakedown as sd
from crack_networks.bem import collinear_exact_amplification, galerkin_matrix
from shakedown.model.errors import InputError


def _collinear(gap, a=1.0):
    return cn.CrackSet([[-(a + gap / 2), 0.0], [a + gap / 2, 0.0]], [a, a], [0.0, 0.0])


def _amplification(model, stress=(0.0, 0.0, 1.0), k=0):
    return model.mean_discontinuities(stress)[:, k] / model.compliance


@pytest.mark.parametrize("gap", [2.0, 0.5, 0.05])
def test_bem_converges_to_exact_collinear_solution(gap):
    exact = collinear_exact_amplification(gap)
    errors = []
    for m in (2, 8, 32):
        model = cn.bem_model(_collinear(gap), n_modes=m)
        errors.append(np.abs(_amplification(model) / exact - 1).max())
    assert errors[0] > errors[1] > errors[2] or errors[1] < 1e-12
    # measured: 32 modes -> < 1e-10 at gap 2a and 0.5a, 2e-9 at 0.05a (rate ~ (1+sqrt(2g/a))^-m)
    assert errors[2] < 1e-8
    shear = cn.bem_model(_collinear(gap), n_modes=32)
    np.testing.assert_allclose(_amplification(shear, (0.0, 1.0, 0.0), k=1), exact, rtol=1e-8)


def test_bem_scale_invariance():
    # amplifications are dimensionless: the same for a set scaled by 7
    m1 = cn.bem_model(_collinear(0.3), n_modes=12)
    m2 = cn.bem_model(_collinear(2.1, a=7.0), n_modes=12)
    np.testing.assert_allclose(_amplification(m2), _amplification(m1), rtol=1e-10)


def test_one_mode_bem_is_elliptic_kachanov():
    cs = cn.sample_crack_set(15, density=0.15, half_length=(0.5, 1.5), rng=3)
    b = cn.bem_model(cs, n_modes=1)
    e = cn.kachanov_model(cs, weighting="elliptic")
    np.testing.assert_allclose(b.stiffness_raw, e.stiffness_raw, atol=1e-13)


def test_bem_stiffness_is_reciprocal_and_quadrature_converged():
    cs = cn.sample_crack_set(20, density=0.15, half_length=(0.5, 1.5), rng=4)
    m = cn.bem_model(cs, n_modes=12)
    # reciprocity of the Galerkin method: symmetric up to the quadrature error (< 1e-8)
    assert m.asymmetry.relative_norm < 1e-8
    m2 = cn.bem_model(cs, n_modes=12, quad_factor=2.0)
    assert np.abs(m2.stiffness_raw - m.stiffness_raw).max() < 1e-8 * m.self_stiffness


def test_galerkin_self_blocks():
    cs = cn.CrackSet([[0.0, 0.0], [5.0, 1.0]], [1.0, 0.5], [0.2, 1.0])
    H = galerkin_matrix(cs, 3).reshape(2, 3, 2, 2, 3, 2)
    np.testing.assert_array_equal(H[0, :, :, 0].reshape(6, 6), -np.eye(6))


def test_kachanov_against_bem_on_a_random_set():
    # cross-method agreement: the signs and sizes of the interaction (incl. the coupling B) and
    # the shakedown bounds; the numbers are recorded in benchmarks/RESULTS_kachanov.md
    cs = cn.sample_crack_set(30, density=0.1, rng=3)
    km = cn.kachanov_model(cs)
    bm = cn.bem_model(cs, n_modes=16)
    n = 30
    off = ~np.kron(np.eye(n), np.ones((2, 2))).astype(bool)
    Kk, Kb = km.stiffness, bm.stiffness
    rel = np.linalg.norm((Kk - Kb)[off]) / np.linalg.norm(Kb[off])
    assert rel < 0.25  # measured 0.13 (the close pairs dominate)
    _, Bk, _, _ = km.blocks()
    _, Bb, _, _ = bm.blocks()
    # off-diagonal entries above 5% of the largest agree in sign; the diagonal B_ii is zero in
    # Kachanov's model but not in the BEM (self-coupling through the neighbours), reported
    big = (np.abs(Bb) > 0.05 * np.abs(Bb).max()) & ~np.eye(n, dtype=bool)
    assert big.sum() > 10
    assert np.all(np.sign(Bk[big]) == np.sign(Bb[big]))
    np.testing.assert_array_equal(np.diag(Bk), 0.0)
    bk = sd.shakedown_bounds(km.system, km.load_cycle(), adjacency=False)
    bb = sd.shakedown_bounds(bm.system, bm.load_cycle(), adjacency=False)
    assert bk.lam1 <= bk.lam2 + 1e-7 and bb.lam1 <= bb.lam2 + 1e-7
    assert abs(bk.lam2 / bb.lam2 - 1) < 0.05  # measured 1e-3 on this set


def test_bem_bad_input():
    cs = cn.sample_crack_set(3, density=0.05, rng=0)
    with pytest.raises(InputError, match="n_modes must be an integer >= 1"):
        cn.bem_model(cs, n_modes=0)
    with pytest.raises(InputError, match="quad_factor must be a finite number > 0"):
        cn.bem_model(cs, quad_factor=-1.0)
    with pytest.raises(InputError, match="poisson_ratio"):
        cn.bem_model(cs, poisson_ratio=0.7)


def test_reference_csv_matches_the_models():
    # data/reference/two_collinear_cracks.csv (written by benchmarks/bench_kachanov.py
    # --write-reference): the exact values and the models' values must stay reproducible
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "data" / "reference" / "two_collinear_cracks.csv"
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=4)
    gaps = data[:, 0]
    np.testing.assert_allclose(collinear_exact_amplification(gaps), data[:, 1], rtol=1e-11)
    for g, kach in zip(gaps, data[:, 2], strict=True):
        amp = _amplification(cn.kachanov_model(_collinear(g)))[0]
        np.testing.assert_allclose(amp, kach, rtol=1e-11)
    np.testing.assert_allclose(data[:, 4], data[:, 1], rtol=1e-8)  # BEM 32 = exact
