"""Direct steady-cycle solver vs plain cycling on seed 002 Fig. 8-type systems.

The system of :func:`shakedown.gallery.fig8_coupled_one_at_a_time` (one node slips at a time,
the memory of the initial state fades geometrically) and two variants with stronger tangential
interaction ``A_01`` (slower fading).  For each: plain cycling with :func:`solve_cycles`
until steady (tol 1e-10), and :func:`steady_cycle` (Newton on the affine pieces; Anderson), both
from ``v = 0``, side by side in one run.  Reported: simulated load periods (period-map
evaluations), wall time (median of ``--repeat`` runs), their ratios, and the agreement of the
steady ``W``.

Run:  python benchmarks/bench_steady.py [--repeat 5] [--steps 8 200] [--out benchmarks/RESULTS_steady.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from functools import partial

import numpy as np

import shakedown as sd
from shakedown import gallery
from shakedown.evolution.steady import steady_cycle


def variant(a01: float):
    """The gallery system (``a01 = 0.9``, ``B = 0.3 I``) or one with a stronger ``A_01``.

    ``K`` stays SPD only while ``b^2 < 1 - a01`` (``A - B C^-1 B^T`` with ``C = I``), so the
    variants use ``B = 0.6 sqrt(1 - a01) I``.
    """
    p = gallery.fig8_coupled_one_at_a_time()
    if a01 == 0.9:
        return p.system, p.load, p.lam
    A = [[1.0, a01], [a01, 1.0]]
    B = 0.6 * np.sqrt(1.0 - a01) * np.eye(2)
    return sd.DiscreteSystem(A, B, p.system.C, p.system.friction), p.load, p.lam


def timed(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--steps", type=int, nargs="+", default=[8, 200])
    ap.add_argument("--a01", type=float, nargs="+", default=[0.9, 0.95])
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    rows = []
    for a01 in args.a01:
        system, load, lam = variant(a01)
        for steps in args.steps:
            for v0 in ((0.0, 0.0), (-0.5, 0.4)):
                plain, t_plain = timed(
                    partial(sd.solve_cycles, system, load, lam, initial_slip=v0,
                            steps_per_cycle=steps, max_cycles=2000), args.repeat)
                for acc in ("newton", "anderson"):
                    sc, t_sc = timed(
                        partial(steady_cycle, system, load, lam, v0, steps_per_cycle=steps,
                                accelerator=acc, max_evaluations=2000), args.repeat)
                    rows.append(dict(
                        a01=a01, steps=steps, start=v0, accelerator=acc,
                        plain_periods=int(plain.n_cycles), plain_s=t_plain,
                        steady_periods=int(sc.n_evaluations), steady_s=t_sc,
                        eval_ratio=plain.n_cycles / sc.n_evaluations, time_ratio=t_plain / t_sc,
                        dW=abs(sc.steady_dissipation - plain.steady_dissipation)
                        / abs(plain.steady_dissipation),
                        status=sc.status, plain_status=str(plain.status),
                    ))
                    print(rows[-1], flush=True)
    lines = [
        "# Direct steady-cycle solver vs plain cycling",
        "",
        "Command: `python benchmarks/bench_steady.py "
        f"--repeat {args.repeat} --steps {' '.join(map(str, args.steps))} "
        f"--a01 {' '.join(map(str, args.a01))}`",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}.  Wall times are medians of "
        f"{args.repeat} runs; both methods measured side by side in the same process.",
        "",
        "System: `gallery.fig8_coupled_one_at_a_time` (seed 002 Fig. 8: coupled two-node, one "
        "node slips at a time, geometric approach to a unique steady state) with "
        "`A = [[1, a01], [a01, 1]]` (B = 0.3 I for a01 = 0.9, else 0.6 sqrt(1 - a01) I); "
        "lam = 0.4; implicit steps; tol = 1e-10; start v = 0 and v = (-0.5, 0.4).",
        "Periods = simulated load periods (period-map evaluations; verification included).",
        "",
        "| a01 | steps/cycle | start v | accelerator | plain periods | steady periods | ratio | "
        "plain time [s] | steady time [s] | time ratio | rel. diff W | status |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['a01']} | {r['steps']} | {r['start']} | {r['accelerator']} | "
            f"{r['plain_periods']} | "
            f"{r['steady_periods']} | {r['eval_ratio']:.1f} | {r['plain_s']:.4f} | "
            f"{r['steady_s']:.4f} | {r['time_ratio']:.1f} | {r['dW']:.1e} | {r['status']} |"
        )
    lines += [
        "",
        "Notes.  The period counts are exact and machine-independent; wall times include the",
        "per-call overhead of `solve_cycles` (tables, energy identity) that each period-map",
        "evaluation pays, so the time ratio is below the evaluation ratio at 8 steps per cycle.",
        "Newton identifies the affine piece with N = 2 extra periods per iteration; from",
        "(-0.5, 0.4) the first pieces are transient (a slower piece, rate ~0.98 per cycle) and",
        "the damped steps / plain-period fallback cost a few more periods.  Anderson is cheaper",
        "per iteration but stalls on those transient pieces and then falls back to plain",
        "cycling (ratio ~1), which is why `accelerator='auto'` uses Newton for N <= 12.",
    ]
    text = "\n".join(lines) + "\n"
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text)
    print(text)


if __name__ == "__main__":
    main()
