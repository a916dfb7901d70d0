"""Every result type has a short ``repr`` (a few lines, no arrays) and a ``verdict()`` (issue 25:
``print(run)`` of a cycle run printed more than 60 lines, and runs had no verdict)."""

import numpy as np
import pytest

import shakedown as sd
from shakedown.model.results import VerdictText, short_repr
from shakedown.stability import NodePartition, mceip_mu

SYSTEM = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                           [[1.5, 0.2], [0.2, 1.5]], 0.7)
LOAD = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0], q_sin=[0.0, 0.5],
                                   p_cos=[0.0, 0.3])


def _short(obj, name):
    text = repr(obj)
    assert text.startswith(name + "(") and text.endswith(")")
    assert text.count("\n") <= 4, text  # a few lines
    assert "array(" not in text and "[[" not in text and "\n0 " not in text  # no arrays, tables
    assert str(obj) == text or len(str(obj).splitlines()) <= 5
    return text


def test_cycle_run_repr_and_verdict():
    run = sd.solve_cycles(SYSTEM, LOAD, 1.5)
    text = _short(run, "CycleRun")
    assert "status='periodic'" in text and "shook_down=False" in text and "lam=1.500" in text
    v = run.verdict()
    assert v.startswith("At lam = 1.500, cyclic slip: W = ") and "per cycle" in v
    assert sd.solve_cycles(SYSTEM, LOAD, 0.2).verdict().startswith("At lam = 0.2000, it shook "
                                                                   "down")


def test_steady_cycle_and_uniqueness_study_repr_and_verdict():
    sc = sd.steady_cycle(SYSTEM, LOAD, 1.5)
    assert "status='converged'" in _short(sc, "SteadyCycle")
    assert sc.verdict().startswith("At lam = 1.500, cyclic slip") and "steady-cycle solver" in \
        sc.verdict()
    study = sd.uniqueness_study(SYSTEM, LOAD, 1.5, 3, rng=0)
    assert "n_states=3" in _short(study, "UniquenessStudy")
    assert study.verdict().startswith("At lam = 1.500, from 3 initial states the steady "
                                      "dissipation is the same")


def test_bounds_repr_and_verdict():
    b = sd.shakedown_bounds(SYSTEM, LOAD)
    text = _short(b, "ShakedownBounds")
    assert "lam1=0.4751" in text and "lam2=1.291" in text
    assert b.verdict().startswith("Shakes down from every initial state")


def test_stability_results_repr_and_verdict():
    K = np.array([[2.0, 0.5], [0.5, 3.0]])  # one node: mu* = A / |B| = 4 (MODEL.md s.5)
    r = mceip_mu(K, NodePartition.all_slip(1, chi=-1.0))
    assert "mu=4.000" in _short(r, "MCEIPResult")
    assert r.verdict().startswith("Critical friction mu* = 4.000 (1 slipping node, certified")
    assert r.verdict(friction=0.3).startswith("Stable: friction 0.3000 is below")
    assert r.verdict(friction=5.0).startswith("Unstable: friction 5.000 is at or above")
    none = mceip_mu(K, NodePartition.all_slip(1, chi=1.0))
    assert none.verdict().startswith("No critical friction found")


def test_short_repr_and_callable_verdict_text():
    class Thing:
        x = 2.6498
        a = np.zeros((3, 4))
        s = "w" * 100

    text = short_repr(Thing(), ("x", "a", "s"))
    assert text.startswith("Thing(x=2.650, a=<array 3x4>, s='www") and "..." in text
    v = VerdictText("the answer")
    assert v == "the answer" and v() == "the answer" and type(v()) is str


@pytest.mark.parametrize("n_states", [2])
def test_sweep_result_repr_and_verdict(tmp_path, n_states):
    from shakedown.studies.sweep import SweepSpec, SystemSource, run_sweep

    spec = SweepSpec(source=SystemSource.of(SYSTEM, LOAD, "coupled"), lams=(0.3, 1.5),
                     n_states=n_states, steps_per_cycle=16)
    res = run_sweep(spec, tmp_path / "store", n_workers=1, progress=False)
    assert "model=\"the model 'coupled' (2 nodes)\"" in _short(res, "SweepResult")
    assert res.verdict() == res.verdict and res.verdict().startswith("The model 'coupled'")


def test_growth_rates_and_cycle_stability_repr_and_verdict():
    import pandas as pd

    from shakedown.stability import CycleStability
    from shakedown.stability.growth import GrowthRates

    g = GrowthRates(mu=0.8, lam=np.array([0.25, 1.5]), modes=(), branch=np.array([0, 1]),
                    curves=None, status="found", message="")
    assert "n_rates=2" in _short(g, "GrowthRates") and "max_rate=1.500" in repr(g)
    assert g.verdict().startswith("At friction 0.8000 the largest growth rate is s = 1.500 "
                                  "[1/time] (2 rates")
    none = GrowthRates(mu=0.8, lam=np.zeros(0), modes=(), branch=np.zeros(0, int), curves=None,
                       status="none", message="")
    assert "no growth rate was found" in none.verdict()
    t = pd.DataFrame({"t": [0.0, 0.25, 0.5], "unstable": [False, True, True]})
    cs = CycleStability(table=t, results=(), min_margin=-0.2)
    assert "n_snapshots=3" in _short(cs, "CycleStability")
    assert cs.verdict().startswith("Unstable during the cycle: the smallest margin alpha* - 1 = "
                                   "-0.2000 <= 0, first at t = 0.2500")
    ok = CycleStability(table=t.assign(unstable=False), results=(), min_margin=0.5)
    assert ok.verdict().startswith("Stable at all 3 snapshots")


def test_uniqueness_summary_numbers_stuck_nodes_from_1():
    """The table keeps 0-based indices (``stuck == "1"``: Python's node 1); the printed summary
    says node 2, as every text a person reads (README: one numbering)."""
    from shakedown import gallery

    p = gallery.fig5_uncoupled_stuck()
    study = sd.uniqueness_study(p.system, p.load, p.lam, 3, rng=1,
                                steps_per_cycle=p.steps_per_cycle, max_cycles=200)
    assert set(study.table["stuck"]) == {"1"}
    assert "stuck sets seen (nodes numbered from 1): {2}" in study.summary()


# ------------------------------------------------------- issue 25: the result types left
ROTATING = sd.DiscreteSystem(2.0 * np.eye(2), np.zeros((2, 1)), [[1.0]], friction=0.5, dim=3)
ROTATING_LOAD = sd.LoadCycle.from_harmonics(q0=np.zeros((1, 2)), p0=[1.0], q_cos=[[1.3, 0.0]],
                                            q_sin=[[0.0, 1.3]])


def test_three_dimensional_bounds_and_runs_repr_and_verdict():
    b = sd.shakedown_bounds(ROTATING, ROTATING_LOAD)
    text = _short(b, "ConeBounds")
    # one node, k = 2, c = 1, f = 0.5, P = 1, |Q| = 1.3: lam2 = f P / |Q| * (A/A) = 0.3846
    assert "status='bounded'" in text and "lam2=0.3846" in text and "safe_state" not in text
    assert b.verdict().startswith("No safe state above lam2 = 0.3846")
    run = sd.solve_cycles(ROTATING, ROTATING_LOAD, 1.0, steps_per_cycle=32)
    assert "status='periodic'" in _short(run, "CycleRun") and "n_nodes=1" in repr(run)
    assert run.verdict().startswith("At lam = 1.000, cyclic slip: W = ")


def test_critical_friction_repr_and_verdict():
    c = SYSTEM.critical_friction()
    assert "well_posed=True" in _short(c, "CriticalFriction")
    assert c.verdict().startswith("Every implicit step has a unique answer: the friction is "
                                  f"below critical (critical multiplier of the friction profile "
                                  f"alpha_c = {c.factor:.4g}")
    bad = SYSTEM.with_friction(5.0).critical_friction()
    assert not bad.well_posed and bad.verdict().startswith("Steps may have several answers")


def test_step_results_repr_and_verdict_2d_and_3d():
    r = sd.solve_step(SYSTEM, [0.0, 0.0], [0.9, -0.2], [1.0, 1.0])
    text = _short(r, "StepResult")
    assert "status='unique'" in text and "n_slip=1" in text and "(slip=" not in text
    assert r.verdict() == ("Step answer (unique): 1 slip backward (node 1); residual 0 "
                           "(relative to the force scale 1.000).")
    from shakedown.evolution.cone_step import ConeStepSolver

    r3 = ConeStepSolver(ROTATING).solve(np.zeros((1, 2)), np.array([[2.0, 0.0]]),
                                         np.array([1.0]))
    assert "n_slip=1" in _short(r3, "ConeStepResult")
    assert r3.verdict().startswith("Step answer (") and "1 slip (node 1)" in r3.verdict()


def test_fretting_results_repr_and_verdict():
    from shakedown.models.half_space import continuum as cont
    from shakedown.models.half_space.bounds import fretting_lam2
    from shakedown.models.half_space.normal import normal_contact

    E, nu, R, P, f = 1.0, 0.3, 1.0, 1e-3, 0.5
    a = float(cont.hertz_radius(P, R, E / (2 * (1 - nu**2))))
    m = sd.half_space_model(radius=R, n_cells=9, width=2.4 * a, friction=f,
                            materials=((E, nu), (E, nu)))
    nc = normal_contact(m, P)
    assert "n_contact_cells=" in _short(nc, "NormalContact")
    assert nc.verdict().startswith("Normal contact: ") and "carry P = 0.001000 [force]" in \
        nc.verdict()
    res = fretting_lam2(m, P, 0.3 * f * P)
    text = _short(res, "FrettingLam2")
    assert "node_lam" not in text and f"critical_cell={res.critical_cell}" in text
    assert res.verdict().startswith(f"No safe state above lam2 = {res.lam2:.4g}"[:26])
    assert f"set by cell {res.critical_cell + 1}," in res.verdict()
