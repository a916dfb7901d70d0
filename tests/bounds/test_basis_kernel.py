"""The compiled pivots of the exact ``lam_high`` LPs (:mod:`shakedown.bounds.basis_kernel`).

The kernel must take the pivots of the NumPy dual simplex (:meth:`.BasisLP._steps`) it replaces
on large problems: the same number of pivots, the same optimal basis and the same optimum to
round-off, on every row of random systems, a degenerate one (every row twice) and a crack
network; also with the working inverse recomputed every few pivots (the hand-back to Python),
under a pivot cap (the dual bound of the screen), with wrong costs finished by the primal
simplex, in a race, and for the no-separation LP (rows violated at the start).  The answers are
certified as before; a corrupted kernel state must give an answer the certificate refuses.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_basis_lp import _tensile_problem
from test_basis_lp_race import _frame as race_frame

import shakedown as sd
from shakedown.bounds import basis_kernel, basis_lp
from shakedown.bounds import inverse_updates as iu
from shakedown.bounds.basis_lp import BasisLP

pytestmark = pytest.mark.skipif(not basis_kernel.HAVE_KERNEL, reason="numba not available")


def _frame(case):
    return race_frame(case, crack_seed=3)


def _both(monkeypatch, lp, k, **kw):
    """The answer of row ``k`` in NumPy and compiled."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 10**9)
    ref = lp.solve(k, **kw)
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    return ref, lp.solve(k, **kw)


def _agree(ref, got):
    assert got.status == ref.status and got.iterations == ref.iterations
    if ref.status == "optimal":
        assert sorted(got.basis) == sorted(ref.basis)
        np.testing.assert_allclose(got.x, ref.x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(got.y, ref.y, rtol=1e-8, atol=1e-10)
        assert max(got.residuals) <= 1e-9
    elif ref.x is not None:  # a capped LP: its dual bound
        assert got.x[-1] == pytest.approx(ref.x[-1], rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("case", ["random40", "dup20", "kachanov150"])
def test_the_kernel_takes_the_pivots_of_numpy(case, monkeypatch):
    f, tab, _ = _frame(case)
    lp = BasisLP(f, tab)
    pivots = 0
    for k in f.J:
        ref, got = _both(monkeypatch, lp, int(k))
        _agree(ref, got)
        pivots += got.iterations
    assert pivots >= len(f.J) // 2  # real work (dup20: many rows tight at the start)
    assert lp.solve(int(f.B[0])) is None


def test_recomputed_inverses_and_caps(monkeypatch):
    """The inverse recomputed in Python every 3 pivots (the kernel hands back and resumes), and
    pivot caps (the screen's dual bounds)."""
    f, tab, _ = _frame("kachanov150")
    lp = BasisLP(f, tab)
    monkeypatch.setattr(iu, "REFACTOR", 3)
    monkeypatch.setattr(iu, "REFACTOR_DIV", 1)
    inverses = []
    orig = BasisLP._inverse
    gathers = []

    def inverse(self, P, T, KT=None):  # the basis gathered from the LP's K[T] rows is K's
        inverses.append(len(P))
        if KT is not None:
            gathers.append(np.array_equal(self._M(P, T, KT), self._M(P, T)))
        return orig(self, P, T, KT)

    monkeypatch.setattr(BasisLP, "_inverse", inverse)
    deep = 0
    for k in f.J[::3]:
        ref, got = _both(monkeypatch, lp, int(k))
        _agree(ref, got)
        deep += got.iterations > 6
        for cap in (1, 4):
            _agree(*_both(monkeypatch, lp, int(k), max_pivots=cap))
    assert deep
    # the kernel handed back for the recomputations: the same as NumPy's, more than the answer's
    counts = []
    for kmin in (10**9, 0):
        monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", kmin)
        inverses.clear()
        lp.solve(int(k))
        counts.append(list(inverses))
    assert counts[0] == counts[1] and len(counts[1]) > 2
    assert gathers and all(gathers)


def test_race_and_wrong_costs(monkeypatch):
    """A race in chunks of 7 pivots gives the kernel's answers of :meth:`solve`; wrong costs
    (clipped multipliers) end at the optimum of the true ones through the primal finish."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    f, tab, _ = _frame("kachanov150")
    lp = BasisLP(f, tab)
    rows = [int(k) for k in f.J[:30]]
    alone = {k: lp.solve(k) for k in rows}
    for k, a in lp.race(rows, chunk=7):
        _agree(alone[k], a)
    wrong = BasisLP(f, tab)
    wrong.cost = f.y * (1 + np.random.default_rng(0).random(len(f.y)))
    wrong.clipped = True
    finished = 0
    for k in rows:
        a = wrong.solve(k)
        assert a.status == "optimal" and a.x[-1] == pytest.approx(alone[k].x[-1], rel=1e-9)
        finished += a.iterations > alone[k].iterations
    assert finished


def test_no_separation_lp_in_the_kernel(monkeypatch):
    """Rows violated at the start and no row held tight (``k = None``): as in NumPy."""
    from shakedown.bounds import dense_path, no_separation

    system, load = _tensile_problem(20, 4)
    seen = []
    orig = no_separation.separation_lp

    def spy(frame, cs):
        out = orig(frame, cs)
        seen.append(out[0])
        return out

    monkeypatch.setattr(dense_path, "separation_lp", spy)
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 10**9)
    ref = sd.shakedown_bounds(system, load)
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    got = sd.shakedown_bounds(system, load)
    assert len(seen) == 2 and seen[1].status == "optimal"
    _agree(seen[0], seen[1])
    assert got.lam_separation == pytest.approx(ref.lam_separation, rel=1e-12)
    assert got.lam1 == pytest.approx(ref.lam1, rel=1e-12)


def test_a_corrupted_state_is_refused(monkeypatch):
    """A kernel that leaves a wrong row in its working basis (the first border's row index
    shifted) ends at a point the certificate refuses: status ``failed``, never ``optimal``."""
    monkeypatch.setattr(basis_lp, "KERNEL_MIN_N", 0)
    f, tab, _ = _frame("kachanov60")
    lp = BasisLP(f, tab)
    orig = basis_kernel.advance
    hit = []

    def corrupt(*args):
        code = orig(*args)
        st, T = args[-3], args[14]
        if st[0] >= 2 and not hit:
            T[0] = (T[0] + 1) % len(lp.rows)  # the tight row recorded is not the one pivoted
            hit.append(True)
        return code

    monkeypatch.setattr(basis_kernel, "advance", corrupt)
    refused = 0
    for k in f.J[:20]:
        hit.clear()
        a = lp.solve(int(k))
        if hit:
            refused += a.status != "optimal"
            assert a.status in ("optimal", "failed")
            if a.status == "optimal":  # only if the optimum does not depend on it: certified
                assert max(a.residuals) <= 1e-9
    assert refused


@pytest.mark.parametrize("case", ["random40", "kachanov150"])
def test_single_precision_slacks_only_choose(case, monkeypatch):
    """The kernel's pass over ``K_P`` in single precision only picks the leaving row: with that
    copy useless (zeroed at every call, so the pass sees ``star - m_J ys`` alone) each row's
    slack it takes is recomputed in double and the pass redone in double when that row is not
    infeasible, so every answer is still the optimum NumPy finds (same value and status)."""
    f, tab, _ = _frame(case)
    lp = BasisLP(f, tab)
    orig = basis_kernel.advance
    calls = []

    def useless(*args):
        args[17][:] = 0.0  # KP32
        calls.append(1)
        return orig(*args)

    monkeypatch.setattr(basis_kernel, "advance", useless)
    for k in f.J[:40]:
        ref, got = _both(monkeypatch, lp, int(k))
        assert got.status == ref.status
        if ref.status == "optimal":
            assert got.x[-1] == pytest.approx(ref.x[-1], rel=1e-12, abs=1e-14)
            assert max(got.residuals) <= 1e-9
    assert calls
