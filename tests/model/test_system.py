"""DiscreteSystem: validation messages, coupling, critical friction (MODEL.md s.1, s.4).

The critical friction is checked against an independent brute-force P-matrix test: every
principal minor of M_S(alpha) = [[C, B^T S], [alpha F C + S B, alpha F B^T S + S A S]] for every
sign matrix S (Klarbring 1990).  Tolerance 1e-6 on alpha: the factor is bracketed at
alpha_c (1 -+ 1e-3) and the minors there differ from 0 by far more than rounding.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import shakedown as sd


def spd(n, seed, coupling=0.5):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n))
    K = M @ M.T + 0.5 * np.eye(2 * n)
    return K[:n, :n], coupling * K[:n, n:], K[n:, n:]


def all_minors_positive(system, alpha):
    n = system.n_nodes
    A, B, C, F = system.A, system.B, system.C, np.diag(system.friction)
    for s in itertools.product((-1.0, 1.0), repeat=n):
        S = np.diag(s)
        M = np.block([[C, B.T @ S], [alpha * F @ C + S @ B, alpha * F @ B.T @ S + S @ A @ S]])
        for size in range(1, 2 * n + 1):
            for J in itertools.combinations(range(2 * n), size):
                if np.linalg.det(M[np.ix_(J, J)]) <= 0:
                    return False
    return True


def test_validation_messages():
    with pytest.raises(sd.ShapeError, match="A must be a square 2-D array"):
        sd.DiscreteSystem(np.ones((2, 3)), np.zeros((2, 2)), np.eye(2), 0.3)
    with pytest.raises(sd.ShapeError, match=r"B must have shape \(2, 2\) to match A"):
        sd.DiscreteSystem(np.eye(2), np.zeros((3, 3)), np.eye(2), 0.3)
    with pytest.raises(sd.InputError, match="C must be finite"):
        sd.DiscreteSystem(np.eye(2), np.zeros((2, 2)), [[1, 0], [0, np.nan]], 0.3)
    with pytest.raises(sd.NotSymmetricError, match="K must be symmetric"):
        sd.DiscreteSystem([[1.0, 0.5], [0.0, 1.0]], np.zeros((2, 2)), np.eye(2), 0.3)
    with pytest.raises(sd.NotPositiveDefiniteError, match="must be positive definite"):
        sd.DiscreteSystem(np.eye(2), 2 * np.eye(2), np.eye(2), 0.3)
    with pytest.raises(sd.InputError, match="friction must be >= 0; node 2"):
        sd.DiscreteSystem(np.eye(2), np.zeros((2, 2)), np.eye(2), [0.1, -0.2])
    with pytest.raises(sd.ShapeError, match=r"friction must be a scalar or have shape \(2,\)"):
        sd.DiscreteSystem(np.eye(2), np.zeros((2, 2)), np.eye(2), [0.1, 0.2, 0.3])
    with pytest.raises(sd.InputError, match="A must be a real 2-D array"):
        sd.DiscreteSystem(object(), np.zeros((2, 2)), np.eye(2), 0.3)


def test_is_coupled():
    A, B, C = spd(3, 0)
    assert sd.DiscreteSystem(A, B, C, 0.3).is_coupled
    assert not sd.DiscreteSystem(A, 0 * B, C, 0.3).is_coupled
    assert sd.DiscreteSystem(A, 0 * B, C, 0.3).critical_friction().factor == np.inf


def test_single_node_critical_friction():
    s = sd.DiscreteSystem([[2.0]], [[0.5]], [[3.0]], friction=0.4)
    cf = s.critical_friction()
    # closed form A / (|B| f): one division, exact to round-off
    assert cf.exact and cf.factor == pytest.approx(2.0 / 0.5 / 0.4, rel=1e-12)
    assert cf.value == pytest.approx(2.0 / 0.5, rel=1e-12)


@pytest.mark.parametrize("n,seed", [(2, 0), (2, 1), (2, 2), (3, 3)])
def test_enumeration_against_brute_force_p_matrix(n, seed):
    A, B, C = spd(n, seed, coupling=0.8)
    f = np.random.default_rng(seed).uniform(0.2, 1.0, n)
    system = sd.DiscreteSystem(A, B, C, f)
    cf = system.critical_friction()
    assert cf.exact and np.isfinite(cf.factor)
    assert all_minors_positive(system, cf.factor * (1 - 1e-3))
    assert not all_minors_positive(system, cf.factor * (1 + 1e-3))
    assert cf.factor <= cf.upper_bound * (1 + 1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_sufficient_bound_below_exact(seed):
    A, B, C = spd(3, seed + 10, coupling=0.8)
    system = sd.DiscreteSystem(A, B, C, 0.5)
    exact = system.critical_friction()
    bound = system.critical_friction(max_exact_nodes=0)
    assert not bound.exact and bound.method == "sufficient-bound"
    assert bound.factor <= exact.factor * (1 + 1e-12)
    # a sufficient bound: below it every M_S(alpha) is a P-matrix (brute force, independent)
    assert all_minors_positive(system, bound.factor * (1 - 1e-6))


@pytest.mark.parametrize("n,seed,units", [(3, 0, 1.0), (4, 1, 1e-6), (5, 2, 3.7e9)])
def test_sufficient_bound_closed_form_with_internode_coupling(n, seed, units):
    """A = a I, C = c I, B = b R with R a random orthogonal matrix (every node couples to every
    other).  The Schur complement is A - B C^-1 B^T = (a - b^2 / c) I and f C f = f^2 c I, so the
    sufficient bound of MODEL.md s.4 / the docstring is alpha_s = sqrt(a c - b^2) / (c f),
    below the necessary single-node bound min_j a / (|b R_jj| f) >= a / (b f).  (The issue-15
    audit: with A in place of the Schur complement the bound becomes sqrt(a / c) / f and
    `bound <= exact` alone did not notice.)  Units: K scaled by `units` leaves alpha unchanged."""
    a, b, c, f = 2.0, 1.3, 1.5, 0.4
    R, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((n, n)))
    system = sd.DiscreteSystem(units * a * np.eye(n), units * b * R, units * c * np.eye(n), f)
    bound = system.critical_friction(max_exact_nodes=0)
    assert bound.method == "sufficient-bound"
    # eigenvalues of well-conditioned 5x5 matrices: relative error ~1e-15; 1e-12 is generous
    assert bound.factor == pytest.approx(np.sqrt(a * c - b**2) / (c * f), rel=1e-12)
    assert bound.value == pytest.approx(np.sqrt(a * c - b**2) / c, rel=1e-12)
    if n <= 3:  # and it is a true lower bound of the exact factor (enumeration, N <= 3)
        assert bound.factor <= system.critical_friction().factor * (1 + 1e-12)
