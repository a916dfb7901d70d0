"""Plot of bench_bounds_scaling.py's results: seconds and peak RSS against N (log-log), slopes.

Usage: python benchmarks/plot_bounds_scaling.py FILE.json ... [--as-base FILE.json ...]
Writes benchmarks/bounds_scaling.png.  Variant names as in the benchmark's docstring; the
labels below describe the runs of RESULTS_bounds_scaling.md's newest section (baseline
8176575).  The ``new`` rows of the files after ``--as-base`` are plotted as ``base`` (runs of
the baseline's code made when it was new, e.g. its N = 2000 run of 1226 s).
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LABELS = {
    "new": "new default (screened start, single-LP dual simplex)",
    "new-exact": "new, intervals=True (every interval)",
    "base": "base 8176575 default (pruned lam1)",
    "base-noadj": "base, adjacency=False",
    "new+adj": "new, adjacency=True",
    "highs": "solver='highs'",
}

args = sys.argv[1:]
cut = args.index("--as-base") if "--as-base" in args else len(args)
rows = [r for f in args[:cut] for r in json.loads(Path(f).read_text())]
have = {(r["n"], r["variant"]) for r in rows}
for f in args[cut + 1:]:
    for r in json.loads(Path(f).read_text()):
        if r["variant"] == "new" and (r["n"], "base") not in have:
            rows.append(dict(r, variant="base"))
fig, (ax, axm) = plt.subplots(1, 2, figsize=(11, 4.5))
for variant, label in LABELS.items():
    pts = sorted((r["n"], r["seconds"], r.get("peak_rss_mb", np.nan)) for r in rows
                 if r["variant"] == variant and np.isfinite(r.get("seconds", np.nan)))
    if not pts:
        continue
    n, t, mem = np.array(pts, float).T
    if len(n) >= 2:
        slope = np.polyfit(np.log(n[-2:]), np.log(t[-2:]), 1)[0]
        label += f"\n(slope {slope:.2f} from N={n[-2]:.0f} to {n[-1]:.0f})"
    line, = ax.loglog(n, t, "o-", label=label)
    axm.loglog(n, mem, "o-", color=line.get_color(), label=variant)
for y, text in ((5.0, "5 s (N = 500 target)"), (120.0, "2 min (N = 2000 target)")):
    ax.axhline(y, color="0.6", ls=":", lw=1)
    ax.text(0.02, y, text, transform=ax.get_yaxis_transform(), fontsize=7, color="0.4",
            va="bottom")
ax.set_xlabel("N (cracks)")
ax.set_ylabel("seconds (median of alternating runs)")
ax.set_title("shakedown_bounds, default options, Kachanov networks", fontsize=10)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=7)
axm.axhline(2048.0, color="0.6", ls=":", lw=1)
axm.text(0.02, 2048.0, "2 GB (N = 2000 target)", transform=axm.get_yaxis_transform(),
         fontsize=7, color="0.4", va="bottom")
axm.set_xlabel("N (cracks)")
axm.set_ylabel("peak RSS of the worker [MB] (Kachanov model included)")
axm.grid(True, which="both", alpha=0.3)
axm.legend(fontsize=7)
out = Path(__file__).parent / "bounds_scaling.png"
fig.tight_layout()
fig.savefig(out, dpi=120)
print(out)
