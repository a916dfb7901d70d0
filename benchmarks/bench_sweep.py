"""Benchmarks of the Monte Carlo sweep (issue 4): the default study's wall time and accuracy.

    python benchmarks/bench_sweep.py                 # everything (about 10 minutes on 2 cores)
    python benchmarks/bench_sweep.py --only study    # the default study: 1 vs 2 workers, Dask
    python benchmarks/bench_sweep.py --only steps    # W* error against steps per cycle / events
    python benchmarks/bench_sweep.py --only engine   # per-task overhead of the stores

Parts
-----
study   The default job (data/scenes/cracks_default.toml: 100 cracks, 1 realisation,
        12 load factors, 4 initial states) from an empty store: one in-process worker (the
        baseline), two local processes, and a local Dask cluster of two worker processes.
        Checks that the three give the same rows bit for bit.
steps   The cost of the implicit solver's time step: W* of the default crack set at a few load
        factors with 16..256 steps per cycle and with the event-driven method, error against
        the finest implicit run (and the events run), and the time per run.
engine  The engine's own overhead: trivial tasks through the Parquet and CSV stores.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SCENE = ROOT / "data" / "scenes" / "cracks_default.toml"


def default_spec(**changes):
    from dataclasses import replace

    from shakedown.scenes.files import tomllib
    from shakedown.studies.sweep import SweepSpec

    raw = tomllib.loads(SCENE.read_text())
    model = {k: v for k, v in raw["model"].items() if k != "kind"}
    spec = SweepSpec.from_scene(model, raw["load"], raw["analyses"]["sweep"])
    return replace(spec, **changes) if changes else spec


def machine() -> str:
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
            f"Python {platform.python_version()}, numpy {np.__version__}")


def bench_study(repeat: int) -> list[str]:
    from shakedown.studies.sweep import run_sweep

    spec = default_spec()
    out = [f"### Default study ({spec.n_cracks} cracks, {spec.n_realisations} realisation, "
           f"{spec.n_lams} load factors, {spec.n_states} initial states, "
           f"{spec.method} {spec.steps_per_cycle} steps/cycle)", "",
           "| execution | wall time (s), median | runs (s/task, median) | speed-up vs 1 worker |",
           "| --- | --- | --- | --- |"]
    results, times = {}, {}

    def one(label, **kw):
        walls = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory() as tmp:
                res = run_sweep(spec, Path(tmp) / "store", progress=False, **kw)
            walls.append(res.wall_seconds)
        results[label], times[label] = res, walls
        print(f"{label}: {walls}", flush=True)

    one("1 worker (in process)", n_workers=1)
    one("2 local processes", n_workers=2)
    try:
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=40) as lc:
            one("Dask LocalCluster, 2 worker processes", scheduler=lc.scheduler_address)
    except ImportError:
        pass
    base = statistics.median(times["1 worker (in process)"])
    ref = results["1 worker (in process)"]
    for label, walls in times.items():
        m = statistics.median(walls)
        task = statistics.median(results[label].task_seconds.to_numpy())
        out.append(f"| {label} | {m:.1f} | {task:.2f} | {base / m:.2f} |")
    diffs = []
    for k, res in results.items():
        for c in ref.runs.columns:
            x, y = ref.runs[c].to_numpy(), res.runs[c].to_numpy()
            same = (x == y) | (pd.isna(x) & pd.isna(y)) if x.dtype.kind == "f" else x == y
            if not same.all():
                diffs.append(f"{k}: column {c} differs in {int((~same).sum())} rows")
    out += ["", "Rows identical, bit for bit, across the executions: "
            + ("yes." if not diffs else "NO: " + "; ".join(diffs))]
    r = ref.realisations.iloc[0]
    s = ref.summary
    out += ["", f"lam1 = {r.lam1:.4f}, lam2 = {r.lam2:.4f} (bounds: {r.bounds_seconds:.1f} s, "
            f"model: {r.build_seconds:.2f} s); runs not steady: "
            f"{int(ref.runs['W_star'].isna().sum())} of {len(ref.runs)}; cycles to steady "
            f"median {ref.runs['cycles_to_steady'].median():.0f}, max "
            f"{ref.runs['cycles_to_steady'].max()}.", "",
            "| lam | W*_min | W*_max | steady | shook down | frac slip (max) | frac open (max) |",
            "| --- | --- | --- | --- | --- | --- | --- |"]
    for _, x in s.iterrows():
        out.append(f"| {x.lam:.4f} | {x.W_star_min:.4g} | {x.W_star_max:.4g} | "
                   f"{int(x.n_steady)} | {int(x.n_shook_down)} | {x.frac_slip_max:.2f} | "
                   f"{x.frac_open_max:.2f} |")
    return out


def bench_steps(lams_rel=(1.25, 2.0), states=(0, 1)) -> list[str]:
    """W* against the time discretisation, on realisation 0 of the default study."""
    from shakedown.evolution import solve_cycles
    from shakedown.studies.sweep import _realisation_task, initial_slip, realisation_model

    spec = default_spec()
    row = _realisation_task(spec, 0)
    _, model, load = realisation_model(spec, 0)
    out = ["### W* against the time discretisation (realisation 0 of the default study)", "",
           "Error relative to the finest implicit run (256 steps/cycle); the event-driven "
           "method on the load sampled at 64 points per cycle (piecewise linear) for comparison.",
           "", "| lam / lam2 | state | method | W* | rel. error | time per run (s) | cycles |",
           "| --- | --- | --- | --- | --- | --- | --- |"]
    for rel in lams_rel:
        lam = rel * row["lam2"]
        for j in states:
            v0 = initial_slip(model.system, load, j, (spec.seed, 0, 1), scale=spec.state_scale)
            cases = [("implicit", n, load) for n in (16, 32, 64, 128, 256)]
            cases.append(("events", 0, load.to_samples(64)))
            vals = {}
            for method, n, ld in cases:
                kw = dict(method=method, max_cycles=spec.max_cycles, tol=spec.tol)
                if method == "implicit":
                    kw["steps_per_cycle"] = n
                t0 = time.perf_counter()
                try:
                    run = solve_cycles(model.system, ld, lam, initial_slip=v0, **kw)
                    W = float(model.normalised_dissipation(run.steady_dissipation, spec.p0))
                    ncyc = len(run.dissipation)
                except Exception as exc:  # noqa: BLE001 - report, do not stop the benchmark
                    W, ncyc = np.nan, f"error: {exc}"[:60]
                vals[(method, n)] = (W, time.perf_counter() - t0, ncyc)
            ref = vals[("implicit", 256)][0]
            for (method, n), (W, dt, ncyc) in vals.items():
                err = abs(W - ref) / abs(ref) if ref else abs(W - ref)
                name = f"implicit {n}" if method == "implicit" else "events (64 samples)"
                out.append(f"| {rel:.2f} | {j} | {name} | {W:.6g} | {err:.2e} | {dt:.2f} | "
                           f"{ncyc} |")
            print(out[-1], flush=True)
    return out


def _trivial(i):
    return dict(i=i, x=float(i) ** 0.5)


def bench_engine(n_tasks: int = 400) -> list[str]:
    from shakedown.studies.store import Task, open_store, run_tasks

    tasks = [Task(f"k{i}", _trivial, (i,)) for i in range(n_tasks)]
    out = ["### Engine overhead (trivial tasks, in process, one append per task)", "",
           "| store | tasks | s per task (median of 3) |", "| --- | --- | --- |"]
    for fmt in ("parquet", "csv"):
        walls = []
        for _ in range(3):
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                run_tasks(tasks, open_store(Path(tmp) / ("s.csv" if fmt == "csv" else "s"),
                                            fmt), progress=False)
                walls.append(time.perf_counter() - t0)
        out.append(f"| {fmt} | {n_tasks} | {statistics.median(walls) / n_tasks * 1e3:.2f} ms |")
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", choices=["study", "steps", "engine"], action="append")
    p.add_argument("--repeat", type=int, default=1, help="repetitions of each study timing")
    args = p.parse_args(argv)
    parts = args.only or ["engine", "steps", "study"]
    lines = [f"Machine: {machine()}", ""]
    for part in parts:
        lines += {"study": lambda: bench_study(args.repeat), "steps": bench_steps,
                  "engine": bench_engine}[part]()
        lines.append("")
    text = "\n".join(lines)
    print(text)
    return text


if __name__ == "__main__":
    pd.set_option("display.width", 120)
    main()
