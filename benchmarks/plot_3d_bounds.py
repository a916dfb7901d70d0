"""The dissipation-vs-lam figure of docs/guide/bounds_3d.md: one coupled 3-D system (N = 3, the
first coupled system of bench_3d_bounds_cycles.py), runs from 4 initial states at 9 load factors,
the 3-D bounds marked.

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/plot_3d_bounds.py docs/guide/bounds_3d_dissipation.png
"""

from __future__ import annotations

import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import shakedown as sd  # noqa: E402
from shakedown.evolution.steady_maps import sample_initial_slips  # noqa: E402
from shakedown.plotting.bounds import plot_dissipation_vs_lam  # noqa: E402

sys.path.insert(0, "benchmarks")
from bench_3d_bounds_cycles import random_3d, random_load  # noqa: E402


def main(path):
    s, load = random_3d(3, 100, True), random_load(3, 200)
    b = sd.shakedown_bounds(s, load, adjacency=True, facets=16)
    lams = b.lam2 * np.array([0.5, 0.7, 0.8, 0.9, 0.95, 1.0, 1.05, 1.15, 1.3])
    V0 = sample_initial_slips(s, load, 4, rng=0)
    W = np.full((lams.size, 4), np.nan)
    for i, lam in enumerate(lams):
        runs = sd.solve_cycles(s, load, lam, initial_slip=V0, steps_per_cycle=24, max_cycles=60,
                               tol=1e-9)
        W[i] = [r.dissipation[-1] for r in runs]
        print(f"lam = {lam:.5g}: last-cycle W = {W[i]}", flush=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    plot_dissipation_vs_lam(lams, W, b, ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    with open(path.replace(".png", ".json"), "w") as fh:
        json.dump(dict(lams=lams.tolist(), W=W.tolist(), lam2=b.lam2, lam_adj_cone=b.lam_adj_cone,
                       lam1_cone=b.lam1_cone, lam2_polygon=b.lam2_polygon, facets=b.facets), fh,
                  indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/guide/bounds_3d_dissipation.png")
