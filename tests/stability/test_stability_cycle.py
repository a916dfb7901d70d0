"""Tie-in of the stability check with cyclic evolutions, the CLI analysis, and the plots."""

import json
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")
import numpy as np
import pandas as pd
import pytest

import shakedown as sd
from shakedown.model.errors import InputError, SceneError
from shakedown.scenes.analyses import stability as analysis
from shakedown.stability import NodePartition, mceip_mu, stability_along_cycle


def coupled_system(f=0.5):
    A = np.array([[3.0, -1.0, 0.0], [-1.0, 3.0, -1.0], [0.0, -1.0, 3.0]])
    B = np.array([[0.2, 0.9, 0.0], [-0.9, 0.3, 0.8], [0.0, -0.8, 0.2]])
    C = np.array([[4.0, -1.0, 0.0], [-1.0, 4.0, -1.0], [0.0, -1.0, 4.0]])
    return sd.DiscreteSystem(A, B, C, friction=f)


def snapshot_table(f=0.5):
    """Hand-made steady_table (contract of CycleRun.steady_table): 3 nodes, 5 times."""
    rows = []
    snaps = [
        # (t, gap, q, p, state)
        (0.0, [0, 0, 0], [0.1, 0.0, -0.1], [1.0, 1.0, 1.0], ["stick"] * 3),
        (0.2, [0, 0, 0], [-f * 1.0, 0.0, -0.1], [1.0, 1.0, 1.0], ["forward", "stick", "stick"]),
        (0.4, [0, 0, 0], [-f * 1.0, f * 2.0, -0.1], [1.0, 2.0, 1.0],
         ["forward", "backward", "stick"]),
        (0.6, [0, 0, 0], [-f * 1.0, f * 2.0, -0.1], [1.0, 2.0, 1.0],
         ["forward", "backward", "stick"]),
        (0.8, [0, 0, 0.3], [-f * 1.0, f * 2.0, 0.0], [1.0, 2.0, 0.0],
         ["forward", "backward", "separation"]),
    ]
    for t, gap, q, p, state in snaps:
        for j in range(3):
            rows.append({"t": t, "node": j, "slip": 0.0, "gap": gap[j], "q": q[j], "p": p[j],
                         "state": state[j]})
    return pd.DataFrame(rows)


def test_margin_at_every_partition_change():
    system = coupled_system()
    tab = snapshot_table()
    cs = stability_along_cycle(system, tab)
    # t = 0.6 repeats the partition of t = 0.4: not a change
    assert cs.table["t"].tolist() == [0.0, 0.2, 0.4, 0.8]
    assert cs.table["n_slip"].tolist() == [0, 1, 2, 2]
    assert cs.table["status"][0] == "no slip node" and np.isinf(cs.table["alpha"][0])
    assert cs.table["state_mismatch"].sum() == 0
    # each alpha is MCEIP-mu of that partition, computed independently here
    part = NodePartition.from_states(["slip", "slip", "stick"], [1.0, -1.0, 0.0])
    ref = mceip_mu(system.K, part, method="enumeration")
    row = cs.table.iloc[2]
    if ref.found:
        assert row["alpha"] == pytest.approx(ref.mu / 0.5, rel=1e-12)
        assert row["mu_star"] == pytest.approx(ref.mu, rel=1e-12)
    else:
        assert np.isinf(row["alpha"])
    assert cs.min_margin == pytest.approx(cs.table["margin"].min())
    assert cs.ever_unstable == bool((cs.table["alpha"] <= 1).any())


def test_margin_with_a_large_friction_is_unstable_and_snapshot_times():
    # node 0 alone: mu* = A_00 / |B_00| = 15 when chi = -sign(B_00) = -1
    system = coupled_system(f=20.0)
    tab = snapshot_table(f=20.0)
    tab.loc[(tab.node == 0) & (tab.t > 0), "q"] *= -1.0  # node 0 would slip backwards
    cs = stability_along_cycle(system, tab, times=[0.21], every_change=False)
    assert cs.table["t"].tolist() == [0.2]
    assert cs.table["alpha"].iloc[0] == pytest.approx(15.0 / 20.0)
    assert cs.ever_unstable


def test_per_node_friction_profile():
    system = coupled_system().with_friction([0.5, 0.25, 0.5])
    tab = snapshot_table()
    tab.loc[(tab.node == 0) & (tab.t > 0), "q"] *= -1.0
    cs = stability_along_cycle(system, tab, times=[0.2], every_change=False)
    # node 0 slips alone with friction 0.5 = max f: alpha* max f = A_00 / |B_00| = 15
    assert cs.table["mu_star"].iloc[0] == pytest.approx(15.0)


def test_cycle_bad_input():
    system = coupled_system()
    with pytest.raises(InputError, match="lacks the columns"):
        stability_along_cycle(system, pd.DataFrame({"t": [0.0], "node": [0]}))
    with pytest.raises(InputError, match="CycleRun"):
        stability_along_cycle(system, [1, 2, 3])
    bad = snapshot_table()
    bad = bad[bad.node != 2]
    with pytest.raises(InputError, match="nodes 0..2"):
        stability_along_cycle(system, bad)


def test_with_solve_cycles():
    # a CycleRun is accepted as it is (a change of solve_cycles' signature must fail here, not
    # skip: the old version turned a TypeError into a skip)
    system = coupled_system(f=0.3)
    load = sd.LoadCycle.from_harmonics([0.0, 0.0, 0.0], [2.0, 2.0, 2.0],
                                       q_cos=[1.0, -0.5, 0.3])
    run = sd.solve_cycles(system, load, lam=1.0, max_cycles=5)
    assert run.status in ("periodic", "not_converged")
    cs = stability_along_cycle(system, run)
    assert len(cs.table) >= 1
    for r in cs.results:
        assert r is None or r.status in ("found", "none")
        assert r is None or r.status == "none" or r.verified


# ----------------------------------------------------------------------------- CLI analysis
def _Out(path):
    from shakedown.scenes.output import OutputFolder

    return OutputFolder(path)  # the real output folder: names are used as given


def _ctx(tmp_path, system, model=None, load=None):
    return SimpleNamespace(system=system, load=load, model=model, output=_Out(tmp_path),
                           progress=lambda it, total=None, desc="": it, log=lambda m: None,
                           scene_path=tmp_path / "scene.toml")


def _options(**kw):
    opts = {k: v[1] for k, v in analysis.OPTIONS.items()}
    opts.update(kw)
    return opts


def test_analysis_protocol_all_slip(tmp_path):
    for _key, (typ, default, help_) in analysis.OPTIONS.items():
        assert isinstance(default, typ) and help_
    K = np.array([[2.0, 0.5], [0.5, 3.0]])
    system = sd.DiscreteSystem(K[:1, :1], K[:1, 1:], K[1:, 1:], friction=0.3)
    out = analysis.run(_ctx(tmp_path, system), _options(chi=[-1]))
    assert out["status"] == "found" and out["mu_star"] == pytest.approx(4.0)
    json.dumps(out, default=str)
    assert (tmp_path / "stability.json").exists() and (tmp_path / "mode.png").exists()


def test_analysis_fe_growth_rates(tmp_path):
    from shakedown import fe

    mat = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.1, np.radians(80), density=1.0)
    cm = fe.FEModel(fe.rectangle(1.0, 1.0, 2, 4, element="Q1"), mat, dirichlet=["top"],
                    contact=["bottom"], periodic=("left", "right"), friction=0.6).condense(
                        mass=True)
    out = analysis.run(_ctx(tmp_path, cm.system, cm),
                       _options(chi=[-1], mu=0.6, lam_max=3.0, n_lam=7))
    assert out["mu_star"] == pytest.approx(0.2629238, abs=5e-8)
    assert len(out["growth_rates"]) == 1 and out["growth_status"] == "found"
    assert (tmp_path / "growth_rates.png").exists() and (tmp_path / "curves.csv").exists()


def test_analysis_bad_options(tmp_path):
    system = coupled_system()
    ctx = _ctx(tmp_path, system)
    with pytest.raises(SceneError, match="'partition'"):
        analysis.run(ctx, _options(partition="most"))
    with pytest.raises(SceneError, match="'chi'"):
        analysis.run(ctx, _options(chi=[1, 1]))
    with pytest.raises(SceneError, match="'states'"):
        analysis.run(ctx, _options(partition="states", states=["slip"]))
    with pytest.raises(SceneError, match="needs a mass"):
        analysis.run(ctx, _options(lam_max=1.0))
    with pytest.raises(SceneError, match="'method'"):
        analysis.run(ctx, _options(method="magic"))


def test_plots_return_axes():
    from shakedown.plotting import stability as sp
    from shakedown.stability import lam_mu_curves

    K = np.array([[2.0, 0.5], [0.5, 3.0]])
    r = mceip_mu(K, NodePartition.all_slip(1, -1.0))
    assert sp.plot_mode(r).figure is not None
    c = lam_mu_curves(K, NodePartition.all_slip(1, -1.0), [0.0, 0.5, 1.0], mass=np.eye(2))
    assert sp.plot_lam_mu(c, mu=4.5) is not None
    assert sp.plot_convergence([11, 21], [1.95, 1.947], reference=1.945) is not None
    cs = stability_along_cycle(coupled_system(), snapshot_table())
    assert sp.plot_cycle_margin(cs) is not None
    pw = mceip_mu(K, NodePartition.all_slip(1, -1.0), method="power")
    assert sp.plot_power_history(pw, reference=4.0) is not None
