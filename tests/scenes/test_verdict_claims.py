"""Verdicts that never overstate (issue 25): each claim with its status, numbers to 4
significant digits with their trailing zeros, advice that settles what it is printed for, and
nodes numbered from 1 in messages.

References: the coupled two-node system of seed 002 Fig. 4 (built-in scene two_node_coupled);
for one or two nodes and for ``B = 0`` "shakedown from every initial state below lam1" is the
seed's theorem, for three or more coupled nodes numerical evidence (README 'Findings').
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.bounds.verdict import bounds_verdict
from shakedown.model.numbers import position, sig
from shakedown.scenes.analyses.cycles import cycles_verdict

COUPLED = dict(A=[[1.0, -0.3], [-0.3, 1.0]], B=[[-0.3, 0.9], [0.4, -0.1]],
               C=[[1.5, 0.2], [0.2, 1.5]])
LOAD = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0], q_sin=[0.0, 0.5],
                                   p_cos=[0.0, 0.3])


def coupled(friction):
    return sd.DiscreteSystem(**COUPLED, friction=friction)


def test_sig_keeps_trailing_zeros():
    assert [sig(x) for x in (2.6498, 1.0, 0.5, 1000.0, -0.047509)] == [
        "2.650", "1.000", "0.5000", "1000", "-0.04751"]
    assert sig(1.0e-5) == "1.000e-05" and sig(0.0) == "0"
    assert (sig(np.inf), sig(-np.inf), sig(np.nan)) == ("inf", "-inf", "nan")
    assert sig(0.12345678, 3) == "0.123"


def test_bounds_verdict_prints_four_significant_digits_with_trailing_zeros():
    # one node, B = 0: lam1 = lam2 = f p0 / |q1| = 0.53 * 5 / 1 = 2.65 exactly (frictional Melan)
    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.53)
    b = sd.shakedown_bounds(s, sd.LoadCycle.from_harmonics([0.0], [5.0], q_cos=[1.0]))
    assert b.lam1 == pytest.approx(2.65, rel=1e-7)
    v = bounds_verdict(b, adjacency=True)
    assert "lam1 = lam2 = 2.650 " in v and "2.65;" not in v


def test_every_state_claim_carries_its_status():
    # two nodes: the seed's theorem
    v = sd.shakedown_bounds(coupled(0.7), LOAD, adjacency=True).verdict()
    assert "lam < lam1 = 0.4751 (proved for one or two nodes)" in v
    # three coupled nodes with 0 < lam_adj < lam1: below lam_adj is numerical evidence
    rng = np.random.default_rng(0)
    M = rng.normal(size=(6, 6))
    K = M @ M.T + 6 * np.eye(6)
    s3 = sd.DiscreteSystem(K[:3, :3], K[:3, 3:], K[3:, 3:], 0.5)
    load3 = sd.LoadCycle.from_harmonics(rng.normal(size=3) * 0.1, 3 + rng.random(3),
                                        q_cos=rng.normal(size=3), q_sin=rng.normal(size=3))
    b = sd.shakedown_bounds(s3, load3, adjacency=True)
    assert 0 < b.lam_adj < b.lam1 and b.lam1 - b.lam_adj > 1e-4 * b.lam1
    v = bounds_verdict(b, adjacency=True)
    assert v.startswith(f"Shakes down from every initial state for lam < lam_adj = "
                        f"{sig(b.lam_adj)} in every run so far (numerical evidence, not a proof)")
    # the same three nodes uncoupled (B = 0): proved again, and lam_adj does not weaken it
    s0 = sd.DiscreteSystem(K[:3, :3], np.zeros((3, 3)), K[3:, 3:], 0.5)
    b0 = sd.shakedown_bounds(s0, load3, adjacency=True)
    v0 = bounds_verdict(b0, adjacency=True)
    assert f" = {sig(b0.lam1)} (proved for B = 0)" in v0
    assert "numerical evidence" not in v0


@pytest.mark.parametrize("options", [dict(), dict(steps_per_cycle=1000), dict(method="events")])
def test_shakedown_below_lam1_is_settled_against_the_exact_load(options):
    # issue 25: friction 0.4, lam = 0.6 < lam1 = 0.6334; the final state of the sampled run sits
    # on the sampled load's friction limit, so the exact peak (higher by the sampling error)
    # broke it at every steps_per_cycle and with events: "raise steps_per_cycle" never decided
    s = coupled(0.4)
    b = sd.shakedown_bounds(s, LOAD)
    assert 0.6 < b.lam1 and b.lam1 == pytest.approx(0.6334, abs=5e-5)
    run = sd.solve_cycles(s, LOAD, 0.6, **options)
    assert run.shook_down and not run.within_sampling_error
    assert "stays stuck" in run.sampling_note and "holds for the exact load" in run.sampling_note
    v = cycles_verdict(run, 0.6)
    assert v.startswith("At lam = 0.6000, it shook down") and "raise steps_per_cycle" not in v
    assert "Checked against the exact load" in v


def _exact_margins_on_a_grid(system, load, lam, v, n=200_001):
    t = np.arange(n) / n
    q, p = load.evaluate(t, lam)
    q = q + system.A @ v
    p = p + system.B.T @ v
    return np.min(system.friction * p - np.abs(q))


def test_settling_steps_end_in_a_state_stuck_under_the_exact_load():
    # cross-check of the closed-form margins by brute force on a fine grid: the state the
    # settling steps reach is stuck under the exact load, the run's own final state is not
    from shakedown.evolution.complementarity import StepSolver
    from shakedown.evolution.sampling import _settle_at_extremes

    s = coupled(0.4)
    run = sd.solve_cycles(s, LOAD, 0.6)
    F = run.force_scale
    assert _exact_margins_on_a_grid(s, LOAD, 0.6, run.final_slip) < -1e-6 * F
    chk = _settle_at_extremes(s, LOAD, 0.6, 200, run.final_slip, 0.0, F, 1e-10 * F,
                              StepSolver(s))
    assert not chk.within
    # the settled state is not returned; redo its one step and check it on the grid
    from shakedown.evolution.sampling import _exact_margins

    mI, tI, mII, tII = _exact_margins(s, LOAD, 0.6, run.final_slip)
    j = int(np.argmin(np.minimum(mI, mII)))
    t = tI[j] if mI[j] <= mII[j] else tII[j]
    r = sd.solve_step(s, run.final_slip, *LOAD.evaluate(t, 0.6))
    assert _exact_margins_on_a_grid(s, LOAD, 0.6, r.slip) >= -1e-9 * F
    assert np.max(np.abs(r.slip - run.final_slip)) <= 10 * run.sampling_error


def test_settling_stops_at_a_fixed_point_with_the_same_verdict():
    # issue 25: a settling step that leaves the state where it was (the exact load's violation
    # within the step's own tolerance) would repeat itself for all 4 N + 4 rounds: the check
    # stops after it, undecided, and says why (the default study did 3636 such steps)
    from shakedown.evolution.complementarity import StepSolver
    from shakedown.evolution.sampling import _settle_at_extremes

    class Counting(StepSolver):
        calls = 0

        def solve(self, *args, **kwargs):
            Counting.calls += 1
            return super().solve(*args, **kwargs)

    s = coupled(0.4)
    run = sd.solve_cycles(s, LOAD, 0.6)
    F = run.force_scale
    loose = Counting(s, feas_tol=1e-3)  # its steps accept the exact load's 3e-5 F violation
    chk = _settle_at_extremes(s, LOAD, 0.6, 200, run.final_slip, run.sampling_error, F,
                              1e-10 * F, loose)
    assert Counting.calls == 1 and chk.within
    assert "1 round(s); the last step left the state where it was" in chk.message
    # with the solver's own tolerance the same start is settled (the fixed point was the
    # tolerance's, not the state's)
    assert not _settle_at_extremes(s, LOAD, 0.6, 200, run.final_slip, run.sampling_error, F,
                                   1e-10 * F, StepSolver(s)).within


def test_unsettled_shakedown_is_decided_by_the_bounds_and_the_decision_is_right():
    s = coupled(0.7)
    b = sd.shakedown_bounds(s, LOAD)
    lam = b.lam2 * (1 + 1e-5)
    run = sd.solve_cycles(s, LOAD, lam, initial_slip=[0.3, 0.3])
    assert run.shook_down and run.within_sampling_error
    v = cycles_verdict(run, lam, bounds=b)
    assert "raise steps_per_cycle" not in v
    assert f"lam > lam2 = {sig(b.lam2)}" in v and "cyclic slip from every initial state" in v


@pytest.mark.slow  # about 60 s: 4000 steps per cycle over many cycles
def test_the_bounds_decision_agrees_with_a_finely_sampled_run():
    s = coupled(0.7)
    lam = sd.shakedown_bounds(s, LOAD).lam2 * (1 + 1e-5)
    # independent check of that decision: with the sampling error far below lam2 * 1e-5
    # (0.5 (1 - cos(pi / 4000)) = 1.5e-7 per unit lam) the same state does slip cyclically
    fine = sd.solve_cycles(s, LOAD, lam, initial_slip=[0.3, 0.3], steps_per_cycle=4000,
                           max_cycles=400)
    assert fine.status == "periodic" and not fine.shook_down and fine.steady_dissipation > 0


def test_messages_number_nodes_and_matrix_entries_from_1():
    with pytest.raises(sd.InputError, match="node 1 has friction -0.4"):
        sd.DiscreteSystem(**COUPLED, friction=[-0.4, 0.2])
    with pytest.raises(sd.NotSymmetricError, match="A row 1, column 2 is 0.3 but A row 2, "
                                                   "column 1 is -0.3|A row 2, column 1"):
        sd.DiscreteSystem([[1.0, 0.3], [-0.3, 1.0]], COUPLED["B"], COUPLED["C"], 0.5)
    assert position((0, 1)) == "row 1, column 2" and position(4) == "entry 5"


def test_cycles_analysis_follows_its_own_advice(tmp_path):
    # the command asks the exact load's bounds when the run cannot decide (issue 25)
    import json

    from shakedown.scenes.cli import main

    lam = sd.shakedown_bounds(coupled(0.7), LOAD).lam2 * (1 + 1e-5)
    out = tmp_path / "o"
    rc = main(["cycles", "two_node_coupled", "-q", "-o", str(out), "--set", f"lam={lam!r}",
               "--set", "initial_slip=[0.3, 0.3]", "--set", "plots=false"])
    assert rc == 0
    v = json.loads((out / "cycles.json").read_text())["verdict"]
    assert "The bounds of the exact load decide it: lam > lam2 = 1.291" in v
    assert "raise steps_per_cycle" not in v
