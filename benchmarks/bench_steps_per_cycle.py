"""Time per implicit step against the steps per cycle (issue 24), side by side with a baseline.

Usage::

    git archive 4d32dcf | tar -x -C /tmp/base      # the code before issue 24
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_steps_per_cycle.py --baseline /tmp/base

Each (code, problem, steps per cycle) runs in its own subprocess (``PYTHONPATH`` set to its
tree, ``OPENBLAS_NUM_THREADS=1``, a time limit ``--timeout`` per run): ``solve_cycles`` for 2
periods, the compiled kernel loaded outside the timing, ``--repeat`` runs, the median and the
worst time per step kept.  Problems:

``one node``
    one node, ``A = 1, B = 0.2, C = 2``, friction 0.3, ``q = 1.5 cos``, ``p = 1 + 0.5 sin``
    (cyclic slip), lam = 1.
``N cracks``
    the default scene's crack network with ``--cracks`` cracks (``bench_step.problem``),
    lam = 0.8.

The baseline built the warm-step basis from the ``(S - 1)^2`` Gram matrix of a period's
increments; a run past the time limit is reported as such.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
STEPS = (64, 256, 1024, 4096, 16384, 65536)


def worker(kind: str, steps: int, repeat: int, pkl: str | None) -> dict:
    import numpy as np

    import shakedown as sd
    from shakedown.evolution.complementarity import StepSolver

    if kind == "node":
        s = sd.DiscreteSystem([[1.0]], [[0.2]], [[2.0]], friction=0.3)
        load = sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.5], p_sin=[0.5])
        lam = 1.0
    else:
        sys.path.insert(0, str(HERE))
        from bench_step import load_problem

        s, load, _ = load_problem(pkl)
        lam = 0.8
    sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),
                    sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,
                    steps_per_cycle=4)  # the compiled kernel loaded outside the timing
    out, W = [], None
    for _ in range(repeat):
        solver = StepSolver(s)
        solver.critical  # noqa: B018  (outside the timing on both sides)
        t = time.perf_counter()
        run = sd.solve_cycles(s, load, lam, steps_per_cycle=steps, max_cycles=2, tol=1e-10,
                              solver=solver)
        out.append((time.perf_counter() - t) / run.statistics["n_steps"])
        W = float(np.asarray(run.dissipation)[-1])
    return {"per_step": out, "W_last": W}


def measure(tree: Path, kind: str, steps: int, repeat: int, pkl, timeout: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    cmd = [sys.executable, __file__, "--worker", kind, str(steps), str(repeat), str(pkl)]
    try:
        r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout,
                           cwd=tree)
    except subprocess.TimeoutExpired:
        return {"timeout": timeout}
    if r.returncode:
        return {"error": (r.stderr.strip().splitlines() or ["?"])[-1][:160]}
    return json.loads(r.stdout.strip().splitlines()[-1])


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        kind, steps, repeat, pkl = sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
        print(json.dumps(worker(kind, steps, repeat, pkl)))
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", required=True, type=Path)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cracks", type=int, default=50)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--steps", default=",".join(map(str, STEPS)))
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(HERE))
    from bench_step import problem

    pkl = problem(a.cracks)
    for tree in (ROOT, a.baseline):  # compile (and cache) each tree's kernel outside the timing
        measure(tree, "node", 64, 1, pkl, 1800)
    print(f"uptime: {os.popen('uptime').read().strip()}")
    print("| problem | steps/cycle | this code: median (worst) us/step | baseline | ratio | "
          "W last (this / base) |\n|---|---|---|---|---|---|")
    for kind, label in (("node", "one node"), ("cracks", f"{a.cracks} cracks")):
        give_up = False  # the baseline past its time limit once: larger sizes are not run
        for steps in map(int, a.steps.split(",")):
            new = measure(ROOT, kind, steps, a.repeat, pkl, a.timeout)
            old = ({"timeout": a.timeout} if give_up else
                   measure(a.baseline, kind, steps, a.repeat, pkl, a.timeout))
            give_up = give_up or "timeout" in old or "error" in old

            def fmt(m):
                if "per_step" in m:
                    return (f"{1e6 * statistics.median(m['per_step']):.1f} "
                            f"({1e6 * max(m['per_step']):.1f})")
                return f"> {m['timeout']:.0f} s per run" if "timeout" in m else m["error"]

            ratio = (f"{statistics.median(old['per_step']) / statistics.median(new['per_step']):.2f}"
                     if "per_step" in old and "per_step" in new else "-")
            w = (f"{new.get('W_last', float('nan')):.6g} / {old.get('W_last', float('nan')):.6g}")
            print(f"| {label} | {steps} | {fmt(new)} | {fmt(old)} | {ratio} | {w} |", flush=True)
    print(f"uptime: {os.popen('uptime').read().strip()}  ({time.strftime('%H:%M:%S')})")


if __name__ == "__main__":
    main()
