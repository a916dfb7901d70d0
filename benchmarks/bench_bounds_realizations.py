"""The bounds engine on many random realizations (issue 26): median, worst case, fallbacks.

Each realization runs in its own process (peak RSS per realization), one BLAS thread:

    OPENBLAS_NUM_THREADS=1 nohup python3 benchmarks/bench_bounds_realizations.py \\
        --kind crack --sizes 500,1000,2000 --count 20 --out /tmp/real.jsonl &
    python3 benchmarks/bench_bounds_realizations.py --report /tmp/real.jsonl

Kinds:

* ``crack``: ``crack_networks.sample_crack_set(N, density, half_length=1, min_spacing=0.1,
  rng=seed)``, ``kachanov_model(shear_modulus=1, poisson_ratio=0.25, friction)``,
  ``load_cycle(static=(-1, 0, -1), cyclic=(0, 1, 0))``; realization ``i`` takes density
  ``DENSITIES[i % 3]``, friction ``FRICTIONS[(i // 3) % 3]`` and seed ``SEED0 + i`` (seeds the
  tests do not use);
* ``dense``: ``bench_bounds.random_problem(N, seed, friction)`` (``K = M M^T + I``);
* ``fe``: the strip of ``bench_fe_bounds.py`` (``fe.rectangle(nx / 100, 0.1, nx, 8)``), friction
  and cyclic shear drawn per realization.

Per realization: the wall and CPU time of ``shakedown_bounds`` (default options; with one BLAS
thread the CPU time is the time on one unshared core), peak RSS, ``lam1``,
``lam2``, the stages' paths and fallbacks (:attr:`ShakedownBounds.stages`), and a check against
HiGHS: the ``lam2`` LP solved by HiGHS from the dense optimal basis (HiGHS's own optimality
check of that basis; 0 iterations when it agrees) and the LP that decides ``lam1`` (``max lam``
with the limiting row tight, or ``min lam`` with a row inactive at 0), each compared to 1e-9
relative.  Results are appended as JSON lines; an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this repository's package

SEED0 = 5000
DENSITIES = (0.05, 0.1, 0.15)
FRICTIONS = (0.3, 0.6, 0.9)


def build(kind, n, i):

    if kind == "crack":
        import crack_networks as cn

        density, friction = DENSITIES[i % 3], FRICTIONS[(i // 3) % 3]
        cs = cn.sample_crack_set(n, density=density, half_length=1.0, min_spacing=0.1,
                                 rng=SEED0 + i)
        m = cn.kachanov_model(cs, shear_modulus=1.0, poisson_ratio=0.25, friction=friction)
        return m.system, m.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0)), \
            dict(density=density, friction=friction, seed=SEED0 + i)
    if kind == "dense":
        sys.path.insert(0, str(Path(__file__).parent))
        from bench_bounds import random_problem

        friction = FRICTIONS[i % 3]
        s, load = random_problem(n, seed=SEED0 + i, friction=friction)
        return s, load, dict(friction=friction, seed=SEED0 + i)
    if kind == "fe":
        from shakedown import fe

        rng = np.random.default_rng(SEED0 + i)
        friction, shear = float(rng.uniform(0.3, 0.9)), float(rng.uniform(0.2, 0.6))
        loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shake": fe.Traction("top", (shear, 0))}
        model = fe.FEModel(fe.rectangle(n / 100, 0.1, n, 8), fe.isotropic(1.0, 0.3),
                           dirichlet={"left": "xy"}, contact=["bottom"], loads=loads,
                           friction=friction)
        cm = model.condense(cache_dir="/tmp/fe_bounds_cache")
        return cm.system, cm.load_cycle(static="dead", cyclic="shake"), \
            dict(friction=friction, shear=shear, seed=SEED0 + i)
    raise ValueError(f"kind must be crack, dense or fe; got {kind!r}")


def check_with_highs(b):
    """Relative differences of lam2 and of the LP deciding lam1 to HiGHS (nondimensional)."""
    from shakedown.bounds.constraints import Scales
    from shakedown.bounds.highs_path import HighsModel

    cs = b.constraints
    sc = Scales.of(cs)
    ch = sc.nondimensional(cs)
    n = ch.n_nodes
    model = HighsModel(ch)
    lam2 = b.lam2 / sc.load_factor
    # the dense optimum's tight rows as HiGHS's start basis (HiGHS checks it in its own terms)
    A = np.hstack([ch.G, -ch.m[:, None]])
    x = np.r_[b.state_at_lam2 / sc.slip, lam2]
    slack = (ch.c - A @ x) / (np.linalg.norm(A, axis=1) * max(1.0, np.abs(x).max()))
    y = b.certificate
    slack[y > 1e-12 * max(np.abs(y).max(initial=0.0), 1e-300)] = -1.0  # the certificate's rows
    T = np.argsort(slack, kind="stable")[: n + 1 if lam2 > 0 else n]  # N + 1 rows in all
    T = np.r_[T, 2 * n] if lam2 <= 0 else T  # lam = 0: the row -lam <= 0 is one of them
    model.start_from(np.sort(T))
    t = time.perf_counter()
    ans = model.run("max")
    out = {"highs_lam2_s": time.perf_counter() - t, "highs_lam2_iters": int(ans.iterations)}
    out["dlam2"] = abs(float(ans.x[-1]) - lam2) / max(1.0, abs(lam2))
    k = b.limiting_constraint
    if k >= 0 and np.isfinite(b.lam1):
        t = time.perf_counter()
        if b.lam1 > 0:  # lam1 = lam_high of the limiting row
            val, ref = model.run("max", tight=(k,)), b.lam1 / sc.load_factor
        else:  # lam1 = 0: the row is inactive at lam = 0 (lam_low > 0, or never active)
            val, ref = model.run("min", tight=(k,)), b.lam_low[k] / sc.load_factor
        v = float(val.x[-1]) if val.status == "optimal" else np.nan
        out["highs_lam1_s"] = time.perf_counter() - t
        out["dlam1"] = abs(v - ref) / max(1.0, abs(lam2)) if np.isfinite(ref) else \
            (0.0 if np.isnan(v) else 1.0)
    return out


def one(kind, n, i):
    import shakedown as sd

    system, load, params = build(kind, n, i)
    t, c = time.perf_counter(), time.process_time()
    b = sd.shakedown_bounds(system, load)
    sec, cpu = time.perf_counter() - t, time.process_time() - c
    rec = dict(kind=kind, n=n, i=i, **params, seconds=sec, cpu_seconds=cpu,
               rss_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
               lam1=b.lam1, lam2=b.lam2, limiting=b.limiting_label, n_lps=b.n_lps,
               fallbacks=sum(s.fallbacks for s in b.stages),
               stages=[s.to_dict() for s in b.stages], residual=max(b.residuals.values()),
               load=os.getloadavg()[0])
    rec.update(check_with_highs(b))
    print(json.dumps(rec), flush=True)


def drive(args):
    done = set()
    out = Path(args.out)
    if out.exists():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done.add((r["kind"], r["n"], r["i"]))
    for n in [int(v) for v in args.sizes.split(",")]:
        for i in range(args.count):
            if (args.kind, n, i) in done:
                continue
            env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
                       NUMBA_NUM_THREADS="1")
            p = subprocess.run([sys.executable, __file__, "--one", args.kind, str(n), str(i)],
                               capture_output=True, text=True, env=env)
            lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
            if p.returncode or not lines:
                rec = dict(kind=args.kind, n=n, i=i, error=p.stderr[-2000:])
                line = json.dumps(rec)
            else:
                line = lines[-1]
            with out.open("a") as f:
                f.write(line + "\n")


def report(path):
    rows = [json.loads(ln) for ln in Path(path).read_text().splitlines()]
    keys = sorted({(r["kind"], r["n"]) for r in rows})
    print("| kind | N | realizations | median CPU s | worst CPU s | worst wall s | worst peak RSS "
          "GB | fallbacks (LPs, realizations) | worst lam2 diff to HiGHS | worst lam1-LP diff | "
          "errors |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for kind, n in keys:
        rs = [r for r in rows if r["kind"] == kind and r["n"] == n and "error" not in r]
        err = sum(1 for r in rows if r["kind"] == kind and r["n"] == n and "error" in r)
        if not rs:
            print(f"| {kind} | {n} | 0 | | | | | | | | {err} |")
            continue
        s = np.array([r["cpu_seconds"] for r in rs])
        fb = [r["fallbacks"] for r in rs]
        print(f"| {kind} | {n} | {len(rs)} | {np.median(s):.3g} | {s.max():.3g} "
              f"(i = {rs[int(np.argmax(s))]['i']}) | {max(r['seconds'] for r in rs):.3g} | "
              f"{max(r['rss_gb'] for r in rs):.2f} | "
              f"{sum(fb)}, {sum(1 for f in fb if f)} | "
              f"{max(r['dlam2'] for r in rs):.1e} | "
              f"{max(r.get('dlam1', 0.0) for r in rs):.1e} | {err} |")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kind", default="crack")
    ap.add_argument("--sizes", default="500,1000,2000")
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--out", default="bounds_realizations.jsonl")
    ap.add_argument("--one", nargs=3, metavar=("KIND", "N", "I"))
    ap.add_argument("--report", metavar="JSONL")
    a = ap.parse_args()
    if a.one:
        one(a.one[0], int(a.one[1]), int(a.one[2]))
    elif a.report:
        report(a.report)
    else:
        drive(a)
