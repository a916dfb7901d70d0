"""Table of benchmarks/bounds_3d_dense_speed.json (bench_3d_bounds.py): per N, the dense path
against the Clarabel path (medians and worst over seeds, ratios per seed, agreement).

    python3 benchmarks/summarise_3d_bounds.py [benchmarks/bounds_3d_dense_speed.json]
"""

from __future__ import annotations

import json
import sys

import numpy as np


def main(path="benchmarks/bounds_3d_dense_speed.json"):
    rows = [r for r in json.load(open(path)) if r.get("status") in ("bounded", "bracket")]
    dense = {(r["N"], r["seed"]): r for r in rows if r.get("path", "").startswith("dense")}
    clar = {(r["N"], r["seed"]): r for r in rows if r.get("path") == "clarabel"}
    print("| N | seeds (dense / Clarabel) | dense CPU median / worst [s] | dense wall median / worst "
          "[s] | Clarabel CPU median / worst [s] | CPU ratio Clarabel / dense (per seed) | "
          "peak RSS dense / Clarabel [MB] | SOCPs dense | fallbacks | bracket width (rel.) | "
          "max abs(lam2 dense - lam2 Clarabel) / lam2 | brackets overlap | load |")
    print("|" + "---|" * 13)
    for n in sorted({k[0] for k in dense}):
        d = [dense[k] for k in sorted(dense) if k[0] == n]
        c = [clar[k] for k in sorted(clar) if k[0] == n]
        both = [(dense[k], clar[k]) for k in sorted(dense) if k in clar and k[0] == n]
        cpu, wall = np.array([r["cpu"] for r in d]), np.array([r["wall"] for r in d])
        ccpu = np.array([r["cpu"] for r in c])
        ratio = ", ".join(f"{b['cpu'] / a['cpu']:.1f}" for a, b in both) or "-"
        diff = max((abs(a["lam2"] - b["lam2"]) / b["lam2"] for a, b in both), default=np.nan)
        overlap = sum(max(a["lam2_lower"], b["lam2_lower"]) <= min(a["lam2_upper"], b["lam2_upper"])
                      for a, b in both)
        width = max(r["width"] for r in d + c)
        fb = sum(len(r.get("fallbacks", [])) for r in d)
        loads = [r["load"] for r in d + c]
        rss = f"{max(r['peak_rss_mb'] for r in d):.0f} / " + \
            (f"{max(r['peak_rss_mb'] for r in c):.0f}" if c else "-")
        cl = f"{np.median(ccpu):.1f} / {ccpu.max():.1f}" if c else "-"
        print(f"| {n} | {len(d)} / {len(c)} | {np.median(cpu):.1f} / {cpu.max():.1f} | "
              f"{np.median(wall):.1f} / {wall.max():.1f} | {cl} | {ratio} | {rss} | "
              f"{', '.join(str(r['socps']) for r in d)} | {fb} | <= {width:.1e} | "
              f"{diff:.1e} | {overlap} / {len(both)} | {min(loads):.0f}-{max(loads):.0f} |")


if __name__ == "__main__":
    main(*sys.argv[1:])
