"""Chord factors per step of the period (ConeStepSolver.chord_reset, cone_reduced.chord_point).

What these tests prove: the triangular solves with LAPACK's LU factors equal a direct solve
(pivoting included); a cyclic run with the chord factors takes chord steps and reaches the
answers of the run without them (W, final slips, to the Newton tolerance); factors of a wrong
matrix for the same piece are rejected after one chord step and the step still reaches the
verified answer of the plain Newton method; the memory budget switches the cache off.
"""

import numpy as np
import pytest
import scipy.linalg as sl
from test_cone_step import random_3d  # (tests/evolution on the path)

import shakedown as sd
from shakedown.evolution import cone_reduced as cr
from shakedown.evolution.cone_step import ConeStepSolver


@pytest.mark.parametrize("m", [1, 7, 40])
def test_lu_solve_equals_a_direct_solve(m):
    rng = np.random.default_rng(m)
    A = rng.normal(size=(m, m))  # no diagonal dominance: rows are interchanged
    b = rng.normal(size=m)
    lu, piv = sl.lu_factor(A)
    x = b.copy()
    cr.lu_solve(lu.T, piv.astype(np.int32), x)
    np.testing.assert_allclose(A @ x, b, rtol=0, atol=1e-10 * np.abs(b).max() * np.linalg.cond(A))
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-8, atol=1e-12)


def _system(n=8, seed=2):
    rng = np.random.default_rng(seed)
    s, *_ = random_3d(n, seed, friction=0.3)
    load = sd.LoadCycle.from_harmonics(q0=0.1 * rng.normal(size=(n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)))
    return s, load


def _off(sol):
    """The solver with its chord cache switched off for every run."""
    reset = sol.chord_reset
    sol.chord_reset = lambda n_slots, budget=0: reset(n_slots, 0)
    return sol


def test_cyclic_run_with_chord_steps_reaches_the_answers_without_them():
    s, load = _system()
    on = sd.solve_cycles(s, load, 0.8, steps_per_cycle=16)
    off = sd.solve_cycles(s, load, 0.8, steps_per_cycle=16, solver=_off(ConeStepSolver(s)))
    assert on.statistics["chord_steps"] > 0 and on.statistics["chord_matrices"] > 0
    assert off.statistics["chord_steps"] == 0
    assert on.period == off.period and on.n_cycles == off.n_cycles
    F = on.force_scale
    k = np.diag(s.A).max()
    assert abs(on.steady_dissipation - off.steady_dissipation) <= 1e-9 * F**2 / k
    assert np.abs(on.final_slip - off.final_slip).max() * k <= 1e-9 * F
    assert on.max_residual <= 1e-9


def test_wrong_factors_are_rejected_and_the_step_is_still_the_verified_answer():
    s, load = _system()
    sol = ConeStepSolver(s)
    sol.chord_reset(4)
    qg, pg = load.evaluate(np.array([0.25]), 0.8)
    rb = sol.base(np.zeros((s.n_nodes, 2)), qg[0], pg[0])
    ref = sol.solve_raw(rb, None)
    assert ref[5].worst <= sol.feas_tol
    # the factors of a wrong matrix for the answer's own piece, from a start near the answer
    _, st = _chord_piece(sol, ref)
    m = int(2 * np.sum(st == 1) + 3 * np.sum(st == 3))
    assert m > 0
    lu, piv = sl.lu_factor(np.eye(m) + 0.5 * np.random.default_rng(0).normal(size=(m, m)))
    sol._chord["x"] = (lu.T, piv.astype(np.int32), st)
    u0 = ref[0] * (1 + 1e-3)
    t0 = dict(sol.totals)
    out = sol.solve_raw(rb, u0, slot="x")
    assert sol.totals["chord_rejected"] - t0["chord_rejected"] == 1
    assert out[5].worst <= sol.feas_tol
    F = out[6]
    assert np.abs(out[1] - ref[1]).max() <= 1e-9 * F


def _chord_piece(sol, ref):
    from shakedown.evolution import cone_kernel as ck
    from shakedown.evolution.cone_step import STICK_SLACK

    d = sol.data
    return ck.chord_at(d.Kn, d.sx, d.sy, d.g, sol.rhoT, sol.rhoN, ref[0].ravel(),
                       ref[1].ravel(), STICK_SLACK * sol.feas_tol * ref[6])


def test_memory_budget_switches_the_cache_off():
    s, _ = _system(n=8)
    sol = ConeStepSolver(s)
    sol.chord_reset(16, budget=(2 * 8) ** 2 * 8 * 16)
    assert sol.chord_on
    sol.chord_reset(17, budget=(2 * 8) ** 2 * 8 * 16)
    assert not sol.chord_on
