"""The certified 3-D uniqueness bound on the friction coefficient (shakedown.model.critical3d).

What these tests prove: the factor ``2 sqrt(lambda_min(S) / lambda_max(F C F))`` computed from
*proven* eigenvalue bounds (an estimate proven by one Cholesky factorisation, no full
eigendecomposition) never exceeds the exact factor from a dense eigendecomposition and is
within 1e-8 of it, on the dense-estimate path and on the Lanczos path; a wrong estimate is
refused (no bound, factor 0) instead of giving a wrong one; a system whose ``S`` is not
positive definite gets no bound; and the factor does not depend on units.
"""

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st

import shakedown.model.critical3d as c3
from shakedown.model.critical3d import fcf_upper_eig, schur_lower_eig, sufficient_factor_3d


def random_k(n, seed, coupling=1.0):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    K[: 2 * n, 2 * n:] *= coupling
    K[2 * n:, : 2 * n] *= coupling
    f = 0.2 + 0.4 * rng.random((n, 2))
    return K[: 2 * n, : 2 * n], K[: 2 * n, 2 * n:], K[2 * n:, 2 * n:], f


def exact_factor(A, B, C, f):
    S = A - B @ np.linalg.solve(C, B.T)
    F = f.max(axis=1)
    s = np.linalg.eigvalsh(0.5 * (S + S.T))[0]
    c = np.linalg.eigvalsh(F[:, None] * C * F[None, :])[-1]
    return 2 * np.sqrt(s / c)


@pytest.mark.parametrize("n,lanczos", [(1, False), (5, False), (40, False), (40, True)])
def test_certified_factor_is_below_and_close_to_the_exact_one(n, lanczos, monkeypatch):
    if lanczos:  # the estimates by ARPACK (products with S^-1 and F C F) as for large N
        monkeypatch.setattr(c3, "DENSE_EIG_MAX", 10)
    A, B, C, f = random_k(n, n)
    got, exact, method = sufficient_factor_3d(A, B, C, f)
    ref = exact_factor(A, B, C, f)
    assert method == "sufficient-bound-3d" and not exact
    assert got <= ref and got >= ref * (1 - 1e-8)


def test_a_wrong_estimate_is_refused(monkeypatch):
    A, B, C, f = random_k(6, 1)
    F = f.max(axis=1)
    good = sufficient_factor_3d(A, B, C, f)[0]
    real = sla.eigvalsh

    def too_high(M, subset_by_index=None, **kw):  # every estimate 1 % off, the wrong way
        w = real(M, subset_by_index=subset_by_index, **kw)
        return w * (0.99 if subset_by_index and subset_by_index[0] > 0 else 1.01)

    monkeypatch.setattr(c3.sla, "eigvalsh", too_high)
    assert schur_lower_eig(A, B, C) == -np.inf  # lambda_min estimate too high: no proof
    assert fcf_upper_eig(C, F) == np.inf  # lambda_max estimate too low: no proof
    assert sufficient_factor_3d(A, B, C, f)[0] == 0.0 < good


def test_no_bound_when_the_slip_stiffness_is_not_positive_definite():
    A, B, C, f = random_k(4, 2)
    A = A - 1.01 * np.linalg.eigvalsh(A - B @ np.linalg.solve(C, B.T))[0] * np.eye(8)
    assert schur_lower_eig(A, B, C) < 0
    assert sufficient_factor_3d(A, B, C, f)[0] == 0.0


@settings(max_examples=8, deadline=None)
@given(stiff=st.floats(1e-6, 1e12))
def test_the_factor_does_not_depend_on_units(stiff):
    A, B, C, f = random_k(5, 3)
    ref = sufficient_factor_3d(A, B, C, f)[0]
    got = sufficient_factor_3d(stiff * A, stiff * B, stiff * C, f)[0]
    np.testing.assert_allclose(got, ref, rtol=1e-9)
    assert got <= exact_factor(A, B, C, f) * (1 + 1e-12)
