"""Cyclic runs of an FE interface: condensed (dense ``K``) against uncondensed (sparse ``K_z``).

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_fe_uncondensed.py --nx 499 999 1999 --repeats 3

The strip of ``bench_fe_bounds.py`` (``fe.rectangle(nx / 100, 0.1, nx, 8)``, P1, E = 1, nu = 0.3,
held at its left end, bottom on a rigid obstacle: ``nx`` contact nodes (the left corner is
held); dead load: top traction (0, -1); cyclic: top traction (0.4, 0) at ``lam``; friction 0.5), run by
:func:`shakedown.solve_cycles` from the welded state (40 steps per cycle, at most
``--cycles`` cycles).  Each measurement is a fresh subprocess (its peak RSS is its own):
``condensed`` = ``model.condense()`` + the run on the dense ``K`` (the compiled kernel's path);
``uncondensed`` = ``model.uncondensed()`` + the run on ``K_z``.  Printed: model time, run
time, steady dissipation, final slips' largest difference between the two, peak RSS.
``--bounds``: ``shakedown_bounds`` (default options) instead of the run ("run" columns; the
"slips differ" column then compares ``(lam1, lam2, lam_separation)``).  Results:
``RESULTS_fe_uncondensed.md``, ``fe_uncondensed.json`` (``fe_uncondensed_bounds.json``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np


def worker(nx: int, kind: str, lam: float, cycles: int, out: str, bounds: bool = False):
    import shakedown as sd
    from shakedown import fe

    loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shake": fe.Traction("top", (0.4, 0.0))}
    model = fe.FEModel(fe.rectangle(nx / 100, 0.1, nx, 8), fe.isotropic(1.0, 0.3),
                       dirichlet={"left": "xy"}, contact=["bottom"], loads=loads, friction=0.5)
    t0 = time.perf_counter()
    m = model.condense() if kind == "condensed" else model.uncondensed()
    t1 = time.perf_counter()
    lc = m.load_cycle(static="dead", cyclic="shake")
    if bounds:  # the bounds (default options) instead of the run
        b = sd.shakedown_bounds(m.system, lc)
        t2 = time.perf_counter()
        np.save(out, np.array([b.lam1, b.lam2, b.lam_separation]))
        print(json.dumps({
            "nx": nx, "n_nodes": m.n_nodes, "kind": kind, "model_s": t1 - t0,
            "run_s": t2 - t1, "status": b.status,
            "n_cycles": 0, "steady_dissipation": float("nan"), "lam1": b.lam1, "lam2": b.lam2,
            "stats": {"n_lps": b.n_lps},
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
        return
    run = sd.solve_cycles(m.system, lc, lam, steps_per_cycle=40, max_cycles=cycles)
    t2 = time.perf_counter()
    np.save(out, run.final_slip)
    print(json.dumps({
        "nx": nx, "n_nodes": m.n_nodes, "kind": kind, "model_s": t1 - t0, "run_s": t2 - t1,
        "status": run.status,
        "n_cycles": run.n_cycles, "steady_dissipation": run.steady_dissipation,
        "max_residual": run.max_residual, "stats": {k: v for k, v in run.statistics.items()
                                                     if isinstance(v, (int, float))},
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--nx", type=int, nargs="+", default=[499, 999, 1999])
    ap.add_argument("--lam", type=float, default=0.86)
    ap.add_argument("--cycles", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default="benchmarks/fe_uncondensed.json")
    ap.add_argument("--bounds", action="store_true",
                    help="measure shakedown_bounds (default options) instead of the run")
    ap.add_argument("--worker", nargs=2)
    a = ap.parse_args()
    if a.worker:
        worker(int(a.worker[0]), a.worker[1], a.lam, a.cycles, f"/tmp/fe_unc_{a.worker[1]}.npy",
               a.bounds)
        return
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    rows = []
    for nx in a.nx:
        res = {"condensed": [], "uncondensed": []}
        for _ in range(a.repeats):
            for kind in ("condensed", "uncondensed"):  # alternating
                p = subprocess.run([sys.executable, __file__, "--worker", str(nx), kind,
                                    "--lam", str(a.lam), "--cycles", str(a.cycles)]
                                   + (["--bounds"] if a.bounds else []),
                                   capture_output=True, text=True, env=env, check=True)
                res[kind].append(json.loads(p.stdout.strip().splitlines()[-1]))
        d = np.load("/tmp/fe_unc_condensed.npy")
        u = np.load("/tmp/fe_unc_uncondensed.npy")
        diff = float(np.abs(d - u).max() / max(np.abs(d).max(), 1e-300))
        row = {"nx": nx, "n_contact_nodes": res["uncondensed"][-1]["n_nodes"],
               "slip_rel_diff": diff}
        for kind, rs in res.items():
            for key in ("model_s", "run_s", "peak_rss_mb"):
                row[f"{kind}_{key}"] = float(np.median([r[key] for r in rs]))
                row[f"{kind}_{key}_all"] = [round(r[key], 3) for r in rs]
            row[f"{kind}_status"] = rs[-1]["status"]
            row[f"{kind}_n_cycles"] = rs[-1]["n_cycles"]
            row[f"{kind}_steady_dissipation"] = rs[-1]["steady_dissipation"]
            for key in ("lam1", "lam2"):
                if key in rs[-1]:
                    row[f"{kind}_{key}"] = rs[-1][key]
            row[f"{kind}_stats"] = rs[-1]["stats"]
        tot = {k: row[f"{k}_model_s"] + row[f"{k}_run_s"] for k in res}
        row["total_ratio"] = tot["condensed"] / tot["uncondensed"]
        rows.append(row)
        print(f"N = {row['n_contact_nodes']}: condensed model {row['condensed_model_s']:.2f} s + run "
              f"{row['condensed_run_s']:.2f} s, {row['condensed_peak_rss_mb']:.0f} MB | "
              f"uncondensed model {row['uncondensed_model_s']:.2f} s + run "
              f"{row['uncondensed_run_s']:.2f} s, {row['uncondensed_peak_rss_mb']:.0f} MB | "
              f"total ratio {row['total_ratio']:.2f}x | slips differ by {diff:.2g} | "
              f"{row['condensed_status']}/{row['uncondensed_status']}, "
              f"{row['condensed_n_cycles']} cycles", flush=True)
    with open(a.json, "w") as fh:
        json.dump({"command": " ".join(sys.argv), "nproc": os.cpu_count(),
                   "loadavg": os.getloadavg(), "rows": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
