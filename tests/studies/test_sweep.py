"""The sweep engine (shakedown.store / shakedown.sweep): stores, resumability, determinism.

What is proved here, with stand-in tasks (no physics needed):
- stores give back exactly what was written (floats bit for bit), survive torn writes, and
  refuse a second live writer;
- a sweep interrupted part way (a task raising KeyboardInterrupt, or the whole process killed
  with SIGKILL) and restarted ends with every row exactly once, equal to an uninterrupted run;
- the rows do not depend on the number of workers (1 in-process vs 2 spawned processes);
- bad input and failing tasks give clear errors.
The crack-network study itself is tested in the last section when crack_networks and the cyclic
solver are installed (skipped otherwise).
"""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from shakedown.model.errors import InputError, SolverError
from shakedown.studies.store import KEY, CsvStore, ParquetStore, Progress, Task, open_store, run_tasks

HERE = Path(__file__).resolve().parent


# ------------------------------------------------------------------ stand-in tasks
def standin(i: int, seed: int = 0, sleep: float = 0.0, marker: str | None = None) -> dict:
    """A deterministic task: a few random numbers and a small linear solve from child seed i."""
    if marker is not None and os.path.exists(marker):
        os.remove(marker)
        raise KeyboardInterrupt(f"simulated Ctrl-C in task {i}")
    if sleep:
        time.sleep(sleep)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))
    M = rng.normal(size=(20, 20))
    x = np.linalg.solve(M @ M.T + 20 * np.eye(20), rng.normal(size=20))
    return dict(i=i, x=float(x.sum()), y=float(rng.normal()), even=bool(i % 2 == 0),
                label=f"t,{i}", nan=np.nan if i % 3 == 0 else float(i))


def failing(i: int) -> dict:
    if i == 2:
        raise ValueError("bad parameter in task 2")
    return dict(i=i)


def tasks_for(n: int, **kw) -> list[Task]:
    return [Task(f"k{i}", standin, (i,), dict(kw)) for i in range(n)]


# ------------------------------------------------------------------ stores
@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_store_round_trip_is_bit_exact(tmp_path, fmt):
    rows = [dict(task_key=f"k{i}", x=x, n=i, flag=bool(i % 2), s=f"a,\"b\" {i}")
            for i, x in enumerate([0.1, 1 / 3, 1e-300, -2.5e300, np.pi, -0.0])]
    store = open_store(tmp_path / ("s.csv" if fmt == "csv" else "s"), fmt)
    with store:
        store.append(rows[:2])
        store.append(rows[2:])
    df = store.read()
    assert list(df[KEY]) == [r["task_key"] for r in rows]
    np.testing.assert_array_equal(df["x"].to_numpy().view(np.uint64),
                                  np.array([r["x"] for r in rows]).view(np.uint64))
    assert list(df["s"]) == [r["s"] for r in rows]
    assert list(df["flag"]) == [r["flag"] for r in rows]
    assert store.keys() == {r["task_key"] for r in rows}


def test_csv_store_cuts_a_torn_last_line(tmp_path):
    path = tmp_path / "rows.csv"
    with CsvStore(path) as st:
        st.append([dict(task_key="a", x=1.0), dict(task_key="b", x=2.0)])
    with open(path, "a") as fh:
        fh.write("c,3.00")  # a kill in the middle of an append: no newline
    st = CsvStore(path)
    assert st.keys() == {"a", "b"}  # a reader skips a torn line without touching the file
    assert path.read_bytes().endswith(b"c,3.00")
    with st:
        st.append([dict(task_key="c", x=3.0)])
    assert list(st.read()[KEY]) == ["a", "b", "c"]


def test_csv_store_refuses_new_columns(tmp_path):
    with CsvStore(tmp_path / "r.csv") as st:
        st.append([dict(task_key="a", x=1.0)])
        with pytest.raises(InputError, match="same columns"):
            st.append([dict(task_key="b", x=1.0, extra=2)])


def test_parquet_store_ignores_and_clears_debris_of_a_killed_write(tmp_path):
    with ParquetStore(tmp_path / "s") as st:
        st.append([dict(task_key="a", x=1.0)])
    (tmp_path / "s" / ".tmp-part-000001-dead.parquet").write_bytes(b"PAR1 half written")
    st = ParquetStore(tmp_path / "s")
    assert st.keys() == {"a"}
    assert list((tmp_path / "s").glob(".tmp-*")), "a reader must not touch a writer's files"
    with st:  # the lock holder clears the debris
        assert not list((tmp_path / "s").glob(".tmp-*"))


def test_store_lock_refuses_a_live_writer_and_takes_over_a_killed_one(tmp_path):
    """The lock is an OS lock (filelock): held while its process lives, gone when it dies,
    even by SIGKILL, so a killed sweep never blocks the next run."""
    st = ParquetStore(tmp_path / "s")
    code = ("import sys, time; from shakedown.studies.tables import ParquetStore\n"
            f"st = ParquetStore({str(tmp_path / 's')!r}); st.__enter__()\n"
            "print('locked', flush=True); time.sleep(60)")
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": str(HERE.parents[1])})
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(InputError, match="in use by another process"), st:
            pass
    finally:
        holder.kill()
        holder.wait()
    with st:
        st.append([dict(task_key="a")])
    assert st.keys() == {"a"}


def test_rows_without_key_are_refused(tmp_path):
    with ParquetStore(tmp_path / "s") as st, pytest.raises(InputError, match="task_key"):
        st.append([dict(x=1)])


# ------------------------------------------------------------------ engine
def test_rows_come_back_in_task_order_with_timings(tmp_path):
    tasks = tasks_for(5)[::-1]
    res = run_tasks(tasks, tmp_path / "s", progress=False)
    assert list(res.rows[KEY]) == [t.key for t in tasks]
    assert res.n_run == 5 and res.n_resumed == 0 and res.failed == {}
    assert set(res.seconds.index) == {t.key for t in tasks} and (res.seconds >= 0).all()
    assert "task_seconds" not in res.rows.columns


def test_one_and_two_workers_are_bit_identical(tmp_path):
    tasks = tasks_for(8)
    one = run_tasks(tasks, tmp_path / "one", n_workers=1, progress=False).rows
    two = run_tasks(tasks, tmp_path / "two", n_workers=2, progress=False).rows
    pd.testing.assert_frame_equal(one, two, check_exact=True)


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_keyboard_interrupt_in_a_task_then_resume(tmp_path, fmt):
    """A task raising KeyboardInterrupt after 4 rows; the restart completes the sweep."""
    n, k = 10, 4
    ref = run_tasks(tasks_for(n), open_store(tmp_path / "ref", fmt), progress=False).rows
    marker = tmp_path / "interrupt"
    marker.write_text("")
    tasks = tasks_for(k) + [Task(f"k{i}", standin, (i,), dict(marker=str(marker)))
                            for i in range(k, n)]
    path = tmp_path / ("s.csv" if fmt == "csv" else "s")
    with pytest.raises(KeyboardInterrupt):
        run_tasks(tasks, open_store(path, fmt), progress=False)
    assert open_store(path, fmt).keys() == {f"k{i}" for i in range(k)}
    res = run_tasks(tasks, open_store(path, fmt), progress=False)
    assert (res.n_resumed, res.n_run) == (k, n - k)
    assert res.rows[KEY].is_unique and len(res.rows) == n
    pd.testing.assert_frame_equal(res.rows, ref, check_exact=True)


def test_sigkill_part_way_then_resume(tmp_path):
    """The whole sweep process (and its workers) killed with SIGKILL after some rows."""
    n = 16
    store = tmp_path / "s"
    script = textwrap.dedent(f"""
        import sys
        sys.path[:0] = [{str(HERE)!r}, {str(HERE.parents[1])!r}]
        from {standin.__module__} import tasks_for
        from shakedown.studies.store import run_tasks
        run_tasks(tasks_for({n}, sleep=0.25), {str(store)!r}, n_workers=2, progress=False)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            if proc.poll() is not None:
                pytest.fail(f"the sweep process ended early with code {proc.returncode}")
            if store.exists() and len(ParquetStore(store).keys()) >= 3:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the sweep process wrote no rows in 120 s")
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    done = ParquetStore(store).keys()
    assert 3 <= len(done) < n
    res = run_tasks(tasks_for(n), store, progress=False)
    assert res.n_resumed == len(done) and res.n_run == n - len(done)
    assert res.rows[KEY].is_unique and len(res.rows) == n
    ref = run_tasks(tasks_for(n), tmp_path / "ref", progress=False).rows
    pd.testing.assert_frame_equal(res.rows, ref, check_exact=True)
    # a third call finds everything done and runs nothing
    again = run_tasks(tasks_for(n), store, progress=False)
    assert (again.n_run, again.n_resumed) == (0, n)


def test_a_failing_task_stops_the_sweep_and_keeps_finished_rows(tmp_path):
    tasks = [Task(f"k{i}", failing, (i,)) for i in range(5)]
    with pytest.raises(SolverError, match="'k2' raised ValueError") as err:
        run_tasks(tasks, tmp_path / "s", progress=False)
    assert Path(err.value.partial) == tmp_path / "s"
    assert ParquetStore(tmp_path / "s").keys() == {"k0", "k1"}
    res = run_tasks(tasks, tmp_path / "s", progress=False, on_error="skip")
    assert set(res.failed) == {"k2"} and "bad parameter" in res.failed["k2"]
    assert list(res.rows[KEY]) == ["k0", "k1", "k3", "k4"]


def test_bad_engine_input(tmp_path):
    with pytest.raises(InputError, match="unique"):
        run_tasks([Task("a", standin, (0,)), Task("a", standin, (1,))], tmp_path / "s")
    with pytest.raises(InputError, match="n_workers"):
        run_tasks(tasks_for(2), tmp_path / "s", n_workers=0)
    with pytest.raises(InputError, match="on_error"):
        run_tasks(tasks_for(2), tmp_path / "s", on_error="ignore")
    with pytest.raises(InputError, match="format"):
        open_store(tmp_path / "x", "feather")


def test_progress_reports_counts_and_time_left():
    out = io.StringIO()
    bar = Progress(10, done=2, desc="runs", stream=out)
    bar.update(3)
    time.sleep(0.01)
    bar.update(1)
    bar.close()
    text = out.getvalue()
    # the shared tqdm display: starts at the 2 tasks found in the store, counts to 6 of 10
    assert "runs:" in text and "2/10" in text and "20%" in text
    assert "6/10" in text and "60%" in text and "<" in text  # elapsed<remaining


def test_progress_of_a_sweep_goes_to_stderr(tmp_path, capsys):
    run_tasks(tasks_for(3), tmp_path / "s", desc="demo")
    err = capsys.readouterr().err
    assert "demo:" in err and "0/3" in err and "3/3" in err  # tqdm lines on stderr


# ------------------------------------------------------------------ the crack-network study
def _study_modules():
    pytest.importorskip("crack_networks")
    pytest.importorskip("shakedown.evolution")
    from shakedown.studies.sweep import SweepSpec, run_sweep

    return SweepSpec, run_sweep


def test_study_is_identical_for_one_and_two_workers_and_resumes(tmp_path):
    SweepSpec, run_sweep = _study_modules()
    spec = SweepSpec(n_cracks=10, n_realisations=2, n_lams=3, n_band=2, n_adj=1, n_refine=1,
                     n_states=2, steps_per_cycle=16, max_cycles=60, seed=5)
    one = run_sweep(spec, tmp_path / "one", n_workers=1, progress=False)
    two = run_sweep(spec, tmp_path / "two", n_workers=2, progress=False)
    for name in ("realisations", "runs", "summary"):
        a, b = getattr(one, name), getattr(two, name)
        a = a.drop(columns=[c for c in a if c.endswith("_seconds")])
        b = b.drop(columns=[c for c in b if c.endswith("_seconds")])
        pd.testing.assert_frame_equal(a, b, check_exact=True)
    # one task per (realisation, load factor): 3 grid + 2 band + (0 or 1) adj + 1 refinement
    n_points = one.summary.groupby("realisation").size()
    assert n_points.between(6, 7).all() and len(one.runs) == 2 * n_points.sum()
    assert set(one.runs["status"]) == {"periodic"}
    again = run_sweep(spec, tmp_path / "one", n_workers=1, progress=False)
    assert again.n_run == 0 and again.n_resumed == 2 + n_points.sum()
    pd.testing.assert_frame_equal(again.runs, one.runs, check_exact=True)
    from dataclasses import replace

    with pytest.raises(InputError, match="another spec .*n_states"):
        run_sweep(replace(spec, n_states=3), tmp_path / "one", progress=False)


def test_study_reproduces_the_seed_findings_at_small_size(tmp_path):
    """Seed 002 s.4.1 (Fig. 11) on 12 interacting cracks: lam1 < lam2; below lam2 some initial
    state shakes down (min W* = 0); just above lam2 the outcome depends on the initial state;
    once every crack slips in the steady cycle the dissipation is unique again."""
    SweepSpec, run_sweep = _study_modules()
    spec = SweepSpec(n_cracks=12, density=0.1, n_lams=7, lam_span=(0.5, 2.5), n_states=4,
                     n_band=2, n_adj=0, n_refine=0, steps_per_cycle=32, max_cycles=100,
                     seed=2024)
    res = run_sweep(spec, tmp_path / "s", n_workers=1, progress=False)
    r = res.realisations.iloc[0]
    assert r.lam1 < r.lam2
    s, runs = res.summary, res.runs
    assert (runs["status"] == "periodic").all()
    scale = float(s["W_star_max"].max())
    # a shaken-down run dissipates nothing: W is a sum of -q dv with dv = 0 up to the solver's
    # zero (FEAS_TOL = 1e-9 relative), so 1e-9 of the largest W* is a safe "zero"
    assert (s.loc[s["lam"] < r.lam2, "W_star_min"] <= 1e-9 * scale).all()
    assert ((s["lam"] > r.lam1) & (s["lam"] < r.lam2)).sum() == 2  # the band is sampled
    above = s[s["lam"] > r.lam2]
    spread = (above["W_star_max"] - above["W_star_min"]) / above["W_star_max"]
    assert spread.max() > 1e-3  # history-dependent damping above lam2
    everyone = runs.groupby("point")["frac_slip"].min() == 1.0
    assert everyone.any(), "the sweep must reach a lam where every crack slips"
    unique = s.set_index("point").loc[everyone[everyone].index]
    # unique steady cycle: the runs converge to the same orbit to the solver's steady-state
    # tolerance (tol = 1e-10 relative change per cycle); 1e-6 leaves room for the approach
    np.testing.assert_allclose(unique["W_star_min"], unique["W_star_max"], rtol=1e-6)


def test_dilute_limit_matches_isolated_cracks(tmp_path):
    """MODEL.md s.7: cracks on the maximum-shear plane (theta = 0) far apart behave as isolated
    cracks: lam1 = lam2 = f and W* = sum pi f (lam - f) (a / abar)^2, from every state."""
    SweepSpec, run_sweep = _study_modules()
    f = 0.6
    spec = SweepSpec(n_cracks=8, density=1e-4, half_length=(0.5, 1.5), orientation=0.0,
                     friction=f, lams=(0.9, 1.5), n_states=2, steps_per_cycle=16,
                     max_cycles=40, seed=1)
    res = run_sweep(spec, tmp_path / "s", n_workers=1, progress=False)
    from shakedown.studies.sweep import realisation_model

    cracks, _, _ = realisation_model(spec, 0)
    a_rel = cracks.half_lengths / cracks.mean_half_length
    r = res.realisations.iloc[0]
    # interaction enters through transmission factors ~ (a / distance)^2 ~ density = 1e-4
    np.testing.assert_allclose([r.lam1, r.lam2], [f, f], rtol=1e-3)
    for lam in spec.lams:
        exact = np.pi * f * (lam - f) * np.sum(a_rel**2)
        got = res.runs.loc[np.isclose(res.runs["lam"], lam), "W_star"].to_numpy()
        # the implicit steps sample the harmonic load at its extremes (t = 0, 1/2), where a
        # single uncoupled node's slip is decided exactly; what is left is the interaction
        np.testing.assert_allclose(got, exact, rtol=1e-3)


def test_dilute_bounds_of_randomly_oriented_cracks(tmp_path):
    """Isolated crack at angle theta under S0 = -p0 I, S1 = p0 (shear xy): it slips when
    lam |cos 2 theta| > f and opens when lam |sin 2 theta| > 1, so
    lam1 = lam2 = min(f / |cos 2 theta|, 1 / |sin 2 theta|); the network's lam2 is the
    smallest over its cracks (MODEL.md s.7 states the first branch, for a closed crack)."""
    SweepSpec, run_sweep = _study_modules()
    spec = SweepSpec(n_cracks=30, density=1e-4, lams=(0.5,), n_states=1, steps_per_cycle=8,
                     max_cycles=10, seed=3)
    res = run_sweep(spec, tmp_path / "s", n_workers=1, progress=False)
    from shakedown.studies.sweep import realisation_model

    cracks, _, _ = realisation_model(spec, 0)
    th = cracks.angles
    with np.errstate(divide="ignore"):
        single = np.minimum(spec.friction / np.abs(np.cos(2 * th)), 1 / np.abs(np.sin(2 * th)))
    r = res.realisations.iloc[0]
    np.testing.assert_allclose(r.lam2, single.min(), rtol=1e-3)  # interaction ~ density


def test_bad_study_input():
    SweepSpec, _ = _study_modules()
    with pytest.raises(InputError, match="static must be 3"):
        SweepSpec(static=(1.0, 2.0))
    with pytest.raises(InputError, match="lams must be 'auto' or"):
        SweepSpec(lams="some")
    with pytest.raises(InputError, match="n_states must be an integer >= 1"):
        SweepSpec(n_states=0)
    with pytest.raises(InputError, match="cyclic must not be zero"):
        SweepSpec(cyclic=(0, 0, 0))
    with pytest.raises(InputError, match="lam_span"):
        SweepSpec(lam_span=(2.0, 1.0))
    with pytest.raises(InputError, match="method"):
        SweepSpec(method="euler")


def test_system_sweep_on_an_uncoupled_two_node_system(tmp_path):
    """Any DiscreteSystem: uncoupled nodes have the same steady W from every initial state
    (seed 002 s.3), W = sum 4 f P (lam Q1 - f P) / k over the slipping nodes (issue 3)."""
    pytest.importorskip("shakedown.evolution")
    import shakedown as sd
    from shakedown.studies.sweep import initial_slips, system_sweep

    k, f, P, Q1 = np.array([2.0, 1.0]), 0.5, np.array([1.0, 2.0]), np.array([1.0, 1.5])
    system = sd.DiscreteSystem(np.diag(k), np.zeros((2, 2)), np.diag(k), friction=f)
    load = sd.LoadCycle.from_harmonics([0.0, 0.0], P, q_cos=Q1)
    slips = initial_slips(system, load, 3, seed=4)
    assert np.all(slips[0] == 0) and np.all(np.abs(slips[1:]) <= 2 * f * P / k)
    rows = system_sweep(system, load, [0.3, 1.2], slips, tmp_path / "s", progress=False,
                        solver=dict(steps_per_cycle=16, max_cycles=50))
    assert len(rows) == 6
    for lam, g in rows.groupby("lam"):
        exact = np.sum(np.clip(4 * f * P * (lam * Q1 - f * P) / k, 0, None))
        # uncoupled nodes, 16 steps hitting the harmonic's extremes: exact up to the steady-state
        # tolerance (1e-10 relative change per cycle) and round-off
        np.testing.assert_allclose(g["W"], exact, rtol=1e-9, atol=1e-12)


def test_sweep_analysis_writes_tables_plots_and_resumes(tmp_path, capsys):
    """`shakedown sweep SCENE` protocol: run(ctx, options) with a crack-network scene."""
    _study_modules()
    import matplotlib

    matplotlib.use("Agg")
    from shakedown.scenes.analyses import sweep as analysis
    from shakedown.scenes.files import AnalysisContext, scene_from_string
    from shakedown.scenes.output import OutputFolder
    from shakedown.scenes.output import Progress as CliProgress

    scene = scene_from_string(textwrap.dedent("""
        [model]
        kind = "crack_network"
        n_cracks = 8
        density = 0.1
        seed = 4
        friction = 0.6
        [load]
        static = [-1.0, 0.0, -1.0]
        cyclic = [0.0, 1.0, 0.0]
        [analyses.sweep]
        n_lams = 3
        n_states = 2
        steps_per_cycle = 16
        max_cycles = 40
        n_workers = 1
    """))
    out = OutputFolder(tmp_path / "out")
    ctx = AnalysisContext(None, None, None, out, CliProgress(enabled=False), None, scene)
    summary = analysis.run(ctx, scene.analyses["sweep"])
    n_points = summary["n_runs"] // 2
    assert n_points >= 3 + 5 and summary["lam1"] <= summary["lam2"]
    assert summary["verdict"].startswith("1 realisation of 8 cracks, friction 0.6: ")
    for name in ("sweep_runs.csv", "sweep_runs.parquet", "sweep_summary.csv", "sweep.json",
                 "sweep_regions.csv", "sweep_verdict.txt", "dissipation_vs_lam.png",
                 "fractions_vs_lam.png"):
        assert (out.path / name).stat().st_size > 0, name
    table = pd.read_csv(out.path / "sweep_summary.csv")
    assert len(table) == n_points and (table["W_star_min"] <= table["W_star_max"]).all()
    assert "W*_min" in capsys.readouterr().out
    again = analysis.run(ctx, scene.analyses["sweep"])
    assert again["n_resumed"] == 1 + n_points
    bad = scene_from_string('[model]\nkind = "matrices"\nA = [[1.0]]\nB = [[0.0]]\nC = [[1.0]]\n'
                            'friction = 0.5\n[analyses.sweep]\n')
    ctx_bad = AnalysisContext(None, None, None, out, CliProgress(enabled=False), None, bad)
    from shakedown.model.errors import SceneError

    with pytest.raises(SceneError, match="needs its built system and load"):
        analysis.run(ctx_bad, bad.analyses["sweep"])
