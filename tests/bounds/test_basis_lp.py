"""Exact ``lam_high`` by the dual simplex in the coordinates of the ``lam2`` basis (issue 14).

Checked against the dual simplex in ``v`` from the ``lam2`` basis (``single_dual_simplex``) and
HiGHS (``linprog``) row by row, on random systems and a crack network; every answer's KKT
residuals recomputed here from scratch; wrong data (a corrupted row of the coordinates, a pivot
cap) must give an answer that the checks reject or a ``failed`` status; and inside the pruning
it must be used and give the exact ``lam1``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from test_bounds import random_problem
from test_pruning import _unscreened_network, assert_fast_matches_full
from test_single_simplex import _kachanov, _lp

import shakedown as sd
from shakedown.bounds import pruning
from shakedown.bounds.barycentric_walk import SimplexFrame
from shakedown.bounds.basis_lp import BasisLP
from shakedown.bounds.certificates import CERT_TOL, kkt_residuals
from shakedown.bounds.facet_walk import certified_rows
from shakedown.bounds.single_simplex import single_dual_simplex


def _setup(system, load, dup=False):
    A, b, e, main, tab = _lp(system, load, dup=dup)
    n = len(e) - 1
    R = A.shape[0] - 1
    G, c, m = A[:R, :n], b[:R], -A[:R, n]
    gn = np.linalg.norm(G, axis=1)
    f = SimplexFrame.of(G / gn[:, None], c / gn, m / gn, main.basis, main.x[:n], main.x[-1])
    assert f is not None
    return f, tab, main


def _highs_lam_high(tab, k):
    n = tab.n - 1
    res = linprog(-tab.e, A_ub=tab.A, b_ub=tab.b, A_eq=tab.A[[k]], b_eq=tab.b[[k]],
                  bounds=[(None, None)] * (n + 1), method="highs")
    assert res.status == 0
    return -res.fun


@pytest.mark.parametrize("case", ["random12", "random40", "dup20", "kachanov60"])
def test_every_row_matches_the_lp_in_v_and_highs(case):
    """``dup20``: every row twice, so every vertex is degenerate and every ratio test ties (the
    copies of the lam2 basis rows are tight at ``sigma = 0``)."""
    if case.startswith("random"):
        system, load = random_problem(int(case[6:]), 1)
    elif case.startswith("dup"):
        system, load = random_problem(20, 2)
    else:
        system, load = _kachanov(60, 3)
    f, tab, main = _setup(system, load, dup=case.startswith("dup"))
    lp = BasisLP(f, tab)
    lam2 = main.x[-1]
    checked = 0
    for k in f.J:
        ans = lp.solve(int(k))
        assert ans.status == "optimal"
        ref = single_dual_simplex(tab, (int(k),))
        assert ref.status == "optimal"
        assert ans.x[-1] == pytest.approx(ref.x[-1], rel=1e-9, abs=1e-12)
        # its own certificate, recomputed: KKT of the LP in v, the point checked from scratch
        res = kkt_residuals(tab.A, tab.b, tab.e, ans.x, ans.y, equal=(int(k),),
                            rownorm=np.ones(tab.R))
        assert max(res) <= 1e-9 and max(ans.residuals) <= 1e-9
        tight = certified_rows(tab.A, tab.b, ans.x)
        assert tight is not None and tight[k] and tight[ans.basis].all()
        assert len(ans.basis) == tab.n and ans.x[-1] <= lam2 * (1 + 1e-12)
        if checked < 6:
            assert ans.x[-1] == pytest.approx(_highs_lam_high(tab, int(k)), rel=1e-7)
            checked += 1
    assert lp.solve(int(f.B[0])) is None  # a row of the lam2 basis: lam_high = lam2


def test_wrong_coordinates_give_an_answer_the_checks_reject():
    system, load = random_problem(30, 2)
    f, tab, main = _setup(system, load)
    good = BasisLP(f, tab)
    bad_f = SimplexFrame.of(f.G, f.c, f.m, f.B, f.x2, f.lam2)
    bad_f.K[:] *= 1.001  # every row of K slightly wrong
    bad_f.KF = np.asfortranarray(bad_f.K)
    bad = BasisLP(bad_f, tab)
    rejected = 0
    for k in f.J[:20]:
        a, g = bad.solve(int(k)), good.solve(int(k))
        assert max(g.residuals) <= 1e-9
        if a.status != "optimal":  # its own KKT check refused it
            rejected += 1
            continue
        # an answer called optimal passed its checks: then it must be right
        tight = certified_rows(tab.A, tab.b, a.x)
        assert max(a.residuals) <= CERT_TOL and tight is not None and tight[k]
        assert a.x[-1] == pytest.approx(g.x[-1], rel=1e-7)
    assert rejected


def test_pivot_cap_is_a_failure():
    system, load = _kachanov(60, 3)
    f, tab, main = _setup(system, load)
    lp = BasisLP(f, tab)
    k = max(f.J, key=lambda k: lp.solve(int(k)).iterations)
    full = lp.solve(int(k))
    assert full.iterations > 3
    capped = lp.solve(int(k), max_pivots=full.iterations - 1)
    assert capped.status == "failed" and capped.iterations == full.iterations - 1
    # a stopped dual simplex bounds lam_high from above (all multipliers > 0 here), falling
    assert capped.x[-1] >= full.x[-1] - 1e-12
    bounds = [lp.solve(int(k), max_pivots=p).x[-1] for p in (1, 2, 3)]
    assert bounds[0] >= bounds[1] >= bounds[2] >= full.x[-1] - 1e-12


def test_pruning_uses_it_and_falls_back_when_it_fails(monkeypatch):
    """The pruning's exact LPs go through it (counted) with the exact lam1; with every answer
    failing, the LPs in v take over and give the same lam1."""
    model, load = _unscreened_network(monkeypatch)
    calls = []
    orig = BasisLP.solve

    def solve(self, k, max_pivots=None):
        calls.append(k)
        return orig(self, k, max_pivots)

    monkeypatch.setattr(BasisLP, "solve", solve)
    fast, _ = assert_fast_matches_full(model.system, load)
    assert calls
    monkeypatch.setattr(BasisLP, "solve", lambda self, k, max_pivots=None:
                        orig(self, k, max_pivots=0))
    again = sd.shakedown_bounds(model.system, load)
    assert again.lam1 == pytest.approx(fast.lam1, rel=1e-12)
    monkeypatch.setattr(pruning._Pruner, "simplex", lambda self: None)
    plain = sd.shakedown_bounds(model.system, load)
    assert plain.lam1 == pytest.approx(fast.lam1, rel=1e-12)


def _tensile_problem(n, seed):
    """A coupled system whose first ``n // 10`` nodes are frictionless with a small mean
    normal load and a cyclic one: keeping them in compression limits ``lam`` below ``lam2``."""
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n)) / np.sqrt(2 * n)
    K = M @ M.T + np.eye(2 * n)
    f = np.full(n, 0.5)
    f[: max(1, n // 10)] = 0.0
    system = sd.DiscreteSystem(K[:n, :n], 0.5 * K[:n, n:], K[n:, n:], f)
    qc, qs = rng.standard_normal((1, n)), rng.standard_normal((1, n))
    qc[:, f == 0] = qs[:, f == 0] = 0.0
    p0 = 1 + rng.random(n)
    p0[f == 0] = 0.3
    pc = 0.3 * rng.standard_normal((1, n))
    pc[:, f == 0] = 1.0
    load = sd.LoadCycle.from_harmonics(0.1 * rng.standard_normal(n), p0, q_cos=qc, q_sin=qs,
                                       p_cos=pc)
    return system, load


@pytest.mark.parametrize("seed", [4, 9])
def test_no_separation_lp_matches_highs(seed, monkeypatch):
    """The no-separation LP by the dual simplex from the lam2 vertex (the separation rows
    violated there): certified, and the limit and the nodes are HiGHS's; when it fails, HiGHS
    answers instead (same result)."""
    from shakedown.bounds import dense_path, no_separation

    system, load = _tensile_problem(20, seed)
    seen = []
    orig = no_separation.separation_lp

    def spy(frame, cs):
        ans, tab = orig(frame, cs)
        seen.append(ans)
        return ans, tab

    monkeypatch.setattr(dense_path, "separation_lp", spy)
    fast = sd.shakedown_bounds(system, load)
    ref = sd.shakedown_bounds(system, load, solver="highs")
    assert seen and seen[0].status == "optimal" and max(seen[0].residuals) <= 1e-9
    res = kkt_residuals(*_sep_rows(seen[0], system, load), seen[0].x, seen[0].y)
    assert max(res) <= 1e-9
    assert fast.lam_separation < fast.lam2 * (1 - 1e-3)
    assert fast.lam_separation == pytest.approx(ref.lam_separation, rel=1e-8)
    assert fast.separation_nodes == ref.separation_nodes and fast.separation_nodes
    monkeypatch.setattr(BasisLP, "solve", lambda self, k, max_pivots=None:
                        orig_solve(self, k, max_pivots=1))
    again = sd.shakedown_bounds(system, load)
    assert again.lam_separation == pytest.approx(ref.lam_separation, rel=1e-8)
    assert again.separation_nodes == ref.separation_nodes


orig_solve = BasisLP.solve


def _sep_rows(ans, system, load):
    """The separation LP's rows (unit norm) rebuilt independently of the solver."""
    from shakedown.bounds.constraints import Scales

    cs = sd.bounds.extreme_constraints(system, load)
    cs = Scales.of(cs).nondimensional(cs)
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.hstack([cs.sep_G, -cs.sep_m[:, None]]),
                   np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, cs.sep_c, 0.0]
    nrm = np.linalg.norm(A, axis=1)
    return A / nrm[:, None], b / nrm, np.r_[np.zeros(n), 1.0]


@pytest.mark.parametrize("dup", [False, True])
def test_primal_finish_repairs_wrong_costs(dup):
    """The dual simplex run on wrong (non-negative) costs ends at a basis optimal for them; the
    primal simplex on the true costs must then reach the true optimum (the path taken when
    multipliers of a degenerate lam2 basis are clipped); also with every row twice."""
    system, load = random_problem(30, 3)
    f, tab, main = _setup(system, load, dup=dup)
    good = BasisLP(f, tab)
    wrong = BasisLP(f, tab)
    rng = np.random.default_rng(0)
    wrong.cost = f.y * (1 + rng.random(len(f.y)))  # wrong, but still >= 0
    wrong.clipped = True
    finished = 0
    for k in f.J[:25]:
        a, g = wrong.solve(int(k)), good.solve(int(k))
        assert a.status == "optimal" and max(a.residuals) <= 1e-9
        assert a.x[-1] == pytest.approx(g.x[-1], rel=1e-9)
        finished += a.iterations > g.iterations
    assert finished  # the finish did some pivots
