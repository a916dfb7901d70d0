"""Speed of the 3-D lam2 (cone engine) against a plain sampled SOCP, side by side in one run.

For random coupled systems (dense K, isotropic f = 0.4, one harmonic, tangential load rotating
elliptically, normal load varying) at each N: the certified cutting-plane lam2
(``sd.shakedown_bounds(..., only=("lam2",))``, bracket to 1e-7) and the baseline, one Clarabel
SOCP with the cones of every node at S equally spaced times (S = 16, 64), which over-estimates
lam2 (a relaxation) and certifies nothing about the times in between.  Medians of REPEATS
timings per system, several systems per N, the worst case beside the median.

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_bounds.py 50 100 200 [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

import shakedown as sd
from shakedown.bounds.cones.data import cone_data
from shakedown.bounds.cones.socp import solve_cuts


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


def timed(fn, repeats):
    ts, val = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        val = fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), val


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sizes", type=int, nargs="+")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--systems", type=int, default=3)
    ap.add_argument("--out", default="benchmarks/bounds_3d_speed.json")
    a = ap.parse_args()
    rows = []
    print("load:", os.getloadavg())
    for n in a.sizes:
        for k in range(a.systems):
            s, load = random_3d(n, k), random_load(n, 1000 + k)
            t_exact, b = timed(lambda s=s, load=load: sd.shakedown_bounds(s, load, only=("lam2",)),
                               a.repeats)
            t16, l16 = timed(lambda s=s, load=load: sampled(s, load, 16), a.repeats)
            t64, l64 = timed(lambda s=s, load=load: sampled(s, load, 64), a.repeats)
            row = dict(N=n, system=k, t_exact=t_exact, lam2=b.lam2, lam2_upper=b.lam2_upper,
                       status=b.status, socps=b.n_socps, cuts=b.n_cuts, t_sampled16=t16,
                       lam_sampled16=l16, t_sampled64=t64, lam_sampled64=l64,
                       load=os.getloadavg()[0])
            rows.append(row)
            print(json.dumps(row), flush=True)
            with open(a.out, "w") as fh:
                json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
