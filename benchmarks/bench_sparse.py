"""Sparse K against its dense twin (issue 14): a truncated Kachanov network, the cyclic solver
(SuperLU assignment factors vs the compiled dense kernel) and the bounds (HiGHS on the sparse
constraint matrix vs the dense path), time and peak memory.

Each measurement runs in a fresh subprocess with one BLAS thread; medians of ``--repeat``.

    python3 benchmarks/bench_sparse.py --sizes 500 1000 2000 --radius 6 --repeat 3
    python3 benchmarks/bench_sparse.py --sizes 500 --bounds --repeat 3
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap

CHILD = textwrap.dedent("""
    import json, resource, sys, time, tracemalloc
    import numpy as np
    import shakedown as sd, crack_networks as cn
    n, radius, kind, what = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
    cs = cn.sample_crack_set(n, density=0.1, half_length=1, min_spacing=0.1, rng=1)
    tracemalloc.start()
    t0 = time.perf_counter()
    m = cn.kachanov_model(cs, 1, 0.25, 0.6, interaction_radius=radius,
                          sparse=(kind == "sparse"))
    s = m.system
    load = m.load_cycle((-1, 0, -1), (0, 1, 0))
    t_model = time.perf_counter() - t0
    out = dict(n=n, radius=radius, kind=kind, what=what, model_s=t_model, nnz=s.nnz)
    if what == "cycles":
        sd.solve_cycles(s, load, 0.3, steps_per_cycle=4, max_cycles=1)  # load the kernel
        t0 = time.perf_counter()
        run = sd.solve_cycles(s, load, 1.2, steps_per_cycle=64, max_cycles=2)
        dt = time.perf_counter() - t0
        out.update(seconds=dt, per_step_ms=1e3 * dt / (64 * run.n_cycles),
                   W=float(run.dissipation[-1]), status=run.status)
    else:
        t0 = time.perf_counter()
        b = sd.shakedown_bounds(s, load)
        out.update(seconds=time.perf_counter() - t0, lam1=b.lam1, lam2=b.lam2, n_lps=b.n_lps,
                   worst_residual=max(b.residuals.values()))
    out["peak_traced_MB"] = tracemalloc.get_traced_memory()[1] / 2**20
    out["maxrss_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))
""")


def run(n, radius, kind, what, timeout):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    try:
        p = subprocess.run([sys.executable, "-c", CHILD, str(n), str(radius), kind, what],
                           capture_output=True, text=True, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(n=n, radius=radius, kind=kind, what=what, seconds=float("inf"),
                    note=f"timeout {timeout} s")
    if p.returncode:
        raise RuntimeError(p.stderr[-2000:])
    out = json.loads(p.stdout.strip().splitlines()[-1])
    with open("/proc/loadavg") as fh:
        out["load"] = fh.read().split()[0]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[500, 1000, 2000])
    ap.add_argument("--radius", type=float, default=6.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--bounds", action="store_true", help="time the bounds, not cyclic runs")
    ap.add_argument("--kinds", nargs="+", default=["sparse", "dense"])
    ap.add_argument("--timeout", type=float, default=1800)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    what = "bounds" if a.bounds else "cycles"
    rows = []
    for n in a.sizes:
        for _ in range(a.repeat):
            for kind in a.kinds:  # alternating, one fresh process each
                r = run(n, a.radius, kind, what, a.timeout)
                rows.append(r)
                print(json.dumps(r), flush=True)
    if a.out:
        with open(a.out, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
