"""Cost and accuracy of the 3-D step and cycles (issue 22), with Siconos FC3D side by side.

Usage::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_cone_step.py [--parts siconos,big,order]
        [--n 100] [--big-n 1000] [--repeats 3] [--out benchmarks/RESULTS_3d_step.md]

Parts
-----
siconos  The steps of one period (64 steps, after two settling periods) of a coupled random
         N-node system (``coupled_system_3d``) solved by this code (warm-started as in
         ``solve_cycles``: from the same step of the previous period; and cold, from zero) and by
         Siconos FC3D solvers (``siconos_fc3d_worker.py`` under ``/usr/bin/python3``: NSGS,
         NSN_AC, NSN_FB, ADMM; warm-started from the previous step's reactions, and cold),
         tolerance 1e-12.  The FC3D problem of a step is ``u = W r + q`` with ``W = K_n^-1``
         in the contact frame (normal first), ``q = -W r_b`` (Siconos' convention with De Saxce's
         modified velocity; see ``to_fc3d``).  Reported: medians over the steps of the median
         over ``--repeats`` runs, the ratio, and the largest difference of the reactions relative
         to the force scale.
big      ``solve_cycles`` of a coupled random system with ``--big-n`` nodes to the steady state
         at 64 steps per period (one process, one BLAS thread), at a load factor where most
         nodes slip every period; wall time, periods, Newton iterations.
order    The convergence order in the number of steps per period: the rotating-load node
         (closed form ``W = 2 pi f P sqrt(Q^2 - f^2 P^2) / k``) and a coupled 4-node system
         (reference: 2048 steps); error, observed order and wall time per S (the
         accuracy-for-speed trade).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
SICONOS_PYTHON = "/usr/bin/python3"
WORKER = HERE / "siconos_fc3d_worker.py"


def coupled_system_3d(n, seed=0, coupling=0.4, friction=0.3, spread=0.1):
    """A well-conditioned random coupled 3-D system ``K = spread M M^T / 3N + I`` and a harmonic
    load (rotating-ish: independent cosine and sine parts per node)."""
    import shakedown as sd

    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = spread * (M @ M.T) / (3 * n) * 10 + np.eye(3 * n)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], coupling * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=friction, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=0.1 * rng.normal(size=(n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)))
    return s, load


def to_fc3d(Kn, RB):
    """Siconos FC3D data of steps with base reactions ``RB`` (k, N, 3) (node order
    ``(q_x, q_y, p)``): ``M = W`` (3N, 3N) and ``Q`` (k, 3N) in the contact frame
    ``(normal, t_x, t_y)``, and the permutation ``perm`` (contact frame -> node order)."""
    n = Kn.shape[0] // 3
    perm = (3 * np.arange(n)[:, None] + np.array([2, 0, 1])[None]).ravel()
    W = np.linalg.inv(Kn)[np.ix_(perm, perm)]
    Q = -(RB.reshape(len(RB), -1)[:, perm] @ W.T)
    return W, Q, perm


def siconos_available(python=SICONOS_PYTHON):
    try:
        r = subprocess.run([python, "-c", "import siconos.numerics"], capture_output=True,
                           timeout=120)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def run_siconos(W, Q, mu, solvers, warm, tol=1e-12, python=SICONOS_PYTHON):
    with tempfile.TemporaryDirectory() as tmp:
        fin, fout = Path(tmp) / "in.npz", Path(tmp) / "out.npz"
        np.savez(fin, M=W, Q=Q, mu=mu)
        env = dict(os.environ, PYTHONPATH="", PYTHONNOUSERSITE="1", OPENBLAS_NUM_THREADS="1")
        cmd = [python, str(WORKER), str(fin), str(fout), "--solvers", ",".join(solvers),
               "--tol", repr(tol)] + (["--warm"] if warm else [])
        subprocess.run(cmd, check=True, env=env)
        with np.load(fout) as d:
            return {k: d[k] for k in d.files}


def period_steps(s, load, lam, S=64, settle=2):
    """Base reactions, warm starts and this code's answers of the steps of period
    ``settle + 1`` (the driver's own path)."""
    from shakedown.evolution.cone_step import ConeStepSolver

    sol = ConeStepSolver(s)
    qg, pg = load.evaluate(np.arange(1, S + 1) / S, lam)
    v = np.zeros((s.n_nodes, 2))
    U_prev = None
    for _ in range(settle + 1):
        RB, U0, U, R = [], [], [], []
        for j in range(S):
            rb = sol.base(v, qg[j], pg[j])
            g = U_prev[j] if U_prev is not None else (U[-1] if U else None)
            u, r, *_ = sol.solve_raw(rb, g, equilibrium=False)
            RB.append(rb)
            U0.append(g)
            U.append(u)
            R.append(r)
            v = v + u[:, :2]
        U_prev = U
    return sol, np.array(RB), U0, np.array(U), np.array(R)


def part_siconos(n, lam, repeats):
    s, load = coupled_system_3d(n)
    sol, RB, U0, U, R = period_steps(s, load, lam)
    F = np.abs(RB).max()
    slipping = float(np.mean([np.mean(np.hypot(*u[:, :2].T) > 0) for u in U]))
    times = {"ours_warm": [], "ours_cold": []}
    for _ in range(repeats):
        for name, guesses in (("ours_warm", U0), ("ours_cold", [None] * len(RB))):
            t = []
            for rb, g in zip(RB, guesses, strict=True):
                t0 = time.perf_counter()
                sol.solve_raw(rb, g, equilibrium=True)
                t.append(time.perf_counter() - t0)
            times[name].append(t)
    W, Q, perm = to_fc3d(sol.data.Kn, RB)
    mu = s.friction_xy[:, 0]
    solvers = ("nsgs", "nsn_ac", "nsn_fb", "admm")
    rows, diffs = {}, {}
    ours = R.reshape(len(R), -1)[:, perm]
    for warm in (True, False):
        per = {k: [] for k in solvers}
        for _ in range(repeats):
            out = run_siconos(W, Q, mu, solvers, warm)
            for k in solvers:
                per[k].append(out[f"{k}_time"])
                ok = out[f"{k}_info"] == 0
                d = np.abs(out[f"{k}_r"] - ours).max(axis=1) / F
                diffs[(k, warm)] = (float(d.max()), int((~ok).sum()))
        for k in solvers:
            rows[(k, warm)] = float(np.median(np.median(np.array(per[k]), axis=0)))
    ours_t = {k: float(np.median(np.median(np.array(v), axis=0))) for k, v in times.items()}
    return dict(n=n, lam=lam, F=F, slipping=slipping, ours=ours_t, siconos=rows, diffs=diffs,
                steps=len(RB))


def part_big(n, lam, S=64):
    import shakedown as sd

    s, load = coupled_system_3d(n, seed=1)
    t0 = time.perf_counter()

    def progress(c, total, W):  # one line per period, so that an interrupted run still reports
        print(f"  N = {n}: period {c} done at {time.perf_counter() - t0:.1f} s, W = {W:.6g}, "
              f"load {os.getloadavg()[0]:.1f}", flush=True)

    run = sd.solve_cycles(s, load, lam, steps_per_cycle=S, max_cycles=200, progress=progress)
    wall = time.perf_counter() - t0
    slipped = n - run.stuck_nodes.size if run.period else -1
    return dict(n=n, lam=lam, wall=wall, status=run.status, cycles=run.n_cycles,
                period=run.period, slipped=slipped, W=run.steady_dissipation,
                newton=run.statistics["newton_iterations"], steps=run.statistics["n_steps"],
                energy=run.energy_identity.discrete_relative_difference if run.period else None)


def part_order():
    import shakedown as sd

    rows = []
    k, f, P, Q = 2.0, 0.5, 1.0, 1.3
    s = sd.DiscreteSystem(k * np.eye(2), np.zeros((2, 1)), [[1.0]], friction=f, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=np.zeros((1, 2)), p0=[P], q_cos=[[Q, 0.0]],
                                       q_sin=[[0.0, Q]])
    W = 2 * np.pi * f * P * np.sqrt(Q**2 - (f * P) ** 2) / k
    s4, load4 = coupled_system_3d(4, seed=3)
    ref = sd.solve_cycles(s4, load4, 0.8, steps_per_cycle=2048).steady_dissipation
    for name, sys_, ld, lam, exact in (("rotating node", s, load, 1.0, W),
                                       ("coupled N = 4", s4, load4, 0.8, ref)):
        prev = None
        for S in (16, 32, 64, 128, 256, 512):
            t0 = time.perf_counter()
            run = sd.solve_cycles(sys_, ld, lam, steps_per_cycle=S)
            wall = time.perf_counter() - t0
            err = abs(run.steady_dissipation - exact) / abs(exact)
            order = np.log2(prev / err) if prev else float("nan")
            rows.append((name, S, run.steady_dissipation, err, order, wall, run.n_cycles))
            prev = err
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default="siconos,big,order")
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--lam", type=float, default=0.8)
    ap.add_argument("--big-n", type=int, default=1000)
    ap.add_argument("--big-lam", type=float, default=0.8)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    lines = [f"Machine: {platform.machine()} {os.cpu_count()} cores, python {platform.python_version()}, "
             f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}",
             f"Load at start: {os.getloadavg()}", ""]
    parts = a.parts.split(",")
    if "siconos" in parts and siconos_available():
        r = part_siconos(a.n, a.lam, a.repeats)
        lines += [f"## Step at N = {r['n']} (lam = {r['lam']}, {r['steps']} steps of one period, "
                  f"{100 * r['slipping']:.0f}% of the node-steps slipping)", "",
                  "| solver | start | median per step [ms] | ratio to ours (same start) | "
                  "max diff / F | not converged |", "|---|---|---|---|---|---|"]
        for warm in (True, False):
            o = r["ours"]["ours_warm" if warm else "ours_cold"]
            lines.append(f"| this code (Newton, verified) | {'warm' if warm else 'cold'} | "
                         f"{1e3 * o:.3f} | 1 | - | - |")
            for k in ("nsgs", "nsn_ac", "nsn_fb", "admm"):
                t = r["siconos"][(k, warm)]
                d, bad = r["diffs"][(k, warm)]
                lines.append(f"| Siconos FC3D {k.upper()} | {'warm' if warm else 'cold'} | "
                             f"{1e3 * t:.3f} | {t / o:.1f}x | {d:.2e} | {bad} |")
        lines += ["", f"Load after: {os.getloadavg()}", ""]
    if "big" in parts:
        r = part_big(a.big_n, a.big_lam)
        lines += [f"## Cycles at N = {r['n']} (lam = {r['lam']}, 64 steps per period)", "",
                  f"status {r['status']}, period {r['period']}, {r['cycles']} periods, "
                  f"{r['slipped']} of {r['n']} nodes slip in the steady orbit, "
                  f"{r['steps']} steps, {r['newton']} Newton iterations, wall "
                  f"**{r['wall']:.1f} s**; energy identity (discrete, relative) {r['energy']}",
                  f"Load after: {os.getloadavg()}", ""]
    if "order" in parts:
        rows = part_order()
        lines += ["## Convergence in the number of steps per period", "",
                  "| problem | S | W | relative error | observed order | wall [s] | periods |",
                  "|---|---|---|---|---|---|---|"]
        for name, S, W, err, order, wall, cyc in rows:
            lines.append(f"| {name} | {S} | {W:.10g} | {err:.3e} | {order:.2f} | {wall:.3f} | "
                         f"{cyc} |")
        lines.append("")
    text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
