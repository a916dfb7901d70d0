"""The polyhedral candidates against the number of facets k (the table of docs/guide/bounds_3d.md).

Random coupled 3-D systems (N = 3, f = 0.4, one harmonic; the generators of
bench_3d_bounds_cycles.py with system seed s and load seed s + 10): lam1_cone, lam_adj_cone and
lam2_polygon on inscribed k-gons for k = 4 .. 64, beside lam2 on the cones.

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_bounds_k.py
"""

from __future__ import annotations

import sys
import time

import shakedown as sd

sys.path.insert(0, "benchmarks")
from bench_3d_bounds_cycles import random_3d, random_load  # noqa: E402


def main():
    print("seed  lam2(cones) | k: lam1_cone lam_adj_cone lam2_polygon [s]")
    for seed in range(3):
        s, load = random_3d(3, seed, True), random_load(3, seed + 10)
        row = []
        for k in (4, 8, 16, 32, 64):
            t0 = time.perf_counter()
            b = sd.shakedown_bounds(s, load, adjacency=True, facets=k)
            row.append(f"{k}: {b.lam1_cone:.5f} {b.lam_adj_cone:.5f} {b.lam2_polygon:.5f} "
                       f"[{time.perf_counter() - t0:.1f}]")
        print(seed, f"{b.lam2:.5f} |", " | ".join(row), flush=True)


if __name__ == "__main__":
    main()
