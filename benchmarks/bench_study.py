"""Benchmarks of the study (issue 13): per-run cost against today's code, the publication-size
study on 2 cores and on a Dask cluster of separate processes, the default `shakedown run`.

    python benchmarks/bench_study.py --only per_run [--prev /tmp/prev-b450]   # vs the baseline
    python benchmarks/bench_study.py --only study     # 20 realisations x 24 lam x 16 states
    python benchmarks/bench_study.py --only dask      # the same rows on `dask scheduler/worker`
    python benchmarks/bench_study.py --only default   # `shakedown run` (the default job)

The baseline is the code of commit af73457 checked out in a worktree (``--base``, default
``/tmp/study-base``: ``git worktree add /tmp/study-base af73457``); every measurement runs in
a fresh subprocess with ``OPENBLAS_NUM_THREADS=1`` and the baseline and the new code alternate,
so that the machine's load hits both alike.  Medians of ``--repeat`` (default 3).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The default scene's crack network (100 cracks, density 0.1, half-length 1, spacing 0.1).
SPEC = ("n_cracks=100, density=0.1, half_length=1.0, min_spacing=0.1, seed=2024, "
        "friction=0.6, steps_per_cycle=64, max_cycles=200")
#: Load factors of the per-run benchmark, in units of lam2: below lam1, in the band, above.
XS = (0.8, 0.975, 0.99, 1.1, 1.5, 2.0)
N_STATES = 8

PER_RUN = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    from shakedown.studies.sweep import SweepSpec, realisation_model, initial_slip, run_row
    from shakedown.bounds.engine import shakedown_bounds
    spec = SweepSpec({spec})
    _, model, load = realisation_model(spec, 0)
    s = model.system
    b = shakedown_bounds(s, load)
    states = [initial_slip(s, load, j, (2024, 0, 1)) for j in range({n})]
    opts = dict(method="implicit", steps_per_cycle=64, max_cycles=200, tol=1e-10)
    new = {new}
    warm = 0.0
    if new:
        from shakedown.evolution.complementarity import StepSolver
        import shakedown as sd
        t0 = time.perf_counter()  # one-time cost per process: load (or compile) the kernel
        sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),
                        sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,
                        steps_per_cycle=4)
        warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    W = []
    for x in {xs}:
        solver = StepSolver(s) if new else None   # one per (realisation, lam) task
        for v in states:
            kw = dict(step_solver=solver) if new else dict()
            W.append(run_row(s, load, x * b.lam2, v, opts, **kw)["W"])
    print(json.dumps(dict(seconds=time.perf_counter() - t0, runs=len(W), W=W, warm=warm)))
""")


def _run(code: str, path: str, timeout=3600) -> dict:
    env = {**os.environ, "PYTHONPATH": path, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=timeout, cwd=path)
    if out.returncode:
        raise RuntimeError(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def load() -> str:
    return open("/proc/loadavg").read().split(" ")[:3].__repr__() if Path(
        "/proc/loadavg").exists() else "n/a"


def bench_per_run(base: str, repeat: int, prev: str | None = None) -> list[str]:
    """Seconds per run: the baseline (``base``, no step solver reuse), optionally the previous
    state of this code (``prev``), and this code, alternating, each in a fresh subprocess."""
    lines = [f"load average before: {load()}"]
    variants = [("base", base, False)] + ([("prev", prev, True)] if prev else []) + [
        ("new", str(ROOT), True)]
    t = {name: [] for name, *_ in variants}
    warm = {name: [] for name, *_ in variants}
    W = {}
    for _ in range(repeat):
        for name, path, new in variants:
            r = _run(PER_RUN.format(spec=SPEC, n=N_STATES, new=new, xs=XS), path)
            t[name].append(r["seconds"] / r["runs"])
            warm[name].append(r.get("warm", 0.0))
            W[name] = r["W"]
    import numpy as np

    a = np.array(W["base"])
    lines.append(f"runs per repeat: {len(XS) * N_STATES} (lam/lam2 in {XS}, {N_STATES} states)")
    mb = statistics.median(t["base"])
    for name, *_ in variants:
        m = statistics.median(t[name])
        d = float(np.max(np.abs(np.array(W[name]) - a) / np.maximum(np.abs(a), 1e-300)))
        lines.append(f"{name:4s} s/run: {[round(x, 4) for x in t[name]]} median {m:.4f}; "
                     f"baseline/{name} {mb / m:.2f}x; max rel. difference of W vs baseline "
                     f"{d:.1e}; one-time kernel load per process (untimed) "
                     f"{statistics.median(warm[name]):.2f} s")
    lines.append(f"load average after: {load()}")
    return lines


STUDY = textwrap.dedent("""
    import json, sys, time
    from shakedown.studies.sweep import SweepSpec, run_sweep
    if __name__ == "__main__":
        spec = SweepSpec({spec}, n_realisations={R}, n_lams={L}, n_band=5, n_adj=2,
                         n_refine=3, n_states={S})
        t0 = time.perf_counter()
        res = run_sweep(spec, sys.argv[1], n_workers={W}, scheduler={sched!r} or None,
                        progress=False, format="csv")
        wall = time.perf_counter() - t0
        res.runs.to_csv(sys.argv[1] + "-runs.csv", float_format="%.17g", index=False)
        print(json.dumps(dict(wall=wall, runs=len(res.runs), verdict=res.verdict,
                              n_points=int(res.summary.groupby("realisation").size().max()),
                              bounds=float(res.realisations["bounds_seconds"].sum()))))
""")


def _study(R, L, S, workers, store, sched=""):
    code = STUDY.format(spec=SPEC, R=R, L=L, S=S, W=workers, sched=sched)
    script = Path(store).with_name(f"run_{Path(store).name}.py")  # not dask.py: it would shadow dask
    script.write_text(code)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, str(script), store], env=env, capture_output=True,
                         text=True, cwd=str(ROOT))
    if out.returncode:
        raise RuntimeError(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def bench_study(R: int, tmp: Path) -> list[str]:
    lines = [f"load average before: {load()}"]
    r = _study(R, 14, 16, 2, str(tmp / "study"))
    lines += [f"{R} realisations x {r['n_points']} load factors x 16 states: {r['runs']} runs, "
              f"wall {r['wall']:.1f} s on 2 workers (bounds {r['bounds']:.1f} s in total)",
              f"verdict: {r['verdict']}", f"load average after: {load()}"]
    return lines


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def bench_dask(R: int, tmp: Path) -> list[str]:
    port = _free_port()
    dask = shutil.which("dask") or "dask"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    sched = subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                              "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    work = subprocess.Popen([dask, "worker", f"tcp://127.0.0.1:{port}", "--nworkers", "2",
                             "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(5)
        d = _study(R, 6, 4, 2, str(tmp / "dask"), sched=f"tcp://127.0.0.1:{port}")
        loc = _study(R, 6, 4, 2, str(tmp / "local"))
    finally:
        work.terminate()
        sched.terminate()
        work.wait()
        sched.wait()
    a = (tmp / "dask-runs.csv").read_bytes()
    b = (tmp / "local-runs.csv").read_bytes()
    cols = ("W", "W_star", "frac_slip")
    return [f"{R} realisations x {d['n_points']} load factors x 4 states ({d['runs']} runs): "
            f"dask (scheduler + 2 worker processes, loopback) {d['wall']:.1f} s, local 2 "
            f"processes {loc['wall']:.1f} s", f"runs tables ({', '.join(cols)}, ...) identical "
            f"byte for byte: {a == b}"]


def bench_default(base: str, repeat: int) -> list[str]:
    lines = [f"load average before: {load()}"]
    t = {"base": [], "new": []}
    for _ in range(repeat):
        for name, path in (("base", base), ("new", str(ROOT))):
            with tempfile.TemporaryDirectory() as d:
                env = {**os.environ, "PYTHONPATH": path}
                t0 = time.perf_counter()
                out = subprocess.run([sys.executable, "-m", "shakedown", "run", "--quiet"],
                                     env=env, cwd=d, capture_output=True, text=True)
                t[name].append(time.perf_counter() - t0)
                if out.returncode:
                    raise RuntimeError(out.stderr[-2000:])
    lines += [f"baseline `shakedown run`: {[round(x, 1) for x in t['base']]} s, median "
              f"{statistics.median(t['base']):.1f} s",
              f"new `shakedown run`: {[round(x, 1) for x in t['new']]} s, median "
              f"{statistics.median(t['new']):.1f} s", f"load average after: {load()}"]
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=["per_run", "study", "dask", "default"], action="append")
    ap.add_argument("--base", default="/tmp/study-base")
    ap.add_argument("--prev", default=None,
                    help="a checkout of the previous code to compare as well (per_run)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--realisations", type=int, default=20)
    args = ap.parse_args(argv)
    parts = args.only or ["per_run", "study", "dask", "default"]
    with tempfile.TemporaryDirectory() as tmp:
        for part in parts:
            print(f"## {part}", flush=True)
            if part == "per_run":
                lines = bench_per_run(args.base, args.repeat, args.prev)
            elif part == "study":
                lines = bench_study(args.realisations, Path(tmp))
            elif part == "dask":
                lines = bench_dask(min(args.realisations, 2), Path(tmp))
            else:
                lines = bench_default(args.base, args.repeat)
            print("\n".join(lines), flush=True)


if __name__ == "__main__":
    main()
