"""Dense LP kernels (shakedown.dense_lp) against HiGHS, with their own optimality conditions.

Random LPs ``max e.x s.t. A x <= b`` with a bounded feasible region (a box is added), so every
LP has an optimum; answers agree with HiGHS to 1e-7 relative (HiGHS's feasibility tolerance)
and are certified by residuals <= dense_lp.CERT_TOL.
"""

from __future__ import annotations

import numpy as np
import pytest

from shakedown import dense_lp
from shakedown.bounds.lp import ReusableLP


def random_lp(n, m, seed):
    rng = np.random.default_rng(seed)
    A = np.vstack([rng.standard_normal((m, n)), np.eye(n), -np.eye(n)])
    b = np.r_[rng.random(m) + 0.1, np.full(2 * n, 5.0)]
    e = rng.standard_normal(n)
    return A, b, e


def highs_max(A, b, e, eq=()):
    lo = np.full(len(b), -np.inf)
    lo[list(eq)] = b[list(eq)]
    lp = ReusableLP(A, lo, b, np.full(A.shape[1], -np.inf), np.full(A.shape[1], np.inf), e)
    ans = lp.solve()
    return ans.objective if ans.status == "optimal" else np.nan


@pytest.mark.parametrize("seed", range(5))
def test_solve_max_matches_highs(seed):
    A, b, e = random_lp(8, 20, seed)
    ans, tab = dense_lp.solve_max(A, b, e)
    assert ans is not None and ans.status == "optimal"
    assert e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-7)
    res = dense_lp.kkt_residuals(A, b, e, ans.x, ans.y)
    # a vertex solved from an 8 x 8 basis: residuals ~1e-15; 1e-9 is well under CERT_TOL
    assert max(res) <= 1e-9
    assert np.all(ans.y >= -1e-12) and np.allclose(A.T @ ans.y, e, atol=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_batch_dual_simplex_equalities(seed):
    A, b, e = random_lp(6, 15, seed)
    ans, tab = dense_lp.solve_max(A, b, e)
    eqs = [(k,) for k in range(len(b))] + [(0, 1), (2, 5)]
    out = dense_lp.batch_dual_simplex(tab, eqs)
    for eq, a in zip(eqs, out, strict=True):
        ref = highs_max(A, b, e, eq)
        if np.isnan(ref):
            assert a.status == "infeasible"
            continue
        assert a.status == "optimal"
        assert e @ a.x == pytest.approx(ref, rel=1e-7, abs=1e-9)
        # own optimality conditions, equality rows two-sided
        res = dense_lp.kkt_residuals(A, b, e, a.x, a.y, equal=eq)
        assert max(res) <= 1e-8
        np.testing.assert_allclose(A[list(eq)] @ a.x, b[list(eq)], atol=1e-9)


def test_infeasible_equalities_detected():
    # x <= 1 and -x <= 0 (0 <= x <= 1); asking x = 1 and 1 - x... row 2: x <= 3 tight is
    # impossible together with x <= 1
    A = np.array([[1.0], [-1.0], [1.0]])
    b = np.array([1.0, 0.0, 3.0])
    ans, tab = dense_lp.solve_max(A, b, np.array([1.0]))
    assert ans.x[0] == pytest.approx(1.0)
    out = dense_lp.batch_dual_simplex(tab, [(2,), (1,)])
    assert out[0].status == "infeasible"
    assert out[1].status == "optimal" and out[1].x[0] == pytest.approx(0.0, abs=1e-12)


def test_unbounded_lp_returns_none():
    A = np.array([[-1.0]])
    ans, tab = dense_lp.solve_max(A, np.array([0.0]), np.array([1.0]))
    assert ans is None and tab is None


@pytest.mark.parametrize("n", [5, 40])
def test_degenerate_optimum_is_completed_not_abandoned(n):
    """Uncoupled lam2 LP: at the optimum one node's two parallel constraints meet and the optimal
    face has dimension N - 1, so far fewer than N + 1 rows are strongly active.  The interior
    point's basis must be completed (dual-feasible) instead of falling back to HiGHS."""
    import shakedown as sd
    from shakedown.bounds import extreme_constraints

    rng = np.random.default_rng(n)
    M = rng.standard_normal((n, n))
    system = sd.DiscreteSystem(M @ M.T + n * np.eye(n), np.zeros((n, n)), np.eye(n), 0.4)
    load = sd.LoadCycle.from_harmonics(0.1 * rng.standard_normal(n), 1 + rng.random(n),
                                       q_cos=rng.standard_normal(n))
    cs = extreme_constraints(system, load)
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, 0.0]
    e = np.r_[np.zeros(n), 1.0]
    ans, _ = dense_lp.solve_max(A, b, e)
    assert ans is not None and ans.status == "optimal"
    assert ans.x[-1] == pytest.approx(highs_max(A, b, e), rel=1e-7)
    # certificate: y >= 0 and A^T y = e (the interior point's accuracy, 1e-8 relative)
    assert np.all(ans.y >= 0) and np.allclose(A.T @ ans.y, e, atol=1e-7)
