"""Bounds of a condensed FE interface: a strip pressed on an obstacle, sheared cyclically.

    python3 benchmarks/bench_fe_bounds.py 499 build    # condense (and cache) 500 contact nodes
    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_fe_bounds.py 499 bounds
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=/tmp/base-8fb python3 benchmarks/bench_fe_bounds.py 499 bounds

``fe.rectangle(nx / 100, 0.1, nx, 8)`` (P1, E = 1, nu = 0.3), held at its left end, bottom on the
obstacle (``nx + 1`` contact nodes), dead load: top traction (0, -1); cyclic: top traction
(0.4, 0); friction 0.5.  The condensed model is cached in ``/tmp/fe_bounds_cache`` so that the
second call times the bounds alone.  Prints the time, ``lam1``, ``lam2``, the worst certificate
residual, whether HiGHS was used, and the peak RSS.  Results: ``RESULTS_bounds_walks.md``.
"""

import resource
import sys
import time

import shakedown as sd
from shakedown import fe

nx = int(sys.argv[1])
loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shake": fe.Traction("top", (0.4, 0.0))}
model = fe.FEModel(fe.rectangle(nx / 100, 0.1, nx, 8), fe.isotropic(1.0, 0.3),
                   dirichlet={"left": "xy"}, contact=["bottom"], loads=loads, friction=0.5)
t = time.perf_counter()
cm = model.condense(cache_dir="/tmp/fe_bounds_cache")
print("condense", round(time.perf_counter() - t, 2), "s, from cache:", cm.from_cache,
      "RSS MB", round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024), flush=True)
if sys.argv[2] == "bounds":
    from shakedown.bounds import engine

    used = []
    orig = engine.solve_highs
    engine.solve_highs = lambda *a, **k: used.append(1) or orig(*a, **k)
    lc = cm.load_cycle(static="dead", cyclic="shake")
    t = time.perf_counter()
    b = sd.shakedown_bounds(cm.system, lc)
    print("bounds", round(time.perf_counter() - t, 2), "s; lam1", b.lam1, "lam2", b.lam2,
          "residual", max(b.residuals.values()), "HiGHS path:", bool(used),
          "peak RSS MB", round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
          flush=True)
