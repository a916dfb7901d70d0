"""Speed, accuracy and memory of the cyclic solver (issue 3).

Usage::

    python benchmarks/bench_evolution.py [--quick] [--out benchmarks]

(a) accuracy: error of the steady W of implicit runs (16 .. 4096 steps per period) against the
    exact event-driven W, and the time to solution, for coupled N = 2, 20, 100 systems
    (plot: evolution_accuracy.png);
(b) cost per step against N: the warm-started active-set solver over a steady period vs the same
    steps solved one by one from scratch by textbook Lemke (``shakedown.lemke.lemke``, dense
    tableau, lexicographic) on the LCP of MODEL.md s.4 in ``(w, dv+, dv-)``, side by side;
(c) peak memory of an N = 2000 run (tracemalloc and ru_maxrss);
(s) Siconos numerics (Debian ``python3-siconos``) as a second from-scratch baseline: the LCPs of
    one steady period (200 steps) are written to an ``.npz``, solved by
    ``benchmarks/siconos_lcp_worker.py`` under ``/usr/bin/python3`` (the only interpreter that
    imports Siconos) with ``SICONOS_LCP_LEMKE`` (+ ``PIVOT``, ``NEWTON_FB``; ``ENUM`` for N = 5),
    and compared with the warm-started solver and textbook Lemke of the same run.  Skipped, with
    a message, when ``/usr/bin/python3 -c "import siconos.numerics"`` fails.

``--parts`` selects the parts (default ``abcs``).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import subprocess
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

import shakedown as sd
from shakedown.evolution.complementarity import StepSolver
from shakedown.evolution.lemke import lemke


def coupled_system(n, seed=0, samples=None, friction_fraction=0.5):
    """Random coupled SPD K (M M^T + 2N I), friction at a fraction of the (sufficient) critical
    value, welded load with compressive p0 = 1 and tangential amplitude ~1.5 f p0."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    f = friction_fraction * min(s.critical_friction().value, 1.0)
    s = s.with_friction(f)
    if samples:
        ph = rng.uniform(0, 2 * np.pi, n)
        t = np.arange(samples)[:, None] / samples
        q1 = 1.5 * f * np.cos(2 * np.pi * t + ph) * rng.uniform(0.5, 1.5, n)
        p1 = 0.2 * np.sin(2 * np.pi * t + ph)
        load = sd.LoadCycle.from_samples(np.zeros(n), np.ones(n), q1, p1)
    else:
        load = sd.LoadCycle.from_harmonics(np.zeros(n), np.ones(n),
                                           q_cos=1.5 * f * rng.normal(size=n),
                                           q_sin=1.5 * f * rng.normal(size=n),
                                           p_cos=0.2 * rng.normal(size=n))
    return s, load


def lcp_matrix(s):
    """M of MODEL.md s.4 in (w, dv+, dv-) (rows p, f p + q, f p - q)."""
    A, B, C, f = s.A, s.B, s.C, s.friction[:, None]
    Rv = [B.T, f * B.T + A, f * B.T - A]
    Rw = [C, f * C + B, f * C - B]
    return np.block([[Rw[i], Rv[i], -Rv[i]] for i in range(3)])


def lemke_step(s, M, v_prev, q_w, p_w):
    """From scratch: build the LCP data of the step and run textbook Lemke."""
    n, f = s.n_nodes, s.friction
    q0 = q_w + s.A @ v_prev
    p0 = p_w + s.B.T @ v_prev
    res = lemke(M, np.concatenate([p0, f * p0 + q0, f * p0 - q0]))
    return res, v_prev + res.z[n:2 * n] - res.z[2 * n:]


SICONOS_PYTHON = "/usr/bin/python3"
SICONOS_WORKER = Path(__file__).resolve().parent / "siconos_lcp_worker.py"


def siconos_available(python=SICONOS_PYTHON):
    """Whether ``python -c "import siconos.numerics"`` succeeds (False if there is no python)."""
    try:
        r = subprocess.run([python, "-c", "import siconos.numerics"], capture_output=True,
                           timeout=120)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def step_lcps(s, starts, qw, pw):
    """The LCPs of the steps in ``(w, dv+, dv-)`` (MODEL.md s.4, as :func:`lemke_step`).

    Returns ``M`` (3N, 3N) (the same for every step) and ``Q`` (k, 3N), rows
    ``(p0, f p0 + q0, f p0 - q0)`` with ``q0 = q_w + A v_prev``, ``p0 = p_w + B^T v_prev``.
    """
    f = s.friction
    q0 = qw + starts @ s.A.T
    p0 = pw + starts @ s.B
    return lcp_matrix(s), np.hstack([p0, f * p0 + q0, f * p0 - q0])


def run_siconos(M, Q, solvers=("lemke",), python=SICONOS_PYTHON, workdir=None, tol=1e-12):
    """Solve ``LCP(M, Q[i])`` for every ``i`` with Siconos in a ``python`` subprocess.

    Returns the worker's output as a dict (see ``siconos_lcp_worker.py``).
    """
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        fin, fout = Path(tmp) / "lcps.npz", Path(tmp) / "solutions.npz"
        np.savez(fin, M=M, Q=Q)
        env = dict(os.environ, PYTHONPATH="", PYTHONNOUSERSITE="1")
        subprocess.run([python, str(SICONOS_WORKER), str(fin), str(fout),
                        "--solvers", ",".join(solvers), "--tol", repr(tol)],
                       check=True, env=env)
        with np.load(fout) as data:
            return {k: data[k] for k in data.files}


def lcp_to_step(s, z, starts, qw, pw):
    """Slips, gaps and reactions ``(v, w, q, p)`` (each (k, N)) from LCP answers ``z`` (k, 3N)."""
    n = s.n_nodes
    w, dv = z[:, :n], z[:, n:2 * n] - z[:, 2 * n:]
    v = starts + dv
    q = qw + v @ s.A.T + w @ s.B.T
    p = pw + v @ s.B + w @ s.C.T
    return v, w, q, p


def part_siconos(sizes, steps, lemke_steps, lemke_all_max_n=100, enum_max_n=5, out=None):
    """Siconos LCP solvers vs the warm-started solver and textbook Lemke (see module doc)."""
    if not siconos_available():
        print(f"Siconos is unavailable ({SICONOS_PYTHON} -c 'import siconos.numerics' failed): "
              "part s skipped", flush=True)
        return []
    rows = []
    for n in sizes:
        s, load = coupled_system(n, seed=100 + n)
        solver = StepSolver(s)
        run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=steps, max_cycles=100, solver=solver)
        v = run.final_slip.copy()
        guess = run.final_active_sets[-1]
        tk = np.arange(1, steps + 1) / steps
        qw, pw = load.evaluate(tk, 1.0)
        warm_t, starts, ans = [], [], []
        for k in range(steps):
            t1 = time.perf_counter()
            r = solver.solve(v, qw[k], pw[k], guess)
            warm_t.append(time.perf_counter() - t1)
            starts.append(v)
            ans.append((r.slip, r.gap, r.q, r.p, r.force_scale))
            v, guess = r.slip, r.active_set
        starts = np.array(starts)
        v_w, g_w, q_w, p_w, fs = (np.array(x) for x in zip(*ans, strict=True))
        M, Q = step_lcps(s, starts, qw, pw)
        # textbook Lemke (shakedown.lemke) on (a subset of) the same LCPs, same process
        n_lemke = steps if n <= lemke_all_max_n else min(lemke_steps, steps)
        idx = np.linspace(0, steps - 1, n_lemke).astype(int)
        lt, lz, lok = [], [], []
        for k in idx:
            t1 = time.perf_counter()
            res = lemke(M, Q[k])
            lt.append(time.perf_counter() - t1)
            lz.append(res.z)
            lok.append(res.success)
        solvers = ["lemke", "pivot", "newton_fb"] + (["enum"] if n <= enum_max_n else [])
        t0 = time.perf_counter()
        sic = run_siconos(M, Q, solvers, workdir=out)
        t_sic = time.perf_counter() - t0
        warm_med = float(np.median(warm_t))
        row = dict(N=n, steps=steps, mean_active=float(np.mean(
            [np.count_nonzero(a) for a in run.final_active_sets])),
            warm_median_ms=warm_med * 1e3, textbook_median_ms=float(np.median(lt)) * 1e3,
            textbook_steps=len(idx), textbook_fail=int(np.sum(~np.array(lok))),
            siconos_subprocess_s=t_sic)
        vt, gt, qt, pt = lcp_to_step(s, np.array(lz), starts[idx], qw[idx], pw[idx])
        ok = np.array(lok)
        row["textbook_max_dslip"] = float(np.abs(vt - v_w[idx])[ok].max(initial=0))
        for name in solvers:
            z = sic[f"{name}_z"]
            good = sic[f"{name}_info"] == 0
            vs, gs, qs, ps = lcp_to_step(s, z, starts, qw, pw)
            dslip = np.abs(vs - v_w)[good].max(initial=0)
            dgap = np.abs(gs - g_w)[good].max(initial=0)
            dreac = np.maximum(np.abs(qs - q_w), np.abs(ps - p_w))[good].max(initial=0)
            med = float(np.median(sic[f"{name}_time"]))
            row.update({f"{name}_median_ms": med * 1e3,
                        f"{name}_build_ms": float(np.median(sic[f"{name}_build"])) * 1e3,
                        f"{name}_iter": float(np.median(sic[f"{name}_iter"])),
                        f"{name}_fail": int(np.sum(~good)),
                        f"{name}_max_dslip": float(dslip), f"{name}_max_dgap": float(dgap),
                        f"{name}_max_dreaction": float(dreac),
                        f"{name}_over_warm": med / warm_med})
        row["textbook_over_siconos_lemke"] = float(np.median(lt)) / (
            row["lemke_median_ms"] / 1e3)
        row["force_scale"] = float(np.median(fs))
        rows.append(row)
        print({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()},
              flush=True)
    return rows


def part_a(sizes, steps_list, out):
    rows = []
    for n in sizes:
        s, load = coupled_system(n, seed=n, samples=64)
        t0 = time.perf_counter()
        ev = sd.solve_cycles(s, load, 1.0, method="events", max_cycles=500,
                             solver=StepSolver(s))
        t_ev = time.perf_counter() - t0
        ref = ev.steady_dissipation
        rows.append(dict(N=n, method="events", steps=0, W=ref, rel_error=0.0, time=t_ev,
                         cycles=ev.n_cycles, status=ev.status,
                         segments=ev.statistics["n_events"]))
        print(f"N={n:4d} events   W={ref:.10g} cycles={ev.n_cycles} "
              f"segments={ev.statistics['n_events']} time={t_ev:.3f}s {ev.status}", flush=True)
        for m in steps_list:
            t0 = time.perf_counter()
            run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=m, max_cycles=500,
                                  solver=StepSolver(s))
            dt = time.perf_counter() - t0
            err = abs(run.steady_dissipation - ref) / abs(ref)
            rows.append(dict(N=n, method="implicit", steps=m, W=run.steady_dissipation,
                             rel_error=err, time=dt, cycles=run.n_cycles, status=run.status,
                             segments=0))
            print(f"N={n:4d} implicit {m:5d}: rel err {err:.3e} cycles={run.n_cycles} "
                  f"time={dt:.3f}s {run.status}", flush=True)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        for i, n in enumerate(sizes):
            r = [x for x in rows if x["N"] == n and x["method"] == "implicit"]
            e = [x for x in rows if x["N"] == n and x["method"] == "events"][0]
            c = f"C{i}"
            ax.loglog([x["time"] for x in r], [max(x["rel_error"], 1e-16) for x in r], "o-",
                      color=c, label=f"implicit N={n} (16..{r[-1]['steps']} steps)")
            ax.axvline(e["time"], color=c, ls="--", lw=1, label=f"events N={n} (exact)")
        ax.set_xlabel("time to steady state [s]")
        ax.set_ylabel("relative error of steady W")
        ax.legend(fontsize="small")
        ax.set_title("implicit steps vs exact events (coupled random systems)")
        fig.tight_layout()
        fig.savefig(out / "evolution_accuracy.png", dpi=120)
    except ImportError:  # pragma: no cover
        pass
    return rows


def part_b(sizes, steps, lemke_max_n, n_lemke_steps):
    rows = []
    for n in sizes:
        s, load = coupled_system(n, seed=100 + n)
        solver = StepSolver(s)
        t0 = time.perf_counter()
        run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=steps, max_cycles=100, solver=solver)
        t_run = time.perf_counter() - t0
        n_run_steps = run.statistics["n_steps"]
        # one more steady period, timed step by step, warm cache
        v = run.final_slip.copy()
        guess = run.final_active_sets[-1]
        tk = np.arange(1, steps + 1) / steps
        qw, pw = load.evaluate(tk, 1.0)
        warm_t, starts, answers = [], [], []
        for k in range(steps):
            t1 = time.perf_counter()
            r = solver.solve(v, qw[k], pw[k], guess)
            warm_t.append(time.perf_counter() - t1)
            starts.append(v)
            answers.append(r.slip)
            v, guess = r.slip, r.active_set
        n_slip = int(np.mean([np.count_nonzero(a) for a in run.final_active_sets]))
        row = dict(N=n, run_time=t_run, run_steps=n_run_steps, run_cycles=run.n_cycles,
                   run_per_step=t_run / n_run_steps, warm_median=float(np.median(warm_t)),
                   mean_active=n_slip, status=run.status)
        if n <= lemke_max_n:
            M = lcp_matrix(s)
            idx = np.linspace(0, steps - 1, min(n_lemke_steps, steps)).astype(int)
            lt, errs, fails, piv = [], [], 0, []
            scale_v = run.force_scale / np.diag(s.A)
            for k in idx:
                t1 = time.perf_counter()
                res, vl = lemke_step(s, M, starts[k], qw[k], pw[k])
                lt.append(time.perf_counter() - t1)
                piv.append(res.pivots)
                if not res.success:
                    fails += 1
                    continue
                errs.append(float(np.max(np.abs(vl - answers[k]) / scale_v)))
            row.update(lemke_median=float(np.median(lt)), lemke_pivots=float(np.median(piv)),
                       lemke_fail=fails, lemke_steps=len(idx),
                       max_diff=max(errs) if errs else float("nan"),
                       ratio=float(np.median(lt) / np.median(warm_t)))
        rows.append(row)
        print({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()},
              flush=True)
    return rows


def part_c(n):
    s, load = coupled_system(n, seed=7, friction_fraction=0.5)
    tracemalloc.start()
    t0 = time.perf_counter()
    run = sd.solve_cycles(s, load, 1.0, steps_per_cycle=8, max_cycles=2,
                          solver=StepSolver(s, check_uniqueness=False))
    dt = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB -> MB on Linux
    sys_mb = 3 * n * n * 8 / 2**20
    out = dict(N=n, steps=run.statistics["n_steps"], time=dt, tracemalloc_peak_MB=peak / 2**20,
               ru_maxrss_MB=rss, system_matrices_MB=sys_mb, status=run.status,
               factorizations=run.statistics["factorizations"])
    print(out, flush=True)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=str(Path(__file__).parent))
    ap.add_argument("--parts", default="abcs")
    args = ap.parse_args()
    out = Path(args.out)
    print(f"machine: {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}, numpy {np.__version__}")
    if "a" in args.parts:
        part_a([2, 20] if args.quick else [2, 20, 100],
               [16, 64, 256] if args.quick else [16, 64, 256, 1024, 4096], out)
    if "b" in args.parts:
        part_b([10, 30] if args.quick else [10, 30, 100, 300, 1000, 2000], 200,
               lemke_max_n=300, n_lemke_steps=20 if args.quick else 40)
    if "c" in args.parts:
        part_c(300 if args.quick else 2000)
    if "s" in args.parts:
        part_siconos([5, 10] if args.quick else [5, 10, 100, 300], 200,
                     lemke_steps=40)


if __name__ == "__main__":
    main()
