"""Benchmark: condensation of the unit square (seed 000 s.7.1) onto its bottom nodes.

For n nodes per edge (P1, union-jack pattern, plane strain, nu = 0.3, top held):

- ``sparse``: ``FEModel.condense()`` (assembly + one sparse LU of K_ii + blocked solves for the
  2N contact right-hand sides), the package's method;
- ``cached``: the same model read back from the on-disk cache;
- ``dense``: the plain dense approach on the same assembled blocks: ``K_ii`` as a dense array,
  ``S = K_cc - K_ci solve(K_ii, K_ic)`` with LAPACK (skipped above ``--dense-max`` nodes).

Each (method, n) runs in a fresh subprocess: wall time is the median of ``--repeat`` runs,
peak memory the growth of the process's peak RSS (``ru_maxrss``) over the baseline after
imports and mesh creation.  Run::

    python benchmarks/bench_fe.py                 # 21..201 nodes, writes a markdown table
    python benchmarks/bench_fe.py --sizes 21 41 --repeat 3
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def model(n: int):
    from shakedown import fe

    mesh = fe.rectangle(1.0, 1.0, n - 1, n - 1, element="P1", pattern="union-jack")
    return fe.FEModel(mesh, fe.isotropic(1.0, 0.3), dirichlet=["top"], contact=["bottom"])


def one(method: str, n: int, repeat: int) -> dict:
    import numpy as np

    from shakedown.models.fe.assembled import Assembled

    m = model(n)
    times = []
    out = {}
    if method == "sparse":
        base = peak_rss_mb()
        for _ in range(repeat):
            t0 = time.perf_counter()
            cm = m.condense()
            times.append(time.perf_counter() - t0)
        out.update(cm.timings)
        out["n_interior_dofs"] = cm.counts["n_interior_dofs"]
        out["K_trace"] = float(np.trace(cm.K))
    elif method == "cached":
        with tempfile.TemporaryDirectory() as d:
            m.condense(cache_dir=d)
            base = peak_rss_mb()
            for _ in range(repeat):
                t0 = time.perf_counter()
                cm = model(n).condense(cache_dir=d)
                times.append(time.perf_counter() - t0)
            assert cm.from_cache
    elif method == "dense":
        base = peak_rss_mb()
        for _ in range(repeat):
            t0 = time.perf_counter()
            a = Assembled(m, mass=False)  # same assembly (its sparse LU is not used below)
            Kii = a.Kii.toarray()
            S = a.Kcc - a.Kci @ np.linalg.solve(Kii, a.Kci.T.toarray())
            S = 0.5 * (S + S.T)
            times.append(time.perf_counter() - t0)
            del Kii
        out["K_trace"] = float(np.trace(S))
    else:
        raise SystemExit(f"unknown method {method}")
    out.update(method=method, n=n, time=statistics.median(times), times=times,
               peak_mb=peak_rss_mb() - base)
    return out


def run_child(method: str, n: int, repeat: int) -> dict:
    cmd = [sys.executable, __file__, "--child", method, str(n), "--repeat", str(repeat)]
    res = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if res.returncode != 0:
        return {"method": method, "n": n, "error": res.stderr.strip().splitlines()[-1:]}
    return json.loads(res.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[21, 41, 61, 81, 101, 141, 201])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dense-max", type=int, default=81, help="largest n for the dense baseline")
    ap.add_argument("--json", default=None, help="also write the raw results here")
    ap.add_argument("--child", nargs=2, metavar=("METHOD", "N"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(one(args.child[0], int(args.child[1]), args.repeat)))
        return
    rows = []
    for n in args.sizes:
        r = {"n": n}
        for method in ("sparse", "cached", "dense"):
            if method == "dense" and n > args.dense_max:
                continue
            res = run_child(method, n, args.repeat)
            r[method] = res
            print(f"n={n:4d} {method:7s} " + (
                f"{res['time']:.3f} s  peak +{res['peak_mb']:.0f} MB" if "time" in res
                else f"failed: {res['error']}"), file=sys.stderr, flush=True)
        rows.append(r)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}; median of {args.repeat} runs\n")
    print("| nodes/edge | interior DOFs | sparse (s) | of which LU + solves (s) | sparse peak (MB) "
          "| cached (s) | dense (s) | dense peak (MB) | dense / sparse time | rel. diff trace(K) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        s, c, d = r.get("sparse", {}), r.get("cached", {}), r.get("dense")
        lu = s.get("factorization", float("nan")) + s.get("condensation", float("nan"))
        if d and "time" in d:
            dd = (f"{d['time']:.3f} | {d['peak_mb']:.0f} | {d['time'] / s['time']:.1f} | "
                  f"{abs(d['K_trace'] - s['K_trace']) / abs(s['K_trace']):.1e}")
        else:
            dd = "skipped | - | - | -"
        print(f"| {r['n']} | {s.get('n_interior_dofs', '-')} | {s.get('time', float('nan')):.3f} "
              f"| {lu:.3f} | {s.get('peak_mb', float('nan')):.0f} | "
              f"{c.get('time', float('nan')):.4f} | {dd} |")


if __name__ == "__main__":
    main()
