"""Benchmark: lam1 + lam2 by the bounds engine vs a straightforward cvxpy model of the same LPs.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bounds.py [--sizes 10 100 1000] [--repeats 3]
        [--cvxpy-subset 20] [--n2000]

For each size a random coupled system (seeded) is solved by
``shakedown_bounds(system, load, adjacency=False, separation=False)`` (lam2, the 2N activity
intervals, lam1 and the Chebyshev safe state) with ``solver="auto"`` and ``solver="highs"``, and
by cvxpy: one ``cvxpy.Problem`` per LP, as a user would write it (the lam2 LP, then for each
constraint ``k`` the LPs ``max lam`` and ``min lam`` with row ``k`` tight).  For large N the cvxpy
route is timed on ``--cvxpy-subset`` of the ``4N`` interval LPs and extrapolated (stated in the
output).  Medians over repeats; peak memory by ``tracemalloc`` (Python-allocated arrays).
"""

from __future__ import annotations

import argparse
import platform
import time
import tracemalloc

import numpy as np

import shakedown as sd
from shakedown.bounds import extreme_constraints, shakedown_bounds


def random_problem(n, seed=0, friction=0.3, coupling=0.3):
    """Random coupled system: ``K = M M^T + I`` (2N x 2N), ``B`` scaled by ``coupling``."""
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n)) / np.sqrt(2 * n)
    K = M @ M.T + np.eye(2 * n)
    system = sd.DiscreteSystem(K[:n, :n], coupling * K[:n, n:], K[n:, n:], friction)
    load = sd.LoadCycle.from_harmonics(
        0.1 * rng.standard_normal(n), 1 + rng.random(n),
        q_cos=rng.standard_normal(n), q_sin=rng.standard_normal(n),
        p_cos=0.3 * rng.standard_normal(n),
    )
    return system, load


def cvxpy_route(system, load, subset=None):
    """lam2 and the activity-interval LPs with one cvxpy Problem per LP; returns (lam1, lam2,
    seconds, number of interval LPs solved, number in the full route)."""
    import cvxpy as cp

    cs = extreme_constraints(system, load)
    n = cs.n_nodes
    t0 = time.perf_counter()
    v, lam = cp.Variable(n), cp.Variable()
    cons = [cs.G @ v <= cs.c + lam * cs.m, lam >= 0]
    lam2 = cp.Problem(cp.Maximize(lam), cons).solve()
    ks = range(2 * n) if subset is None else range(min(subset, 2 * n))
    hi, lo = [], []
    for k in ks:
        for sense, out in ((cp.Maximize, hi), (cp.Minimize, lo)):
            v, lam = cp.Variable(n), cp.Variable()
            cons = [cs.G @ v <= cs.c + lam * cs.m, lam >= 0,
                    cs.G[k] @ v == cs.c[k] + lam * cs.m[k]]
            out.append(cp.Problem(sense(lam), cons).solve())
    seconds = time.perf_counter() - t0
    lam1 = min(hi) if max(lo) <= 1e-7 * max(1.0, lam2) else 0.0
    return lam1, lam2, seconds, 2 * len(hi), 4 * n


def timed(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), out


def peak_memory(fn):
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cvxpy-subset", type=int, default=20,
                    help="constraints k whose interval LPs cvxpy solves when N >= 300")
    ap.add_argument("--highs-max", type=int, default=300, help="largest N for the HiGHS route")
    ap.add_argument("--n2000", action="store_true", help="also run N = 2000 once (engine only)")
    args = ap.parse_args(argv)
    print(f"# machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print("| N | engine (auto) s | HiGHS-only s | cvxpy s | cvxpy / engine | LPs | pivots | "
          "peak MB | lam1 | lam2 | max abs diff vs cvxpy |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    sizes = list(args.sizes) + ([2000] if args.n2000 else [])
    for n in sizes:
        system, load = random_problem(n)
        reps = args.repeats if n <= 1000 else 1

        def run(solver="auto", system=system, load=load):
            return shakedown_bounds(system, load, adjacency=False, separation=False, solver=solver)

        t_auto, b = timed(run, reps)
        mem = peak_memory(run) if n <= 1000 else float("nan")
        t_highs = float("nan")
        if n <= args.highs_max:
            t_highs, _ = timed(lambda: run("highs"), 1 if n > 100 else reps)
        cv = "-"
        ratio = "-"
        diff = "-"
        if n <= 1000:
            subset = None if n < 300 else args.cvxpy_subset
            t_cv, (l1, l2, secs, done, full) = timed(
                lambda s=system, ld=load, k=subset: cvxpy_route(s, ld, k), 1 if n >= 100 else reps
            )
            if done < full:
                secs = secs / (done + 1) * (full + 1)  # extrapolated: per-LP time x all LPs
                cv = f"{secs:.3g} (extrapolated from {done} of {full} interval LPs + lam2 LP)"
                diff = f"lam2: {abs(l2 - b.lam2):.1e}"
            else:
                cv = f"{secs:.3g}"
                diff = f"{max(abs(l1 - b.lam1), abs(l2 - b.lam2)):.1e}"
            ratio = f"{secs / t_auto:.1f}"
        print(f"| {n} | {t_auto:.3g} | {t_highs:.3g} | {cv} | {ratio} | {b.n_lps} | "
              f"{b.simplex_iterations} | {mem:.0f} | {b.lam1:.10g} | {b.lam2:.10g} | {diff} |",
              flush=True)


if __name__ == "__main__":
    main()
