"""The 3-D step's single-precision Krylov products against double-precision ones, by conditioning.

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_cone_conditioning.py [--n 100] [--repeats 4]

A coupled system ``K = Q diag(logspace(0, d, 3N)) Q^T`` (random ``Q``: condition number ``10^d``;
``B`` scaled by 0.3, friction 0.2) and one step (``v = 0``, random tangential load, normal load
0.5-1.5), solved warm from 10 guesses (the answer perturbed by 1e-4 of its largest component).
The same solver with and without single-precision buffers (``cone_reduced.new_buffers(n,
single)``), interleaved per repeat; CPU per step (median over guesses and repeats), Newton
iterations per step, the largest difference of the reactions, and the single-precision solver's
tally (Krylov solves tried in single precision, and those that went on in double).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np


def system(n, decades, seed=0):
    import shakedown as sd

    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(3 * n, 3 * n)))
    K = (Q * np.logspace(0, decades, 3 * n)) @ Q.T
    K = 0.5 * (K + K.T)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.3 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=0.2, dim=3)
    return s, rng


def measure(n, decades, repeats):
    from shakedown.evolution import cone_kernel as ck
    from shakedown.evolution.cone_step import ConeStepSolver

    s, rng = system(n, decades)
    single, double = ConeStepSolver(s), ConeStepSolver(s)
    double._buffers = ck.new_buffers(n, False)
    v, q, p = np.zeros((n, 2)), rng.normal(size=(n, 2)), 0.5 + rng.random(n)
    ref = double.solve(v, q, p)
    u = np.column_stack([ref.slip_increment, ref.gap])
    guesses = [u + 1e-4 * np.abs(u).max() * rng.normal(size=u.shape) for _ in range(10)]
    rb = single.base(v, q, p)
    cpu = {"single": [], "double": []}
    its = {"single": 0, "double": 0}
    R = {}
    for rep in range(repeats):
        order = (("single", single), ("double", double))
        for name, sol in order if rep % 2 == 0 else order[::-1]:
            for k, g in enumerate(guesses):
                c0 = time.process_time()
                out = sol.solve_raw(rb, g)
                cpu[name].append(time.process_time() - c0)
                its[name] += out[4]
                R[(name, k)] = out[1]
    diff = max(np.abs(R[("single", k)] - R[("double", k)]).max() for k in range(len(guesses)))
    steps = repeats * len(guesses)
    return dict(decades=decades, single=float(np.median(cpu["single"])),
                double=float(np.median(cpu["double"])), its_single=its["single"] / steps,
                its_double=its["double"] / steps, diff=float(diff / ref.force_scale),
                tally=tuple(int(x) for x in single._buffers[4]), m=int(2 * np.sum(ref.states == 1)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--decades", default="1,2,3,4,5,6.5")
    a = ap.parse_args()
    print(f"Machine: {platform.machine()} {os.cpu_count()} cores, python "
          f"{platform.python_version()}, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}; load {os.getloadavg()}\n")
    print("| cond(K) | slip unknowns | single [ms] | double [ms] | double / single | Newton its "
          "(single, double) | max diff / F | single-precision solves tried, went on in double |")
    print("|---|---|---|---|---|---|---|---|")
    for d in (float(x) for x in a.decades.split(",")):
        r = measure(a.n, d, a.repeats)
        print(f"| 1e{d:g} | {r['m']} | {1e3 * r['single']:.3f} | {1e3 * r['double']:.3f} | "
              f"{r['double'] / r['single']:.2f}x | {r['its_single']:.1f}, {r['its_double']:.1f} | "
              f"{r['diff']:.1e} | {r['tally'][0]}, {r['tally'][1]} |")
    print(f"\nLoad after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
