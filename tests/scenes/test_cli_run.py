"""`shakedown run` end to end (issue 15: no test ran it): a scene with the bounds and cycles
analyses, run as a subprocess exactly as a user types it; the files it writes are checked
against the API and against the physics of MODEL.md (equilibrium and Coulomb's law on every
row of the steady-cycle table)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import shakedown as sd

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
[scene]
name = "run_test"
[model]
kind = "matrices"
A = [[2.0, 0.5], [0.5, 2.0]]
B = [[0.2, 0.1], [-0.1, 0.3]]
C = [[3.0, 0.0], [0.0, 3.0]]
friction = 0.4
[load]
q0 = [0.0, 0.1]
p0 = [1.0, 1.0]
q_cos = [1.0, 0.0]
q_sin = [0.0, 1.0]
[analyses.bounds]
plots = false
[analyses.cycles]
lam = 0.9
"""


@pytest.fixture(scope="module")
def run_output(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli_run")
    scene = d / "scene.toml"
    scene.write_text(SCENE)
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run([sys.executable, "-m", "shakedown", "run", str(scene), "-o",
                        str(d / "out"), "-q"], capture_output=True, text=True, env=env,
                       cwd=d, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return d / "out", r


def system_and_load():
    s = sd.DiscreteSystem([[2.0, 0.5], [0.5, 2.0]], [[0.2, 0.1], [-0.1, 0.3]],
                          [[3.0, 0.0], [0.0, 3.0]], friction=0.4)
    load = sd.LoadCycle.from_harmonics([0.0, 0.1], [1.0, 1.0], q_cos=[1.0, 0.0], q_sin=[0.0, 1.0])
    return s, load


def test_run_writes_the_bounds_of_the_api(run_output):
    out, r = run_output
    s, load = system_and_load()
    b = sd.shakedown_bounds(s, load)
    data = json.loads((out / "bounds.json").read_text())
    # the same LPs: agreement to the certificate tolerance (1e-7 relative), measured exact
    assert data["lam1"] == pytest.approx(b.lam1, rel=1e-9)
    assert data["lam2"] == pytest.approx(b.lam2, rel=1e-9)
    assert data["status"] == "bounded"
    assert "lam2" in r.stdout and f"{b.lam2:.4g}" in r.stdout  # printed to 4 digits (JSON: full)


def test_run_steady_cycle_obeys_equilibrium_and_coulomb(run_output):
    out, _ = run_output
    s, load = system_and_load()
    cyc = json.loads((out / "cycles.json").read_text())
    assert cyc["status"] == "periodic" and cyc["lam"] == 0.9
    # lam = 0.9 is far above lam2 = 0.394: no state is safe, the steady cycle dissipates
    assert not cyc["shook_down"] and cyc["steady_dissipation"] > 0
    tab = pd.read_csv(out / "steady_cycle.csv")
    assert set(tab["state"]) <= set(sd.STATE_NAMES) and len(tab) > 0
    f = 0.4
    # every row: (q, p) = (q_w, p_w)(t) + K (v, w) at the row's time, with the node states of
    # MODEL.md s.1.  Written with 17 significant digits: round-off ~1e-15 of the force scale 1.
    tol = 1e-12
    for t, g in tab.groupby("t"):
        g = g.sort_values("node")
        v, w = g["slip"].to_numpy(), g["gap"].to_numpy()
        qw, pw = load.evaluate(np.array(t), cyc["lam"])
        np.testing.assert_allclose(g["q"], qw + s.A @ v + s.B @ w, atol=tol)
        np.testing.assert_allclose(g["p"], pw + s.B.T @ v + s.C @ w, atol=tol)
        for _, row in g.iterrows():
            q, p, st = row["q"], row["p"], row["state"]
            if st == "separation":
                assert abs(p) <= tol and abs(q) <= tol and row["gap"] > 0
            else:
                assert p >= -tol and row["gap"] == 0
                if st == "stick":
                    assert abs(q) <= f * p + tol
                elif st == "forward":
                    assert q == pytest.approx(-f * p, abs=tol)
                else:
                    assert q == pytest.approx(f * p, abs=tol)
    assert {"forward", "backward"} & set(tab["state"])  # the cycle slips
