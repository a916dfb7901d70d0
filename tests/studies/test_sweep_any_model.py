"""``shakedown sweep`` for every model kind (issue 25): load factors from the bounds or listed
(``lams``, alias ``lam``), initial states, tables numbered from 1, the figure and the verdict.
What a realisation is depends on the model (``draws_realisations`` of its builder), not on
``kind == "crack_network"``.

Cross-checks: the sweep's bounds against ``shakedown_bounds`` of the scene's own system, and a
run of the sweep against ``solve_cycles`` called directly from the same initial state (zero).
"""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import shakedown as sd
from shakedown.model.errors import InputError, SceneError
from shakedown.scenes.cli import main
from shakedown.scenes.files import load_scene, scene_from_string

ROOT = Path(__file__).resolve().parents[2]
FAST = ["--set", "n_states=3", "--set", "n_workers=1", "--set", "steps_per_cycle=32",
        "--set", "max_cycles=60"]


def _sweep(tmp_path, scene, *sets):
    out = tmp_path / "out"
    rc = main(["sweep", str(scene), "-q", "-o", str(out), *FAST, *sets])
    assert rc == 0
    return out


@pytest.mark.parametrize("scene, sets", [
    ("two_node_coupled", ["--set", "lam=[0.3,0.6,0.9]"]),
    (ROOT / "data/scenes/two_node_npz.toml", ["--set", "lams=[0.3,0.9]"]),
    ("hertz_ellipse", ["--set", "model.n_nodes=9", "--set", "lam=[0.5,1.0]"]),
    (ROOT / "data/scenes/fe_unit_square.toml", ["--set", "lam=1.0"]),
])
def test_sweep_runs_for_every_model_kind(tmp_path, scene, sets):
    out = _sweep(tmp_path, scene, *sets)
    lams = json.loads(sets[-1].split("=", 1)[1]) if "[" in sets[-1] else [1.0]
    verdict = (out / "sweep_verdict.txt").read_text()
    n = len(lams)
    assert verdict.startswith("The model '") and f"{n} load factor{'s' * (n != 1)} x 3 " \
        "initial states." in verdict
    assert "raise lam_span" not in verdict  # lam_span is unused with listed load factors
    runs = pd.read_csv(out / "sweep_runs.csv")
    np.testing.assert_allclose(sorted(runs["lam"].unique()), sorted(lams), rtol=1e-15)
    # numbered from 1 in files, as on stdout: realisation 1, initial states 1..3
    assert set(runs["realisation"]) == {1} and set(runs["state"]) == {1, 2, 3}
    assert (runs["W"] == runs["W_star"]).all()  # a given system: W* is W
    assert (out / "dissipation_vs_lam.png").stat().st_size > 0
    data = json.loads((out / "sweep.json").read_text())
    assert data["spec"]["source"]["n_nodes"] >= 1 and len(data["spec"]["source"]["digest"]) == 64
    assert {r["realisation"] for r in data["summary"] + data["realisations"]} == {1}
    summary = pd.read_csv(out / "sweep_summary.csv")
    assert set(summary["realisation"]) == {1}


def test_listed_sweep_agrees_with_direct_runs_and_bounds(tmp_path):
    out = _sweep(tmp_path, "two_node_coupled", "--set", "lam=[0.3,0.9,1.5]")
    scene = load_scene("two_node_coupled")
    from shakedown.scenes.files import build as build_model

    system, load, _ = build_model(scene)
    b = sd.shakedown_bounds(system, load)
    rel = pd.read_csv(out / "sweep_realisations.csv")
    assert rel["lam1"].iloc[0] == pytest.approx(b.lam1, rel=1e-9)
    assert rel["lam2"].iloc[0] == pytest.approx(b.lam2, rel=1e-9)
    runs = pd.read_csv(out / "sweep_runs.csv")
    for lam in (0.9, 1.5):
        row = runs[(runs["lam"] == lam) & (runs["state_kind"] == "zero")].iloc[0]
        direct = sd.solve_cycles(system, load, lam, steps_per_cycle=32, max_cycles=60)
        assert row["W"] == pytest.approx(direct.steady_dissipation, rel=1e-9, abs=1e-12)
        assert bool(row["shook_down"]) == direct.shook_down
    # above lam2 every initial state slips cyclically (proved): the sweep shows it
    assert (runs[runs["lam"] == 1.5]["W"] > 0).all()


def test_auto_load_factors_come_from_the_models_own_bounds(tmp_path):
    out = _sweep(tmp_path, "two_node_coupled", "--set", "n_lams=3", "--set", "n_band=1",
                 "--set", "n_adj=0", "--set", "n_refine=0")
    rel = pd.read_csv(out / "sweep_realisations.csv")
    lam2 = rel["lam2"].iloc[0]
    lam = np.sort(pd.read_csv(out / "sweep_runs.csv")["lam"].unique())
    # lam_span (0.5, 2.5) x lam2 evenly in 3 points, and the middle of (lam1, lam2)
    expect = np.sort([0.5 * lam2, 1.5 * lam2, 2.5 * lam2,
                      0.5 * (rel["lam1"].iloc[0] + lam2)])
    np.testing.assert_allclose(lam, expect, rtol=1e-12)


def test_dispatch_is_on_the_model_not_on_its_kind(tmp_path):
    from shakedown.scenes.analyses.sweep import OPTIONS, spec_from_scene
    from shakedown.scenes.builders.crack_network import draws_realisations
    from shakedown.scenes.files import build as build_model

    opts = {k: v[1] for k, v in OPTIONS.items()}
    random = scene_from_string('[model]\nkind = "crack_network"\nn_cracks = 6\nseed = 1\n')
    assert draws_realisations(random.model) and spec_from_scene(random, opts).source is None
    # the same kind with one friction per crack is one given system, swept as such
    given = scene_from_string('[model]\nkind = "crack_network"\nn_cracks = 3\nseed = 1\n'
                              'friction = [0.5, 0.6, 0.7]\n')
    assert not draws_realisations(given.model)
    system, load, _ = build_model(given)
    spec = spec_from_scene(given, opts, system, load)
    assert spec.source is not None and spec.source.n_nodes == 3 and spec.node_word == "node"
    with pytest.raises(SceneError, match="n_realisations = 3: a 'crack_network' model is one "
                                         "given system"):
        spec_from_scene(given, {**opts, "n_realisations": 3}, system, load)


def test_system_source_is_keyed_on_content_and_a_changed_model_is_not_resumed(tmp_path):
    from shakedown.studies.sweep import SweepSpec, SystemSource, run_sweep

    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    load = sd.LoadCycle.from_harmonics([0.0], [2.0], q_cos=[1.0])
    a, b = SystemSource.of(s, load, "one"), SystemSource.of(s, load, "one")
    assert a == b and hash(a) == hash(b)
    c = SystemSource.of(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.6), load, "one")
    assert c != a
    spec = SweepSpec(source=a, lams=(0.5, 1.5), n_states=2, steps_per_cycle=16)
    res = run_sweep(spec, tmp_path / "store", n_workers=1, progress=False)
    # one node, B = 0: lam1 = lam2 = f p0 / |q1| = 1; below it W = 0, above it W > 0
    assert res.realisations["lam1"].iloc[0] == pytest.approx(1.0, rel=1e-7)
    w = res.runs.groupby("lam")["W"].max()
    assert w.loc[0.5] == 0 and w.loc[1.5] > 0
    # the figure of a given system: W in its unit, the model named, nodes (not cracks)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from shakedown.plotting.sweep import plot_fractions

    ax = res.plot()
    assert ax.get_ylabel() == "$W$ per cycle [force x length]"
    assert "the model 'one' (1 node)" in ax.get_title()
    assert "every node slips" in " ".join(t.get_text() for t in ax.get_legend().get_texts()) \
        or not np.isfinite(res.realisations["lam_u"]).any()
    assert plot_fractions(res).get_ylabel() == "fraction of nodes (steady cycle) [-]"
    plt.close("all")
    with pytest.raises(InputError, match="another spec"):
        run_sweep(SweepSpec(source=c, lams=(0.5, 1.5), n_states=2, steps_per_cycle=16),
                  tmp_path / "store", n_workers=1, progress=False)
    with pytest.raises(InputError, match="one realisation"):
        SweepSpec(source=a, n_realisations=2)
