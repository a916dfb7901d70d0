"""The single-LP dual simplex with an explicit basis inverse (issue 14: long paths on large
crack networks) against the batched dual simplex, HiGHS and the exact intervals.

``single_dual_simplex`` must give the batched solver's answer (same pivoting rules, so the same
optimal value; the certificate is re-checked from scratch) on random systems, with every row
duplicated (ties in every ratio test), on Kachanov networks, and inside the pruning of ``lam1``
(``SINGLE_MIN_N`` patched to 0 so that small problems take this path).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_bounds import random_problem
from test_pruning import assert_fast_matches_full

import crack_networks as cn
import shakedown as sd
from shakedown.bounds import dense_lp, pruning, single_simplex
from shakedown.bounds.single_simplex import single_dual_simplex


def _lp(system, load, dup=False):
    from shakedown.bounds.constraints import Scales

    cs = sd.bounds.extreme_constraints(system, load)
    cs = Scales.of(cs).nondimensional(cs)
    n = cs.n_nodes
    G, c, m = cs.G, cs.c, cs.m
    A = np.vstack([np.hstack([G, -m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[c, 0.0]
    e = np.r_[np.zeros(n), 1.0]
    main, tab = dense_lp.solve_max(A, b, e)
    assert main is not None
    if dup:  # every row twice (the lam row last): the same optimal basis, now degenerate
        R = len(c)
        A = np.vstack([A[:R], A[:R], A[R:]])
        b = np.r_[b[:R], b[:R], b[R:]]
        T = np.where(main.basis == R, 2 * R, main.basis)
        tab = dense_lp.Tableau(A, b, e, T)
        assert not tab.singular and tab.dual_feasible
        main = dense_lp.batch_dual_simplex(tab, [()])[0]
        assert main.status == "optimal"
    return A, b, e, main, tab


def _kachanov(n, seed):
    cracks = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(seed))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    return model.system, model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))


@pytest.mark.parametrize("case", ["random30", "random60", "dup30", "kachanov60"])
def test_single_matches_batch_and_highs(case, monkeypatch):
    # refactorise often on the way (random systems: paths of 1-2 pivots; Kachanov: longer)
    every = 3 if case.startswith("kachanov") else 1
    monkeypatch.setattr(single_simplex, "REFACTOR_EVERY", every)
    if case == "kachanov60":
        system, load = _kachanov(60, 3)
    else:
        n = int(case.removeprefix("random").removeprefix("dup"))
        system, load = random_problem(n, 1, coupling=0.5)
    dup = case.startswith("dup")  # the batch may leave a tied LP uncertified ("failed")
    A, b, e, main, tab = _lp(system, load, dup=dup)
    R = A.shape[0] - 1
    rows = [k for k in range(R) if k not in set(main.basis.tolist())]
    ref = dense_lp.batch_dual_simplex(tab, [(k,) for k in rows])
    from scipy.optimize import linprog

    long_paths = 0
    for k, a in zip(rows, ref, strict=True):
        s = single_dual_simplex(tab, (k,))
        long_paths += s.iterations > every
        if a.status == "optimal" or not dup:
            assert s.status == a.status
        if s.status != "optimal":
            continue
        if a.status == "optimal":
            assert s.x[-1] == pytest.approx(a.x[-1], rel=1e-9, abs=1e-12)
        assert max(s.residuals) <= dense_lp.CERT_TOL
        # the certificate from scratch: feasible, row k tight, multipliers of the objective
        assert np.all(A @ s.x - b <= 1e-9 * (1 + np.abs(b)))
        assert abs(A[k] @ s.x - b[k]) <= 1e-9 * (1 + abs(b[k]))
        y = s.y
        assert np.all(np.delete(y, k) >= -1e-9 * np.abs(y).max())
        np.testing.assert_allclose(A.T @ y, e, atol=1e-8 * max(1.0, np.abs(y).max()))
        if k % 5 == 0 or a.status != "optimal":  # and HiGHS on the same LP
            res = linprog(-e, A_ub=np.delete(A, k, 0), b_ub=np.delete(b, k), A_eq=A[k:k + 1],
                          b_eq=b[k:k + 1], bounds=(None, None), method="highs")
            assert s.x[-1] == pytest.approx(-res.fun, rel=1e-7, abs=1e-9)
    assert long_paths


def test_single_reports_a_pivot_cap_as_failed():
    system, load = _kachanov(60, 3)
    A, b, e, main, tab = _lp(system, load)
    k = next(k for k in range(A.shape[0] - 1) if k not in set(main.basis.tolist()))
    full = single_dual_simplex(tab, (k,))
    assert full.status == "optimal" and full.iterations > 2
    capped = single_dual_simplex(tab, (k,), max_pivots=full.iterations - 1)
    assert capped.status == "failed" and capped.iterations == full.iterations - 1


@pytest.mark.parametrize("n,seed", [(120, 2), (80, 5)])
def test_pruning_through_the_single_path(n, seed, monkeypatch):
    """lam1 with every lone LP (start LP, a lone capped LP) solved by the single-LP path equals the
    exact intervals and HiGHS (the LPs in ``v``: without the coordinates of the lam2 basis)."""
    monkeypatch.setattr(pruning._Pruner, "simplex", lambda self: None)
    monkeypatch.setattr(pruning, "SINGLE_MIN_N", 0)
    monkeypatch.setattr(pruning, "SCREEN_ROWS", 0)  # (a screened LP may finish in the screen)
    monkeypatch.setattr(pruning, "UNSCREENED_LPS", 1)
    monkeypatch.setattr(single_simplex, "REFACTOR_EVERY", 16)
    calls = []
    orig = pruning.single_dual_simplex

    def spy(*a, **kw):
        calls.append(1)
        return orig(*a, **kw)

    monkeypatch.setattr(pruning, "single_dual_simplex", spy)
    system, load = _kachanov(n, seed)
    fast, _ = assert_fast_matches_full(system, load)
    assert calls
    h = sd.shakedown_bounds(system, load, solver="highs", separation=False)
    assert fast.lam1 == pytest.approx(h.lam1, rel=1e-6)


def test_clamped_finish_of_the_lam2_lp(monkeypatch):
    """The last resort of ``solve_max`` (a stalled interior point's basis with negative
    multipliers; N = 2000, seed 2 and, issue 26, rng=77 with multipliers down to -5.8e-4 of the
    largest): clamped multipliers, a single-LP dual simplex and a primal finish give the
    certified optimum (HiGHS agrees), however negative the multipliers (formerly those below
    -1e-4 of the largest were refused and the whole computation went to HiGHS)."""
    from scipy.optimize import linprog

    system, load = _kachanov(60, 3)
    A, b, e, main, tab = _lp(system, load)
    ref = linprog(-e, A_ub=A, b_ub=b, bounds=(None, None), method="highs")
    # a neighbouring basis: swap one basic row for a near-tight non-basic one
    slack = b - A @ main.x
    out = [k for k in np.argsort(slack) if k not in set(main.basis.tolist())]
    for j in out[:20]:
        T = main.basis.copy()
        T[int(np.argmin(main.y[T]))] = j
        t2 = dense_lp.Tableau(A, b, e, np.sort(T))
        if not t2.singular and t2.y0.min() < 0:
            break
    assert not t2.singular and t2.y0.min() < 0
    ymax = np.abs(t2.y0).max()
    for y0 in (t2.y0.copy(), np.minimum(t2.y0, -1e-2 * ymax)):  # slightly / clearly negative
        t2.y0 = y0
        ans, tab2 = dense_lp.finish_from(A, b, e, t2, 0)
        assert ans is not None and ans.x[-1] == pytest.approx(-ref.fun, rel=1e-9)
        assert max(ans.residuals) <= dense_lp.CERT_TOL and tab2.dual_feasible
    # and a tiny negative multiplier on the optimal basis itself: clamped, then certified
    t3 = dense_lp.Tableau(A, b, e, main.basis)
    t3.y0 = t3.y0.copy()
    t3.y0[np.argmin(t3.y0)] = -1e-7 * np.abs(t3.y0).max()
    assert not t3.dual_feasible
    ans, _ = dense_lp.finish_from(A, b, e, t3, 0)
    assert ans is not None and ans.status == "optimal"
    assert ans.x[-1] == pytest.approx(-ref.fun, rel=1e-9)
    assert max(ans.residuals) <= dense_lp.CERT_TOL
