"""lam1 + lam2 for large random coupled systems (N = 1000, 2000): time, LPs, pivots, peak RSS.

Run from the repository root:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bounds_large.py
(the same systems as bench_bounds.py's ``random_problem``; engine only, no baseline: HiGHS
alone needs more than 10 minutes at N = 2000 and cvxpy days, see RESULTS_bounds.md).
"""

import resource
import sys
import time

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from bench_bounds import random_problem

import shakedown as sd

for n in (1000, 2000):
    s, L = random_problem(n)
    t = time.perf_counter()
    b = sd.shakedown_bounds(s, L, adjacency=False, separation=False)
    print(n, "lam1+lam2", time.perf_counter() - t, b.lam1, b.lam2, b.n_lps, b.simplex_iterations,
          max(b.residuals.values()), flush=True)
    print("peak RSS MB", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, flush=True)
