"""Verdicts of the cycles and stability analyses (issue 9): the answer first, in words, with
units, nodes numbered from 1; cross-checked against the bounds and the run objects.

Stability reference: one slip node with ``K = [[2, 0.5], [0.5, 3]]`` has ``mu* = A / |B| = 4``
(MCEIP-mu on a single node: ``(A - mu chi B) x = 0``).
"""

import json

import numpy as np
import pytest

import shakedown as sd
from shakedown.model.numbers import sig
from shakedown.scenes.files import load_scene, run_scene, scene_from_string
from shakedown.scenes.output import OutputFolder, Progress

SCENE = load_scene("two_node_coupled")

UNITS = """
[scene]
name = "units"
force_unit = "N"
length_unit = "mm"
[model]
kind = "matrices"
A = [[1.0, -0.3], [-0.3, 1.0]]
B = [[-0.3, 0.9], [0.4, -0.1]]
C = [[1.5, 0.2], [0.2, 1.5]]
friction = 0.7
[load]
q0 = [0.1, -0.1]
p0 = [1.0, 1.0]
q_cos = [0.5, 0.0]
q_sin = [0.0, 0.5]
p_cos = [0.0, 0.3]
[analyses.cycles]
plots = false
"""


def _run(scene, tmp_path, name, **options):
    from shakedown.scenes.options import apply_overrides

    scene = apply_overrides(scene, [name], [f"{k}={v}" for k, v in options.items()])
    out = OutputFolder(tmp_path / name)
    return run_scene(scene, out, Progress(enabled=False), only=[name])[name], out.path


@pytest.fixture(scope="module")
def bounds():
    from shakedown.scenes.files import build

    system, load, _ = build(SCENE)
    return sd.shakedown_bounds(system, load)


def test_below_lam1_it_shakes_down_and_says_so(tmp_path, bounds):
    lam = 0.5 * bounds.lam1
    res, out = _run(SCENE, tmp_path, "cycles", lam=lam, plots="false")
    assert res["verdict"].startswith(f"At lam = {lam:.4g}, it shook down")
    assert "W = 0" in res["verdict"]
    assert json.loads((out / "cycles.json").read_text())["verdict"] == res["verdict"]


def test_above_lam2_cyclic_slip_with_w_in_the_scene_units(tmp_path, bounds):
    lam = 1.5 * bounds.lam2
    res, out = _run(scene_from_string(UNITS), tmp_path, "cycles", lam=lam)
    v = res["verdict"]
    W = res["steady_dissipation"]
    assert W > 0
    assert v.startswith(f"At lam = {lam:.4g}, cyclic slip: W = {W:.4g} N mm per cycle, period")
    # the slipping nodes of the verdict are those with a slip state in steady_cycle.csv (from 1)
    import pandas as pd

    t = pd.read_csv(out / "steady_cycle.csv")
    slipping = sorted(set(t.loc[t.state.isin(["forward", "backward"]), "node"]))
    assert slipping and min(slipping) >= 1
    names = ", ".join(str(j) for j in slipping)
    assert f"node{'s' * (len(slipping) > 1)} {names} slip" in v


def test_a_stuck_node_is_not_listed_as_slipping(tmp_path):
    """Seed 002 Fig. 5 (gallery): node 2 stays stuck while node 1 slips every cycle."""
    from shakedown.scenes.analyses.cycles import cycles_verdict

    p = sd.gallery.get("fig5_uncoupled_stuck")
    run = sd.solve_cycles(p.system, p.load, p.lam, steps_per_cycle=64, max_cycles=100)
    assert list(run.stuck_nodes) == [1]
    v = cycles_verdict(run, p.lam)
    assert v.endswith("period 1, node 1 slips."), v


def test_without_units_w_is_force_times_length(tmp_path, bounds):
    res, _ = _run(SCENE, tmp_path, "cycles", lam=1.5 * bounds.lam2, plots="false")
    assert "[force x length] per cycle" in res["verdict"]


def test_not_converged_says_how_many_cycles(tmp_path, bounds):
    res, _ = _run(SCENE, tmp_path, "cycles", lam=1.5 * bounds.lam2, max_cycles=1,
                  plots="false")
    assert res["status"] == "not_converged"
    assert "did not reach a steady state in 1 cycle" in res["verdict"]


def test_uniqueness_study_says_whether_the_initial_state_matters(tmp_path, bounds):
    lam = 0.5 * (bounds.lam1 + bounds.lam2)  # between lam1 and lam2: the initial state decides
    res, _ = _run(SCENE, tmp_path, "cycles", lam=lam, n_initial_states=6, max_cycles=60,
                  steps_per_cycle=64, plots="false")
    v = res["verdict"]
    assert "From 6 initial states" in v
    assert ("differs" in v) == (not res["unique_dissipation"])


STABILITY = """
[model]
kind = "matrices"
A = [[2.0]]
B = [[0.5]]
C = [[3.0]]
friction = {f}
[load]
q0 = [0.0]
p0 = [1.0]
[analyses.stability]
chi = [-1]
plots = false
"""


@pytest.mark.parametrize("f, word", [(0.3, "Stable"), (4.5, "Unstable"), (40.0, "Unstable")])
def test_stability_verdict_compares_friction_with_mu_star(f, word, tmp_path):
    res, _ = _run(scene_from_string(STABILITY.format(f=f)), tmp_path, "stability")
    assert res["mu_star"] == pytest.approx(4.0, rel=1e-12)  # A / |B|, a 1x1 eigenproblem
    relation = "is below" if word == "Stable" else "is at or above"
    # 4 significant digits with their trailing zeros (issue 25)
    assert res["verdict"].startswith(f"{word}: friction {sig(f)} {relation} the critical friction "
                                     "mu* = 4.000 ")


def test_stability_growth_rate_is_called_s_not_lam(tmp_path):
    res, out = _run(scene_from_string(STABILITY.format(f=0.3)), tmp_path, "stability")
    data = json.loads((out / "stability.json").read_text())
    assert "lam" not in " ".join(data)  # no key named after the load factor
    assert "lam" not in res["verdict"]


def test_old_option_names_of_stability_still_work():
    from shakedown.scenes.files import validate_options

    opts = validate_options("<t>", "stability", {"lam_max": 2.0, "n_lam": 5})
    assert opts["growth_rate_max"] == 2.0 and opts["n_growth_rates"] == 5
    with pytest.raises(sd.SceneError, match="not both"):
        validate_options("<t>", "stability", {"lam_max": 2.0, "growth_rate_max": 2.0})


def test_constraints_csv_numbers_nodes_from_one(tmp_path):
    import pandas as pd

    _, out = _run(SCENE, tmp_path, "bounds", plots="false")
    t = pd.read_csv(out / "constraints.csv")
    n = len(t) // 2
    assert list(t["node"]) == [*range(1, n + 1)] * 2
    assert list(t["constraint"]) == [f"I_{j}" for j in range(1, n + 1)] + [
        f"II_{j}" for j in range(1, n + 1)]
    data = json.loads((out / "bounds.json").read_text())
    assert data["limiting_constraint"] in set(t["constraint"]) and data["node_numbering"] == "from 1"
    assert np.isfinite(data["lam1"])
