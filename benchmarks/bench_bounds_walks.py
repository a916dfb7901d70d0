"""Bounds with the default options at N = 500 - 2000: today's code against a baseline commit.

Run from the repository root (the baseline is a worktree of an earlier commit)::

    git worktree add --detach /tmp/base-8fb 8fb0d9d
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bounds_walks.py \\
        --cases random:1000 kachanov1:1000 kachanov2:1000 --repeats 3 --base /tmp/base-8fb
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bounds_walks.py \\
        --cases random:2000 kachanov2:2000 --repeats 3 --base-repeats 1 --base /tmp/base-8fb

Cases: ``random:N`` is ``bench_bounds.random_problem(N)`` (dense random coupled system, seed 0:
``lam1`` within 0.3 % of ``lam2``, the case where the pruning's walks dominate);
``kachanovS:N`` an N-crack network (``sample_crack_set(N, density=0.1, half_length=1,
min_spacing=0.1, rng=S)``, ``kachanov_model(shear_modulus=1, poisson_ratio=0.25,
friction=0.6)``, static ``(-1, 0, -1)``, cyclic ``(0, 1, 0)``), dense interaction.  Each run is
``shakedown_bounds(system, load)`` with the default options, in its own subprocess with
``OPENBLAS_NUM_THREADS=1``; the two sides alternate.  Printed per run: seconds, ``lam1``,
``lam2``, LPs, simplex iterations, walk pivots, peak RSS; then a table of medians and ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def problem(case: str):
    import numpy as np

    kind, n = case.split(":")
    n = int(n)
    if kind == "random":
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from bench_bounds import random_problem

        return random_problem(n)
    import crack_networks as cn

    seed = int(kind.removeprefix("kachanov"))
    cracks = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(seed))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    return model.system, model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))


def worker(case: str) -> dict:
    import resource
    import time

    import shakedown as sd
    from shakedown.bounds import facet_walk

    system, load = problem(case)
    pivots = [0]

    def counting(cls):
        orig = cls.walk_to

        def walk_to(self, k, cap):
            p0 = self.pivots
            out = orig(self, k, cap)
            pivots[0] += self.pivots - p0
            return out

        cls.walk_to = walk_to

    counting(facet_walk.FacetWalk)
    try:
        from shakedown.bounds import barycentric_walk
        counting(barycentric_walk.BarycentricWalk)
    except ImportError:  # the baseline has no barycentric walk
        pass
    t = time.perf_counter()
    b = sd.shakedown_bounds(system, load)
    sec = time.perf_counter() - t
    return dict(case=case, seconds=sec, lam1=float(b.lam1), lam2=float(b.lam2),
                n_lps=int(b.n_lps), iterations=int(b.simplex_iterations), walk_pivots=pivots[0],
                residual=float(max(b.residuals.values())),
                peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def run(case, path, timeout):
    env = dict(os.environ, PYTHONPATH=str(path), OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", case]
    load = Path("/proc/loadavg").read_text().split()[0]
    try:
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout,
                           cwd=str(path))
    except subprocess.TimeoutExpired:
        return dict(case=case, seconds=float("nan"), note=f"timeout {timeout} s")
    if p.returncode:
        return dict(case=case, seconds=float("nan"), note=p.stderr[-300:])
    out = json.loads(p.stdout.strip().splitlines()[-1])
    out["load_at_start"] = float(load)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker")
    ap.add_argument("--cases", nargs="+", default=["random:1000", "kachanov2:1000"])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--base-repeats", type=int, default=None)
    ap.add_argument("--base", default=None, help="worktree of the baseline commit")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--out", default=None, help="JSON lines file (appended)")
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(a.worker)))
        return
    base_rep = a.repeats if a.base_repeats is None else a.base_repeats
    rows = []
    for case in a.cases:
        runs = {"new": [], "base": []}
        for r in range(max(a.repeats, base_rep if a.base else 0)):
            sides = [("new", ROOT)] if r < a.repeats else []
            if a.base and r < base_rep:
                sides.append(("base", Path(a.base)))
            for side, path in sides:
                out = run(case, path, a.timeout)
                out["side"] = side
                print(json.dumps(out), flush=True)
                if a.out:
                    with open(a.out, "a") as fh:
                        fh.write(json.dumps(out) + "\n")
                runs[side].append(out)
        rows.append((case, runs))
    print("\n| case | new s (median, runs) | base s | ratio | new / base lam1 | peak RSS new / "
          "base (MB) | walk pivots |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for case, runs in rows:
        new = [o["seconds"] for o in runs["new"]]
        base = [o["seconds"] for o in runs["base"]]
        mn = statistics.median(new)
        mb = statistics.median(base) if base else float("nan")
        lam = (f"{runs['new'][0].get('lam1', float('nan')):.15g} / "
               f"{runs['base'][0].get('lam1', float('nan')) if base else float('nan'):.15g}")
        rss = (f"{max(o.get('peak_rss_mb', 0) for o in runs['new']):.0f} / "
               f"{max((o.get('peak_rss_mb', 0) for o in runs['base']), default=0):.0f}")
        piv = (f"{runs['new'][0].get('walk_pivots', '-')} / "
               f"{runs['base'][0].get('walk_pivots', '-') if base else '-'}")
        print(f"| {case} | {mn:.2f} {[round(x, 2) for x in new]} | {mb:.2f} "
              f"{[round(x, 2) for x in base]} | {mb / mn:.1f}x | {lam} | {rss} | {piv} |")


if __name__ == "__main__":
    main()
