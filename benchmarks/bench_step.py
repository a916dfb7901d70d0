"""Cost of the implicit step and of cyclic runs (issues 13/14), side by side with the baseline.

Usage::

    python benchmarks/bench_step.py --baseline /tmp/step-base [--parts scaling,warm,rows,siconos,big]

``--baseline`` is a checkout of the code to compare with (``git worktree add /tmp/step-base
af73457``: the code before this work); each side runs in its own subprocess (``PYTHONPATH`` set
to its tree, ``OPENBLAS_NUM_THREADS=1``) on the same problems, pickled once.  Problems: the
default scene's crack networks (``shakedown/scenes/builtin/default.toml``: Kachanov, density 0.1,
friction 0.6, far field S0 = {-1, 0, -1}, S1 = {0, 1, 0}) with ``N`` cracks, realisation 0.

Parts
-----
events   the exact event-driven path (2 periods from the zero state) against N <= 1000.
scaling  per-step cost of ``solve_cycles`` (implicit, 64 steps per period, 2 periods from the
         zero state, lam = 0.8) against N = 100 .. 2000; log-log slopes; ``step_scaling.png``.
warm     a warm step (the guess is the answer, its factor cached) against one pair of
         triangular solves with the cached factor (LAPACK getrs), N = 100 and 1000.
rows     per run of the default study (12 load factors from 0.5 lam1 to 2 lam2, 4 initial
         states, ``shakedown.studies.sweep.run_row``): baseline, this code one run at a time,
         this code with the 4 states of each load factor together.
siconos  the steps of one steady period at N = 100 (lam = 0.8) solved by Siconos FC2D NSGS
         (``benchmarks/siconos_fc2d_worker.py`` under ``/usr/bin/python3``, tolerance 1e-14,
         warm-started from the previous step) against this code's steps; the answers compared.
big      the 1000-crack realisation: Kachanov assembly, (bounds with ``--bounds``: another
         engineer's stage, see ``bench_bounds.py``), 4 initial states to the steady state at 64
         steps per period, lam = 0.8 (one process, one BLAS thread).
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
    sys.path.insert(0, str(ROOT))
CACHE = Path(tempfile.gettempdir()) / "shakedown_bench_step"
KW = dict(method="implicit", steps_per_cycle=64, tol=1e-10)


# ---------------------------------------------------------------------------- problems
def problem(n: int) -> Path:
    """Pickle ``(A, B, C, friction, load, slips[4])`` of the default scene with n cracks."""
    path = CACHE / f"cracks_{n}.pkl"
    if path.exists():
        return path
    CACHE.mkdir(exist_ok=True)
    from shakedown.scenes.files import tomllib
    from shakedown.studies.sweep import SweepSpec, initial_slip, realisation_model

    raw = tomllib.loads((ROOT / "shakedown/scenes/builtin/default.toml").read_text())
    model = {k: v for k, v in raw["model"].items() if k != "kind"}
    model["n_cracks"] = n
    spec = SweepSpec.from_scene(model, raw["load"], raw["analyses"]["sweep"])
    _, m, load = realisation_model(spec, 0)
    s = m.system
    slips = np.array([initial_slip(s, load, j, (spec.seed, 0, 1), scale=spec.state_scale)
                      for j in range(4)])
    path.write_bytes(pickle.dumps((s.A, s.B, s.C, s.friction, load, slips)))
    return path


def load_problem(path):
    import shakedown as sd

    A, B, C, f, load, slips = pickle.loads(Path(path).read_bytes())
    return sd.DiscreteSystem(A, B, C, friction=f), load, slips


# ---------------------------------------------------------------------------- workers
def worker_steps(a):
    import shakedown as sd
    from shakedown.evolution.complementarity import StepSolver

    s, load, _ = load_problem(a.pkl)
    s.critical_friction()  # once per system (cached in this code; warmed for both sides)
    sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),  # load the
                    sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,  # compiled
                    steps_per_cycle=4)  # kernel (once per process) outside the timing
    out, later = [], []
    for _ in range(a.repeat):
        solver = StepSolver(s)
        solver.critical  # noqa: B018  (computed outside the timed region on both sides)
        t = time.perf_counter()
        run = sd.solve_cycles(s, load, a.lam, max_cycles=a.cycles, solver=solver, **KW)
        out.append((time.perf_counter() - t) / run.statistics["n_steps"])
        # the next periods with the same solver (its caches warm), as in a long run
        t = time.perf_counter()
        nxt = sd.solve_cycles(s, load, a.lam, initial_slip=run.final_slip, max_cycles=a.cycles,
                              solver=solver, **KW)
        later.append((time.perf_counter() - t) / nxt.statistics["n_steps"])
    return dict(per_step=out, per_step_later=later, n_steps=run.statistics["n_steps"],
                factorizations=run.statistics["factorizations"], W=run.dissipation.tolist(),
                W_later=nxt.dissipation.tolist())


def worker_events(a):
    """The event-driven path: 2 periods from the zero state, seconds and events."""
    import shakedown as sd
    from shakedown.evolution.complementarity import StepSolver

    s, load, _ = load_problem(a.pkl)
    s.critical_friction()
    sd.solve_cycles(sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5),
                    sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[1.0]), 1.0,
                    steps_per_cycle=4, method="events")  # load the kernel outside the timing
    out = []
    for _ in range(a.repeat):
        solver = StepSolver(s)
        solver.critical  # noqa: B018
        t = time.perf_counter()
        run = sd.solve_cycles(s, load, a.lam, max_cycles=a.cycles, solver=solver,
                              method="events", steps_per_cycle=64, tol=1e-10)
        out.append(time.perf_counter() - t)
    return dict(seconds=out, events=run.statistics["n_events"], W=run.dissipation.tolist())


def worker_rows(a):
    from shakedown.studies.sweep import run_row

    s, load, slips = load_problem(a.pkl)
    lams = json.loads(a.lams)
    opts = dict(KW, max_cycles=200)
    walls, Ws = [], None
    for _ in range(a.repeat):
        s2, _, _ = load_problem(a.pkl)  # a fresh system: nothing cached from the last repeat
        t = time.perf_counter()
        if a.batched:
            import shakedown as sd

            Ws = []
            for lam in lams:
                runs = sd.solve_cycles(s2, load, lam, initial_slip=slips, max_cycles=200, **KW)
                Ws += [r.steady_dissipation for r in runs]
        else:
            Ws = [run_row(s2, load, lam, v, opts)["W"] for lam in lams for v in slips]
        walls.append(time.perf_counter() - t)
    return dict(per_run=[w / len(Ws) for w in walls], W=Ws)


def worker_warm(a):
    import shakedown as sd
    from shakedown.evolution.complementarity import StepSolver

    s, load, _ = load_problem(a.pkl)
    try:  # the Python step with its own LU cache (this code: the compiled loop is timed below)
        solver = StepSolver(s, kernel=False)
    except TypeError:  # the baseline has no kernel option
        solver = StepSolver(s)
    run = sd.solve_cycles(s, load, a.lam, max_cycles=200, solver=solver, record_history=True,
                          **KW)
    n = s.n_nodes
    qg, pg = load.evaluate(np.arange(1, 65) / 64, a.lam)
    acts = run.final_active_sets
    m = [np.count_nonzero(x != 0) + np.count_nonzero(x == 3) for x in acts]
    k = int(np.argmax(m))  # the step of the steady period with the largest system
    tab = run.history
    last = tab[tab["t"] == tab["t"].max() - 1 + k / 64].drop_duplicates("node", keep="last")
    last = last.sort_values("node")
    v = last["slip"].to_numpy(float)
    assert v.shape == (n,)
    q_w, p_w, guess = qg[k], pg[k], acts[k]
    for _ in range(3):
        r = solver.solve(v, q_w, p_w, guess)
    reps = max(20, int(2e8 / max(n * n * 20, 1)))

    def med(fn):
        ts = []
        for _ in range(5):
            t = time.perf_counter()
            for _ in range(reps):
                fn()
            ts.append((time.perf_counter() - t) / reps)
        return statistics.median(ts)

    res = dict(m=int(m[k]), n=n, step=med(lambda: solver.solve(v, q_w, p_w, guess)),
               iterations=int(r.iterations), factorizations=int(r.factorizations))
    F = solver._cache.get(guess.tobytes())
    if F is not None:  # this code and the baseline keep the LU the same way
        import scipy.linalg as sla
        from scipy.linalg import get_lapack_funcs

        getrs = get_lapack_funcs("getrs", (s.K,))
        rhs = np.random.default_rng(0).normal(size=F.free.size)
        res["getrs"] = med(lambda: getrs(F.lu[0], F.lu[1], rhs))
        res["lu_solve"] = med(lambda: sla.lu_solve(F.lu, rhs, check_finite=False))
        if hasattr(solver, "next_base"):
            base = (q_w + s.A @ v, p_w + s.B.T @ v)
            res["step_warm_base"] = med(lambda: solver.solve(v, q_w, p_w, guess, base=base,
                                                             verify=False))
    try:
        from shakedown.evolution import kernel
    except ImportError:  # the baseline has no compiled kernel
        return res
    if kernel.HAVE_KERNEL:
        res.update(_kernel_warm(s, v, q_w, p_w, guess, med))
    return res


def _kernel_warm(s, v, q_w, p_w, guess, med):
    """Warm steps inside the compiled period loop, and getrs on the same system: ``R`` steps
    with the same welded reactions from the state before step k (the first one solves step k,
    the others are zero-increment steps on the same assignment: the guess is the answer and its
    inverse is cached; with :mod:`.kernel_shortcut`, from the third step on, the responses
    kept for the assignment)."""
    import scipy.linalg as sla
    from scipy.linalg import get_lapack_funcs

    from shakedown.evolution import kernel, kernel_cache

    try:
        from shakedown.evolution import kernel_shortcut
    except ImportError:  # before the shortcut
        kernel_shortcut = None
    from shakedown.evolution.complementarity import StepSolver

    solver = StepSolver(s)
    n = s.n_nodes
    R = 200
    QW, PW = np.tile(q_w, (R, 1)), np.tile(p_w, (R, 1))
    kc = solver.kernel_cache
    arr = [np.zeros((R + 1, n)) for _ in range(4)]
    ST, ACT = np.zeros((R + 1, n), np.int8), np.zeros((R, n), np.int8)
    SC, RES, WD = np.zeros(R), np.zeros(R), np.zeros(1)
    extra = () if kernel_shortcut is None else kernel_shortcut.state(n, QW, PW)
    if hasattr(kernel, "C_PROBE"):  # no prediction from a previous period (issue 26)
        extra = (*extra, np.zeros((0, n), np.int8))

    def go():
        arr[0][0] = v
        q0, p0 = QW[0] + s.A @ v, PW[0] + s.B.T @ v
        g = np.array(guess, np.int8)
        done = kernel.march(s.K, solver.f, solver.diag, QW, PW, 0, q0, p0, g, solver.feas_tol,
                            solver.max_iter, kc.mult, kc.keys, kc.hashes, kc.offs, kc.sizes,
                            kc.pool, kc.ipool, kc.fpool, kc.meta, kc.counters, kc.seen, arr[0],
                            arr[1], arr[2], arr[3], ST, ACT, SC, RES, WD, *extra)
        assert done == R, done

    go()
    c0 = kc.counters.copy()
    go()
    d = kc.counters - c0
    assert d[kernel.C_FACT] == 0 and d[kernel.C_ITER] == R, d  # every step warm
    assert np.all(ACT == ACT[0]), "the assignment changed"
    free, coef = kernel_cache._layout(np.array(guess, np.int8), solver.f, n)
    lu = sla.lu_factor(kernel_cache._matrix(s.K, free, coef, n))
    getrs = get_lapack_funcs("getrs", (s.K,))
    rhs = np.random.default_rng(0).normal(size=free.size)
    short = int(d[kernel.C_SHORT]) if hasattr(kernel, "C_SHORT") else 0
    return dict(kernel_step=med(go) / R, kernel_steps=R, kernel_m=int(free.size),
                kernel_getrs=med(lambda: getrs(lu[0], lu[1], rhs)), kernel_short=short)


def worker_siconos_problems(a):
    """Our steps of one steady period, and the FC2D problems of the same steps (to .npz)."""
    import shakedown as sd
    from shakedown.evolution.complementarity import StepSolver

    s, load, _ = load_problem(a.pkl)
    n = s.n_nodes
    solver = StepSolver(s)
    run = sd.solve_cycles(s, load, a.lam, max_cycles=200, solver=solver, record_history=True,
                          **KW)
    tab = run.steady_table.sort_values(["t", "node"])
    V = tab["slip"].to_numpy(float).reshape(-1, n)  # row 0: start of the orbit
    qg, pg = load.evaluate(np.arange(1, 65) / 64, a.lam)
    acts = run.final_active_sets
    guesses = np.vstack([acts[-1:], acts[:-1]])
    ts, res = [], []
    for _ in range(3):
        t = time.perf_counter()
        res = [solver.solve(V[k], qg[k], pg[k], guesses[k]) for k in range(64)]
        ts.append((time.perf_counter() - t) / 64)
    G = np.linalg.inv(s.K)
    perm = np.ravel(np.column_stack([n + np.arange(n), np.arange(n)]))  # (normal, tangential)
    M = G[np.ix_(perm, perm)]
    Q = np.array([-(G @ np.concatenate([qg[k] + s.A @ V[k], pg[k] + s.B.T @ V[k]]))[perm]
                  for k in range(64)])
    np.savez(a.out, M=M, Q=Q, mu=s.friction, q=np.array([r.q for r in res]),
             p=np.array([r.p for r in res]), dv=np.array([r.slip_increment for r in res]),
             w=np.array([r.gap for r in res]), scale=np.array([r.force_scale for r in res]),
             diag=np.diag(s.K))
    out = dict(per_step=ts)
    try:  # the same 64 steps by the compiled period loop (this code only)
        from shakedown.evolution import fast_period
        from shakedown.model.threads import single_blas_thread
    except ImportError:
        return out
    if fast_period.usable(solver):
        arr = [np.zeros((65, n)) for _ in range(4)]
        st, act = np.zeros((65, n), np.int8), np.zeros((64, n), np.int8)
        sc, rs = np.zeros(64), np.zeros(64)

        def period():
            fast_period.run_period(solver, qg, pg, V[0], acts[-1], *arr, st, act, sc, rs, {})

        tk = []
        with single_blas_thread():
            for _ in range(3):
                t = time.perf_counter()
                period()
                tk.append((time.perf_counter() - t) / 64)
        q = np.array([r.q for r in res])
        out.update(per_step_kernel=tk, kernel_dq=float(
            np.max(np.abs(arr[2][1:] - q) / np.array([r.force_scale for r in res])[:, None])))
    return out


WORKERS = dict(steps=worker_steps, events=worker_events, rows=worker_rows, warm=worker_warm,
               siconos_problems=worker_siconos_problems)


def run_worker(tree, task, **kw):
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", task]
    for k, v in kw.items():
        if v is True:
            cmd.append(f"--{k}")
        elif v is not False and v is not None:
            cmd += [f"--{k}", str(v)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if out.returncode:
        raise RuntimeError(f"{task} in {tree} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------------- parts
def med(x):
    return statistics.median(x)


def part_scaling(base, ns, lines):
    lines += ["## Per-step cost against N (crack networks, lam = 0.8, 64 steps per period, "
              "2 periods, medians of 3)", "",
              "| N | baseline ms/step | this ms/step | speed-up | factorizations (base / this) | "
              "periods 3-4, caches warm: baseline ms/step | this ms/step | speed-up |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    rows = []
    for n in ns:
        pk = problem(n)
        kw = dict(pkl=pk, lam=0.8, cycles=2, repeat=3)
        b = run_worker(base, "steps", **kw)
        t = run_worker(ROOT, "steps", **kw)
        assert np.allclose(b["W"], t["W"], rtol=1e-8), (b["W"], t["W"])
        assert np.allclose(b["W_later"], t["W_later"], rtol=1e-8), (b["W_later"], t["W_later"])
        bl, tl = med(b["per_step_later"]), med(t["per_step_later"])
        rows.append((n, med(b["per_step"]), med(t["per_step"]), bl, tl))
        lines.append(f"| {n} | {1e3 * rows[-1][1]:.3g} | {1e3 * rows[-1][2]:.3g} | "
                     f"{rows[-1][1] / rows[-1][2]:.1f}x | {b['factorizations']} / "
                     f"{t['factorizations']} | {1e3 * bl:.3g} | {1e3 * tl:.3g} | "
                     f"{bl / tl:.1f}x |")
        print(lines[-1], flush=True)
    N = np.array([r[0] for r in rows], float)
    tb, tt = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    lb, lt = np.array([r[3] for r in rows]), np.array([r[4] for r in rows])
    sel = N >= 400
    if sel.sum() >= 2:
        sb = np.polyfit(np.log(N[sel]), np.log(tb[sel]), 1)[0]
        st = np.polyfit(np.log(N[sel]), np.log(tt[sel]), 1)[0]
        slb = np.polyfit(np.log(N[sel]), np.log(lb[sel]), 1)[0]
        slt = np.polyfit(np.log(N[sel]), np.log(lt[sel]), 1)[0]
        lines += ["", f"Log-log slope of the per-step cost for N >= 400 (least squares): periods "
                  f"1-2 baseline {sb:.2f}, this code {st:.2f}; periods 3-4 (caches warm) "
                  f"baseline {slb:.2f}, this code {slt:.2f}."]
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 4))
        ax.loglog(N, 1e3 * tb, "o-", color="C0", label="baseline (af73457), periods 1-2")
        ax.loglog(N, 1e3 * tt, "s-", color="C1", label="this code, periods 1-2")
        ax.loglog(N, 1e3 * lb, "o--", color="C0", mfc="none",
                  label="baseline, periods 3-4 (caches warm)")
        ax.loglog(N, 1e3 * lt, "s--", color="C1", mfc="none",
                  label="this code, periods 3-4 (caches warm)")
        ax.set_xlabel("N (contact nodes)")
        ax.set_ylabel("ms per step")
        ax.set_title("implicit step, crack networks" + (
            f"\nslope N>=400: {st:.2f} (periods 1-2), {slt:.2f} (3-4)" if sel.sum() >= 2
            else ""), fontsize=10)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(HERE / "step_scaling.png", dpi=120)
        lines += ["", "![scaling](step_scaling.png)"]
    except ImportError:
        pass
    lines.append("")


def part_events(base, ns, lines):
    lines += ["## The event-driven path against N (lam = 0.8, 2 periods from the zero state, "
              "medians of 3)", "", "| N | events | baseline s | this s | speed-up |",
              "| --- | --- | --- | --- | --- |"]
    for n in ns:
        kw = dict(pkl=problem(n), lam=0.8, cycles=2, repeat=3)
        b = run_worker(base, "events", **kw)
        t = run_worker(ROOT, "events", **kw)
        assert np.allclose(b["W"], t["W"], rtol=1e-8), (b["W"], t["W"])
        mb, mt = med(b["seconds"]), med(t["seconds"])
        lines.append(f"| {n} | {t['events']} | {mb:.3g} | {mt:.3g} | {mb / mt:.1f}x |")
        print(lines[-1], flush=True)
    lines.append("")


def part_warm(base, lines):
    lines += ["## Warm step against one triangular-solve pair with the cached factor "
              "(lam = 0.8, the steady period's largest system, medians of 5)", "",
              "| N | m (unknowns) | getrs us | baseline step us | this step us | this step, "
              "base given, us | this step / getrs | compiled period loop, us per warm step | "
              "compiled / getrs |", "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for n in (100, 1000):
        pk = problem(n)
        b = run_worker(base, "warm", pkl=pk, lam=0.8)
        t = run_worker(ROOT, "warm", pkl=pk, lam=0.8)
        lines.append(f"| {n} | {t['m']} | {1e6 * t['getrs']:.1f} | {1e6 * b['step']:.1f} | "
                     f"{1e6 * t['step']:.1f} | {1e6 * t['step_warm_base']:.1f} | "
                     f"{t['step'] / t['getrs']:.1f} ({t['step_warm_base'] / t['getrs']:.1f} "
                     f"with the base) | {1e6 * t.get('kernel_step', np.nan):.1f} | "
                     f"{t.get('kernel_step', np.nan) / t.get('kernel_getrs', np.nan):.1f} |")
        print(lines[-1], flush=True)
    lines.append("")


def part_rows(base, lines):
    pk = problem(100)
    from shakedown.bounds.engine import shakedown_bounds

    s, load, _ = load_problem(pk)
    b = shakedown_bounds(s, load)
    lams = np.linspace(0.5 * b.lam1, 2 * b.lam2, 12).tolist()
    kw = dict(pkl=pk, lams=json.dumps(lams), repeat=3)
    rb = run_worker(base, "rows", **kw)
    rt = run_worker(ROOT, "rows", **kw)
    rbt = run_worker(ROOT, "rows", batched=True, **kw)
    Wb, Wt, Wbt = (np.array(r["W"]) for r in (rb, rt, rbt))
    scale = np.nanmax(np.abs(Wb))
    lines += [f"## Per run of the default study (100 cracks, lam1 = {b.lam1:.4f}, "
              f"lam2 = {b.lam2:.4f}, 12 load factors x 4 initial states, medians of 3)", "",
              "| code | s per run | speed-up |", "| --- | --- | --- |",
              f"| baseline run_row | {med(rb['per_run']):.4f} | 1 |",
              f"| this run_row | {med(rt['per_run']):.4f} | "
              f"{med(rb['per_run']) / med(rt['per_run']):.1f}x |",
              f"| this, 4 states together | {med(rbt['per_run']):.4f} | "
              f"{med(rb['per_run']) / med(rbt['per_run']):.1f}x |", "",
              f"Largest |W difference| / max W: this {np.nanmax(np.abs(Wt - Wb)) / scale:.1e}, "
              f"batched {np.nanmax(np.abs(Wbt - Wb)) / scale:.1e}.", ""]
    print("\n".join(lines[-9:]), flush=True)


def part_siconos(lines):
    if subprocess.run(["/usr/bin/python3", "-c", "import siconos.numerics"],
                      capture_output=True, check=False).returncode:
        lines += ["## Siconos FC2D NSGS: skipped (`/usr/bin/python3 -c 'import "
                  "siconos.numerics'` fails; `apt-get install python3-siconos`)", ""]
        return
    pk = problem(100)
    with tempfile.TemporaryDirectory() as tmp:
        pin, pout = Path(tmp) / "in.npz", Path(tmp) / "out.npz"
        ours = run_worker(ROOT, "siconos_problems", pkl=pk, lam=0.8, out=pin)
        ts = []
        for _ in range(3):
            subprocess.run(["/usr/bin/python3", str(HERE / "siconos_fc2d_worker.py"), str(pin),
                            str(pout), "--warm"], check=True)
            o = np.load(pout)
            ts.append(float(np.mean(o["time"])))
        d = np.load(pin)
        n = d["q"].shape[1]
        r, u = o["r"], o["u"]
        dp = np.abs(r[:, 0::2] - d["p"]).max(axis=1) / d["scale"]
        dq = np.abs(r[:, 1::2] - d["q"]).max(axis=1) / d["scale"]
        ds = (np.abs(u[:, 1::2] - d["dv"]) * d["diag"][:n]).max(axis=1) / d["scale"]
        worst = float(max(dp.max(), dq.max(), ds.max()))
        lines += ["## Siconos FC2D NSGS on the same steps (N = 100, one steady period, "
                  "64 steps, medians of 3)", "",
                  "| solver | us per step | ratio |", "| --- | --- | --- |",
                  f"| Siconos FC2D NSGS (tol 1e-14, warm start, driver call only) | "
                  f"{1e6 * med(ts):.0f} | {med(ts) / med(ours['per_step']):.1f}x |",
                  f"| this code (StepSolver.solve, warm guess, full verification) | "
                  f"{1e6 * med(ours['per_step']):.0f} | 1 |",
                  *([f"| this code, the compiled period loop (the same 64 steps, as "
                     f"solve_cycles runs them) | {1e6 * med(ours['per_step_kernel']):.1f} | "
                     f"{med(ours['per_step_kernel']) / med(ours['per_step']):.2f}; Siconos / "
                     f"this {med(ts) / med(ours['per_step_kernel']):.0f}x; its q differ from "
                     f"StepSolver.solve's by {ours['kernel_dq']:.1e} of the force scale |"]
                    if "per_step_kernel" in ours else []), "",
                  f"Siconos converged on {int(np.sum(o['info'] == 0))}/64 steps, "
                  f"{float(np.median(o['iters'])):.0f} NSGS sweeps (median). Largest "
                  f"difference of p, q (/ force scale) and of slips (x K_jj / force scale): "
                  f"{worst:.1e}.", ""]
        print("\n".join(lines[-8:]), flush=True)


def part_big(base, lines, with_bounds=False):
    """1000 cracks: assembly, (bounds), 4 initial states to the steady state; the baseline
    runs the same 4 states one after the other (``run_row``), this code both ways."""
    import crack_networks  # noqa: F401  (import time outside the measurement)

    t0 = time.perf_counter()
    pk = CACHE / "cracks_1000.pkl"
    if pk.exists():
        pk.unlink()
    problem(1000)
    t1 = time.perf_counter()
    lam = 0.8
    rows = [f"| Kachanov assembly and 4 initial states (this code) | {t1 - t0:.1f} | |"]
    if with_bounds:
        from shakedown.bounds.engine import shakedown_bounds

        s, load, _ = load_problem(pk)
        t2 = time.perf_counter()
        b = shakedown_bounds(s, load)
        rows.append(f"| bounds (lam1 = {b.lam1:.4f}, lam2 = {b.lam2:.4f}) | "
                    f"{time.perf_counter() - t2:.1f} | |")
    kw = dict(pkl=pk, lams=json.dumps([lam]), repeat=1)
    rb = run_worker(base, "rows", **kw)
    rt = run_worker(ROOT, "rows", **kw)
    rbt = run_worker(ROOT, "rows", batched=True, **kw)
    for label, r in (("baseline, 4 runs one after the other", rb),
                     ("this code, 4 runs one after the other", rt),
                     ("this code, 4 states together", rbt)):
        rows.append(f"| {label} (lam = {lam}) | {4 * r['per_run'][0]:.1f} | "
                    f"{rb['per_run'][0] / r['per_run'][0]:.1f}x |")
    dW = max(abs(x - y) for x, y in zip(rb["W"], rbt["W"], strict=True))
    lines += ["## The 1000-crack realisation (one process, one BLAS thread, one repeat)", "",
              "| phase | s | speed-up |", "| --- | --- | --- |", *rows, "",
              f"Steady W of the 4 states: {', '.join(f'{w:.6g}' for w in rb['W'])} (baseline); "
              f"largest difference of the batched run {dW:.1e}.", ""]
    print("\n".join(lines[-(len(rows) + 6):]), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", default="/tmp/step-base")
    ap.add_argument("--parts", default="scaling,warm,rows,siconos,big")
    ap.add_argument("--ns", default="100,200,400,1000,2000")
    ap.add_argument("--out", default=str(HERE / "RESULTS_step.md"))
    ap.add_argument("--worker")
    for k in ("pkl", "lam", "cycles", "repeat", "lams"):
        ap.add_argument(f"--{k}")
    ap.add_argument("--batched", action="store_true")
    ap.add_argument("--bounds", action="store_true", help="time the bounds in part big")
    a, _ = ap.parse_known_args()
    if a.worker:
        a.lam = None if a.lam is None else float(a.lam)
        a.cycles = None if a.cycles is None else int(a.cycles)
        a.repeat = None if a.repeat is None else int(a.repeat)
        print(json.dumps(WORKERS[a.worker](a)))
        return
    parts = a.parts.split(",")
    load_avg = os.getloadavg()
    lines = ["# Step solver benchmarks (issues 13/14)", "",
             f"Command: `python benchmarks/bench_step.py --baseline {a.baseline} --parts "
             f"{a.parts}`  ", f"Machine: {os.cpu_count()} cores, Python "
             f"{sys.version.split()[0]}, numpy {np.__version__}, one BLAS thread per process; "
             f"load average at the start {load_avg[0]:.1f} / {load_avg[1]:.1f} / "
             f"{load_avg[2]:.1f} (a shared machine: the ratios measured side by side count, "
             "not the absolute times).", ""]
    if "scaling" in parts:
        part_scaling(a.baseline, [int(x) for x in a.ns.split(",")], lines)
    if "warm" in parts:
        part_warm(a.baseline, lines)
    if "events" in parts:
        part_events(a.baseline, [int(x) for x in a.ns.split(",") if int(x) <= 1000], lines)
    if "rows" in parts:
        part_rows(a.baseline, lines)
    if "siconos" in parts:
        part_siconos(lines)
    if "big" in parts:
        part_big(a.baseline, lines, with_bounds=a.bounds)
    la = os.getloadavg()
    lines.append(f"Load average at the end: {la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f}.")
    Path(a.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
