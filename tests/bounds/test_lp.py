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
    # certificate: y >= 0 (up to round-off of the basis solve: -5e-19 measured) and A^T y = e
    # (the interior point's accuracy, 1e-8 relative)
    assert np.all(ans.y >= -1e-14 * np.abs(ans.y).max()) and np.allclose(A.T @ ans.y, e, atol=1e-7)


def test_degenerate_vertex_basis_skips_dependent_rows():
    """More than ``n`` rows active at the optimum and the ``n`` with the largest ``z / s``
    linearly dependent (the 20-node tensile problem of ``test_basis_lp`` with numpy 2.4.6, OpenBLAS 0.3.31:
    rank 19 of 21): the crossover's basis is the first ``n`` independent rows in that order,
    not ``None`` (which sent the LP to HiGHS)."""
    from shakedown.bounds.ipm import identify_basis

    rng = np.random.default_rng(5)
    n = 6
    V = rng.standard_normal((n, n))
    A = np.vstack([V[:2], V[:2].sum(0), V[2:], rng.standard_normal((4, n))])  # row 2 = 0 + 1
    r = np.r_[9.0, 8.0, 7.0, 6.0, 5.0, 4.0, 3.0, 1e-12 * np.ones(4)]  # z / s, slacks 1
    T = identify_basis(A, r, np.ones(len(r)), n)
    assert T is not None and list(T) == [0, 1, 3, 4, 5, 6]
    assert np.linalg.matrix_rank(A[T]) == n
    # no n independent rows among all of them: None, never a singular basis
    assert identify_basis(np.vstack([V[:3], V[:3]]), np.ones(6), np.ones(6), n) is None
    # the end to end case: certified by the dense path, equal to HiGHS
    A2, b2, e2 = _tensile_lp()
    ans, _ = dense_lp.solve_max(A2, b2, e2)
    assert ans is not None and ans.status == "optimal" and max(ans.residuals) <= 1e-9
    assert ans.x[-1] == pytest.approx(highs_max(A2, b2, e2), rel=1e-9)


def _tensile_lp():
    from test_basis_lp import _tensile_problem

    from shakedown.bounds import extreme_constraints

    system, load = _tensile_problem(20, 4)
    cs = extreme_constraints(system, load)
    n = system.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    return A, np.r_[cs.c, 0.0], np.r_[np.zeros(n), 1.0]


# ---------------------------------------------------------------------- issue 13/14 regressions
def _default_scene_lp():
    """The lam2 LP of the default scene's first realisation (100 Kachanov cracks, seed 2024,
    ``SeedSequence(2024, spawn_key=(0, 0))`` as the sweep draws it): the LP on which the interior
    point stalled (dual residual 2e-5 after 400 iterations, every LP then sent to HiGHS)."""
    import crack_networks as cn
    import shakedown as sd

    ss = np.random.SeedSequence(2024, spawn_key=(0, 0))
    cracks = cn.sample_crack_set(100, rng=np.random.default_rng(ss), density=0.1,
                                 half_length=1.0, min_spacing=0.1)
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    return model.system, model.load_cycle(static=(-1, 0, -1), cyclic=(0, 1, 0)), sd


def test_interior_point_does_not_stall_on_the_default_scene(monkeypatch):
    """Its optimum is a non-degenerate vertex with one multiplier 2.2e-7 against 0.52: the normal
    matrix reaches condition 1e14 and the dual residual cannot go below ~1e-7 (ipm.py docstring).
    The interior point must hand a usable iterate to the crossover, and no LP may need HiGHS."""
    from shakedown.bounds import highs_path
    from shakedown.bounds.constraints import Scales
    from shakedown.bounds.ipm import ipm

    system, load, sd = _default_scene_lp()
    cs = sd.bounds.extreme_constraints(system, load)
    ch = Scales.of(cs).nondimensional(cs)
    n = cs.n_nodes
    A = np.vstack([np.hstack([ch.G, -ch.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[ch.c, 0.0]
    rn = np.linalg.norm(A, axis=1)
    x, s, z, status, it = ipm(A / rn[:, None], b / rn, np.r_[np.zeros(n), 1.0])
    assert status in ("converged", "approximate") and it <= 40
    calls = []
    real = highs_path.HighsModel.run
    monkeypatch.setattr(highs_path.HighsModel, "run",
                        lambda self, *a, **k: calls.append(a) or real(self, *a, **k))
    auto = sd.shakedown_bounds(system, load, separation=False)
    assert calls == []
    ref = sd.shakedown_bounds(system, load, separation=False, solver="highs")
    # both certified vertices: measured agreement 7e-14 (lam1) and 7e-15 (lam2)
    assert auto.lam1 == pytest.approx(ref.lam1, rel=1e-9)
    assert auto.lam2 == pytest.approx(ref.lam2, rel=1e-9)


def _kachanov_tableau(n_cracks=60, seed=5):
    """The lam2 tableau of a Kachanov network: its interval / adjacency LPs need tens of pivots
    each (more than the initial capacity 16 of the basis update and than REINVERT_EVERY)."""
    import crack_networks as cn
    from shakedown.bounds import extreme_constraints
    from shakedown.bounds.constraints import Scales

    cracks = cn.sample_crack_set(n_cracks, density=0.15, rng=seed)
    m = cn.kachanov_model(cracks, friction=0.6)
    cs = extreme_constraints(m.system, m.load_cycle((-1, 0, -1), (0, 1, 0)))
    cs = Scales.of(cs).nondimensional(cs)
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, 0.0]
    e = np.r_[np.zeros(n), 1.0]
    ans, tab = dense_lp.solve_max(A, b, e)
    return A, b, e, ans, tab


def test_basis_update_over_many_pivots_matches_highs():
    """Woodbury update with bordering, rank-one replacement, capacity growth and periodic
    reinversion: every answer certified and equal to HiGHS (1e-7: HiGHS's tolerance)."""
    from shakedown.bounds.dual_simplex import REINVERT_EVERY

    A, b, e, ans, tab = _kachanov_tableau()
    n = A.shape[1] - 1
    # "min lam" from a vertex of H(0): the adjacency LPs walk far (many pivots)
    T1 = tab.T0.copy()
    T1[int(np.argmax(np.abs(tab.W[:, 2 * n])))] = 2 * n
    start = dense_lp.batch_dual_simplex(dense_lp.Tableau(A, b, -e, T1), [()])[0]
    tab0 = dense_lp.Tableau(A, b, -e, start.basis)
    eqs = [(j, n + j) for j in range(0, n, 3)] + [(k,) for k in range(0, 2 * n, 7)]
    out = dense_lp.batch_dual_simplex(tab0, eqs, width=5)
    assert max(a.iterations for a in out) > 2 * max(16, REINVERT_EVERY)
    for eq, a in zip(eqs, out, strict=True):
        ref = highs_max(A, b, -e, eq)
        if np.isnan(ref):  # the row is never tight (never active)
            assert a.status == "infeasible"
            continue
        assert a.status == "optimal"
        assert -e @ a.x == pytest.approx(ref, rel=1e-7, abs=1e-9)
        assert max(dense_lp.kkt_residuals(A, b, -e, a.x, a.y, equal=eq)) <= 1e-9


def test_answers_are_reproducible_and_independent_of_the_pool_width():
    """Bit-identical answers run to run; the same answers whatever the number of LPs pivoting
    together (same pivots; x to rounding: the batched products may sum in another order, 1e-13
    measured)."""
    A, b, e, ans, tab = _kachanov_tableau(40, 2)
    eqs = [(k,) for k in range(A.shape[0] - 1)]
    many = dense_lp.batch_dual_simplex(tab, eqs, width=64)
    again = dense_lp.batch_dual_simplex(tab, eqs, width=64)
    one = dense_lp.batch_dual_simplex(tab, eqs, width=1)
    for a, c, d in zip(one, many, again, strict=True):
        np.testing.assert_array_equal(c.x, d.x)
        np.testing.assert_array_equal(c.basis, d.basis)
        assert a.status == c.status and a.iterations == c.iterations
        np.testing.assert_array_equal(a.basis, c.basis)
        np.testing.assert_allclose(a.x, c.x, rtol=1e-11, atol=1e-12)


def test_degenerate_lps_match_highs():
    """Duplicated rows, rows through the same vertex and parallel rows (ties in the ratio test
    and in pricing)."""
    rng = np.random.default_rng(3)
    A0, b0, e = random_lp(5, 12, 1)
    x0 = rng.standard_normal(5) * 0.1
    through = rng.standard_normal((6, 5))
    A = np.vstack([A0, A0[:4], through, 2.0 * A0[4:6]])
    b = np.r_[b0, b0[:4], through @ x0 + 0.0, 2.0 * b0[4:6]]
    b[len(b0) + 4 : len(b0) + 10] = through @ x0 + np.abs(through @ x0).max()  # all tied
    ans, tab = dense_lp.solve_max(A, b, e)
    assert ans is not None and e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-7)
    eqs = [(k,) for k in range(len(b))] + [(0, len(b0)), (1, 2, 3)]
    for eq, a in zip(eqs, dense_lp.batch_dual_simplex(tab, eqs), strict=True):
        ref = highs_max(A, b, e, eq)
        if np.isnan(ref):
            assert a.status in ("infeasible", "failed")
            continue
        if a.status == "failed":
            continue  # not certified: the engine hands it to HiGHS
        assert a.status == "optimal"
        assert e @ a.x == pytest.approx(ref, rel=1e-7, abs=1e-9)


# ---------------------------------------------------------------------- certificates object
def test_kkt_residuals_object_to_wrong_answers():
    A, b, e = random_lp(6, 15, 4)
    ans, _ = dense_lp.solve_max(A, b, e)
    x, y = ans.x, ans.y
    assert max(dense_lp.kkt_residuals(A, b, e, x, y)) <= 1e-12
    top = int(np.argmax(y))
    worse = [
        (x + 1e-3 * (A[top] / np.linalg.norm(A[top])), y, 0),  # infeasible point
        (x, np.where(np.arange(len(y)) == top, -y, y), 1),  # a negative multiplier
        (x, 1.001 * y, 2),  # A^T y != e
        (x - 1e-3 * A[top] / np.linalg.norm(A[top]), y, 3),  # y_top > 0 on a slack row
    ]
    for xx, yy, which in worse:
        res = dense_lp.kkt_residuals(A, b, e, xx, yy)
        assert res[which] > 1e3 * dense_lp.CERT_TOL, which


def test_a_wrong_tableau_is_never_certified():
    """A corrupted tableau W makes the dual simplex pivot wrongly; its answers must either be
    right (and certified) or come back "failed" (then the engine asks HiGHS)."""
    A, b, e = random_lp(8, 20, 6)
    ans, tab = dense_lp.solve_max(A, b, e)
    tab.W = tab.W + 1e-2 * np.random.default_rng(0).standard_normal(tab.W.shape)
    eqs = [(k,) for k in range(len(b))]
    out = dense_lp.batch_dual_simplex(tab, eqs)
    statuses = {a.status for a in out}
    assert "failed" in statuses
    for eq, a in zip(eqs, out, strict=True):
        if a.status == "optimal":
            assert e @ a.x == pytest.approx(highs_max(A, b, e, eq), rel=1e-7, abs=1e-9)


def test_answers_are_shared_only_when_the_basis_proves_them():
    """``dense_path._share``: an optimal basis of "row k tight" answers "row j tight" (j basic)
    only if every other basic multiplier is >= 0; a vertex at lam = 0 answers every "min lam"
    group of basic rows."""
    from shakedown.bounds.dense_path import _share

    groups = [(0,), (1,), (2,), (0, 2)]
    by_row = {0: [0, 3], 1: [1], 2: [2, 3]}
    basis = np.array([0, 1, 2])
    y = np.array([0.5, -0.2, 0.3, 0.0])  # row 1 (the equality of group 1) has y < 0
    ans = dense_lp.DenseAnswer("optimal", np.array([0.0, 0.7]), y, basis, 3, (0.0,) * 4)
    out, done = np.full(4, np.nan), np.zeros(4, bool)
    _share(ans, 1, groups, by_row, out, done, "max", lam_row=3)
    # y_1 < 0 forbids sharing with the groups that make row 1 an inequality (only group 1 itself)
    assert list(done) == [False, True, False, False]
    y2 = np.array([0.5, 0.2, 0.3, 0.0])
    ans2 = dense_lp.DenseAnswer("optimal", np.array([0.0, 0.7]), y2, basis, 3, (0.0,) * 4)
    _share(ans2, 1, groups, by_row, out, done, "max", lam_row=3)
    assert done.all() and np.all(out == 0.7)
    # lam = 0 at a vertex with the row lam >= 0 basic: every basic group has lam_low = 0
    ans3 = dense_lp.DenseAnswer("optimal", np.array([0.0, 0.0]), y, np.array([0, 2, 3]), 1,
                                (0.0,) * 4)
    out, done = np.full(4, np.nan), np.zeros(4, bool)
    _share(ans3, 0, groups, by_row, out, done, "min", lam_row=3)
    assert list(done) == [True, False, True, True] and np.all(out[done] == 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_vectorised_sharing_follows_the_same_rule(seed):
    """``_share`` on one-row groups (the interval LPs) uses an index array instead of a loop
    over the basis (``_by_row``'s ``"single"``): on random bases, multipliers (none, one or
    several negative), answered groups and ``min`` / ``max`` it decides exactly what the loop
    decides."""
    from shakedown.bounds.dense_path import _by_row, _share

    rng = np.random.default_rng(seed)
    R = 40
    for trial in range(60):
        rows = rng.choice(R - 1, size=rng.integers(1, R - 1), replace=False)
        groups = [(int(r),) for r in rows]
        fast = _by_row(groups, R)
        assert "single" in fast
        slow = {k: v for k, v in fast.items() if k != "single"}
        T = rng.choice(R, size=12, replace=False)
        if trial % 3 == 0:
            T[0] = R - 1  # the row lam >= 0 basic
        y = np.abs(rng.standard_normal(R))
        y[rng.choice(T, size=int(rng.integers(0, 3)), replace=False)] *= -1.0
        sense = "min" if trial % 2 else "max"
        lam = 0.0 if sense == "min" and trial % 3 == 0 else 0.4
        ans = dense_lp.DenseAnswer("optimal", np.array([0.1, lam]), y, T, 1, (0.0,) * 4)
        done0 = rng.random(len(groups)) < 0.3
        res = []
        for by_row in (fast, slow):
            out, done = np.full(len(groups), np.nan), done0.copy()
            _share(ans, 0, groups, by_row, out, done, sense, lam_row=R - 1)
            res.append((out, done))
        np.testing.assert_array_equal(res[0][1], res[1][1])
        np.testing.assert_array_equal(res[0][0], res[1][0])


def _independent_rows_one_by_one(A, order, n, rtol=1e-9, floor=0.0):
    """The row-by-row Gram-Schmidt that :func:`~shakedown.bounds.ipm._independent_rows` blocks."""
    Q, picked = np.empty((n, A.shape[1])), []
    for i in order:
        a = A[i]
        na = np.linalg.norm(a)
        if na == 0.0:
            continue
        r = a - (a @ Q[: len(picked)].T) @ Q[: len(picked)]
        r -= (r @ Q[: len(picked)].T) @ Q[: len(picked)]
        if np.linalg.norm(r) > rtol * max(na, floor):
            Q[len(picked)] = r / np.linalg.norm(r)
            picked.append(int(i))
            if len(picked) == n:
                return np.sort(picked)
    return None


@pytest.mark.parametrize("block", [1, 3, 7, 64])
@pytest.mark.parametrize("seed", range(4))
def test_blocked_independent_rows_pick_the_rows_of_the_row_by_row_rule(block, seed):
    """Issue 26: the blocked Gram-Schmidt picks the same rows as the row-by-row one, with
    dependent rows (sums of earlier rows, inside a block and across block boundaries), zero
    rows, duplicates and a rank below ``n``."""
    from shakedown.bounds.ipm import _independent_rows

    rng = np.random.default_rng(seed)
    n = 12
    V = rng.standard_normal((9, n))  # rank 9 < n from these alone
    rows = [V[0], V[1], V[0] + V[1], np.zeros(n), V[2], V[2], *V[3:],
            V[3] - 2 * V[5], rng.standard_normal(n), rng.standard_normal(n), V[1],
            rng.standard_normal(n), rng.standard_normal(n)]
    A = np.array(rows) * rng.uniform(0.5, 2.0, len(rows))[:, None]
    order = rng.permutation(len(A))
    for k in (n, n + 3):  # n reachable, then not: None
        want = _independent_rows_one_by_one(A, order, k)
        got = _independent_rows(A, order, k, block=block)
        if want is None:
            assert got is None
        else:
            assert got is not None and list(got) == list(want)
    assert np.linalg.matrix_rank(A[_independent_rows(A, order, n, block=block)]) == n


@pytest.mark.parametrize("n, m", [(5, 1), (40, 39), (120, 70)])
def test_null_space_equals_the_complete_qr(n, m):
    """The completion's null space from the Householder reflectors (``ormqr`` on ``[0; I]``)
    is the complete QR's last ``n - m`` columns: orthonormal, orthogonal to ``X``'s columns,
    with the same triangular diagonal (the rank test of :func:`complete_basis`)."""
    from shakedown.bounds.ipm import _null_space

    X = np.random.default_rng(n + m).standard_normal((n, m)) * 1e3
    Q, rd = _null_space(X)
    Qf, Rf = np.linalg.qr(X, mode="complete")
    assert Q.shape == (n, n - m)
    assert np.allclose(Q, Qf[:, m:], atol=1e-12, rtol=0)
    assert np.allclose(Q.T @ Q, np.eye(n - m), atol=1e-12, rtol=0)
    assert np.abs(X.T @ Q).max() <= 1e-12 * np.abs(X).max() * n
    assert np.allclose(rd, np.abs(np.diag(Rf)), rtol=1e-13, atol=0)


def test_complete_basis_refuses_dependent_strongly_active_rows():
    """The strongly active rows must be independent (their rank from the QR factor at hand,
    issue 26, formerly an SVD): three strongly active rows of rank 2 give no completion, three
    independent ones a non-singular basis that contains them."""
    from shakedown.bounds.ipm import complete_basis

    rng = np.random.default_rng(11)
    n = 6
    V = rng.standard_normal((n, n))
    rest = rng.standard_normal((8, n))
    r = np.r_[1e3, 1e3, 1e3, 1e-6 * rng.uniform(1, 2, 8)]  # z / s: 3 strongly active rows
    e = V[0] + V[1]
    A_dep = np.vstack([V[0], V[1], V[0] + V[1], rest])
    assert complete_basis(A_dep, r, np.ones(len(r)), e, n) is None
    A_ind = np.vstack([V[0], V[1], V[2], rest])
    T = complete_basis(A_ind, r, np.ones(len(r)), e, n)
    assert T is not None and {0, 1, 2} <= set(T.tolist())
    assert np.linalg.matrix_rank(A_ind[T]) == n


def test_tableau_builds_its_inverse_and_tableau_only_on_use():
    """Issue 26: a basis refused for its multipliers costs one LU factorisation, not the
    ``O(n^2 R)`` tableau; what is computed on use equals the direct formulas."""
    from shakedown.bounds.dual_simplex import Tableau

    rng = np.random.default_rng(3)
    R, n = 30, 8
    A, b, e = rng.standard_normal((R, n)), rng.uniform(1, 2, R), rng.standard_normal(n)
    tab = Tableau(A, b, e, np.arange(n))
    tab.dual_feasible  # noqa: B018 (the check a refused basis gets)
    assert not {"Binv", "W", "x0", "act0"} & set(vars(tab))
    As = A / np.linalg.norm(A, axis=1)[:, None]
    B = As[:n]
    np.testing.assert_allclose(tab.y0, np.linalg.solve(B.T, e), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tab.Binv, np.linalg.inv(B), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tab.W, np.linalg.solve(B.T, As.T), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tab.x0, np.linalg.solve(B, tab.b[:n]), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tab.act0, As @ tab.x0, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_centrality_correctors_reach_the_same_optimum(seed):
    """Gondzio's correctors (``ipm(..., correctors=2)``, the Chebyshev centre's setting, issue
    26) change the path, not the answer: the same optimum as plain Mehrotra, certified by the
    crossover, in no more iterations; ``solve_max`` uses none unless asked (the crossover of
    a corrected, stalled iterate failed on a 2000-node FE strip)."""
    from shakedown.bounds.ipm import ipm

    rng = np.random.default_rng(100 + seed)
    R, n = 160, 40
    A = rng.standard_normal((R, n))
    A /= np.linalg.norm(A, axis=1)[:, None]
    b = rng.uniform(0.5, 2.0, R)
    e = rng.standard_normal(n)
    plain = ipm(A, b, e)
    corr = ipm(A, b, e, correctors=2)
    assert plain[3] == corr[3] == "converged"
    assert corr[4] <= plain[4]
    np.testing.assert_allclose(corr[0], plain[0], atol=1e-6)
    ans, _ = dense_lp.solve_max(A, b, e, correctors=2)
    assert ans.status == "optimal" and e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-9)
