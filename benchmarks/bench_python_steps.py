"""The default ``shakedown run`` with every step in Python (issue 25), side by side with a baseline.

``SHAKEDOWN_KERNEL=numpy`` runs what a first run (numba's cache cold, the kernel compiled in the
background) runs: the Python step path of :mod:`shakedown.evolution.complementarity`.  Each run
is one fresh process (``shakedown run --out <fresh folder>``), its process CPU time measured
around ``main()`` (imports excluded), alternated between this tree and ``--baseline DIR`` (e.g.
``git archive main | tar -x -C DIR``); the load average is printed before each run.  After the
runs, the written ``sweep_runs.csv`` of the first run of each tree are compared: identical
discrete columns, the largest relative difference of every float column.  Usage::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_python_steps.py --baseline DIR [--repeats 3]
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHILD = ("import sys, time; sys.argv = ['shakedown', 'run', '--out', sys.argv[1], '-q']; "
         "from shakedown.scenes.cli import main; t0 = time.process_time(); w0 = time.time()\n"
         "try:\n    main()\nexcept SystemExit:\n    pass\n"
         "print('CPU', time.process_time() - t0, 'WALL', time.time() - w0)")


def run(tree: Path, out: Path) -> tuple[float, float]:
    env = dict(os.environ, SHAKEDOWN_KERNEL="numpy", OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1",
               PYTHONPATH=str(tree))
    res = subprocess.run([sys.executable, "-c", CHILD, str(out)], cwd=out.parent, env=env,
                         capture_output=True, text=True, check=True)
    line = [x for x in res.stdout.splitlines() if x.startswith("CPU")][-1].split()
    return float(line[1]), float(line[3])


def compare(a: Path, b: Path) -> str:
    ra = list(csv.DictReader(open(a / "sweep_runs.csv")))
    rb = list(csv.DictReader(open(b / "sweep_runs.csv")))
    if len(ra) != len(rb):
        return f"row counts differ: {len(ra)} vs {len(rb)}"
    worst, differ = {}, set()
    for x, y in zip(ra, rb, strict=True):
        for k in x:
            try:
                fx, fy = float(x[k]), float(y[k])
            except ValueError:
                if x[k] != y[k]:
                    differ.add(k)
                continue
            if k == "wall_s":
                continue
            if fx != fy and (float(fx).is_integer() and float(fy).is_integer()):
                differ.add(k)
            d = abs(fx - fy) / max(abs(fx), abs(fy), 1e-300) if fx != fy else 0.0
            worst[k] = max(worst.get(k, 0.0), d)
    rel = ", ".join(f"{k} {v:.1e}" for k, v in worst.items() if v > 0) or "none"
    return (f"{len(ra)} rows; columns that differ as text/integers: {sorted(differ) or 'none'}; "
            f"largest relative float differences: {rel}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", type=Path, required=True)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    trees = {"this": ROOT, "baseline": args.baseline.resolve()}
    times = {k: [] for k in trees}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats):
            for name, tree in trees.items():
                load = os.getloadavg()[0]
                out = Path(tmp) / f"{name}{r}" / "out"
                out.parent.mkdir()
                cpu, wall = run(tree, out)
                times[name].append(cpu)
                print(f"{name:8s} run {r + 1}: CPU {cpu:6.2f} s  wall {wall:6.2f} s  load {load:.2f}",
                      flush=True)
        for name in trees:
            print(f"{name:8s} median CPU {statistics.median(times[name]):.2f} s "
                  f"(min {min(times[name]):.2f}, max {max(times[name]):.2f})")
        print(f"ratio this/baseline (medians): "
              f"{statistics.median(times['this']) / statistics.median(times['baseline']):.3f}")
        print("sweep_runs.csv:", compare(Path(tmp) / "this0" / "out", Path(tmp) / "baseline0" / "out"))
        for r in range(1, args.repeats):
            print(f"  this run {r + 1} vs run 1:", compare(Path(tmp) / f"this{r}" / "out",
                                                          Path(tmp) / "this0" / "out"))


if __name__ == "__main__":
    main()
