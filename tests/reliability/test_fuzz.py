"""Fuzz the public entry points and the CLI with malformed arrays and scenes (issue 10).

Every call must end in a subclass of :class:`shakedown.ShakedownError` (an input error naming
the field) or in a result whose ``status`` says what happened; a raw ``ValueError`` /
``TypeError`` / ``IndexError`` / LAPACK crash, or a file outside the output folder, fails the
test.  Budget: ``max_examples`` 25-50 per entry point (a few seconds each); derandomised in CI
(the ``ci`` hypothesis profile of tests/conftest.py), exploring freely in local runs.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import crack_networks as cn
import shakedown as sd
from shakedown import stability as stab

FUZZ = settings(max_examples=50, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                       HealthCheck.function_scoped_fixture])

ODD_FLOATS = st.sampled_from([np.nan, np.inf, -np.inf, 0.0, -0.0, 1e308, -1e308, 5e-324,
                              1e-300, -1.0, 1.0, 2.5])
FLOATS = st.one_of(st.floats(-1e6, 1e6, allow_nan=False), ODD_FLOATS)


def shaped(n_max=3, dims=(0, 1, 2)):
    return st.tuples(*[st.integers(0, n_max)] * 2).flatmap(
        lambda s: st.sampled_from(dims).map(lambda d: s[:d]))


def bad_arrays(n_max=3, dims=(0, 1, 2)):
    """Arrays and array-likes a careless caller might pass."""
    return st.one_of(
        shaped(n_max, dims).flatmap(lambda s: hnp.arrays(float, s, elements=FLOATS)),
        shaped(n_max, dims).flatmap(lambda s: hnp.arrays(complex, s)),
        shaped(n_max, dims).flatmap(lambda s: hnp.arrays(bool, s)),
        st.sampled_from([None, "abc", [[1.0, 2.0], [3.0]], [["x", 1.0]], {"a": 1}, object(),
                         [], [[]], 1.0, np.nan, [1.0, None]]),
    )


def survives(fn, *args, **kwargs):
    """Run ``fn``; a package error is fine, anything else is a failure of the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn(*args, **kwargs)
        except sd.ShakedownError as exc:
            assert str(exc), "an error must say what is wrong"
            return None


def good_system(n=2):
    rng = np.random.default_rng(n)
    M = rng.standard_normal((2 * n, 2 * n))
    K = M @ M.T + np.eye(2 * n)
    return sd.DiscreteSystem(K[:n, :n], 0.3 * K[:n, n:], K[n:, n:], 0.5)


SYSTEM = good_system()
LOAD = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.2])


# ------------------------------------------------------------------ model objects
@FUZZ
@given(A=bad_arrays(), B=bad_arrays(), C=bad_arrays(), f=bad_arrays(dims=(0, 1)))
def test_fuzz_discrete_system(A, B, C, f):
    s = survives(sd.DiscreteSystem, A, B, C, f)
    if s is not None:
        assert np.all(np.isfinite(s.K)) and s.n_nodes >= 1


@FUZZ
@given(q0=bad_arrays(dims=(0, 1)), p0=bad_arrays(dims=(0, 1)), qc=bad_arrays(),
       q1=bad_arrays(), n=st.one_of(st.integers(-2, 5), ODD_FLOATS, st.just("7")),
       order=st.one_of(st.lists(st.integers(-3, 3), max_size=3), bad_arrays(dims=(1,))))
def test_fuzz_load_cycle(q0, p0, qc, q1, n, order):
    h = survives(sd.LoadCycle.from_harmonics, q0, p0, q_cos=qc)
    s = survives(sd.LoadCycle.from_samples, q0, p0, q1, q1)
    for load in (h, s, LOAD):
        if load is not None:
            survives(load.to_samples, n)
            survives(load.permuted, order)
            survives(load.sampling_error, n)


# ------------------------------------------------------------------ analyses
@FUZZ
@given(q0=bad_arrays(dims=(1,)), qc=bad_arrays(dims=(1, 2)))
def test_fuzz_bounds(q0, qc):
    load = survives(sd.LoadCycle.from_harmonics, q0, [1.0, 1.0], q_cos=qc)
    if load is not None:
        b = survives(sd.shakedown_bounds, SYSTEM, load)
        if b is not None:
            assert isinstance(b.status, str) and b.status


@settings(FUZZ, max_examples=40)
@given(lam=st.one_of(FLOATS, st.just("1"), st.none()),
       steps=st.one_of(st.integers(-1, 20), ODD_FLOATS),
       cycles=st.one_of(st.integers(-1, 5), ODD_FLOATS),
       v0=st.one_of(st.none(), bad_arrays(dims=(1,))),
       w0=st.one_of(st.none(), bad_arrays(dims=(1,))),
       method=st.sampled_from(["implicit", "events", "bogus", None]))
def test_fuzz_solve_cycles(lam, steps, cycles, v0, w0, method):
    run = survives(sd.solve_cycles, SYSTEM, LOAD, lam, initial_slip=v0, initial_gap=w0,
                   method=method, steps_per_cycle=steps, max_cycles=cycles)
    if run is not None:
        assert run.status in ("periodic", "not_converged", "step_failed", "non_finite")
        if run.status == "periodic":
            assert np.isfinite(run.steady_dissipation)


@FUZZ
@given(K=bad_arrays(n_max=4), prof=st.one_of(st.none(), bad_arrays(dims=(0, 1))),
       chi=bad_arrays(dims=(0, 1)), method=st.sampled_from(stab.METHODS + ("nope",)),
       lam=st.one_of(FLOATS, st.just("x")))
def test_fuzz_mceip(K, prof, chi, method, lam):
    part = survives(stab.NodePartition.all_slip, 2, chi=chi)
    for k in (K, SYSTEM.K, SYSTEM):
        r = survives(stab.mceip_mu, k, part or stab.NodePartition.all_slip(2, 1.0),
                     method=method, friction_profile=prof, lam=lam)
        if r is not None:
            assert r.status in ("found", "none", "not-converged")


@FUZZ
@given(gap=bad_arrays(dims=(0, 1)), q=bad_arrays(dims=(0, 1)), p=bad_arrays(dims=(0, 1)),
       f=bad_arrays(dims=(0, 1)), mu=FLOATS)
def test_fuzz_classify_and_growth(gap, q, p, f, mu):
    survives(stab.classify_nodes, gap, q, p, f)
    survives(stab.growth_rates, SYSTEM, stab.NodePartition.all_slip(2, 1.0), mu, lam_max=mu)
    survives(stab.layer_growth_rates, q, mu)


@settings(FUZZ, max_examples=25)
@given(lam=st.one_of(FLOATS, st.just("x")), states=st.one_of(st.integers(-1, 3), bad_arrays()),
       n_evals=st.one_of(st.integers(-1, 3), ODD_FLOATS), times=bad_arrays(dims=(0, 1)))
def test_fuzz_steady_uniqueness_cycle_stability(lam, states, n_evals, times):
    from shakedown.evolution import steady_cycle, uniqueness_study

    sc = survives(steady_cycle, SYSTEM, LOAD, lam, max_evaluations=n_evals, steps_per_cycle=16)
    if sc is not None:
        assert isinstance(sc.status, str)
    u = survives(uniqueness_study, SYSTEM, LOAD, lam, states, steps_per_cycle=16,
                 max_cycles=5)
    if u is not None:
        assert len(u.table) >= 1
    run = sd.solve_cycles(SYSTEM, LOAD, 1.0, steps_per_cycle=16)
    survives(stab.stability_along_cycle, SYSTEM, run, times=times)
    survives(stab.stability_along_cycle, SYSTEM, times)
    survives(sd.safe_region, SYSTEM, LOAD, lam)


# ------------------------------------------------------------------ model builders
@FUZZ
@given(c=bad_arrays(dims=(0, 1, 2)), a=bad_arrays(dims=(0, 1)), ang=bad_arrays(dims=(0, 1)),
       mu=FLOATS, nu=FLOATS, f=FLOATS)
def test_fuzz_cracks(c, a, ang, mu, nu, f):
    cs = survives(cn.CrackSet, c, a, ang)
    if cs is not None:
        survives(cn.kachanov_model, cs, shear_modulus=mu, poisson_ratio=nu, friction=f)


@settings(FUZZ, max_examples=30)
@given(w=FLOATS, h=FLOATS, nx=st.one_of(st.integers(-1, 3), ODD_FLOATS),
       E=FLOATS, nu=FLOATS)
def test_fuzz_fe(w, h, nx, E, nu):
    mesh = survives(sd.fe.rectangle, w, h, nx, 2)
    mat = survives(sd.fe.isotropic, E, nu)
    if mesh is not None and mat is not None:
        survives(lambda: sd.fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"])
                 .condense().system)


# ------------------------------------------------------------------ scenes and the CLI
VALUES = st.one_of(
    FLOATS.filter(np.isfinite), st.integers(-5, 300), st.booleans(),
    st.sampled_from(["", "../../escaped", "/etc/passwd", "bogus", "..", "x/y", "\u00e9t\u00e9"]),
    st.lists(st.floats(-3, 3), max_size=3), st.lists(st.lists(st.floats(-3, 3), max_size=3),
                                                     max_size=3),
)
BASE = {
    "scene": {"name": "fz"},
    "model": {"kind": "matrices", "A": [[2.0, 0.5], [0.5, 2.0]], "B": [[0.2, 0.1], [-0.1, 0.3]],
              "C": [[3.0, 0.0], [0.0, 3.0]], "friction": 0.4},
    "load": {"q0": [0.0, 0.1], "p0": [1.0, 1.0], "q_cos": [1.0, 0.0]},
    "analyses": {"bounds": {"plots": False}},
}
KEYS = [("scene", "name"), ("model", "kind"), ("model", "A"), ("model", "friction"),
        ("model", "file"), ("model", "symmetry_rtol"), ("load", "q0"), ("load", "q_cos"),
        ("load", "file"), ("load", "q1"), ("analyses", "bounds"), ("analyses", "bogus"),
        ("model", "B"), ("load", "p0"), ("analyses", "cycles"), ("analyses", "stability")]


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return repr(v) if np.isfinite(v) else ("nan" if np.isnan(v) else
                                               ("inf" if v > 0 else "-inf"))
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    return str(v)


def to_toml(scene):
    out = []
    for table, body in scene.items():
        if table == "analyses":
            for name, opts in body.items():
                out.append(f"[analyses.{name}]")
                out += [f"{k} = {toml_value(v)}" for k, v in (opts or {}).items()] \
                    if isinstance(opts, dict) else []
        else:
            out.append(f"[{table}]")
            out += [f"{k} = {toml_value(v)}" for k, v in body.items()]
    return "\n".join(out) + "\n"


@st.composite
def scenes(draw):
    scene = json.loads(json.dumps(BASE))
    for _ in range(draw(st.integers(1, 3))):
        table, key = draw(st.sampled_from(KEYS))
        if table == "analyses":
            scene["analyses"][key] = draw(st.dictionaries(
                st.sampled_from(["lam", "max_cycles", "steps_per_cycle", "nope", "initial_slip",
                                 "method", "tol", "n_initial_states", "seed", "chi", "mu",
                                 "partition", "states", "time", "load_factor", "growth_rate_max",
                                 "n_growth_rates", "adjacency", "plot_lams", "sampling_scale"]),
                VALUES, max_size=3))
            scene["analyses"][key]["plots"] = False  # figures are not what is fuzzed here
        else:
            scene[table][key] = draw(VALUES)
    return to_toml(scene)


def files_outside(root, out):
    return sorted(p for p in root.rglob("*") if p.is_file() and out not in p.parents
                  and p.name != "scene.toml")


@FUZZ
@given(text=scenes())
def test_fuzz_scenes_in_process(tmp_path_factory, text):
    from shakedown.scenes.cli import main

    root = tmp_path_factory.mktemp("fz")
    (root / "scene.toml").write_text(text)
    cwd = os.getcwd()
    os.chdir(root)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main(["run", "scene.toml", "-q", "-o", "out"])
    finally:
        os.chdir(cwd)
    assert code in (0, 2)
    assert files_outside(root, root / "out") == []


@pytest.mark.parametrize("text", [
    to_toml({**BASE, "scene": {"name": "../../escaped"}}),
    to_toml({**BASE, "model": {**BASE["model"], "A": [[1.0, 2.0], [2.0, 1.0]]}}),
    to_toml({**BASE, "analyses": {"cycles": {"lam": 1e300, "plots": True}}}),
    "[model\nkind = 1",
])
def test_fuzz_cli_subprocess(tmp_path, text):
    (tmp_path / "scene.toml").write_text(text)
    env = dict(os.environ, PYTHONPATH=str(Path(sd.__file__).parents[1]),
               OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-m", "shakedown", "run", "scene.toml", "-q"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "shakedown: error:" in proc.stderr
    assert files_outside(tmp_path, tmp_path / "shakedown-out") == []


def test_fe_huge_modulus_is_refused_in_words():
    """E = 1e308 (found by test_fuzz_fe): the material's positivity check no longer overflows,
    and the assembly says that the stiffness overflows instead of a singular-matrix message
    or numpy's LinAlgError."""
    mat = sd.fe.isotropic(1e308, 0.0)
    assert np.isfinite(mat.D).all()
    mesh = sd.fe.rectangle(1.0, 1.0, 2, 2)
    with pytest.raises(sd.InputError, match="stiffness matrix overflows"):
        sd.fe.FEModel(mesh, mat, dirichlet=["top"], contact=["bottom"]).condense()
