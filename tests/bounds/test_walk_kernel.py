"""The compiled pivots of the barycentric walk (:mod:`shakedown.bounds.walk_kernel`).

Two walks from the same vertex, one in NumPy and one compiled, are sent to the same targets:
they must answer the same, take the same number of pivots, stand at the same vertex and cover
the same rows, also with the working inverse recomputed every few pivots and vertices checked
two at a time (the kernel's hand-backs to Python), and under a pivot cap.  A corrupted frame
must not get a row covered; the pruning with the kernel gives the ``lam1`` of NumPy.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from test_barycentric_walk import _face_nonempty, _problem, _vertex
from test_pruning import _unscreened_network

import shakedown as sd
from shakedown.bounds import barycentric_walk as bwm
from shakedown.bounds import basis_lp, walk_kernel
from shakedown.bounds import inverse_updates as iu
from shakedown.bounds.barycentric_walk import UNCHECKED, BarycentricWalk, SimplexFrame

pytestmark = pytest.mark.skipif(not walk_kernel.HAVE_KERNEL, reason="numba not available")


def _pair(f, t, T):
    return BarycentricWalk(f, t, T), BarycentricWalk(f, t, T)


def _step(monkeypatch, walks, k, cap):
    out = []
    for w, kmin in zip(walks, (10**9, 0), strict=True):
        monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", kmin)
        out.append(w.walk_to(k, cap))
    return out


def _judged(w, k, out, G, b):
    """``out`` of ``w.walk_to(k, ...)``, a row left unchecked checked now; a decision
    (``True``: face non-empty, ``False``: empty) must be the truth (HiGHS)."""
    if out is UNCHECKED:
        assert w.flush()
        out = bool(w.covered[k])
    if out is True or out is False:
        assert out is _face_nonempty(G, b, int(k))
    return out


def _same_state(a, b):
    assert a.pivots == b.pivots and a.broken == b.broken
    assert a.P == b.P and a.Tl == b.Tl
    np.testing.assert_allclose(b.sP, a.sP, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b.sJ, a.sJ, rtol=1e-9, atol=1e-11)
    assert np.array_equal(a.covered, b.covered) and np.array_equal(a.unchecked, b.unchecked)


@pytest.mark.parametrize("n,seed,frac,cap", [(30, 1, 0.9, 500), (30, 2, 0.99, 500),
                                             (60, 3, 0.95, 500), (60, 3, 0.95, 3)])
@pytest.mark.parametrize("hand_backs", [False, True])
def test_the_kernel_walks_as_numpy(n, seed, frac, cap, hand_backs, monkeypatch):
    if hand_backs:  # recomputations every 3 pivots, vertices checked 2 at a time
        monkeypatch.setattr(iu, "REFACTOR", 3)
        monkeypatch.setattr(iu, "REFACTOR_DIV", 1)
        monkeypatch.setattr(bwm, "CHECK_BATCH", 2)
    G, c, m, B, x2, lam2 = _problem(n, seed)
    t = frac * lam2
    T = _vertex(G, c + t * m, seed)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    walks = _pair(f, t, T)
    assert all(w.ok for w in walks)
    counts = {id(w): 0 for w in walks}
    orig = BarycentricWalk._refactor

    def refactor(self):
        counts[id(self)] = counts.get(id(self), 0) + 1
        return orig(self)

    monkeypatch.setattr(BarycentricWalk, "_refactor", refactor)
    seen = set()
    for k in f.J:
        res = _step(monkeypatch, walks, int(k), cap)
        assert res[0] == res[1] or (res[0] is res[1])
        seen.add(res[0] if res[0] is not UNCHECKED else "unchecked")
        _same_state(*walks)
        assert counts[id(walks[0])] == counts[id(walks[1])]  # the kernel hands back as due
        if res[0] is UNCHECKED:
            assert walks[0].flush() == walks[1].flush()
        if res[0] is False or walks[0].broken:
            walks = _pair(f, t, walks[0].T)  # on from the same vertex, as the pruning does
            counts.update({id(w): 0 for w in walks})
    assert walks[1].pivots or len(seen) > 1
    assert {True, False} & seen or cap < 10


def test_degenerate_walks_decide_rightly(monkeypatch):
    """Every row twice (each tight with its twin: ties in every ratio test, where the kernel's
    sums, in another order than NumPy's, may break them otherwise): every decision of the
    compiled walk is the truth (HiGHS, per row)."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    G, c, m, B, x2, lam2 = _problem(20, 2)
    R = len(c)
    G, c, m = np.vstack([G, G]), np.r_[c, c], np.r_[m, m]
    t = 0.95 * lam2
    b = c + t * m
    res = linprog(np.random.default_rng(2).standard_normal(G.shape[1]), A_ub=G, b_ub=b,
                  bounds=(None, None), method="highs-ds")
    T = np.flatnonzero(np.abs(b - G @ res.x)[:R] <= 1e-9)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    w = BarycentricWalk(f, t, T)
    assert w.ok
    decided = 0
    for k in f.J:
        out = _judged(w, k, w.walk_to(int(k), 500), G, b)
        decided += out is True or out is False
        if out is False or w.broken:
            w = BarycentricWalk(f, t, w.T)
            assert w.ok
    assert decided >= len(f.J) // 2
    for j in np.flatnonzero(w.covered):
        assert _face_nonempty(G, b, j)


def test_a_corrupted_frame_covers_nothing_false(monkeypatch):
    """A row of the frame negated: the compiled walk may believe it tight, the check in ``v``
    never covers it (as ``test_wrong_barycentric_data_is_never_certified`` in NumPy)."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    G, c, m, B, x2, lam2 = _problem(30, 2)
    t = 0.99 * lam2
    b = c + t * m
    T = _vertex(G, b, 2)
    bad = SimplexFrame.of(G, c, m, B, x2, lam2)
    w = BarycentricWalk(bad, t, T)
    assert w.ok
    empty = [int(k) for k in bad.J if not _face_nonempty(G, b, k)]
    assert empty
    moved = 0
    for k in empty:
        bad.K[bad.loc[k]] = -bad.K[bad.loc[k]]
        bad.KF = np.asfortranarray(bad.K)
        p0 = w.pivots
        assert w.walk_to(k, 500) is not True
        moved += w.pivots > p0
        w.flush()
        assert not w.covered[k]
    assert moved
    for j in np.flatnonzero(w.covered):
        assert _face_nonempty(G, b, j)


def test_the_pruning_with_the_kernels_gives_numpys_lam1(monkeypatch):
    model, load = _unscreened_network(monkeypatch)
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 10**9)
    ref = sd.shakedown_bounds(model.system, load)
    pivots = []
    orig = walk_kernel.pivots

    def spy(*args):
        st = args[-2]
        before = int(st[1])
        code = orig(*args)
        pivots.append(int(st[1]) - before)
        return code

    monkeypatch.setattr(walk_kernel, "pivots", spy)
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    got = sd.shakedown_bounds(model.system, load)
    assert sum(pivots) > 0  # the kernel walked
    assert got.lam1 == pytest.approx(ref.lam1, rel=1e-12)
    assert got.limiting_constraint == ref.limiting_constraint
    np.testing.assert_allclose(got.lam_high, ref.lam_high, rtol=1e-10)


def test_single_precision_pricing_only_chooses(monkeypatch):
    """The walk's pricing pass over ``K_T`` in single precision only picks the entering
    coordinate: with that copy useless (noise at every call) the reduced cost of the one it
    picks is recomputed in double and the pricing redone in double when it does not improve.
    So every pivot (one per call here) still moves along an edge on which the target's
    objective does not decrease, and every decision is the truth."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    G, c, m, B, x2, lam2 = _problem(40, 5)
    f = SimplexFrame.of(G, c, m, B, x2, lam2)
    t = 0.95 * lam2
    b = c + t * m
    w = BarycentricWalk(f, t, _vertex(G, b, 5))
    assert w.ok
    orig = walk_kernel.pivots
    calls = []
    rng = np.random.default_rng(0)

    def useless(*args):
        args[14][:] = 1e3 * rng.standard_normal(args[14].shape)  # KT32: noise
        calls.append(1)
        return orig(*args)

    monkeypatch.setattr(walk_kernel, "pivots", useless)
    decided = moves = 0
    for k in f.J[:60]:
        g = f.K[f.loc[k]]
        for _ in range(400):
            before = float(g[w.P] @ w.sP)
            out = w.walk_to(int(k), 0)  # one pivot
            if w.broken:
                break
            moves += 1
            assert float(g[w.P] @ w.sP) >= before - 1e-9 * (1.0 + abs(before)), k
            out = _judged(w, k, out, G, b)
            if out is True or out is False:
                decided += 1
                break
        if out is False or w.broken:
            w = BarycentricWalk(f, t, w.T)
            assert w.ok
    assert calls and moves and decided >= 30
