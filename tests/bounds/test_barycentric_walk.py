"""Facet walks in barycentric coordinates of the ``lam2`` simplex (issue 14).

The walk works with an ``(m + 1)``-square basis (``m`` rows outside the ``lam2`` basis tight);
everything it reports is checked in ``v``.  These tests compare its decisions with independent
LPs (HiGHS via ``linprog``), check the simplex's vertices against direct solves, feed it wrong
data (its check must reject every point), and run the pruning with the hand-over to the walk in
``v`` forced (tight-row limit 1) against every interval computed exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from test_bounds import random_problem
from test_pruning import _unscreened_network, assert_fast_matches_full

import shakedown as sd
from shakedown.bounds import barycentric_walk as bwm
from shakedown.bounds import inverse_updates as iu
from shakedown.bounds import pruning
from shakedown.bounds.barycentric_walk import UNCHECKED, BarycentricWalk, SimplexFrame


def _problem(n, seed):
    """Unit-norm rows ``G v <= c + lam m``, the lam2 optimum and its basis (tight rows)."""
    system, load = random_problem(n, seed)
    cs = sd.bounds.extreme_constraints(system, load)
    nrm = np.linalg.norm(cs.G, axis=1)
    G, c, m = cs.G / nrm[:, None], cs.c / nrm, cs.m / nrm
    res = linprog(np.r_[np.zeros(n), -1.0], A_ub=np.hstack([G, -m[:, None]]), b_ub=c,
                  bounds=[(None, None)] * n + [(0, None)], method="highs-ds")
    x2, lam2 = res.x[:n], res.x[-1]
    s = c + lam2 * m - G @ x2
    B = np.argsort(np.abs(s))[: n + 1]
    assert np.abs(s[B]).max() <= 1e-9 and np.sort(np.abs(s))[n + 1] > 1e-7  # nondegenerate
    return G, c, m, B, x2, lam2


def _vertex(G, b, seed):
    """Rows defining a vertex of ``{G v <= b}`` (minimum of a random objective)."""
    n = G.shape[1]
    g = np.random.default_rng(seed).standard_normal(n)
    res = linprog(g, A_ub=G, b_ub=b, bounds=(None, None), method="highs-ds")
    T = np.flatnonzero(np.abs(b - G @ res.x) <= 1e-9 * (1 + np.abs(b)))
    assert len(T) == n
    return T


def _face_nonempty(G, b, k):
    res = linprog(-G[k], A_ub=G, b_ub=b, bounds=(None, None), method="highs")
    return bool(-res.fun >= b[k] - 1e-9 * (1 + abs(b[k])))


@pytest.mark.parametrize("n,seed", [(12, 0), (30, 1)])
def test_coordinates_are_the_slacks_of_the_basis_rows(n, seed):
    """``v = x* - E sigma``, ``lam = lam2 - y . sigma`` give the basis rows the slacks
    ``sigma``, and the other rows ``G_J v - b_J(lam) = K sigma - r(lam)``; ``y`` are the optimal
    multipliers (``y >= 0``, ``G_B^T y = 0``, ``-m_B . y = 1``); with ``y > 0`` the vertices
    ``sigma = (lam2 - t) e_a / y_a`` are those of the simplex of the basis rows at ``t``."""
    G, c, m, B, x2, lam2 = _problem(n, seed)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    assert f is not None
    assert f.y.min() >= -1e-12 and np.abs(G[B].T @ f.y).max() <= 1e-9
    assert -m[B] @ f.y == pytest.approx(1.0, rel=1e-9)
    rng = np.random.default_rng(seed)
    for _ in range(3):
        sig = rng.random(n + 1)
        v, lam = x2 - f.E @ sig, lam2 - f.y @ sig
        np.testing.assert_allclose(c[B] + lam * m[B] - G[B] @ v, sig, atol=1e-9)
        np.testing.assert_allclose(G[f.J] @ v - c[f.J] - lam * m[f.J], f.K @ sig - f.r(lam),
                                   atol=1e-9)
    t = 0.7 * lam2
    b = c + t * m
    for a in range(n + 1):
        v = x2 - f.E[:, a] * (lam2 - t) / f.y[a]
        rows = np.delete(B, a)
        np.testing.assert_allclose(v, np.linalg.solve(G[rows], b[rows]), atol=1e-9)


def test_frame_refuses_what_is_not_a_basis():
    n = 12
    G, c, m, B, x2, lam2 = _problem(n, 0)
    R = len(c)
    assert SimplexFrame.of(G, c, m, np.r_[B[:-1], R], x2, lam2) is None  # the lam >= 0 row
    assert SimplexFrame.of(G, c, m, B[:-1], x2, lam2) is None  # too few rows
    assert SimplexFrame.of(G, c, m, np.r_[B[:-1], B[0]], x2, lam2) is None  # a repeated row
    G2, c2, m2 = np.vstack([G, G[B[0]]]), np.r_[c, c[B[0]]], np.r_[m, m[B[0]]]
    assert SimplexFrame.of(G2, c2, m2, np.r_[B[:-1], R], x2, lam2) is None  # singular Q
    assert SimplexFrame.of(G2, c2, m2, B, x2, lam2) is not None


@pytest.mark.parametrize("n,seed,frac", [(12, 0, 0.5), (30, 1, 0.9), (30, 2, 0.99)])
def test_walk_decisions_match_independent_lps(n, seed, frac):
    """For every row: ``True`` only where the face is non-empty at ``t`` (and then the row is
    covered by a checked vertex), ``False`` only where it is empty (HiGHS, per row)."""
    G, c, m, B, x2, lam2 = _problem(n, seed)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = frac * lam2
    b = c + t * m
    w = BarycentricWalk(f, t, _vertex(G, b, seed))
    assert w.ok
    empty = 0
    for k in f.J:
        res = w.walk_to(int(k), 500)
        if res is UNCHECKED:  # tight at the current vertex, checked with the next batch
            assert w.unchecked[k] and not w.covered[k]
            assert w.flush()
            res = bool(w.covered[k])
        assert not w.broken
        truth = _face_nonempty(G, b, k)
        assert res is truth  # every row decided (short walks at this size), and rightly
        if res:
            assert w.covered[k]
        else:
            empty += 1
            w = BarycentricWalk(f, t, w.T)  # go on from the same vertex, as the pruning does
            assert w.ok
    assert empty or frac < 0.99  # near lam2 some faces are empty
    for k in np.flatnonzero(w.covered):
        assert _face_nonempty(G, b, k)
    # the vertex it reports in v is the one it walked to
    x = np.linalg.solve(G[w.T], b[w.T])
    assert np.max(G @ x - b) <= 1e-9
    np.testing.assert_allclose(w.s, b - G @ x, atol=1e-9)  # the slacks that rank targets


def test_wrong_barycentric_data_is_never_certified():
    """A corrupted frame maps vertices to wrong points: the check in ``v`` rejects the start;
    corrupted rows ``h`` let the walk believe a row is tight where it is not: never covered."""
    n, seed = 30, 2
    G, c, m, B, x2, lam2 = _problem(n, seed)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = 0.99 * lam2
    b = c + t * m
    T = _vertex(G, b, seed)
    good = BarycentricWalk(f, t, T)
    assert good.ok
    bad = SimplexFrame.of(G, c, m, B, x2, lam2)
    bad.ET = bad.ET * (1 + 1e-3)  # the map back to v
    assert not BarycentricWalk(bad, t, T).ok
    empty = [int(k) for k in f.J if not _face_nonempty(G, b, k)]
    assert empty
    bad = SimplexFrame.of(G, c, m, B, x2, lam2)
    w = BarycentricWalk(bad, t, T)
    assert w.ok
    for k in empty:
        kl = bad.loc[k]
        bad.K[kl] = -bad.K[kl]  # the walk now sees a wrong row k
        bad.KF = np.asfortranarray(bad.K)
        assert w.walk_to(k, 500) is not True
        w.flush()  # a vertex reached but not yet checked is checked now (issue 26)
        assert not w.covered[k]


def test_a_target_reached_counts_only_once_its_vertex_is_checked():
    """Issue 26: a walk that reaches its target returns :data:`UNCHECKED` and checks the vertex
    with the next batch.  A row scaled wrongly in the frame (the walk believes it tight where it
    is slack) is reached, but the check in ``v`` never covers it; the right rows are covered."""
    n, seed = 30, 2
    G, c, m, B, x2, lam2 = _problem(n, seed)
    t = 0.99 * lam2
    b = c + t * m
    T = _vertex(G, b, seed)
    empty = [int(k) for k in SimplexFrame.of(G, c, m, B, x2, lam2).J
             if not _face_nonempty(G, b, k)]
    assert len(empty) >= 3
    for k in empty[:3]:
        bad = SimplexFrame.of(G, c, m, B, x2, lam2)
        w = BarycentricWalk(bad, t, T)
        bad.K[bad.loc[k]] *= 10.0  # the walk's row k: tight 10x too early
        bad.KF = np.asfortranarray(bad.K)
        assert w.walk_to(k, 500) is UNCHECKED and w.unchecked[k]
        assert w.flush() and not w.unchecked.any()
        assert not w.covered[k]
        for j in np.flatnonzero(w.covered):
            assert _face_nonempty(G, b, j)


def test_pruning_hands_over_to_the_walk_in_v(monkeypatch):
    """Every barycentric walker breaks down at its fifth pivot (as at the tight-row limit): the
    pruning goes on in ``v`` from the same vertex, and the answers are those of every interval
    computed exactly."""
    model, load = _unscreened_network(monkeypatch)
    seen = []
    orig, pivot = BarycentricWalk.facet_walk, BarycentricWalk._pivot

    def facet_walk(self):
        seen.append(self.broken)
        return orig(self)

    def breaking_pivot(self, g, kl):
        return None if self.pivots >= 4 else pivot(self, g, kl)

    monkeypatch.setattr(BarycentricWalk, "facet_walk", facet_walk)
    monkeypatch.setattr(BarycentricWalk, "_pivot", breaking_pivot)
    assert_fast_matches_full(model.system, load)
    assert any(seen)


def test_pruning_uses_the_barycentric_walk_and_agrees(monkeypatch):
    """The default pruning on a network walks in barycentric coordinates (counted) and gives
    the exact answers; with the walk disabled (the walk in ``v`` only) the same ``lam1``."""
    model, load = _unscreened_network(monkeypatch)
    pivots = []
    orig = BarycentricWalk.walk_to

    def walk_to(self, k, cap):
        p0 = self.pivots
        out = orig(self, k, cap)
        pivots.append(self.pivots - p0)
        return out

    monkeypatch.setattr(BarycentricWalk, "walk_to", walk_to)
    assert_fast_matches_full(model.system, load)
    assert sum(pivots) > 0
    fast = sd.shakedown_bounds(model.system, load)
    monkeypatch.setattr(pruning._Pruner, "fast_walk", lambda self, t, T: None)
    slow = sd.shakedown_bounds(model.system, load)
    assert fast.lam1 == pytest.approx(slow.lam1, rel=1e-12)
    assert fast.limiting_constraint == slow.limiting_constraint


def test_working_inverse_recomputed_when_due(monkeypatch):
    """The explicit inverse of the working basis is recomputed from scratch when
    :func:`refactor_due` says (every ``REFACTOR`` pivots on small bases, ``m / REFACTOR_DIV``
    on large ones), and the one updated in between agrees with it."""
    assert not iu.refactor_due(49, 10) and iu.refactor_due(50, 10)
    assert not iu.refactor_due(399, 800) and iu.refactor_due(400, 800)
    monkeypatch.setattr(iu, "REFACTOR", 3)
    monkeypatch.setattr(iu, "REFACTOR_DIV", 4)  # (recomputations often enough to count here)
    G, c, m, B, x2, lam2 = _problem(30, 1)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = 0.9 * lam2
    seen = []
    orig = BarycentricWalk._refactor

    def refactor(self):
        if hasattr(self, "W"):  # the updated inverse against the fresh one
            due, old = (self.since, len(self.P)), self.W.copy()
            ok = orig(self)
            seen.append((due, float(np.abs(old - self.W).max() / np.abs(self.W).max())))
            return ok
        return orig(self)

    monkeypatch.setattr(BarycentricWalk, "_refactor", refactor)
    w = BarycentricWalk(f, t, _vertex(G, c + t * m, 1))
    assert w.ok
    for k in f.J:
        w.walk_to(int(k), 500)
    assert w.pivots >= 6 and len(seen) >= w.pivots // 8
    assert all(since == max(3, size // iu.REFACTOR_DIV) for (since, size), _ in seen)
    assert max(d for _, d in seen) <= 1e-9


def test_a_drifted_vertex_is_recomputed_before_the_walk_gives_up():
    """Issue 26: with the working inverse recomputed rarely (``m / 4`` updates at large ``m``)
    the updated vertex can drift off by more than the check's tolerance; the walk then
    recomputes its basis from scratch and checks the current vertex once more before it calls
    itself broken.  A vertex that is wrong for its basis is refused, not covered."""
    G, c, m, B, x2, lam2 = _problem(30, 1)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = 0.9 * lam2
    b = c + t * m
    w = BarycentricWalk(f, t, _vertex(G, b, 1))
    assert w.ok
    for k in f.J[:10]:
        w.walk_to(int(k), 500)
    w.flush()
    assert not w.broken and w.pivots >= 3 and w.since > 0
    exact = w.sP.copy()
    w.sP = w.sP * (1.0 + 1e-3)  # the drift of many updates, exaggerated
    w._buffer.append(w._vertex())
    assert w.flush() and not w.broken and w.since == 0
    np.testing.assert_allclose(w.sP, exact, rtol=1e-9, atol=1e-12)
    # a basis whose vertex is infeasible cannot be rescued: broken
    w.since = 1
    w.rJ = w.rJ - 1.0  # every row outside the lam2 basis moved in: the vertex violates them
    w._buffer.append(w._vertex() * 1.5)
    assert not w.flush() and w.broken


@pytest.mark.parametrize("kernel", [False, True])
def test_every_row_ever_tight_is_checked(kernel, monkeypatch):
    """Issue 26: a vertex is checked only before a pivot loosens a tight row not yet covered
    and where a walk ends, not after every pivot.  With the walk's record of covered rows wiped
    before each target (so that every row that loosens is one not yet covered), each row must
    be in the batch (or covered) when it loosens, every row tight at some vertex must end
    covered (no check fails here), and fewer vertices are checked than visited; the compiled
    walk covers the same rows as NumPy's."""
    from shakedown.bounds import basis_lp

    G, c, m, B, x2, lam2 = _problem(60, 3)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = 0.95 * lam2
    b = c + t * m

    def run(compiled, spy=None, wipe=True):
        monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0 if compiled else 10**9)
        w = BarycentricWalk(f, t, _vertex(G, b, 3))
        assert w.ok
        w.seen = []  # the rows covered after each target
        for k in f.J:
            if wipe:
                w.covered[:] = False  # as if nothing had been checked yet
                w._held = False
            if spy is not None:
                spy["start"].update(f.J[w.Tl])
            w.walk_to(int(k), 500)
            assert not w.broken
            assert w.flush()
            w.seen.append(w.covered.copy())
            if spy is not None:
                assert w.covered[sorted(spy["start"])].all()
                spy["start"].clear()
        return w

    loosened, checked, tight = [], [], {"start": set()}
    orig_update, orig_check = BarycentricWalk._update, bwm.batch_check

    def update(self, kind, q, e, j, *args):
        if e < 0:  # tight row Tl[j] loosens: it must be checked or in the batch
            r = self.f.J[self.Tl[j]]
            loosened.append(bool(self.covered[r] or self.unchecked[r]))
        orig_update(self, kind, q, e, j, *args)
        tight["start"].update(f.J[self.Tl])  # every vertex visited: its tight rows

    def batch_check(G_, b_, X):
        checked.append(len(X))
        return orig_check(G_, b_, X)

    monkeypatch.setattr(BarycentricWalk, "_update", update)
    monkeypatch.setattr(bwm, "batch_check", batch_check)
    ref = run(False, spy=tight)
    assert len(loosened) >= 10 and all(loosened)
    checked.clear()
    plain = run(False, wipe=False)  # as the pruning walks: most vertices are not checked
    assert sum(checked) < plain.pivots // 2
    if kernel:
        got = run(True)
        assert got.pivots == ref.pivots
        assert all(np.array_equal(u, v) for u, v in zip(got.seen, ref.seen, strict=True))
