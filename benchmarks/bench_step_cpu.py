"""CPU time per implicit step of ``solve_cycles`` in one tree (issue 25: the warm step before and
after a change of the kernel's call types), for side-by-side runs alternated between two trees.

Usage (one process per tree and repeat; the kernel loaded outside the timing)::

    for r in 1 2 3; do for t in /tmp/base /work/wt/firstrun; do
        OPENBLAS_NUM_THREADS=1 PYTHONPATH=$t python3 benchmarks/bench_step_cpu.py 200 $t; done; done

A random coupled system (``M M^T + N I``, friction at half the sufficient bound), a one-harmonic
load, 64 steps per period, 6 periods from the zero state, 5 repeats with a fresh solver each:
the median and the minimum of the process CPU time per step [us].
"""

import sys
import time

import numpy as np

import shakedown as sd
from shakedown.evolution.complementarity import StepSolver


def main():
    n, label = int(sys.argv[1]), sys.argv[2]
    rng = np.random.default_rng(1)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(0.5 * min(s.critical_friction().value, 2.0))
    load = sd.LoadCycle.from_harmonics(np.zeros(n), np.full(n, 2.0 * n),
                                       q_cos=rng.normal(size=n) * n,
                                       q_sin=rng.normal(size=n) * n)
    sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),  # the kernel
                    sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,  # loaded
                    steps_per_cycle=4)
    out = []
    for _ in range(5):
        solver = StepSolver(s)
        t = time.process_time()
        sd.solve_cycles(s, load, 1.0, steps_per_cycle=64, max_cycles=6, solver=solver)
        out.append((time.process_time() - t) / solver.totals["steps"] * 1e6)
    print(f"{label} n={n} us/step CPU median {np.median(out):.2f} min {min(out):.2f} "
          f"steps {solver.totals['steps']}")


if __name__ == "__main__":
    main()
