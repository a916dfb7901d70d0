"""First run after installing: what the compiled kernel costs to compile, cold and warm.

Each measurement runs in a fresh process with its own numba cache folder (``NUMBA_CACHE_DIR``):
``cold`` starts from an empty folder (what the first ``shakedown run`` after installing pays;
without ``NUMBA_CACHE_DIR`` the cache is ``shakedown/evolution/__pycache__/*.nbi, *.nbc``
beside the package), ``warm`` reuses the folder the cold run filled.  The work is one
``solve_cycles`` of the built-in two-node scene, which compiles the same kernel functions as any
run (the period loop ``march`` and everything it calls).  Reported: wall and CPU time of the
process (CPU time is the better measure on a shared machine: it does not count the time the
process waits for a core), and the CPU time of the ten largest compilations (inclusive of the
functions they call, from numba's ``numba:compile`` events).

Usage::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_first_run.py [--repeats 3] [--opt 3]

``--opt`` sets ``NUMBA_OPT`` (LLVM optimisation level, numba's default 3) for the child
processes, to measure what a lower level would save.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

CHILD = r"""
import json, time
w0, c0 = time.perf_counter(), time.process_time()
from numba.core import event as ev
import shakedown as sd
w1, c1 = time.perf_counter(), time.process_time()
starts, comp = {}, []
class L(ev.Listener):
    def on_start(self, e):
        starts[id(e)] = time.process_time()
    def on_end(self, e):
        d = e.data["dispatcher"].py_func
        comp.append((time.process_time() - starts.pop(id(e), time.process_time()),
                     d.__module__ + "." + d.__qualname__))
ev.register("numba:compile", L())
s = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                      [[1.5, 0.2], [0.2, 1.5]], 0.7)
load = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0],
                                   q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
run = sd.solve_cycles(s, load, 1.5)
w2, c2 = time.perf_counter(), time.process_time()
comp.sort(reverse=True)
print(json.dumps(dict(import_wall=w1 - w0, import_cpu=c1 - c0, run_wall=w2 - w1,
                      run_cpu=c2 - c1, W=run.steady_dissipation, top=comp[:10])))
"""


def child(cache: str, opt: int | None) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1")
    if opt is not None:
        env["NUMBA_OPT"] = str(opt)
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--opt", type=int, default=None)
    args = ap.parse_args()
    rows = []
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as cache:
            load = os.getloadavg()[0]
            t = time.strftime("%H:%M:%S")
            cold = child(cache, args.opt)
            warm = child(cache, args.opt)
        rows.append((t, load, cold, warm))
        print(f"{t} load {load:.1f}: cold run {cold['run_wall']:.1f} s wall, "
              f"{cold['run_cpu']:.1f} s CPU; warm {warm['run_wall']:.2f} s wall, "
              f"{warm['run_cpu']:.2f} s CPU; import {warm['import_wall']:.2f} s; "
              f"W = {cold['W']:.12g} / {warm['W']:.12g}", flush=True)
    print("largest compilations of the last cold run (CPU s, inclusive):")
    for cpu, name in rows[-1][2]["top"]:
        print(f"  {cpu:7.2f}  {name}")


if __name__ == "__main__":
    main()
