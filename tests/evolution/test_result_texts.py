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
