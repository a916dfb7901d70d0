"""Half-space contact with friction (issue 23): Cattaneo-Mindlin, Mindlin-Deresiewicz, the scene.

References (Johnson, *Contact Mechanics*, 1985, s.7.2): Cattaneo-Mindlin stick radius
``c = a (1 - Q/fP)^(1/3)`` and tangential displacement (eq. 7.50), the Mindlin-Deresiewicz
dissipation per cycle (eq. 7.58).  With ``nu = 0`` in both bodies Mindlin's solution is exact
(:mod:`shakedown.models.half_space.continuum`).  Tolerances are the measured discretisation
errors at these grids (``benchmarks/RESULTS_half_space.md``) with a margin.
"""

import sys

import numpy as np
import pytest

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.scenes.builders.half_space import SPHERE_FRETTING, build_from_scene
from shakedown.studies import half_space as hs

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

E, R, P, F = 1.0, 1.0, 1e-3, 0.5


def setup(n, nu=0.0):
    mats = ((E, nu), (E, nu))
    e_star = E / (2 * (1 - nu**2))
    a = float(cont.hertz_radius(P, R, e_star))
    m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * a, friction=F, materials=mats)
    return m, a, cont.tangential_compliance_constant(mats)


@pytest.fixture(scope="module")
def model15():
    return setup(15)


def test_cattaneo_mindlin_stick_radius_and_compliance(model15):
    # measured at n = 15 (12.5 cells across the contact): c 0.3 %, 0.6 %, 0.9 %; delta 0.4 %
    m, a, ct = model15
    states = hs.static_path(m, [(0, 0, P), (0.3 * F * P, 0, P), (0.6 * F * P, 0, P),
                                (0.9 * F * P, 0, P)], substeps=3)
    for X, (res, qf, pf) in zip((0.0, 0.3, 0.6, 0.9), states, strict=True):
        assert res.success
        assert np.sum(pf) == pytest.approx(P) and np.sum(qf[:, 0]) == pytest.approx(X * F * P, abs=1e-12 * P)
        if X == 0:
            continue
        c = cont.cattaneo_mindlin_radius(X * F * P, P, F, a)
        assert hs.stick_radius(m, qf, pf, X * F * P, P) == pytest.approx(c, rel=0.015)
        d = hs.tangential_displacement(m, qf, pf)
        assert d[0] == pytest.approx(cont.mindlin_displacement(X * F * P, P, F, a, ct), rel=0.01)
        assert abs(d[1]) <= 1e-12 * abs(d[0])  # nu = 0: no transverse displacement
        # cells stick inside c and slip at f p outside, as in Mindlin's solution
        st = np.insert(res.states, m.reference, 0)
        slip, stick = st == 1, st == 0
        rho = np.hypot(*m.xy_cells.T)
        assert np.all(rho[slip] > c - m.h) and np.all(rho[stick] < c + m.h)
        np.testing.assert_allclose(np.hypot(*qf[slip].T), F * pf[slip], rtol=1e-8)


def test_mindlin_deresiewicz_dissipation_and_loop(model15):
    m, a, ct = model15
    X = 0.6
    run, loop = hs.fretting_run(m, P, X * F * P, steps_per_cycle=40, max_cycles=4)
    W = cont.mindlin_deresiewicz_dissipation(X * F * P, P, F, a, ct)
    assert run.status == "periodic"
    # discretisation error of W oscillates with the grid (+15 %, -11 %, -0.9 %, +1.9 % at
    # n = 11, 15, 21, 25 for X = 0.5; benchmarks/RESULTS_half_space.md): 15 % here
    assert run.steady_dissipation == pytest.approx(W, rel=0.15)
    # the engine's dissipation sum_k f p |dv| and the loop area closed integral Q d(delta) are
    # independent measures (trapezoidal rule on 40 instants: O(1/S^2), measured 0.4 %)
    assert loop["W_loop"] == pytest.approx(run.steady_dissipation, rel=0.01)
    # the reference cell stays stuck, so the condensation is exact along the run
    qm, pm = loop["q_full"][:, m.reference], loop["p_full"][:, m.reference]
    assert np.all(np.hypot(*qm.T) < F * pm)


def test_poisson_ratio_makes_mindlin_approximate():
    # nu = 0.3: Cerruti's x^2/r^3 term gives transverse shear q_y (Mindlin assumes q_y = 0);
    # measured max |q_y| / (f p0 h^2) = 0.014 at n = 11: small but not zero
    m, a, _ = setup(11, nu=0.3)
    res, qf, pf = hs.static_path(m, [(0, 0, P), (0.6 * F * P, 0, P)], substeps=3)[-1]
    p0 = cont.hertz_peak_pressure(P, R, m.e_star)
    qy = np.abs(qf[:, 1]).max() / (F * p0 * m.h**2)
    assert 1e-4 < qy < 0.1
    assert np.sum(qf[:, 1]) == pytest.approx(0.0, abs=1e-12 * P)


def test_sphere_fretting_scene_builds_and_rejects_bad_keys():
    raw = tomllib.loads(SPHERE_FRETTING.read_text())
    assert raw["model"]["kind"] == "half_space"
    raw["model"]["n_cells"] = 7
    system, load, model = build_from_scene(raw["model"], raw["load"], None)
    assert system.dim == 3 and system.n_nodes == 48 and not system.is_coupled
    assert load.dim == 3 and load.q0.shape == (48, 2)
    for bad_model, bad_load, match in (({**raw["model"], "colour": 1}, raw["load"], "colour"),
                                       (raw["model"], {"Qx": 1.0}, "P0"),
                                       ({**raw["model"], "profile": "ellipsoid"}, raw["load"], "width"),
                                       ({**raw["model"], "friction": -1.0}, raw["load"], "friction")):
        with pytest.raises(sd.SceneError, match=match):
            build_from_scene(bad_model, bad_load, None)


@pytest.mark.slow  # ~20 s on the shared machine (imports, plots)
def test_sphere_fretting_scene_runs_from_the_cli(tmp_path):
    from shakedown.scenes.cli import main

    out = tmp_path / "out"
    rc = main(["run", "sphere_fretting", "-q", "-o", str(out), "--set", "model.n_cells=9",
               "--set", "fretting.steps_per_cycle=16", "--set", "fretting.amplitudes=[0.5, 1.0]"])
    assert rc == 0
    import json

    summary = json.loads((out / "fretting.json").read_text())
    assert summary["status"] == "periodic" and summary["reference_cell_ok"]
    assert summary["steady_dissipation"] == pytest.approx(summary["W_loop"], rel=0.05)
    assert summary["verdict"].startswith("Partial slip")
    for name in ("contact_maps.png", "stuck_zone.png", "hysteresis.png", "steady_cycle.csv",
                 "dissipation_amplitude.png", "dissipation_amplitude.csv"):
        assert (out / name).stat().st_size > 0


def test_fretting_analysis_matrix_free_engine_matches_the_dense_one(tmp_path):
    import json

    from shakedown.scenes.cli import main

    out = {}
    for engine in ("dense", "fft"):
        rc = main(["run", "sphere_fretting", "-q", "-o", str(tmp_path / engine), "--set",
                   "model.n_cells=9", "--set", "fretting.steps_per_cycle=16", "--set",
                   f"fretting.engine={engine}", "--set", "fretting.plots=false"])
        assert rc == 0
        out[engine] = json.loads((tmp_path / engine / "fretting.json").read_text())
    d, f = out["dense"], out["fft"]
    assert f["engine"] == "fft" and d["engine"] == "dense"
    for key in ("steady_dissipation", "W_loop"):
        assert f[key] == pytest.approx(d[key], rel=1e-6)
    assert (f["n_stuck_cells"], f["status"], f["cycles_to_steady"]) == \
        (d["n_stuck_cells"], d["status"], d["cycles_to_steady"])


def test_a_scene_above_the_dense_limit_builds_without_the_dense_system():
    from shakedown.models.half_space import DENSE_MAX_CELLS
    from shakedown.scenes.builders.half_space import build

    n = int(np.sqrt(DENSE_MAX_CELLS)) + 1
    system, load, m = build({"profile": "sphere", "radius": 1.0, "n_cells": n, "E1": 1.0, "nu1": 0.0,
                             "E2": 1.0, "nu2": 0.0}, {"P0": 1e-3, "Qx": 2e-4}, None)
    assert m.n_cells > DENSE_MAX_CELLS and "stiffness" not in m.__dict__
    with pytest.raises(sd.SceneError, match="DENSE_MAX_CELLS.*fretting"):
        _ = system.A
    with pytest.raises(sd.SceneError, match="no dense load"):
        _ = load.q0
