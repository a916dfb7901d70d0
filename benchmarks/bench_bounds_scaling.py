"""Bounds with the default options on Kachanov crack networks: time and memory against N,
today's code side by side with a baseline commit (``--base``) and with HiGHS.

Usage (from the repository root)::

    git worktree add /tmp/bounds-b450 b450214          # the baseline, once
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bounds_scaling.py \\
        --sizes 100 200 500 --repeats 3 --base /tmp/bounds-b450 --variants new base \\
        [--highs 100 200] --out benchmarks/bounds_scaling_pruned_small.json

(The first sections of RESULTS_bounds_scaling.md used ``--base /tmp/bounds-base`` = af73457.)

Each measurement runs in a fresh subprocess (``--worker``) with ``PYTHONPATH`` pointing at the
code under test, so both versions see the same machine load in the same run; the variants of
one size alternate, and the median over ``--repeats`` is reported.  The network:
``crack_networks.sample_crack_set(N, density=0.1, half_length=1, min_spacing=0.1, rng=1)``,
``kachanov_model(shear_modulus=1, poisson_ratio=0.25, friction=0.6)``, the seed's load
``S0 = (-1, 0, -1)``, ``S1 = (0, 1, 0)`` (the default scene's model at other sizes).  Timed:
``shakedown_bounds(system, load)`` only (not the Kachanov assembly).  Variants:

* ``new``: this checkout, default options (``lam1``, ``lam2``, activity intervals, separation
  check, safe state; ``lam_adj`` is opt-in since issue 14);
* ``new+adj``: this checkout with ``adjacency=True``;
* ``new-exact``: this checkout with ``intervals=True`` (every activity interval exactly: the
  default before the pruning of issue 14);
* ``base``: the baseline commit with its default options (af73457: with the ``N`` adjacency
  LPs; b450214: without them, every interval exactly);
* ``base-noadj``: the baseline with ``adjacency=False``;
* ``highs``: this checkout, ``solver="highs"`` (every LP by HiGHS), default options.

Peak memory: the worker's peak resident set size (``ru_maxrss``), which includes the
interpreter, numpy and the Kachanov matrices.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worker(n: int, variant: str) -> dict:
    import numpy as np

    import crack_networks as cn
    import shakedown as sd

    cracks = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(1))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    load = model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))
    kw = {}
    if variant in ("new+adj",):
        kw["adjacency"] = True
    if variant == "base-noadj":
        kw["adjacency"] = False
    if variant == "highs":
        kw["solver"] = "highs"
    if variant == "new-exact":
        kw["intervals"] = True
    bounds = sd.shakedown_bounds  # import the analysis before the clock starts
    t = time.perf_counter()
    b = bounds(model.system, load, **kw)
    sec = time.perf_counter() - t
    return dict(n=n, variant=variant, seconds=sec, lam1=float(b.lam1), lam2=float(b.lam2),
                lam_adj=float(b.lam_adj), n_lps=int(b.n_lps), iterations=int(b.simplex_iterations),
                limiting=int(b.limiting_constraint),
                n_exact=int(getattr(b, "lam_high_exact", np.ones(0, bool)).sum()),
                residual=float(max(b.residuals.values())),
                peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def run(n, variant, base, timeout):
    path = base if variant.startswith("base") else str(ROOT)
    env = dict(os.environ, PYTHONPATH=path, OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, __file__, "--worker", str(n), variant]
    load = Path("/proc/loadavg").read_text().split()[0]  # 1-minute load when this run starts
    try:
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout,
                           cwd=path)
    except subprocess.TimeoutExpired:
        return dict(n=n, variant=variant, seconds=float("nan"), note=f"timeout {timeout} s")
    if p.returncode:
        return dict(n=n, variant=variant, seconds=float("nan"), note=p.stderr[-300:])
    out = json.loads(p.stdout.strip().splitlines()[-1])
    out["load_at_start"] = float(load)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker", nargs=2)
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 500])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--base", default="/tmp/bounds-b450")
    ap.add_argument("--variants", nargs="+", default=["new", "new+adj", "base", "base-noadj"])
    ap.add_argument("--highs", type=int, nargs="*", default=[], help="sizes also run by HiGHS")
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "bounds_scaling.json"))
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(int(args.worker[0]), args.worker[1])))
        return
    print("loadavg:", Path("/proc/loadavg").read_text().strip(), flush=True)
    rows = []
    for n in args.sizes:
        variants = list(args.variants) + (["highs"] if n in args.highs else [])
        runs = {v: [] for v in variants}
        for _ in range(args.repeats):
            for v in variants:
                runs[v].append(run(n, v, args.base, args.timeout))
        for rs in runs.values():
            secs = [r["seconds"] for r in rs]
            row = dict(rs[-1])
            row["seconds"] = statistics.median(secs)
            row["all_seconds"] = secs
            row["all_load_at_start"] = [r.get("load_at_start") for r in rs]
            row["loadavg"] = Path("/proc/loadavg").read_text().split()[:3]
            rows.append(row)
            print(json.dumps(row), flush=True)
    print("loadavg:", Path("/proc/loadavg").read_text().strip(), flush=True)
    Path(args.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
