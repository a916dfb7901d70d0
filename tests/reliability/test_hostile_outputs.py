"""Hostile output folders, stores, manifests and caches; faults of the disk and of stdout
(issue 24).  Each case asserts the exact outcome: what is in the folder afterwards, the exit
status and the message, or the rows a store returns."""

from __future__ import annotations

import errno
import json
import os
import shutil
import warnings

import numpy as np
import pytest
from hostile_common import CRACK_SCENE, CYCLES_SCENE, error_class, files_under, run_cli, scene_text, snapshot

from shakedown.model.errors import InputError, SceneError
from shakedown.studies.store import Task, run_tasks


def _scene(tmp_path, text=None, name="s.toml"):
    p = tmp_path / name
    p.write_text(text or scene_text())
    return p


def _victim(tmp_path):
    v = tmp_path / "victim"
    v.mkdir(exist_ok=True)
    (v / "keep.txt").write_text("precious")
    return v


# ---------------------------------------------------------------- links in the output path
@pytest.mark.parametrize("name", ["CITATIONS.bib", "scene.resolved.toml", "summary.json",
                                  "manifest.json", "bounds.json"])
def test_a_link_planted_as_a_result_file_is_not_followed(tmp_path, name):
    victim = _victim(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / name).symlink_to(victim / "keep.txt")
    code, _, err = run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out)])
    assert (victim / "keep.txt").read_text() == "precious"
    assert code == 2 and "symbolic link" in err and name in err


def test_a_link_planted_as_the_output_folder_is_refused(tmp_path, monkeypatch):
    victim = _victim(tmp_path)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "shakedown-out").mkdir()
    (tmp_path / "shakedown-out" / "hostile").symlink_to(victim)
    code, _, err = run_cli(["bounds", str(_scene(tmp_path)), "-q"])
    assert code == 2 and "symbolic link" in err
    assert files_under(victim) == ["keep.txt"]


def test_a_link_above_the_output_folder_is_refused(tmp_path):
    victim = _victim(tmp_path)
    (tmp_path / "up").symlink_to(victim)
    code, _, err = run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o",
                            str(tmp_path / "up" / "deeper")])
    assert code == 2 and "symbolic link" in err and files_under(victim) == ["keep.txt"]


def test_a_linked_fe_cache_dir_is_refused(tmp_path):
    pytest.importorskip("skfem")
    from shakedown.models.fe import cache

    victim = _victim(tmp_path)
    (tmp_path / "fe_cache").symlink_to(victim)
    with pytest.raises(InputError, match="symbolic link"):
        cache.save(tmp_path / "fe_cache", "k" * 64, {"K": np.eye(2)})
    assert files_under(victim) == ["keep.txt"]


# ---------------------------------------------------------------- provenance
def test_a_failed_run_leaves_the_folder_as_it_was(tmp_path):
    out = tmp_path / "out"
    assert run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out)])[0] == 0
    before = snapshot(out)
    code, _, err = run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out),
                            "--set", "model.friction=-1"])
    assert code == 2 and "friction" in err
    assert snapshot(out) == before


def test_a_refused_sweep_leaves_the_resolved_scene_of_the_earlier_run(tmp_path):
    out = tmp_path / "out"
    s = _scene(tmp_path, CRACK_SCENE.format(seed=3, fmt="csv"))
    assert run_cli(["sweep", str(s), "-q", "-o", str(out)])[0] == 0
    before = snapshot(out)
    code, _, err = run_cli(["sweep", str(s), "-q", "-o", str(out), "--set", "max_cycles=41"])
    assert code == 2 and "another spec" in err
    assert snapshot(out) == before


def test_the_resolved_scene_keeps_the_units_and_reruns_bit_for_bit(tmp_path):
    units = 'force_unit = "N"\nlength_unit = "mm"'
    s = _scene(tmp_path, CYCLES_SCENE.format(A="[[2.0]]", units=units))
    assert run_cli(["cycles", str(s), "-q", "-o", str(tmp_path / "a")])[0] == 0
    code, text, _ = run_cli(["cycles", str(tmp_path / "a" / "scene.resolved.toml"), "-o",
                             str(tmp_path / "b")])
    assert code == 0 and "[force x length]" not in text and "N mm" in text
    a, b = (json.loads((tmp_path / d / "cycles.json").read_text()) for d in "ab")
    assert a == b


def test_provenance_describes_the_results_of_the_folder(tmp_path):
    out = tmp_path / "out"
    run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out)])
    run_cli(["bounds", str(_scene(tmp_path, scene_text(A="[[4.0]]"), "t.toml")), "-q", "-o",
             str(out)])
    man = json.loads((out / "manifest.json").read_text())
    assert man["resolved_scene"]["model"]["A"] == [[4.0]]
    assert "A = [[4.0]]" in (out / "scene.resolved.toml").read_text()
    import hashlib

    for name, digest in man["output_files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest, name


class ClosedPipe:
    """A stdout whose reader has gone (``| true``)."""

    def write(self, text):
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")

    def flush(self):
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")


def test_a_closed_stdout_costs_no_file(tmp_path):
    out = tmp_path / "out"
    code, _, _ = run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out)],
                         stdout=ClosedPipe())
    assert code == 0
    assert {"summary.json", "manifest.json", "CITATIONS.bib", "scene.resolved.toml",
            "bounds.json"} <= set(files_under(out))


def test_a_full_disk_is_a_clear_error_and_leaves_no_debris(tmp_path, monkeypatch):
    out = tmp_path / "out"
    real = os.replace

    def full(src, dst, *a, **k):
        if str(dst).endswith(".json"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(src, dst, *a, **k)

    monkeypatch.setattr(os, "replace", full)
    code, _, err = run_cli(["bounds", str(_scene(tmp_path)), "-q", "-o", str(out)])
    assert code == 74 and "disk is full" in err and ".json" in err
    assert files_under(out) == []


# ---------------------------------------------------------------- manifests
def _manifest(tmp_path):
    out = tmp_path / "m"
    s = _scene(tmp_path, CRACK_SCENE.format(seed=3, fmt="csv"))
    assert run_cli(["bounds", str(s), "-q", "-o", str(out)])[0] == 0
    return out / "manifest.json"


def test_a_manifest_may_not_name_a_scheduler(tmp_path):
    m = _manifest(tmp_path)
    data = json.loads(m.read_text())
    data["resolved_scene"]["analyses"]["sweep"] = {"scheduler": "tcp://198.51.100.1:8786"}
    m.write_text(json.dumps(data))
    code, _, err = run_cli(["sweep", str(m), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and "scheduler" in err and str(m) in err


@pytest.mark.parametrize("text, word", [("[" * 100000 + "]" * 100000, "nest"),
                                        ('{"resolved_scene": ' * 40 + "{}" + "}" * 40, "nest"),
                                        ('{"resolved_scene": {}, "input_files": [1]}',
                                         "input_files")], ids=["deep list", "deep tables", "inputs"])
def test_hostile_manifests_are_refused(tmp_path, text, word):
    m = tmp_path / "manifest.json"
    m.write_text(text)
    code, _, err = run_cli(["bounds", str(m), "-q", "-o", str(tmp_path / "o")])
    assert code == 2 and word in err and str(m) in err


# ---------------------------------------------------------------- stores
def rows_of(i):
    return [{"i": i, "j": j, "x": i + 0.1 * j} for j in range(3)]


TASKS = [Task(f"t{i}", rows_of, (i,)) for i in range(4)]
EXPECTED = [(i, j) for i in range(4) for j in range(3)]


def _run(path, fmt):
    from shakedown.studies.tables import open_store

    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        out = run_tasks(TASKS, open_store(path, fmt), progress=False)
    got = list(zip(out.rows["i"].astype(int), out.rows["j"].astype(int), strict=True))
    return got, out, [str(x.message) for x in w]


def test_a_cut_csv_store_reruns_the_damaged_task(tmp_path):
    p = tmp_path / "runs.csv"
    _run(p, "csv")
    p.write_bytes(p.read_bytes()[:-40])
    got, out, said = _run(p, "csv")
    assert got == EXPECTED and out.n_run == 1 and any("run again" in s for s in said)


def test_a_garbage_line_in_a_csv_store_is_cut(tmp_path):
    p = tmp_path / "runs.csv"
    _run(p, "csv")
    p.write_bytes(p.read_bytes() + b'garbage,"\xff,1\n')
    got, out, said = _run(p, "csv")
    assert got == EXPECTED and out.n_run == 0 and any("no block" in s for s in said)


def test_an_edited_csv_row_is_detected_and_rerun(tmp_path):
    p = tmp_path / "runs.csv"
    _run(p, "csv")
    p.write_bytes(p.read_bytes().replace(b",3.1000000000000001,t3,", b",9.5,t3,"))
    got, out, said = _run(p, "csv")
    assert got == EXPECTED and out.n_run == 1 and any("SHA-256" in s for s in said)
    assert float(out.rows.loc[(out.rows.i == 3) & (out.rows.j == 1), "x"].iloc[0]) == 3.1


def _parts(p):
    return sorted(p.glob("part-*.parquet"))


def test_a_copied_parquet_part_gives_no_duplicate_rows(tmp_path):
    pytest.importorskip("pyarrow")
    p = tmp_path / "store"
    _run(p, "parquet")
    first = _parts(p)[0]
    shutil.copy(first, p / "part-000099-copy.parquet")
    got, out, said = _run(p, "parquet")
    assert got == EXPECTED and out.n_run == 0 and any("duplicate" in s for s in said)


def test_a_parquet_part_with_a_renamed_column_is_rerun(tmp_path):
    pyarrow = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    p = tmp_path / "store"
    _run(p, "parquet")
    part = _parts(p)[1]
    t = pq.read_table(part)
    pq.write_table(t.rename_columns([("y" if c == "x" else c) for c in t.column_names])
                   .replace_schema_metadata(t.schema.metadata), part)
    got, out, said = _run(p, "parquet")
    assert got == EXPECTED and out.n_run == 1 and not out.rows["x"].isna().any()
    assert pyarrow is not None and any(part.name in s for s in said)


def test_a_truncated_parquet_part_is_rerun(tmp_path):
    pytest.importorskip("pyarrow")
    p = tmp_path / "store"
    _run(p, "parquet")
    part = _parts(p)[2]
    part.write_bytes(part.read_bytes()[:50])
    got, out, said = _run(p, "parquet")
    assert got == EXPECTED and out.n_run == 1 and (p / "damaged" / part.name).is_file()


def test_reading_a_damaged_part_without_repair_names_it(tmp_path):
    pytest.importorskip("pyarrow")
    from shakedown.studies.tables import ParquetStore

    p = tmp_path / "store"
    _run(p, "parquet")
    part = _parts(p)[0]
    part.write_bytes(b"PAR1 not really")
    with pytest.raises(error_class("DamagedFileError"), match=part.name):
        ParquetStore(p).read()


def test_an_invalid_spec_json_is_refused_with_the_file_named(tmp_path):
    out = tmp_path / "out"
    s = _scene(tmp_path, CRACK_SCENE.format(seed=3, fmt="csv"))
    assert run_cli(["sweep", str(s), "-q", "-o", str(out)])[0] == 0
    (out / "sweep_store" / "spec.json").write_text('{"n_cracks": ')
    code, _, err = run_cli(["sweep", str(s), "-q", "-o", str(out)])
    assert code == 2 and "spec.json" in err and "Traceback" not in err


# ---------------------------------------------------------------- caches
def test_an_edited_fe_cache_file_is_detected(tmp_path):
    pytest.importorskip("skfem")
    from shakedown.models.fe import cache

    arrays = {"K": np.array([[2.0, 0.5], [0.5, 3.0]]), "f": np.ones(2)}
    key = "a" * 64
    path = cache.save(tmp_path, key, arrays)
    ok = cache.load(tmp_path, key, mass=False)
    assert ok is not None and np.array_equal(ok["K"], arrays["K"])
    with np.load(path) as z:
        edited = {k: z[k] for k in z.files}
    edited["K"] = edited["K"] * 4.0
    np.savez(path, **edited)
    with pytest.warns(RuntimeWarning, match="fails its check"):
        assert cache.load(tmp_path, key, mass=False) is None
    shutil.copy(path, cache.path_for(tmp_path, "b" * 64))  # another key's name
    with pytest.warns(RuntimeWarning, match="fails its check"):
        assert cache.load(tmp_path, "b" * 64, mass=False) is None


def test_scene_error_is_an_input_error():
    assert issubclass(SceneError, InputError)
