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
         NSN_AC, NSN_FB, ADMM; warm-started from the previous step's reactions, cold, and from
         this code's own start, the reactions ``r_b + K u0`` of the same step of the previous
         period: "this code's start", compared with this code's warm time),
         tolerance 1e-12.  The FC3D problem of a step is ``u = W r + q`` with ``W = K_n^-1``
         in the contact frame (normal first), ``q = -W r_b`` (Siconos' convention with De Saxce's
         modified velocity; see ``to_fc3d``).  Reported: medians over the steps of the median
         over ``--repeats`` runs, the ratio, and the largest difference of the reactions relative
         to the force scale.
big      ``solve_cycles`` of a coupled random system with ``--big-n`` nodes to the steady state
         at 64 steps per period (one process, one BLAS thread), at a load factor where most
         nodes slip every period; wall time, periods, Newton iterations.
answers  The cyclic runs of ``ANSWER_PROBLEMS`` (N = 6..150, two seeds, two load factors, 32
         steps per period) in this tree and in ``--baseline``: periods, differences of the
         answers, Newton iterations, CPU.
hot      The warm steps of period 3 timed in sequence and each repeated in place (hot caches):
         how much of a step is the memory traffic between steps (:func:`part_hot`).
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
if "--repo" in sys.argv:  # import shakedown from another tree (e.g. main, for the baseline)
    sys.path.insert(0, sys.argv[sys.argv.index("--repo") + 1])
else:
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


def run_siconos(W, Q, mu, solvers, warm, tol=1e-12, python=SICONOS_PYTHON, R0=None):
    """Siconos on the problems ``(W, Q[j])``: from the previous problem's reactions (``warm``),
    from zero, or from ``R0[j]`` (k, 3N) (contact frame) when given."""
    with tempfile.TemporaryDirectory() as tmp:
        fin, fout = Path(tmp) / "in.npz", Path(tmp) / "out.npz"
        np.savez(fin, M=W, Q=Q, mu=mu, **({} if R0 is None else dict(R0=R0)))
        env = dict(os.environ, PYTHONPATH="", PYTHONNOUSERSITE="1", OPENBLAS_NUM_THREADS="1")
        cmd = [python, str(WORKER), str(fin), str(fout), "--solvers", ",".join(solvers),
               "--tol", repr(tol)] + (["--warm"] if warm else []) + (
            ["--given"] if R0 is not None else [])
        subprocess.run(cmd, check=True, env=env)
        with np.load(fout) as d:
            return {k: d[k] for k in d.files}


def period_steps(s, load, lam, S=64, settle=2):
    """Base reactions, warm starts, their products ``K u0`` (node order, from the previous
    period's ``r - r_b``, as ``solve_cycles`` takes them) and this code's answers of the steps of
    period ``settle + 1`` (the driver's own path, without its extrapolation, which starts at
    period 4)."""
    from shakedown.evolution.cone_step import ConeStepSolver

    sol = ConeStepSolver(s)
    qg, pg = load.evaluate(np.arange(1, S + 1) / S, lam)
    v = np.zeros((s.n_nodes, 2))
    U_prev = KU_prev = None
    for _ in range(settle + 1):
        RB, U0, KU0, U, R = [], [], [], [], []
        for j in range(S):
            rb = sol.base(v, qg[j], pg[j])
            g = U_prev[j] if U_prev is not None else (U[-1] if U else None)
            KU0.append(KU_prev[j] if KU_prev is not None else None)
            u, r, *_ = sol.solve_raw(rb, g, equilibrium=False)
            RB.append(rb)
            U0.append(g)
            U.append(u)
            R.append(r)
            v = v + u[:, :2]
        U_prev, KU_prev = U, [r - rb for r, rb in zip(R, RB, strict=True)]
    return sol, np.array(RB), U0, KU0, np.array(U), np.array(R)


def time_steps(sol, RB, guesses, products=None):
    """Wall and CPU time [s] per step of ``sol.solve_raw`` (full verification, the equilibrium
    recomputed with ``K``), and answers; ``products``: ``K u0`` of the guesses (None: the step
    computes it)."""
    wall, cpu, R = [], [], []
    products = [None] * len(RB) if products is None else products
    for rb, g, ku in zip(RB, guesses, products, strict=True):
        kw = {} if ku is None else dict(ku0=ku)
        t0, c0 = time.perf_counter(), time.process_time()
        out = sol.solve_raw(rb, g, equilibrium=True, **kw)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        R.append(out[1].ravel())
    return np.array(wall), np.array(cpu), np.array(R)


def part_hot(n, lam, repeats, seed=0):
    """The warm steps of period 3 (as in :func:`part_siconos`) timed in sequence, as a cyclic
    run meets them (each step's data, ``K`` of (3N)^2 doubles and the reduced matrices, partly
    evicted from the caches by the previous step), and each step repeated in place (``repeats +
    1`` solves in a row, the median of the last ``repeats``: hot caches).  CPU per step [s]:
    medians over the steps, and the median per-step ratio sequence / hot."""
    sol, RB, U0, KU0, _, _ = period_steps(*coupled_system_3d(n, seed=seed), lam)
    seq = np.median([time_steps(sol, RB, U0, KU0)[1] for _ in range(repeats)], axis=0)
    hot = []
    for rb, g, ku in zip(RB, U0, KU0, strict=True):
        c = []
        for _ in range(repeats + 1):
            c0 = time.process_time()
            sol.solve_raw(rb, g, equilibrium=True, ku0=ku)
            c.append(time.process_time() - c0)
        hot.append(np.median(c[1:]))
    hot = np.array(hot)
    return dict(seed=seed, seq=float(np.median(seq)), hot=float(np.median(hot)),
                ratio=float(np.median(seq / hot)))


def part_steptimes(inp, out):
    """Time this tree's step on the steps of ``inp`` (written by :func:`part_siconos`): the
    baseline (``--repo``) side of the comparison."""
    import shakedown as sd
    from shakedown.evolution.cone_step import ConeStepSolver

    with np.load(inp) as d:
        A, B, C, f, RB, U0 = (d[k] for k in ("A", "B", "C", "f", "RB", "U0"))
    sol = ConeStepSolver(sd.DiscreteSystem(A, B, C, friction=f, dim=3))
    res = {}
    for name, guesses in (("warm", list(U0)), ("cold", [None] * len(RB))):
        time_steps(sol, RB[:2], guesses[:2])  # compile / warm the caches
        res[f"{name}_wall"], res[f"{name}_cpu"], res[f"{name}_R"] = time_steps(sol, RB, guesses)
    np.savez(out, **res)


def part_siconos(n, lam, repeats, seed=0, baseline=None, solvers=("nsgs", "nsn_ac")):
    """Ours (this tree), the baseline tree (``baseline``, in a subprocess) and Siconos on the
    same steps, repeats interleaved; per start the median over the steps of the median over the
    repeats, wall and CPU."""
    s, load = coupled_system_3d(n, seed=seed)
    sol, RB, U0, KU0, U, R = period_steps(s, load, lam)
    F = np.abs(RB).max()
    slipping = float(np.mean([np.mean(np.hypot(*u[:, :2].T) > 0) for u in U]))
    W, Q, perm = to_fc3d(sol.data.Kn, RB)
    mu = s.friction_xy[:, 0]
    # the reactions of this code's warm starts (r_b + K u0), in Siconos' contact frame
    R0 = (RB + np.array(KU0)).reshape(len(RB), -1)[:, perm]
    ours = R.reshape(len(R), -1)
    times = {}  # (who, start, clock) -> list over repeats of per-step arrays
    diffs = {}

    def add(key, arr):
        times.setdefault(key, []).append(arr)

    with tempfile.TemporaryDirectory() as tmp:
        fin, fout = Path(tmp) / "steps.npz", Path(tmp) / "base.npz"
        np.savez(fin, A=s.A, B=s.B, C=s.C, f=s.friction_xy[:, 0], RB=RB, U0=np.array(U0))
        for _ in range(repeats):
            for start, guesses, kus in (("warm", U0, KU0), ("warm, K u0 computed", U0, None),
                                        ("cold", [None] * len(RB), None)):
                w_, c_, Rr = time_steps(sol, RB, guesses, kus)
                add(("this code", start, "wall"), w_)
                add(("this code", start, "cpu"), c_)
                diffs[("this code", start)] = (float(np.abs(Rr - ours).max() / F), 0)
            if baseline:
                env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
                subprocess.run([sys.executable, __file__, "--parts", "steptimes", "--repo",
                                baseline, "--steps-in", str(fin), "--steps-out", str(fout)],
                               check=True, env=env)
                with np.load(fout) as d:
                    for start in ("warm", "cold"):
                        add(("main", start, "wall"), d[f"{start}_wall"])
                        add(("main", start, "cpu"), d[f"{start}_cpu"])
                        diffs[("main", start)] = (
                            float(np.abs(d[f"{start}_R"] - ours).max() / F), 0)
            for start in ("warm", "cold", "this code's start"):
                out = run_siconos(W, Q, mu, solvers, start == "warm",
                                  R0=R0 if start == "this code's start" else None)
                for k in solvers:
                    add((f"Siconos {k.upper()}", start, "wall"), out[f"{k}_time"])
                    add((f"Siconos {k.upper()}", start, "cpu"), out[f"{k}_cpu"])
                    ok = out[f"{k}_info"] == 0
                    d = np.abs(out[f"{k}_r"] - ours[:, perm]).max(axis=1) / F
                    diffs[(f"Siconos {k.upper()}", start)] = (float(d.max()), int((~ok).sum()))
    med = {k: float(np.median(np.median(np.array(v), axis=0))) for k, v in times.items()}
    # paired per repeat (this code and Siconos timed within the same repeat, seconds apart):
    # fastest Siconos solver's median per step / this code's, one ratio per repeat
    paired = {}
    for start in ("warm", "cold", "this code's start"):
        ours = np.median(times[("this code", "warm" if start == "this code's start" else start,
                                "cpu")], axis=1)
        sic = np.min([np.median(times[(f"Siconos {k.upper()}", start, "cpu")], axis=1)
                      for k in solvers], axis=0)
        paired[start] = (sic / ours).tolist()
    return dict(n=n, lam=lam, seed=seed, F=F, slipping=slipping, med=med, diffs=diffs,
                steps=len(RB), solvers=solvers, paired=paired)


def part_big(n, lam, S=64, anderson=0, max_cycles=200):
    import shakedown as sd

    s, load = coupled_system_3d(n, seed=1)
    s4, load4 = coupled_system_3d(4, seed=1)  # compile (or load) the numba kernels first
    sd.solve_cycles(s4, load4, lam, steps_per_cycle=S, max_cycles=2)
    t0, c0 = time.perf_counter(), time.process_time()

    def progress(c, total, W):  # one line per period, so that an interrupted run still reports
        print(f"  N = {n}: period {c} done at {time.perf_counter() - t0:.1f} s wall, "
              f"{time.process_time() - c0:.1f} s CPU, W = {W:.10g}, "
              f"load {os.getloadavg()[0]:.1f}", flush=True)

    kw = dict(anderson_memory=anderson) if anderson else {}
    run = sd.solve_cycles(s, load, lam, steps_per_cycle=S, max_cycles=max_cycles,
                          progress=progress, **kw)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    slipped = n - run.stuck_nodes.size if run.period else -1
    tag = Path(sd.__file__).resolve().parent.parent.name
    np.save(f"/tmp/bench_cone_big_{n}_{anderson}_{tag}_slip.npy", run.final_slip)
    return dict(n=n, lam=lam, wall=wall, cpu=cpu, anderson=anderson, status=run.status, cycles=run.n_cycles,
                period=run.period, slipped=slipped, W=run.steady_dissipation,
                newton=run.statistics["newton_iterations"], steps=run.statistics["n_steps"],
                energy=run.energy_identity.discrete_relative_difference if run.period else None)


ANSWER_PROBLEMS = [(n, seed, lam) for n in (6, 20, 60, 150) for seed in (0, 1)
                   for lam in (0.5, 0.8)]


def part_runs(out, S=32):
    """``solve_cycles`` (plain cycling) of :data:`ANSWER_PROBLEMS` in this tree: periods, steady
    dissipation, final slips, the last period's reactions and the CPU time, saved to ``out``."""
    import shakedown as sd

    res = {}
    for k, (n, seed, lam) in enumerate(ANSWER_PROBLEMS):
        s, load = coupled_system_3d(n, seed=seed)
        c0 = time.process_time()
        run = sd.solve_cycles(s, load, lam, steps_per_cycle=S)
        res[f"cpu{k}"] = time.process_time() - c0
        res[f"cycles{k}"] = run.n_cycles
        res[f"W{k}"] = run.steady_dissipation
        res[f"slip{k}"] = run.final_slip
        res[f"q{k}"] = run.steady_orbit[-1].q
        res[f"F{k}"] = run.force_scale
        res[f"k{k}"] = float(np.diag(s.A).max())
        res[f"newton{k}"] = run.statistics["newton_iterations"]
    np.savez(out, **res)


def part_answers(baseline):
    """The cyclic runs of :data:`ANSWER_PROBLEMS` in this tree and in ``baseline`` (subprocesses,
    one after the other): the largest differences of the answers and the CPU times."""
    outs = []
    with tempfile.TemporaryDirectory() as tmp:
        for repo in (str(HERE.parent), baseline):
            out = Path(tmp) / f"runs{len(outs)}.npz"
            env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
            subprocess.run([sys.executable, __file__, "--parts", "runs", "--repo", repo,
                            "--steps-out", str(out)], check=True, env=env)
            with np.load(out) as d:
                outs.append({k: d[k] for k in d.files})
    a, b = outs
    rows = []
    for k, (n, seed, lam) in enumerate(ANSWER_PROBLEMS):
        F = float(a[f"F{k}"])
        kmax = float(a[f"k{k}"])  # slips in units of F / max_i A_ii
        rows.append((n, seed, lam, int(a[f"cycles{k}"]), int(b[f"cycles{k}"]),
                     abs(float(a[f"W{k}"]) / float(b[f"W{k}"]) - 1),
                     float(np.abs(a[f"slip{k}"] - b[f"slip{k}"]).max() * kmax / F),
                     float(np.abs(a[f"q{k}"] - b[f"q{k}"]).max() / F),
                     int(a[f"newton{k}"]), int(b[f"newton{k}"]),
                     float(a[f"cpu{k}"]), float(b[f"cpu{k}"])))
    return rows


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
    ap.add_argument("--anderson", type=int, default=0,
                    help="part big: anderson_memory of solve_cycles (0: plain cycling)")
    ap.add_argument("--big-max-cycles", type=int, default=200,
                    help="part big: budget of periods (a few: a per-period comparison)")
    ap.add_argument("--repo", default=None, help="import shakedown from this tree (baseline)")
    ap.add_argument("--baseline", default=None,
                    help="parts siconos, answers: the baseline tree (e.g. /work/main)")
    ap.add_argument("--seeds", type=int, default=1, help="part siconos: random systems")
    ap.add_argument("--steps-in", default=None)
    ap.add_argument("--steps-out", default=None)
    a = ap.parse_args()
    lines = [f"Machine: {platform.machine()} {os.cpu_count()} cores, python {platform.python_version()}, "
             f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}",
             f"Load at start: {os.getloadavg()}", ""]
    parts = a.parts.split(",")
    if "steptimes" in parts:
        part_steptimes(a.steps_in, a.steps_out)
        return
    if "runs" in parts:
        part_runs(a.steps_out)
        return
    if "answers" in parts:
        rows = part_answers(a.baseline)
        lines += ["## Cyclic runs: this code against the baseline (plain cycling, 32 steps per "
                  "period)", "", "| N | seed | lam | periods (this, base) | W rel. diff | "
                  "final slip diff / (F / k) | last reactions diff / F | Newton its (this, base) "
                  "| CPU [s] (this, base) |", "|---|---|---|---|---|---|---|---|---|"]
        for n, sd_, lam, c1, c2, dw, dv, dq, i1, i2, t1, t2 in rows:
            lines.append(f"| {n} | {sd_} | {lam} | {c1}, {c2} | {dw:.1e} | {dv:.1e} | {dq:.1e} "
                         f"| {i1}, {i2} | {t1:.2f}, {t2:.2f} |")
        lines.append("")
    if "siconos" in parts and siconos_available():
        summary = []
        for seed in range(a.seeds):
            r = part_siconos(a.n, a.lam, a.repeats, seed=seed, baseline=a.baseline)
            m = r["med"]
            lines += [f"### Step at N = {r['n']}, system seed {seed} (lam = {r['lam']}, "
                      f"{r['steps']} steps of one period, {100 * r['slipping']:.0f}% of the "
                      "node-steps slipping)", "",
                      "| solver | start | median per step, wall [ms] | CPU [ms] | ratio to this "
                      "code (CPU) | max diff / F | not converged |", "|---|---|---|---|---|---|---|"]
            who = ["this code"] + (["main"] if a.baseline else []) + [
                f"Siconos {k.upper()}" for k in r["solvers"]]
            for start in ("warm", "warm, K u0 computed", "cold", "this code's start"):
                o = m[("this code", "warm" if start == "this code's start" else start, "cpu")]
                rows = {"warm, K u0 computed": ["this code"],
                        "this code's start": [w_ for w_ in who if w_.startswith("Siconos")]}
                for w_ in rows.get(start, who):
                    t, c = m[(w_, start, "wall")], m[(w_, start, "cpu")]
                    d, bad = r["diffs"][(w_, start)]
                    lines.append(f"| {w_} | {start} | {1e3 * t:.3f} | {1e3 * c:.3f} | "
                                 f"{c / o:.1f}x | {d:.2e} | {bad} |")
                if start == "warm, K u0 computed":
                    continue
                sic = min(m[(w_, start, "cpu")] for w_ in who if w_.startswith("Siconos"))
                base = "warm" if start == "this code's start" else start
                summary.append((seed, start, sic / o,
                                m[("main", base, "cpu")] / o if a.baseline else float("nan"),
                                r["paired"][start]))
            lines += ["", f"Load after: {os.getloadavg()}", ""]
        lines += ["### Summary over systems: fastest Siconos solver / this code (CPU per step)", "",
                  "| start | median | worst (smallest) | main / this code (median) | paired per "
                  "repeat: median, worst (seeds x repeats) |",
                  "|---|---|---|---|---|"]
        for start in ("warm", "cold", "this code's start"):
            x = np.array([q[2] for q in summary if q[1] == start])
            y = np.array([q[3] for q in summary if q[1] == start])
            z = np.concatenate([q[4] for q in summary if q[1] == start])
            lines.append(f"| {start} | {np.median(x):.1f}x | {x.min():.1f}x | "
                         f"{np.median(y):.2f}x | {np.median(z):.1f}x, {z.min():.1f}x "
                         f"({z.size}) |")
        lines.append("")
    if "hot" in parts:
        lines += ["## Warm steps of period 3: in sequence against repeated in place (CPU)", "",
                  "| seed | in sequence [ms] | repeated in place [ms] | sequence / in place "
                  "(median per step) |", "|---|---|---|---|"]
        for seed in range(a.seeds):
            r = part_hot(a.n, a.lam, a.repeats, seed=seed)
            lines.append(f"| {seed} | {1e3 * r['seq']:.3f} | {1e3 * r['hot']:.3f} | "
                         f"{r['ratio']:.2f}x |")
        lines += ["", f"Load after: {os.getloadavg()}", ""]
    if "big" in parts:
        r = part_big(a.big_n, a.big_lam, anderson=a.anderson, max_cycles=a.big_max_cycles)
        import shakedown

        lines += [f"## Cycles at N = {r['n']} (lam = {r['lam']}, 64 steps per period, "
                  f"anderson_memory = {r['anderson']}, code {Path(shakedown.__file__).parent})", "",
                  f"status {r['status']}, period {r['period']}, {r['cycles']} periods, "
                  f"{r['slipped']} of {r['n']} nodes slip in the steady orbit, "
                  f"{r['steps']} steps, {r['newton']} Newton iterations, wall "
                  f"{r['wall']:.1f} s, CPU **{r['cpu']:.1f} s**, W = {r['W']:.12g}; energy identity "
                  f"(discrete, relative) {r['energy']}",
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
