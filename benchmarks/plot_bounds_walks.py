"""Plot of ``bench_bounds_walks.py``: bounds time against N, today's code and the baseline.

    python3 benchmarks/plot_bounds_walks.py benchmarks/bounds_walks_1000.json \\
        benchmarks/bounds_walks_2000.json --out benchmarks/bounds_walks.png

Reads the JSON lines the benchmark appends (``--out``); medians per (case, side); log-log axes
with the slope between the two largest N of each series in the legend.
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("files", nargs="+")
    ap.add_argument("--out", default="benchmarks/bounds_walks.png")
    a = ap.parse_args()
    runs = defaultdict(list)
    for path in a.files:
        for line in open(path):
            o = json.loads(line)
            if o.get("seconds") == o.get("seconds"):  # not nan
                runs[(o["case"].split(":")[0], int(o["case"].split(":")[1]), o["side"])].append(
                    o["seconds"])
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    styles = {"new": "-", "base": "--"}
    colours = {"random": "C0", "kachanov1": "C1", "kachanov2": "C2"}
    for kind in colours:
        for side in ("new", "base"):
            pts = sorted((n, statistics.median(v)) for (k, n, s), v in runs.items()
                         if k == kind and s == side)
            if not pts:
                continue
            n, t = np.array(pts).T
            label = f"{kind}, {'today' if side == 'new' else 'before (8fb0d9d)'}"
            if len(n) >= 2:
                slope = np.log(t[-1] / t[-2]) / np.log(n[-1] / n[-2])
                label += f" (slope {slope:.1f})"
            ax.loglog(n, t, styles[side], marker="o", color=colours[kind], label=label)
    ax.axhline(120, color="grey", lw=0.8, ls=":")
    ax.text(520, 130, "target at N = 2000: 2 min", color="grey", fontsize=8)
    ax.set_xlabel("nodes N")
    ax.set_ylabel("shakedown_bounds, default options [s]")
    ax.set_title("Bounds against N: one core, medians (baseline at N = 2000: one run)")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.out, dpi=150)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
