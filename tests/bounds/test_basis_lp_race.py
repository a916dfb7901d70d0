"""Several exact "max lam" LPs side by side (:meth:`.BasisLP.race`, issue 26).

The race must give every row the answer :meth:`.BasisLP.solve` gives (pivot for pivot: the same
iterations and the same vectors, bit for bit), in any schedule; a row whose dual bound has
dropped below ``below`` must be finished before any other LP moves on; and a row below
``below`` placed last in the batch must be found after fewer pivots than by solving the rows one
after the other.  Inside the pruning (the capped batches go through it and lam1 stays exact):
``test_pruning.py::test_capped_batches_stopped_by_a_lower_incumbent``.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_basis_lp import _setup
from test_bounds import random_problem
from test_single_simplex import _kachanov

from shakedown.bounds.basis_lp import BasisLP
from shakedown.model.errors import InputError


def _frame(case, crack_seed=2):
    """The frame of a named test problem: ``randomN``, ``dup20`` (every row twice) or
    ``kachanovN`` (a network of ``N`` cracks drawn with ``crack_seed``)."""
    if case.startswith("random"):
        system, load = random_problem(int(case[6:]), 1)
    elif case.startswith("dup"):
        system, load = random_problem(20, 2)
    else:
        system, load = _kachanov(int(case[8:]), crack_seed)
    return _setup(system, load, dup=case.startswith("dup"))


def _same(a, b):
    """The same answer bit for bit; its residuals (the race certifies its answers together,
    :func:`~shakedown.bounds.certificates.batch_residuals`, in another order of the sums) to
    round-off of the residuals themselves."""
    if a is None or b is None:
        return a is None and b is None
    return (a.status == b.status and a.iterations == b.iterations
            and all(np.array_equal(u, v, equal_nan=True) for u, v in
                    ((a.x, b.x), (a.y, b.y), (a.basis, b.basis)))
            and np.allclose(a.residuals, b.residuals, rtol=0.0, atol=1e-14, equal_nan=True))


@pytest.mark.parametrize("case", ["random40", "dup20", "kachanov60"])
@pytest.mark.parametrize("chunk", [1, 7])
def test_race_gives_the_answers_of_solve(case, chunk):
    """Every row once, each with :meth:`solve`'s answer bit for bit, whether or not a bound
    below which LPs are finished first is given (``dup20``: every row twice, every vertex
    degenerate; rows of the lam2 basis give ``None`` as in :meth:`solve`)."""
    f, tab, main = _frame(case)
    lp = BasisLP(f, tab)
    rows = [int(k) for k in f.J[:24]] + [int(f.B[0])]
    alone = {k: lp.solve(k) for k in rows}
    lams = sorted(a.x[-1] for a in alone.values() if a is not None and a.status == "optimal")
    for below in (None, lams[len(lams) // 2]):
        seen = list(lp.race(rows, below=below, chunk=chunk))
        assert sorted(k for k, _ in seen) == sorted(rows)
        assert all(_same(a, alone[k]) for k, a in seen)
        assert dict(seen)[int(f.B[0])] is None


def _spy(monkeypatch):
    """Log of every pivot of every LP: ``(row, dual bound after it)`` (the NumPy pivots:
    these problems are below ``basis_lp.KERNEL_MIN_N``)."""
    log = []
    orig = BasisLP._steps

    def steps(self, k, *args, **kw):
        g = orig(self, k, *args, **kw)
        while True:
            try:
                bound, pivots = next(g)
            except StopIteration as done:
                return done.value
            log.append((k, bound))
            yield bound, pivots

    monkeypatch.setattr(BasisLP, "_steps", steps)
    return log


@pytest.mark.parametrize("n,seed,among", [(120, 2, 40), pytest.param(200, 3, 200, marks=pytest.mark.slow)])
def test_a_row_below_the_bound_is_found_first(n, seed, among, monkeypatch):
    """The 8 rows of least ``lam_high`` (among the first ``among`` rows outside the lam2 basis)
    of a crack network, the least last and ``below`` between it and the others: the race (turns
    of 5 pivots: these LPs are short) yields that row's answer as the first below ``below``;
    once its dual bound is below ``below`` no other LP moves; and it takes fewer pivots in all
    than the rows one after the other up to it."""
    f, tab, main = _setup(*_kachanov(n, seed))
    lp = BasisLP(f, tab)
    alone = {int(k): lp.solve(int(k)) for k in f.J[:among]}
    lam = {k: a.x[-1] for k, a in alone.items() if a is not None and a.status == "optimal"}
    rows = sorted(lam, key=lambda k: -lam[k])[-8:]
    low = rows[-1]
    below = 0.5 * (lam[low] + lam[rows[-2]])
    sequential = sum(alone[k].iterations for k in rows)
    log = _spy(monkeypatch)
    first = next((k, a) for k, a in lp.race(rows, below=below, chunk=5) if a.x[-1] < below)
    assert first[0] == low and _same(first[1], alone[low])
    cross = next(i for i, (k, b) in enumerate(log) if b < below)
    assert log[cross][0] == low
    assert {k for k, _ in log[cross:]} == {low}  # nothing else moved after the crossing
    assert sum(1 for k, _ in log if k == low) == alone[low].iterations
    assert len(log) < sequential


@pytest.mark.parametrize("chunk", [0, -3, 2.5, "10"])
def test_race_rejects_a_bad_chunk(chunk):
    f, tab, main = _frame("random40")
    with pytest.raises(InputError, match="chunk"):
        next(BasisLP(f, tab).race([int(f.J[0])], chunk=chunk))


def test_the_race_certifies_together_what_solve_certifies_alone():
    """The race's certificates (:meth:`BasisLP._certify`, one pass for a batch): the residuals
    of :func:`kkt_residuals` for each answer, and a wrong answer in the batch -- a point moved
    off its optimum, multipliers of the wrong sign -- refused while the others pass."""
    from dataclasses import replace

    from shakedown.bounds.certificates import CERT_TOL, kkt_residuals

    f, tab, main = _frame("kachanov60")
    lp = BasisLP(f, tab)
    rows = [int(k) for k in f.J[:6]]
    alone = {k: lp.solve(k) for k in rows}
    rows = [k for k in rows if alone[k] is not None and alone[k].status == "optimal"]
    assert len(rows) >= 4
    unverified = [(k, replace(alone[k], status="unverified")) for k in rows]
    good = lp._certify(unverified)
    for (k, a), ref in zip(good, rows, strict=True):
        assert k == ref and a.status == "optimal"
        want = kkt_residuals(tab.A, tab.b, tab.e, a.x, a.y, equal=(k,), rownorm=np.ones(tab.R))
        assert np.allclose(a.residuals, want, rtol=0.0, atol=1e-14)
    bad = list(unverified)
    k1, a1 = bad[1]
    bad[1] = (k1, replace(a1, x=a1.x + 1e-3 * np.abs(a1.x).max()))  # violates rows
    k2, a2 = bad[2]
    y2 = a2.y.copy()
    y2[np.argmax(y2)] *= -1.0  # a multiplier of the wrong sign
    bad[2] = (k2, replace(a2, y=y2))
    out = lp._certify(bad)
    assert [a.status for _, a in out] == ["optimal", "failed", "failed"] + ["optimal"] * (len(rows) - 3)
    assert all(max(a.residuals) <= CERT_TOL for _, a in out if a.status == "optimal")
