"""Hostile input at the Python API, the scene fields and every file reader (issue 24).

Each case asserts the exact outcome: the error type and the field or file named, or the
correct answer.  The longer versions (bigger files, more steps) run under ``-m slow``.
"""

from __future__ import annotations

import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest
from hostile_common import CRACK_SCENE, error_class, run_cli, scene_text

import shakedown as sd
from shakedown.model.errors import InputError, SceneError

SYSTEM = dict(A=[[2.0, 0.5], [0.5, 2.0]], B=[[0.1, 0.0], [0.0, 0.1]], C=[[3.0, 0.2], [0.2, 3.0]])


def two_node(scale=1.0):
    return sd.DiscreteSystem(*(np.array(SYSTEM[k]) * scale for k in "ABC"), friction=0.5)


def two_load(scale=1.0):
    return sd.LoadCycle.from_harmonics(np.zeros(2), np.ones(2) * scale,
                                       q_cos=np.array([0.8, 0.3]) * scale,
                                       p_sin=np.array([0.2, 0.1]) * scale)


# ---------------------------------------------------------------- Python API: values
@pytest.mark.parametrize("field, value", [
    ("A", np.array([[True]])), ("A", [[True]]), ("B", [[False]]), ("C", [["3.0"]]),
    ("A", [[10**400]]),
])
def test_matrix_entries_must_be_numbers(field, value):
    m = {"A": [[2.0]], "B": [[0.2]], "C": [[3.0]], field: value}
    with pytest.raises(InputError, match=rf"^{field} must be"):
        sd.DiscreteSystem(m["A"], m["B"], m["C"], friction=0.4)


@pytest.mark.parametrize("lam", [True, "0.5", np.bool_(True), 10**400, -0.5, float("nan")])
def test_load_factor_must_be_a_number(lam):
    with pytest.raises(InputError, match="lam"):
        sd.solve_cycles(two_node(), two_load(), lam, steps_per_cycle=8, max_cycles=2)


def test_load_factor_as_numpy_number_is_fine():
    a = sd.solve_cycles(two_node(), two_load(), np.float32(1.5), steps_per_cycle=16)
    b = sd.solve_cycles(two_node(), two_load(), 1.5, steps_per_cycle=16)
    assert a.dissipation[-1] == b.dissipation[-1] > 0


@pytest.mark.parametrize("fd_step", [-1, 0, float("inf"), "1e-4", True])
def test_steady_cycle_fd_step_must_be_positive(fd_step):
    with pytest.raises(InputError, match="fd_step"):
        sd.steady_cycle(two_node(), two_load(), 1.5, fd_step=fd_step, steps_per_cycle=8)


@pytest.mark.parametrize("n_jobs", [True, 0, 1.5, "2"])
def test_uniqueness_n_jobs_must_be_an_integer(n_jobs):
    from shakedown.evolution.uniqueness import uniqueness_study

    with pytest.raises(InputError, match="n_jobs"):
        uniqueness_study(two_node(), two_load(), 1.5, 2, n_jobs=n_jobs, steps_per_cycle=8)


@pytest.mark.parametrize("field, value", [("E", "210e9"), ("E", True), ("nu", "0.3"),
                                          ("nu", False), ("E", 10**400)])
def test_fe_material_values_must_be_numbers(field, value):
    from shakedown.models.fe.materials import isotropic

    kw = {"E": 1.0, "nu": 0.3, field: value}
    with pytest.raises(InputError, match=rf"^{field} must be"):
        isotropic(kw["E"], kw["nu"])


def test_energy_scale_underflow_is_refused_not_a_zero_division():
    with pytest.raises(InputError, match="energy scale"):
        sd.solve_cycles(two_node(1e150), two_load(1e-150), 1.5, steps_per_cycle=16)


def test_rescaled_units_within_range_give_the_same_answer():
    ref = sd.solve_cycles(two_node(), two_load(), 1.5, steps_per_cycle=16).dissipation[-1]
    for k in (1e-9, 1e12):  # forces x k, stiffness x k: energies x k
        w = sd.solve_cycles(two_node(k), two_load(k), 1.5, steps_per_cycle=16).dissipation[-1]
        assert w / k == pytest.approx(ref, rel=1e-9)


def test_subnormal_dissipation_warns():
    from shakedown.evolution.cycle_results import _energy

    class Rec:  # one record whose dissipation is a subnormal number
        t = np.array([0.0, 1.0])
        v = np.zeros((2, 1))
        w = np.zeros((2, 1))
        dissipation = 1e-310

    load = sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0])
    with pytest.warns(RuntimeWarning, match="subnormal"):
        _energy([Rec()], load, 1.0, np.ones(2), 1.0, 1e-10)


def test_many_steps_per_cycle_cost_linearly():
    # issue 24: 10^4 steps of one node ran for more than a minute ((S-1)^2 Gram matrix)
    code = ("import shakedown as sd, time; s = sd.DiscreteSystem([[1.0]], [[0.2]], [[2.0]], "
            "friction=0.3); ld = sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.5], "
            "p_sin=[0.5]); r = sd.solve_cycles(s, ld, 1.0, steps_per_cycle=20000, max_cycles=3);"
            "print(r.dissipation[-1])")
    t = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-500:]
    assert float(r.stdout) > 0 and time.perf_counter() - t < 240


# ---------------------------------------------------------------- scene fields
def _scene_file(tmp_path, text, name="s.toml", mode="w"):
    p = tmp_path / name
    if mode == "w":
        p.write_text(text)
    else:
        p.write_bytes(text)
    return p


@pytest.mark.parametrize("A, field", [("[[true]]", "'A'"), ('[["2.0"]]', "'A'"),
                                      (f"[[{10**400}]]", "A")], ids=["bool", "text", "huge int"])
def test_scene_arrays_must_be_numbers(tmp_path, A, field):
    p = _scene_file(tmp_path, scene_text(A=A))
    code, _, err = run_cli(["bounds", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and field in err and "Traceback" not in err


def test_deeply_nested_scene_is_refused(tmp_path):
    p = _scene_file(tmp_path, scene_text() + "\n[load.x]\ny = " + "[" * 5000 + "]" * 5000)
    code, _, err = run_cli(["bounds", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and "nested" in err and str(p) in err


@pytest.mark.parametrize("data, word", [(b"\xff\xfe[\x00m\x00", "UTF-16"),
                                        (b"[scene]\nname = \"\xc3\x28\"\n", "UTF-8")])
def test_scene_in_another_encoding_is_refused(tmp_path, data, word):
    p = _scene_file(tmp_path, data, mode="b")
    code, _, err = run_cli(["bounds", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and word in err and str(p) in err


def test_negative_seed_is_refused(tmp_path):
    p = _scene_file(tmp_path, CRACK_SCENE.format(seed=-1, fmt="csv"))
    code, _, err = run_cli(["bounds", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and "'seed'" in err and ">= 0" in err


@pytest.mark.parametrize("opt", ['lam_span=["a", 2]', "lams=[true, 1.0]", 'lams=[1.0, "x"]'])
def test_option_lists_of_the_wrong_type_are_refused(tmp_path, opt):
    p = _scene_file(tmp_path, CRACK_SCENE.format(seed=1, fmt="csv"))
    key = opt.split("=")[0]
    code, _, err = run_cli(["sweep", str(p), "-q", "-o", str(tmp_path / "o"), "--set", opt])
    assert code == 2 and repr(key) in err and "Traceback" not in err


def test_stability_at_a_negative_load_factor_is_refused(tmp_path):
    p = _scene_file(tmp_path, scene_text().replace(
        "[analyses.bounds]\nplots = false", "[analyses.stability]\npartition = \"welded\"\n"
        "load_factor = -1.0\nplots = false"))
    code, _, err = run_cli(["stability", str(p), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and "load_factor" in err


# ---------------------------------------------------------------- model files
def _npz_with_header(path, shape):
    """An .npz whose member declares ``shape`` but holds 8 bytes."""
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                               "shape": shape})
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("K.npy", np.lib.format.magic(1, 0) + buf.getvalue()[8:] + b"\0" * 8)


@pytest.mark.parametrize("shape", [(10**6, 10**6), (10**9,), (3, 3)])
def test_npz_declared_sizes_are_checked_before_allocating(tmp_path, shape):
    from shakedown.models.formats.readers import ModelFileError, read_matrix

    p = tmp_path / "k.npz"
    _npz_with_header(p, shape)
    with pytest.raises(ModelFileError, match=r"k\.npz.*(declares|holds only)"):
        read_matrix(p)


@pytest.mark.parametrize("size_line", ["1000000000 1000000000 3", "3 3 100000000000"])
def test_mtx_declared_sizes_are_checked(tmp_path, size_line):
    from shakedown.models.formats.readers import ModelFileError, read_matrix

    p = tmp_path / "k.mtx"
    p.write_text(f"%%MatrixMarket matrix coordinate real general\n{size_line}\n1 1 1.0\n")
    with pytest.raises(ModelFileError, match=r"k\.mtx.*(declares|size line|dense|not a readable)"):
        read_matrix(p)


def test_mtx_pattern_file_is_refused(tmp_path):
    from shakedown.models.formats.readers import ModelFileError, read_matrix

    p = tmp_path / "k.mtx"
    p.write_text("%%MatrixMarket matrix coordinate pattern general\n2 2 2\n1 1\n2 2\n")
    with pytest.raises(ModelFileError, match="pattern"):
        read_matrix(p)


def test_mtx_real_file_still_reads(tmp_path):
    from shakedown.models.formats.readers import read_matrix

    p = tmp_path / "k.mtx"
    p.write_text("%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2.0\n2 1 0.5\n"
                 "2 2 3.0\n")
    np.testing.assert_array_equal(read_matrix(p), [[2.0, 0.5], [0.5, 3.0]])


@pytest.mark.parametrize("header, n_samples, field", [
    ("t,q_1,p_1", 10**8, "n_samples"), ("t,q_1,p_1,q_1000000000", 16, "q_1000000000"),
    ("t,q_1,p_1", "16", "n_samples"), ("t,q_1,p_1", True, "n_samples"),
])
def test_load_record_sizes_are_checked(tmp_path, header, n_samples, field):
    from shakedown.models.formats.readers import ModelFileError
    from shakedown.models.formats.records import read_load_record

    p = tmp_path / "r.csv"
    extra = ",0" if header.count(",") == 3 else ""
    p.write_text(header + "\n" + "".join(f"{t},{np.cos(t)},1{extra}\n" for t in range(5)))
    with pytest.raises(ModelFileError, match=field):
        read_load_record(p, 4.0, n_samples=n_samples)


def test_huge_model_file_is_refused_by_its_size(tmp_path, monkeypatch):
    from shakedown.models.formats.readers import ModelFileError, read_matrix

    p = tmp_path / "k.mtx"
    p.write_text("%%MatrixMarket matrix array real general\n1 1\n2.0\n")
    with open(p, "r+b") as f:
        f.truncate(5 * 2**30)  # 5 GiB (sparse): the default limit is 4 GiB
    t = time.perf_counter()
    with pytest.raises(ModelFileError, match=r"k\.mtx.*bytes, more than the limit"):
        read_matrix(p)
    assert time.perf_counter() - t < 5  # refused by its size, not read


def test_mesh_reader_that_exits_is_contained(tmp_path, monkeypatch):
    pytest.importorskip("skfem")
    from skfem import Mesh

    from shakedown.models.fe import meshes

    def exits(path):
        raise SystemExit("meshio: bad file")

    monkeypatch.setattr(Mesh, "load", staticmethod(exits))
    p = tmp_path / "m.vtu"
    p.write_text("<VTKFile/>")
    with pytest.raises(InputError, match=r"m\.vtu.*SystemExit"):
        meshes.from_file(p)


@pytest.mark.slow
def test_hostile_vtu_files_never_exit_the_process(tmp_path):
    pytest.importorskip("meshio")
    from shakedown.models.fe import meshes

    rng = np.random.default_rng(0)
    base = b'<?xml version="1.0"?><VTKFile type="UnstructuredGrid"><UnstructuredGrid>'
    for k in range(20):
        p = tmp_path / f"m{k}.vtu"
        p.write_bytes(base + rng.bytes(int(rng.integers(0, 400))))
        with pytest.raises(InputError, match=f"m{k}.vtu"):
            meshes.from_file(p)


def test_damaged_file_error_is_an_input_error():
    assert issubclass(error_class("DamagedFileError"), ValueError)
    assert issubclass(error_class("OutputError"), OSError)
    assert issubclass(SceneError, InputError)
