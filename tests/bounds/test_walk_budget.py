"""Walk or LP (issue 26): :class:`~shakedown.bounds.walk_budget.WalkBudget` lets the pruning
stop walking where its walks decide rows for more pivots than the exact LPs, and walk again
where they turn cheaper.  The counts choose only who decides a row: ``lam1``, ``lam2`` and every
exact ``lam_high`` stay those of the full computation either way, and the choice, made on pivot
counts, is the same on every run."""

from __future__ import annotations

import numpy as np
from test_pruning import _unscreened_network, assert_fast_matches_full

import shakedown as sd
from shakedown.bounds import pruning, walk_budget
from shakedown.bounds.walk_budget import WalkBudget


def test_walks_are_tried_until_the_counts_are_trusted():
    b = WalkBudget()
    for _ in range(walk_budget.MIN_WALKS - 1):
        b.walked("short", 100, 0)  # walks that decide nothing
    b.solved(10, 100)
    assert b.worth("short")  # too few walks counted yet
    b.walked("short", 100, 0)
    assert not b.worth("short")
    assert b.worth("long")  # counted separately


def test_the_cheaper_way_wins_and_the_choice_follows_the_counts():
    b = WalkBudget()
    w = walk_budget.LP_PIVOT_WEIGHT
    for _ in range(walk_budget.MIN_WALKS):
        b.walked("short", 20, 1)  # 20 walk pivots per row
    rows = 2 * walk_budget.MIN_LP_ROWS
    b.solved(round(20 / w * rows), rows)  # LPs: 20 / w LP pivots per row
    assert b.worth("short")  # a tie: walk
    b.solved(0, 1)  # LPs now slightly cheaper per row
    assert not b.worth("short")
    b.solved(10**6, 1)  # dearer again: walk
    assert b.worth("short")


def _short_walks(monkeypatch):
    """The 120-crack network of :func:`test_pruning._unscreened_network` with walks of 2 pivots
    (the walks and LPs decide most rows) and the budget's counts trusted early."""
    monkeypatch.setattr(pruning, "WALK_CAP", 2)
    monkeypatch.setattr(pruning, "LONG_WALK_CAP", 2)
    monkeypatch.setattr(walk_budget, "MIN_WALKS", 4)
    monkeypatch.setattr(walk_budget, "MIN_LP_ROWS", 1)
    model, load = _unscreened_network(monkeypatch)
    return model.system, load


def test_answers_do_not_depend_on_who_decides(monkeypatch):
    """From an unscreened start, with short walks (the walks and LPs decide most rows): with
    LPs counted free, walking stops as soon as the counts are trusted and the LPs decide the
    rest; counted dear, walking never stops.  Both give the full computation's answers."""
    budgets = []
    run = pruning._Pruner.run

    def spy(self):
        budgets.append(self.budget)
        return run(self)

    monkeypatch.setattr(pruning._Pruner, "run", spy)
    system, load = _short_walks(monkeypatch)
    out = {}
    for weight in (0.0, 1e9):
        monkeypatch.setattr(walk_budget, "LP_PIVOT_WEIGHT", weight)
        budgets.clear()
        fast, _ = assert_fast_matches_full(system, load)
        assert 0 < fast.lam1 < fast.lam2
        (b,) = budgets  # (the full computation does not prune)
        out[weight] = b
    free, dear = out[0.0], out[1e9]
    assert free.lps[1] > dear.lps[1] > 0  # more rows decided by LPs ...
    assert free.walks["short"][0] < dear.walks["short"][0] / 2  # ... fewer walks
    assert free.walks["short"][0] >= walk_budget.MIN_WALKS  # (the counts were trusted first)


def test_the_choice_is_the_same_on_every_run(monkeypatch):
    system, load = _short_walks(monkeypatch)
    a = sd.shakedown_bounds(system, load)
    b = sd.shakedown_bounds(system, load)
    np.testing.assert_array_equal(a.lam_high, b.lam_high)
    np.testing.assert_array_equal(a.lam_high_exact, b.lam_high_exact)
    assert a.lam1 == b.lam1 and a.n_lps == b.n_lps and a.simplex_iterations == b.simplex_iterations
