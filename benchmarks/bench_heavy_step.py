"""The heavy-switching step (issue 26): N = 1000, lam = 3 lam2, 40 steps per period, side by side.

Usage::

    git archive <commit> | tar -x -C /tmp/heavy-base     # the code to compare with
    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_heavy_step.py --baseline /tmp/heavy-base \\
        [--random 0,1,2,3,4] [--cracks 0,1] [--n 1000] [--repeat 3]

Systems: ``bench_bounds.random_problem(N, seed)`` (random dense coupled SPD ``K = M M^T + I``,
friction 0.3, a two-harmonic load) and the default scene's crack networks
(``bench_step.problem``: Kachanov, density 0.1, friction 0.6) of realisation ``r``; ``lam2`` of
each by :func:`shakedown.shakedown_bounds` (computed once, cached in the temporary directory).
At ``lam = 3 lam2`` most nodes slip and many change state at every step.

Each side (this tree and ``--baseline``) runs in its own subprocess (``PYTHONPATH`` set to its
tree, one BLAS thread), ``--repeat`` times with a fresh :class:`StepSolver`: periods 1-2 from
the zero state (one ``solve_cycles`` call), then (untimed) up to ``--settle`` periods more with
the same solver towards the orbit (stopping when periodic), then two more periods (or one, if
the first is already periodic) from there with the same solver: the steady periods.  Per step:
wall time and the process CPU time (``time.process_time``, the one-core figure on a loaded
machine), medians over the repeats.  "One getrs": LAPACK's pair of triangular solves with the
LU of the largest assignment matrix of the last period (and of the median one), as
``bench_step.py --parts warm`` measures it.  Answers: the dissipation of every period, the
final slips and gaps, and the reactions they give, compared with the baseline relative to the
run's force scale.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if "--worker" not in sys.argv:  # the driver builds the problems with this tree's code
    sys.path[:0] = [str(ROOT), str(HERE)]
CACHE = Path(tempfile.gettempdir()) / "shakedown_bench_heavy"
SPC = 40


def build(kind: str, seed: int, n: int) -> Path:
    """Pickle ``(A, B, C, friction, load, lam2)`` of one system (driver side, this tree)."""
    path = CACHE / f"{kind}_{n}_{seed}.pkl"
    if path.exists():
        return path
    CACHE.mkdir(exist_ok=True)
    import shakedown as sd

    if kind == "random":
        from bench_bounds import random_problem

        s, load = random_problem(n, seed)
    else:
        from bench_step import problem

        if seed != 0:
            raise SystemExit("crack networks: realisation 0 only (bench_step.problem)")
        A, B, C, f, load, _ = pickle.loads(problem(n).read_bytes())
        s = sd.DiscreteSystem(A, B, C, friction=f)
    t = time.perf_counter()
    lam2 = float(sd.shakedown_bounds(s, load).lam2)
    print(f"{kind} {seed}: lam2 = {lam2:.6g} ({time.perf_counter() - t:.1f} s)", flush=True)
    path.write_bytes(pickle.dumps((s.A, s.B, s.C, s.friction, load, lam2)))
    return path


def worker(a):
    """One side: ``repeat`` x (periods 1-2, settling, 2 steady periods) with a fresh solver;
    getrs."""
    import scipy.linalg as sla
    from scipy.linalg import get_lapack_funcs

    import shakedown as sd
    from shakedown.evolution import kernel_cache
    from shakedown.evolution.complementarity import StepSolver

    A, B, C, f, load, lam2 = pickle.loads(Path(a.pkl).read_bytes())
    s = sd.DiscreteSystem(A, B, C, friction=f)
    s.critical_friction()
    sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),  # compile /
                    sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,  # load the
                    steps_per_cycle=4)  # kernel outside the timing
    kw = dict(method="implicit", steps_per_cycle=SPC, tol=1e-10)
    lam = 3.0 * lam2
    out = dict(first=[], first_cpu=[], steady=[], steady_cpu=[], counters=[])
    for _ in range(a.repeat):
        solver = StepSolver(s)
        solver.critical  # noqa: B018
        kc = solver.kernel_cache
        runs = []
        for phase in ("first", "settle", "steady"):
            c0 = kc.counters.copy()
            init = None if not runs else runs[-1].final_slip
            if phase == "settle":  # untimed: towards the orbit (stops early when periodic)
                runs.append(sd.solve_cycles(s, load, lam, max_cycles=a.settle, solver=solver,
                                            initial_slip=init, **kw))
                continue
            t, tc = time.perf_counter(), time.process_time()
            run = sd.solve_cycles(s, load, lam, max_cycles=2, solver=solver, initial_slip=init,
                                  **kw)
            dt, dc = time.perf_counter() - t, time.process_time() - tc
            steps = run.statistics["n_steps"]
            out[phase].append(dt / steps)
            out[phase + "_cpu"].append(dc / steps)
            out["counters"].append(((kc.counters - c0) / steps).tolist())
            runs.append(run)
    r1, r2 = runs[0], runs[-1]
    n = s.n_nodes
    q0w, p0w = load.evaluate(0.0, lam)
    R = np.concatenate([q0w, p0w]) + s.K @ np.concatenate([r2.final_slip, r2.final_gap])
    acts = np.asarray(r2.final_active_sets)
    m = (acts != 0).sum(1) + (acts == 3).sum(1)
    getrs = get_lapack_funcs("getrs", (s.K,))
    g = {}
    for label, k in (("max", int(np.argmax(m))), ("median", int(np.argsort(m)[m.size // 2]))):
        free, coef = kernel_cache._layout(np.array(acts[k], np.int8), s.friction, n)
        lu = sla.lu_factor(kernel_cache._matrix(s.K, free, coef, n))
        rhs = np.random.default_rng(0).normal(size=free.size)
        ts = []
        for _ in range(5):
            t = time.process_time()
            for _ in range(50):
                getrs(lu[0], lu[1], rhs)
            ts.append((time.process_time() - t) / 50)
        g[label] = (int(free.size), statistics.median(ts))
    out.update(W=r1.dissipation.tolist() + r2.dissipation.tolist(), settled=runs[1].status,
               v=r2.final_slip.tolist(),
               w=r2.final_gap.tolist(), R=R.tolist(), F=float(r2.force_scale),
               diag=s.K.diagonal().tolist(), getrs=g, lam=lam, n=n,
               names=["iter", "hits", "fact", "upd", "steps", "lu", "short", "probe"])
    return out


def run_worker(tree, **kw):
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker"]
    for k, v in kw.items():
        cmd += [f"--{k}", str(v)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if out.returncode:
        raise RuntimeError(f"worker in {tree} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def compare(b, t):
    """Largest differences of this side from the baseline: W (relative to max |W|), reactions
    and ``K_jj``-scaled slips and gaps (relative to the force scale)."""
    Wb, Wt = np.array(b["W"]), np.array(t["W"])
    dW = float(np.abs(Wb - Wt).max() / np.abs(Wb).max())
    F, D = b["F"], np.array(b["diag"])
    n = b["n"]
    dR = float(np.abs(np.array(b["R"]) - np.array(t["R"])).max() / F)
    dv = float(np.max(np.abs(np.array(b["v"]) - np.array(t["v"])) * D[:n]) / F)
    dw = float(np.max(np.abs(np.array(b["w"]) - np.array(t["w"])) * D[n:]) / F)
    return dW, max(dR, dv, dw)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", default="/tmp/heavy-base")
    ap.add_argument("--random", default="0,1,2,3,4")
    ap.add_argument("--cracks", default="0")
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=None, help="write the markdown table here")
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--pkl")
    ap.add_argument("--settle", type=int, default=6)
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(a)))
        return
    systems = [("random", int(x)) for x in a.random.split(",") if x] + [
        ("cracks", int(x)) for x in a.cracks.split(",") if x]
    load0 = os.getloadavg()
    lines = [f"Command: `OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_heavy_step.py --baseline "
             f"{a.baseline} --random {a.random} --cracks {a.cracks} --n {a.n} --repeat "
             f"{a.repeat} --settle {a.settle}`; load average at the start {load0[0]:.1f} / {load0[1]:.1f} / "
             f"{load0[2]:.1f}.", "",
             "| system | lam2 | m max / median | getrs us (max m / median m) | periods 1-2: main "
             "ms/step CPU (wall) | this | main / getrs | this / getrs | 2 periods after settling: main "
             "| this | main / getrs | this / getrs | this: fact. / updates / probes per step "
             "(settled) | W diff / max W | state diff / F |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | "
             "--- | --- |"]
    summary = []
    for kind, seed in systems:
        pk = build(kind, seed, a.n)
        lam2 = pickle.loads(pk.read_bytes())[-1]
        b = run_worker(a.baseline, pkl=pk, repeat=a.repeat, settle=a.settle)
        t = run_worker(ROOT, pkl=pk, repeat=a.repeat, settle=a.settle)
        dW, dS = compare(b, t)
        gm = t["getrs"]["max"][1]
        row = {}
        for side, r in (("b", b), ("t", t)):
            for ph in ("first", "steady"):
                row[side + ph] = statistics.median(r[ph + "_cpu"])
                row[side + ph + "_wall"] = statistics.median(r[ph])
        cs = np.array(t["counters"][1::2], float).mean(axis=0)  # per step, the steady 2
        names = t["names"]
        per = {k: cs[names.index(k)] if k in names else 0.0 for k in ("fact", "upd", "probe")}
        lines.append(
            f"| {kind} {seed} ({t['settled']}) | {lam2:.4g} | {t['getrs']['max'][0]} / "
            f"{t['getrs']['median'][0]} "
            f"| {1e6 * gm:.0f} / {1e6 * t['getrs']['median'][1]:.0f} | "
            f"{1e3 * row['bfirst']:.2f} ({1e3 * row['bfirst_wall']:.2f}) | "
            f"{1e3 * row['tfirst']:.2f} ({1e3 * row['tfirst_wall']:.2f}) | "
            f"{row['bfirst'] / gm:.0f}x | {row['tfirst'] / gm:.0f}x | "
            f"{1e3 * row['bsteady']:.2f} ({1e3 * row['bsteady_wall']:.2f}) | "
            f"{1e3 * row['tsteady']:.2f} ({1e3 * row['tsteady_wall']:.2f}) | "
            f"{row['bsteady'] / gm:.0f}x | **{row['tsteady'] / gm:.1f}x** | "
            f"{per['fact']:.2f} / {per['upd']:.2f} / {per['probe']:.2f} | {dW:.1e} | {dS:.1e} |")
        print(lines[-1], flush=True)
        summary.append((row["bfirst"] / gm, row["tfirst"] / gm, row["bsteady"] / gm,
                        row["tsteady"] / gm, dW, dS))
    S = np.array(summary)
    la = os.getloadavg()
    lines += ["", "Ratios to one getrs (largest m), CPU time: periods 1-2 main median "
              f"{np.median(S[:, 0]):.0f}x (worst {S[:, 0].max():.0f}x), this {np.median(S[:, 1]):.0f}x"
              f" (worst {S[:, 1].max():.0f}x); steady periods main {np.median(S[:, 2]):.0f}x (worst "
              f"{S[:, 2].max():.0f}x), this {np.median(S[:, 3]):.1f}x (worst {S[:, 3].max():.1f}x). "
              f"Largest W difference {S[:, 4].max():.1e} of max W, largest state/reaction "
              f"difference {S[:, 5].max():.1e} of the force scale.  Load average at the end "
              f"{la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f}.", ""]
    text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
