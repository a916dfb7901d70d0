"""Speed of the certified 3-D lam2: the dense interior point path against the Clarabel path.

For random coupled systems (dense K, isotropic f = 0.4, one harmonic, tangential load rotating
elliptically, normal load varying) at each N: the certified cutting-plane lam2
(``sd.shakedown_bounds(..., only=("lam2",), solver=S)``, bracket to the default rtol = 1e-6)
with ``S = "dense"`` (the dense interior point, :mod:`shakedown.bounds.cones.dense_ipm`, each
answer checked, Clarabel where a check fails; ``"auto"`` takes it from 150 nodes on) and
``S = "clarabel"`` (the path before this
change: every SOCP by Clarabel).  Each measurement runs in its own process (one thread, BLAS
pinned by the caller's environment), so its peak memory (``ru_maxrss``) is its own; CPU time
(``time.process_time``) is the one-core figure on a loaded machine, wall time beside it, the
load average (1 min) recorded with each row.

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 python3 benchmarks/bench_3d_bounds.py 100 200 \
        --seeds 0 1 2 --solvers dense clarabel --out benchmarks/bounds_3d_dense_speed.json

``--sampled S`` adds the plain sampled SOCP (Clarabel, ``S`` equally spaced times, no
certificate) of the earlier version of this benchmark.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this repository's package
import shakedown as sd  # noqa: E402
from shakedown.bounds.cones.data import cone_data  # noqa: E402
from shakedown.bounds.cones.engine import cone_bounds  # noqa: E402
from shakedown.bounds.cones.socp import solve_cuts  # noqa: E402


def random_3d(n, seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    return sd.DiscreteSystem(K[: 2 * n, : 2 * n], K[: 2 * n, 2 * n:], K[2 * n:, 2 * n:],
                             friction=0.4, dim=3)


def random_load(n, seed):
    rng = np.random.default_rng(seed)
    return sd.LoadCycle.from_harmonics(
        q0=0.2 * n * rng.normal(size=(n, 2)), p0=n * (1 + rng.random(n)),
        q_cos=n * rng.normal(size=(n, 2)), q_sin=n * rng.normal(size=(n, 2)),
        p_cos=0.2 * n * rng.normal(size=n), p_sin=0.2 * n * rng.normal(size=n))


def sampled(system, load, S):
    d = cone_data(system, load)
    n = system.n_nodes
    t = np.arange(S) / S
    ans = solve_cuts(d, np.repeat(np.arange(n), S), np.tile(t, n))
    return ans.lam * d.load_factor


def one(n, seed, solver, rtol=1e-6):
    """One measurement in this process; prints a JSON row."""
    s, load = random_3d(n, seed), random_load(n, 1000 + seed)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0, c0 = time.perf_counter(), time.process_time()
    if solver.startswith("sampled"):
        val = sampled(s, load, int(solver[7:]))
        row = dict(lam=val)
    else:
        # = sd.shakedown_bounds(..., solver=solver) for dim 3, which does not pass rtol on
        b = cone_bounds(s, load, only=("lam2",), solver=solver, rtol=rtol)
        row = dict(lam2=b.lam2, lam2_lower=b.lam2_lower, lam2_upper=b.lam2_upper,
                   width=(b.lam2_upper - b.lam2_lower) / b.lam2_upper, status=b.status,
                   socps=b.n_socps, cuts=b.n_cuts, iterations=b.iterations, path=b.path,
                   paths=list(b.socp_paths), fallbacks=list(b.fallbacks))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    row.update(N=n, seed=seed, solver=solver, rtol=rtol, wall=wall, cpu=cpu, peak_rss_mb=rss / 1024,
               setup_rss_mb=rss0 / 1024, load=os.getloadavg()[0])
    print(json.dumps(row), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sizes", type=int, nargs="*")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--solvers", nargs="+", default=["dense", "clarabel"])
    ap.add_argument("--sampled", type=int, nargs="*", default=[])
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--rtol", type=float, default=1e-6, help="relative width of the bracket")
    ap.add_argument("--out", default="benchmarks/bounds_3d_dense_speed.json")
    ap.add_argument("--one", nargs=4, metavar=("N", "SEED", "SOLVER", "RTOL"),
                    help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        one(int(a.one[0]), int(a.one[1]), a.one[2], float(a.one[3]))
        return
    rows = []
    if os.path.exists(a.out):
        with open(a.out) as fh:
            rows = json.load(fh)
    solvers = list(a.solvers) + [f"sampled{S}" for S in a.sampled]
    for n in a.sizes:
        for seed in a.seeds:
            for solver in solvers:
                cmd = [sys.executable, __file__, "--one", str(n), str(seed), solver, str(a.rtol)]
                try:
                    p = subprocess.run(cmd, capture_output=True, text=True, timeout=a.timeout)
                    row = json.loads(p.stdout.strip().splitlines()[-1])
                except subprocess.TimeoutExpired:
                    row = dict(N=n, seed=seed, solver=solver, status="timeout",
                               wall=a.timeout, load=os.getloadavg()[0])
                except (IndexError, json.JSONDecodeError):
                    row = dict(N=n, seed=seed, solver=solver, status="error",
                               stderr=p.stderr[-2000:])
                rows.append(row)
                print(json.dumps({k: v for k, v in row.items() if k != "paths"}), flush=True)
                with open(a.out, "w") as fh:
                    json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
