"""Plot of bench_bounds_scaling.py's results: seconds against N (log-log) with the slopes.

Usage: python benchmarks/plot_bounds_scaling.py benchmarks/bounds_scaling_*.json
Writes benchmarks/bounds_scaling.png.
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

rows = [r for f in sys.argv[1:] for r in json.loads(Path(f).read_text())]
fig, ax = plt.subplots(figsize=(7, 4.5))
for variant in ("new", "new+adj", "base", "base-noadj", "highs"):
    pts = sorted((r["n"], r["seconds"]) for r in rows
                 if r["variant"] == variant and np.isfinite(r.get("seconds", np.nan)))
    if not pts:
        continue
    n, t = np.array(pts, float).T
    label = variant
    if len(n) >= 2:
        slope = np.polyfit(np.log(n[-2:]), np.log(t[-2:]), 1)[0]
        label += f" (slope {slope:.2f} from N={n[-2]:.0f} to {n[-1]:.0f})"
    ax.loglog(n, t, "o-", label=label)
ax.set_xlabel("N (cracks)")
ax.set_ylabel("seconds (median)")
ax.set_title("shakedown_bounds on Kachanov networks")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
out = Path(__file__).parent / "bounds_scaling.png"
fig.tight_layout()
fig.savefig(out, dpi=120)
print(out)
