"""Kachanov assembly (issue 14): time and peak memory at 2000 cracks against the baseline
commit, and the error of the truncated interaction against the full matrix.

    python benchmarks/bench_kachanov_assembly.py [--base /tmp/study-base] [--repeat 3]

Each measurement is a fresh subprocess (``OPENBLAS_NUM_THREADS=1``); the peak memory is the
peak of the memory traced by :mod:`tracemalloc` during the assembly (numpy reports its buffers
to it; the process's ``ru_maxrss`` was tried first and did not see the temporaries).  Baseline
and new code alternate; medians of ``--repeat``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ASSEMBLE = textwrap.dedent("""
    import json, time, tracemalloc
    import numpy as np
    import crack_networks as cn
    cs = cn.sample_crack_set({n}, density=0.1, min_spacing=0.1, rng=1)
    tracemalloc.start()  # numpy reports its buffers to tracemalloc
    t0 = time.perf_counter()
    {what}
    t = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    print(json.dumps(dict(seconds=t, peak_mb=peak, checksum=float(np.sum(K[:50, :50])))))
""")
WHAT = {
    "assembly": "K = cn.kachanov.stiffness_from_factors(cn.transmission_factors(cs), "
                "cs.half_lengths, 1.0, 0.25)",
    "model": "K = cn.kachanov_model(cs, validate=True).stiffness_raw",
}


def _run(code, path):
    env = {**os.environ, "PYTHONPATH": path, "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         cwd=path)  # not the caller's folder: "" on sys.path would win
    if out.returncode:
        raise RuntimeError(out.stderr[-2000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def side_by_side(base, n, repeat):
    lines = []
    for what, code in WHAT.items():
        res = {"base": [], "new": []}
        for _ in range(repeat):
            for name, path in (("base", base), ("new", str(ROOT))):
                res[name].append(_run(ASSEMBLE.format(n=n, what=code), path))
        same = res["base"][0]["checksum"] == res["new"][0]["checksum"]
        for name in ("base", "new"):
            s = [r["seconds"] for r in res[name]]
            m = [r["peak_mb"] for r in res[name]]
            lines.append(f"| {what} | {name} | {n} | {statistics.median(s):.2f} "
                         f"({', '.join(f'{x:.2f}' for x in s)}) | {statistics.median(m):.0f} "
                         f"({', '.join(f'{x:.0f}' for x in m)}) | {same} |")
    return lines


TRUNC = textwrap.dedent("""
    import json, resource, time
    import numpy as np
    import crack_networks as cn
    cs = cn.sample_crack_set({n}, density={rho}, min_spacing=0.1, rng=1)
    full = cn.kachanov_stiffness(cs)
    off = np.linalg.norm(full - np.diag(np.diag(full)))
    out = []
    for r in {radii}:
        t0 = time.perf_counter()
        Ks = cn.kachanov_stiffness(cs, interaction_radius=r)
        t = time.perf_counter() - t0
        D = Ks.toarray() - full
        out.append(dict(radius=r, seconds=t, nnz=int(Ks.nnz), fill=Ks.nnz / full.size,
                        rel_fro=float(np.linalg.norm(D) / off),
                        rel_max=float(np.abs(D).max() / np.abs(full - np.diag(np.diag(full))).max())))
    print(json.dumps(out))
""")

BOUNDS = textwrap.dedent("""
    import json
    import numpy as np
    import crack_networks as cn
    import shakedown as sd
    cs = cn.sample_crack_set({n}, density={rho}, min_spacing=0.1, rng=1)
    out = []
    for r in [None] + {radii}:
        m = cn.kachanov_model(cs, friction=0.6, interaction_radius=r)
        load = m.load_cycle()
        b = sd.shakedown_bounds(m.system, load, adjacency=False, separation=False)
        run = sd.solve_cycles(m.system, load, 1.5 * b.lam2, steps_per_cycle=64)
        out.append(dict(radius=r, lam1=b.lam1, lam2=b.lam2, W=run.steady_dissipation))
    print(json.dumps(out))
""")


def truncation(n, rho, radii):
    rows = _run(TRUNC.format(n=n, rho=rho, radii=list(radii)), str(ROOT))
    return [f"| {n} | {rho} | {r['radius']} | {r['fill']:.3f} | {r['seconds']:.2f} | "
            f"{r['rel_fro']:.2e} | {r['rel_max']:.2e} |" for r in rows]


def truncation_bounds(n, rho, radii):
    rows = _run(BOUNDS.format(n=n, rho=rho, radii=list(radii)), str(ROOT))
    ref = rows[0]
    out = []
    for r in rows[1:]:
        out.append(f"| {n} | {rho} | {r['radius']} | {abs(r['lam1'] / ref['lam1'] - 1):.1e} | "
                   f"{abs(r['lam2'] / ref['lam2'] - 1):.1e} | {abs(r['W'] / ref['W'] - 1):.1e} |")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--base", default="/tmp/study-base")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--only-assembly", action="store_true")
    args = ap.parse_args(argv)
    print("| what | code | N | seconds, median (runs) | peak MB, median (runs) | same K |")
    print("| --- | --- | --- | --- | --- | --- |")
    print("\n".join(side_by_side(args.base, args.n, args.repeat)), flush=True)
    if args.only_assembly:
        return
    print("\n| N | density | radius (a_i + a_j) | fill | seconds | rel. Frobenius error "
          "(off-diagonal) | rel. max error |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    print("\n".join(truncation(args.n, 0.1, (1.5, 3, 6, 12))), flush=True)
    print("\n| N | density | radius | lam1 rel. error | lam2 rel. error | W(1.5 lam2) rel. "
          "error |")
    print("| --- | --- | --- | --- | --- | --- |")
    print("\n".join(truncation_bounds(150, 0.1, [1.5, 3, 6, 12])), flush=True)


if __name__ == "__main__":
    main()
