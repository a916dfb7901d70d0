"""Bring your own model: matrices and load records from files (shakedown.models.formats).

Reference data: data/models/make_examples.py writes every example file from a model the
package also builds another way (the built-in two_node_coupled scene; a unit square assembled
by scikit-fem), so reading the file must give that model back.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.models.formats import (
    ModelFileError,
    condense_stiffness,
    read_load_record,
    read_matrix,
    read_vector,
)
from shakedown.scenes import build, load_scene
from shakedown.scenes.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "data" / "scenes"
MODELS = ROOT / "data" / "models"


def _built(name):
    return build(load_scene(SCENES / f"{name}.toml"))


# ---------------------------------------------------------------- reduced stiffness files
@pytest.mark.parametrize("scene", ["two_node_mtx", "two_node_csv", "two_node_mat", "two_node_npz"])
def test_reduced_stiffness_files_give_the_builtin_system(scene):
    ref, ref_load, _ = build(load_scene("two_node_coupled"))
    system, load, _ = _built(scene)
    # written with 17 significant digits (or binary .mat): every double round-trips exactly
    np.testing.assert_array_equal(system.K, ref.K)
    np.testing.assert_array_equal(system.friction, ref.friction)
    np.testing.assert_array_equal(load.q0, ref_load.q0)


def test_scenes_from_mtx_mat_gmsh_and_csv_record_run(tmp_path, capsys):
    """The issue's 'done when': a scene from each new format runs through the command."""
    for name in ("two_node_mtx", "two_node_mat", "gmsh_square", "two_node_record",
                 "square_full_stiffness"):
        out = tmp_path / name
        assert main(["bounds", str(SCENES / f"{name}.toml"), "-o", str(out), "-q"]) == 0, name
        assert (out / "bounds.json").is_file() and (out / "manifest.json").is_file()
    assert "lam2" in capsys.readouterr().out


# ---------------------------------------------------------------- full stiffness + Gmsh
def test_gmsh_mesh_equals_the_generated_rectangle():
    pytest.importorskip("skfem")
    pytest.importorskip("meshio")
    system, load, cm = _built("gmsh_square")
    fe = sd.fe
    ref = fe.FEModel(fe.rectangle(1.0, 1.0, 4, 4, element="P1"), fe.isotropic(1.0, 0.3),
                     dirichlet=["top"], contact=["bottom"],
                     loads={"static": [fe.BodyForce([0.01, -0.02])],
                            "cyclic": [fe.BodyForce([0.005, 0.0])]}, friction=0.5).condense()
    # the .msh holds the same nodes (16 digits) and triangles: same matrix up to round-off
    # of the solves (measured 2e-16 relative)
    np.testing.assert_allclose(system.K, ref.K, rtol=1e-12, atol=1e-12 * np.abs(ref.K).max())
    assert cm.counts["n_contact_nodes"] == 5


def test_full_stiffness_condensation_matches_the_fe_package():
    """Cross-check: a full K exported from scikit-fem and condensed by condense_stiffness gives
    the same system and welded reactions as shakedown.fe's own condensation (gmsh_square)."""
    pytest.importorskip("skfem")
    full, full_load, _ = _built("square_full_stiffness")
    fe_sys, fe_load, _ = _built("gmsh_square")
    scale = np.abs(fe_sys.K).max()
    # two independent factorizations of a 50-DOF SPD matrix (condition ~1e2): measured
    # difference 4e-16 * max|K|; 1e-12 leaves room for other BLAS
    np.testing.assert_allclose(full.K, fe_sys.K, rtol=0, atol=1e-12 * scale)
    r_scale = np.abs(fe_load.p0).max()
    for name in ("q0", "p0"):
        np.testing.assert_allclose(getattr(full_load, name), getattr(fe_load, name), rtol=0,
                                   atol=1e-12 * r_scale)
    np.testing.assert_allclose(full_load.q_cos, fe_load.q_cos, rtol=0, atol=1e-12 * r_scale)
    assert np.all(full_load.p0 > 0)  # the body force presses the bottom on the floor


def _spring_model(k1=3.0, k2=1.5, kn=2.0, c=0.4):
    """DOFs (0-based): 0 tangential, 1 normal (both outward / along t), 2 interior, 3 fixed.

    Tangential DOF 0 is tied to interior DOF 2 by k1, which is tied to the support DOF 3 by
    k2 (two springs in series: k1 k2 / (k1 + k2)); the normal DOF 1 sits on spring kn; c couples
    DOFs 0 and 1 directly.
    """
    K = np.array([[k1, c, -k1, 0.0],
                  [c, kn, 0.0, 0.0],
                  [-k1, 0.0, k1 + k2, -k2],
                  [0.0, 0.0, -k2, k2]])
    return K


def test_condense_stiffness_springs_in_series():
    k1, k2, kn, c = 3.0, 1.5, 2.0, 0.4
    cs = condense_stiffness(_spring_model(k1, k2, kn, c), [0], [1], fixed_dofs=[3])
    A, B, C = cs.blocks
    assert A[0, 0] == pytest.approx(k1 * k2 / (k1 + k2), rel=1e-14)
    assert C[0, 0] == pytest.approx(kn, rel=1e-14)
    # w = -u_n for an outward DOF: the coupling changes sign (MODEL.md s.1 frame)
    assert B[0, 0] == pytest.approx(-c, rel=1e-14)
    flipped = condense_stiffness(_spring_model(k1, k2, kn, c), [0], [1], fixed_dofs=[3],
                                 normal_sign=-1)
    assert flipped.blocks[1][0, 0] == pytest.approx(c, rel=1e-14)
    np.testing.assert_array_equal(flipped.blocks[0], A)
    np.testing.assert_array_equal(flipped.blocks[2], C)


def test_welded_reaction_signs_follow_model_md():
    """MODEL.md s.1 sanity check: a tangential push F gives q_w = -F; pressing the body onto
    the obstacle (a force along the outward normal, towards it) gives a compressive p_w = +F."""
    cs = condense_stiffness(_spring_model(), [0], [1], fixed_dofs=[3])
    F = 0.7
    q, p = cs.welded([F, 0.0, 0.0, 0.0])
    assert q[0] == pytest.approx(-F, rel=1e-14) and p[0] == 0
    q, p = cs.welded([0.0, F, 0.0, 0.0])
    assert p[0] == pytest.approx(F, rel=1e-14) and q[0] == 0
    _, p = cs.welded([0.0, -F, 0.0, 0.0])  # pulled away from the obstacle: tension
    assert p[0] == pytest.approx(-F, rel=1e-14)
    # a force on the interior DOF reaches the contact node through the springs: k1 / (k1 + k2)
    q, _ = cs.welded([0.0, 0.0, F, 0.0])
    assert q[0] == pytest.approx(-F * 3.0 / 4.5, rel=1e-14)


@pytest.mark.parametrize("factor", [1e-6, 3.7e-3, 1.0, 6.1e5, 1e12])
def test_condensation_is_unit_free(factor):
    """Stiffness in other units (factor 1e-6 .. 1e12): the reduced K scales by the same factor."""
    K = _spring_model()
    ref = condense_stiffness(K, [0], [1], fixed_dofs=[3]).K
    scaled = condense_stiffness(K * factor, [0], [1], fixed_dofs=[3]).K
    np.testing.assert_allclose(scaled / factor, ref, rtol=1e-14, atol=0)


def test_condensation_without_scikit_fem_gives_the_same_system(monkeypatch):
    """The plain-SuperLU fallback (no 'fe' extra) and the shared boundary-layer factorization
    agree: same Schur complement and welded reactions to round-off (measured 4e-16)."""
    from shakedown.models.formats import stiffness

    Kfull = read_matrix(MODELS / "square_full_K.mtx", sparse=True)
    f = read_vector(MODELS / "square_force.mtx")
    args = ([1, 11, 21, 31, 41], [2, 12, 22, 32, 42])
    kw = dict(fixed_dofs=[9, 10, 19, 20, 29, 30, 39, 40, 49, 50], normal_sign=-1, dof_base=1)
    shared = condense_stiffness(Kfull, *args, **kw)
    monkeypatch.setattr(stiffness, "_factorize", lambda Kii, Kci, n: stiffness._SuperLU(Kii))
    plain = condense_stiffness(Kfull, *args, **kw)
    scale = np.abs(shared.K).max()
    np.testing.assert_allclose(plain.K, shared.K, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(plain.welded(f), shared.welded(f), rtol=0,
                               atol=1e-13 * np.abs(f).sum())


def test_condense_refuses_a_floating_body_and_bad_dofs():
    K = _spring_model()
    with pytest.raises(sd.InputError, match="fixed_dofs"):
        # k1 = 0 and DOF 3 not held: the interior springs float free of the contact DOFs
        condense_stiffness(_spring_model(k1=0.0), [0], [1])
    with pytest.raises(sd.InputError, match=r"normal_dofs\[1\] = 5 is outside .* 1\.\.4"):
        condense_stiffness(K, [1], [5], fixed_dofs=[4], dof_base=1)
    with pytest.raises(sd.InputError, match="twice"):
        condense_stiffness(K, [0], [0], fixed_dofs=[3])
    with pytest.raises(sd.InputError, match="not symmetric"):
        bad = K.copy()
        bad[0, 2] += 1e-3
        condense_stiffness(bad, [0], [1], fixed_dofs=[3])


def test_uncondensed_stiffness_equals_the_condensed_one(tmp_path):
    """``uncondensed_stiffness`` (K_z signed and reordered, never condensed) against
    ``condense_stiffness`` of the same export: the same reduced stiffness, welded reactions,
    bounds and run; the scene key ``sparse = true`` with ``stiffness_file`` builds it."""
    from shakedown.model.uncondensed import UncondensedSystem
    from shakedown.models.formats import uncondensed_stiffness

    Kfull = read_matrix(MODELS / "square_full_K.mtx", sparse=True)
    f = read_vector(MODELS / "square_force.mtx")
    args = ([1, 11, 21, 31, 41], [2, 12, 22, 32, 42])
    kw = dict(fixed_dofs=[9, 10, 19, 20, 29, 30, 39, 40, 49, 50], normal_sign=-1, dof_base=1)
    cs = condense_stiffness(Kfull, *args, **kw)
    us = uncondensed_stiffness(Kfull, *args, **kw)
    system = us.system(0.5)
    assert isinstance(system, UncondensedSystem) and us.K is None and us.n_nodes == 5
    scale = np.abs(cs.K).max()
    np.testing.assert_allclose(system.K.toarray(), cs.K, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(np.hstack(us.blocks), np.hstack(cs.blocks), rtol=0,
                               atol=1e-13 * scale)
    np.testing.assert_allclose(us.welded(f), cs.welded(f), rtol=0,
                               atol=1e-13 * np.abs(f).sum())
    # the springs: tangential k1 k2 / (k1 + k2), the coupling's sign (MODEL.md s.1 frame)
    sp_ = uncondensed_stiffness(_spring_model(), [0], [1], fixed_dofs=[3]).system(0.3)
    np.testing.assert_allclose(sp_.K.toarray(), condense_stiffness(
        _spring_model(), [0], [1], fixed_dofs=[3]).K, rtol=1e-14)
    # a body that is not held: refused, naming the stiffness
    with pytest.raises(sd.InputError, match="Kz"):
        uncondensed_stiffness(_spring_model(k1=0.0), [0], [1])
    # the scene route
    scene = (SCENES / "square_full_stiffness.toml").read_text().replace(
        "friction = 0.5", "friction = 0.5\nsparse = true").replace("../models/",
                                                                  str(MODELS) + "/")
    (tmp_path / "s.toml").write_text(scene)
    s2, load2, m2 = build(load_scene(tmp_path / "s.toml"))
    s1, load1, _ = _built("square_full_stiffness")
    assert isinstance(s2, UncondensedSystem) and m2.K is None
    np.testing.assert_allclose(load2.q0, load1.q0, rtol=0, atol=1e-13 * np.abs(load1.q0).max())
    b1, b2 = sd.shakedown_bounds(s1, load1), sd.shakedown_bounds(s2, load2)
    assert b2.lam1 == pytest.approx(b1.lam1, rel=1e-9)
    assert b2.lam2 == pytest.approx(b1.lam2, rel=1e-9)
    with pytest.raises(sd.SceneError, match="two sources"):
        (tmp_path / "t.toml").write_text(scene.replace("sparse = true",
                                                       "sparse = true\nA = [[1.0]]"))
        build(load_scene(tmp_path / "t.toml"))
    r1 = sd.solve_cycles(s1, load1, 1.1 * b1.lam2, steps_per_cycle=32, max_cycles=40)
    r2 = sd.solve_cycles(s2, load2, 1.1 * b1.lam2, steps_per_cycle=32, max_cycles=40)
    assert r1.status == r2.status and r1.n_cycles == r2.n_cycles
    assert r2.steady_dissipation == pytest.approx(r1.steady_dissipation, rel=1e-8)


# ---------------------------------------------------------------- load records
def test_record_gives_the_harmonic_load_within_its_sampling_error():
    cycle, fit = read_load_record(MODELS / "two_node_record.csv", 0.02, n_samples=256)
    ref = load_scene("two_node_coupled")
    _, ref_load, _ = build(ref)
    t = np.arange(256) / 256
    q_ref = ref_load.q0 + np.cos(2 * np.pi * t)[:, None] * ref_load.q_cos[0] + \
        np.sin(2 * np.pi * t)[:, None] * ref_load.q_sin[0]
    q = cycle.q0 + cycle.q1
    # the record has ~200 uneven samples per period of a unit-frequency harmonic of amplitude
    # 0.5: linear interpolation errs by at most (2 pi h)^2 / 8 * 0.5 with h the largest gap
    rec = np.loadtxt(MODELS / "two_node_record.csv", delimiter=",", skiprows=1)
    h = np.diff(rec[:, 0]).max() / 0.02
    bound = (2 * np.pi * h) ** 2 / 8 * 0.5 + fit.max_error
    assert np.abs(q - q_ref).max() <= bound
    assert 0 <= fit.relative_error < 1e-2 and fit.n_record_samples > 100


def _pw_linear_record(path, period, t_scale=1.0, n=16):
    """A periodic piecewise-linear signal with breakpoints on the n-sample grid, recorded at
    those breakpoints plus the midpoints (where it is linear): resampling is exact."""
    rng = np.random.default_rng(5)
    knots = rng.normal(size=(n, 2)) + np.array([0.0, 3.0])
    tk = np.arange(2 * n + 1) / (2 * n)
    vals = np.array([np.interp(tk, np.arange(n + 1) / n, np.append(knots[:, k], knots[0, k]))
                     for k in range(2)]).T
    rows = np.column_stack([tk * period * t_scale, vals])
    np.savetxt(path, rows, delimiter=",", header="t,q_1,p_1", comments="", fmt="%.17g")
    return knots


@given(st.sampled_from([1e-6, 2.3e-2, 1.0, 7.7e4, 1e12]))
@settings(max_examples=5, deadline=None)
def test_record_resampling_is_exact_on_its_grid_in_any_time_unit(tmp_path_factory, t_scale):
    path = tmp_path_factory.mktemp("rec") / "r.csv"
    knots = _pw_linear_record(path, 1.0, t_scale)
    cycle, fit = read_load_record(path, t_scale, n_samples=16)
    # the samples are the knots themselves up to the rounding of t (relative 1e-16 of t)
    np.testing.assert_allclose(cycle.q0 + cycle.q1[:, 0], knots[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(cycle.p0 + cycle.p1[:, 0], knots[:, 1], rtol=0, atol=1e-12)
    assert fit.relative_error < 1e-12


def test_record_refuses_a_coarse_resampling(tmp_path):
    path = tmp_path / "r.csv"
    _pw_linear_record(path, 1.0, n=64)
    with pytest.raises(ModelFileError, match=r"r\.csv.*raise n_samples"):
        read_load_record(path, 1.0, n_samples=4, max_error=1e-3)


# ---------------------------------------------------------------- bad files
SECRET = "SECRET-CONTENT-42"


@pytest.mark.parametrize("name, text, call, expected", [
    ("k.mtx", f"{SECRET}\n1 1\n", "matrix", r"k\.mtx: line 1: not a Matrix Market header"),
    ("k.csv", f"1,2\n3,{SECRET}\n", "matrix", r"k\.csv: line 2, column 2: not a number \(text\)"),
    ("k.csv", "1,2\n3\n", "matrix", r"k\.csv: line 2 has 1 columns"),
    ("k.txt", "1", "matrix", r"k\.txt: unknown file type '\.txt'"),
    ("r.csv", f"t,q_1,p_1\n0,1,1\n0,{SECRET},1\n", "record", r"r\.csv: line 3, column 2 \('q_1'\)"),
    ("r.csv", "t,q_1,p_1\n0,1,1\n0,1,1\n", "record", r"r\.csv: time must increase"),
    ("r.csv", f"t,q_1,{SECRET}\n0,1,1\n", "record", r"r\.csv: header column 3 is not"),
    ("r.csv", "t,q_1,p_1,q_2\n0,1,1,1\n1,1,1,1\n", "record", r"r\.csv: columns missing: p_2"),
    ("r.csv", "t,q_1,p_1\n0,1,1\n0.5,1,1\n", "record", r"r\.csv: the record covers t = 0\.\.0\.5"),
])
def test_bad_files_name_the_file_and_the_problem_not_the_content(tmp_path, name, text, call,
                                                                 expected):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ModelFileError, match=expected) as info:
        read_matrix(path) if call == "matrix" else read_load_record(path, 1.0)
    assert SECRET not in str(info.value)
    assert isinstance(info.value, sd.InputError)


def test_containers_name_the_missing_variable_and_refuse_pickles(tmp_path):
    scipy.io.savemat(tmp_path / "m.mat", {"Ktt": np.eye(2)})
    with pytest.raises(ModelFileError, match=r"m\.mat: has no variable 'K'; it holds Ktt"):
        read_matrix(tmp_path / "m.mat", "K")
    np.save(tmp_path / "o.npy", np.array([{"a": 1}], dtype=object))
    np.savez(tmp_path / "o.npz", K=np.array([{"a": 1}], dtype=object))
    with pytest.raises(ModelFileError, match=r"o\.npz: array 'K' holds Python objects"):
        read_matrix(tmp_path / "o.npz", "K")
    with pytest.raises(ModelFileError, match="no such file"):
        read_vector(tmp_path / "missing.mtx")
    np.savez(tmp_path / "v.npz", f=np.ones(3))
    with pytest.raises(ModelFileError, match="has 3 entries; expected 4"):
        read_vector(tmp_path / "v.npz", "f", size=4)


def test_scene_errors_name_the_key_and_the_file(tmp_path):
    (tmp_path / "k.mtx").write_text("%%MatrixMarket matrix array real general\n3 3\n" +
                                    "1\n" * 9)
    (tmp_path / "s.toml").write_text('[model]\nkind = "matrices"\nK_file = "k.mtx"\n'
                                     'friction = 0.5\n[load]\nq0 = [0]\np0 = [1]\n')
    with pytest.raises(sd.SceneError, match=r"s\.toml: \[model\] K_file 'k\.mtx'.*square of size 2N"):
        build(load_scene(tmp_path / "s.toml"))
    (tmp_path / "s.toml").write_text('[model]\nkind = "matrices"\nK_file = "k.mtx"\n'
                                     'tangential_dofs = [1]\nfriction = 0.5\n')
    with pytest.raises(sd.SceneError, match="need 'stiffness_file'"):
        build(load_scene(tmp_path / "s.toml"))
