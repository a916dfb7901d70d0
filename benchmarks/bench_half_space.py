"""Half-space contact (issue 23): Hertz convergence and the FFT operator against the dense matrices.

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py hertz
      OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py operator
      OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py matrix_free --case similar
      OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py matrix_free --case coupled
      OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py lam2
Prints markdown tables (copied into benchmarks/RESULTS_half_space.md).

Hertz: sphere R = 1, E1 = E2 = 1, nu = 0.3 (E* = 0.5495), P = 1e-3, window 3 a (the contact
diameter spans 2n/3 cells), frictionless normal contact by Polonsky-Keer with FFT products
(:func:`shakedown.models.half_space.normal.normal_contact`).
"""

from __future__ import annotations

import argparse
import os
import time
import tracemalloc

import numpy as np

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.models.half_space.normal import normal_contact

E, NU, R, P = 1.0, 0.3, 1.0, 1e-3
MATS = ((E, NU), (E, NU))
E_STAR = E / (2 * (1 - NU**2))
A_H = float(cont.hertz_radius(P, R, E_STAR))
P0 = float(cont.hertz_peak_pressure(P, R, E_STAR))


def exact_cell_means(m, k=24):
    """Cell means of the Hertz pressure by k x k Gauss points per cell (force per cell)."""
    gx, gw = np.polynomial.legendre.leggauss(k)
    u = 0.5 * m.h * gx
    X = m.xy_cells[:, 0, None, None] + u[None, :, None]
    Y = m.xy_cells[:, 1, None, None] + u[None, None, :]
    p = cont.hertz_pressure(np.hypot(X, Y), P, R, E_STAR)
    return 0.25 * np.einsum("kab,a,b->k", p, gw, gw) * m.h**2


def hertz(ns):
    rows = []
    for n in ns:
        m = sd.half_space_model(radius=R, n_cells=n, width=3.0 * A_H, materials=MATS)
        t0 = time.perf_counter()
        sol = normal_contact(m, P, rtol=1e-12)
        dt = time.perf_counter() - t0
        # radius from the second moment of the pressure: int rho^2 p dA / P = 2 a^2 / 5
        # (cell centres + h^2/6 for the cell's own second moment)
        mom = np.sum(sol.p * (np.sum(m.xy_cells**2, axis=1) + m.h**2 / 6)) / P
        a_mom = np.sqrt(2.5 * mom)
        a_area = np.sqrt(np.count_nonzero(sol.contact) * m.h**2 / np.pi)
        ex = exact_cell_means(m)
        rms = np.sqrt(np.mean((sol.p - ex)[ex > 0] ** 2)) / (P0 * m.h**2)
        centre = sol.p[m.reference] / ex[m.reference] - 1
        d_err = sol.approach / float(cont.hertz_approach(P, R, E_STAR)) - 1
        rows.append((n, m.h / A_H, a_mom / A_H - 1, a_area / A_H - 1, centre, rms, d_err,
                     sol.iterations, dt, sol.residual))
    print("| n | h/a | a_moment/a - 1 | a_area/a - 1 | p_centre/exact - 1 | rms(p - exact)/p0 "
          "| d/delta - 1 | PK iterations | time [s] | KKT residual |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.4f} | {r[2]:+.2e} | {r[3]:+.2e} | {r[4]:+.2e} | {r[5]:.2e} "
              f"| {r[6]:+.2e} | {r[7]} | {r[8]:.2f} | {r[9]:.1e} |")
    h = np.array([r[1] for r in rows])
    for j, name in ((2, "a_moment"), (4, "p_centre"), (5, "rms pressure"), (6, "approach")):
        e = np.abs([r[j] for r in rows])
        rate = np.polyfit(np.log(h), np.log(e), 1)[0]
        print(f"rate {name}: {rate:.2f}")


def _median_time(fn, reps=3):
    ts = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), float(np.max(ts))


def operator(ns, dense_max=32):
    print("| n | cells | 3N | F x: FFT [ms] | F x: dense [ms] | dense/FFT | FFT memory [MB] "
          "| dense F [MB] | K x: CG-FFT [ms] (iters) | K x: dense [ms] | build dense K [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    rng = np.random.default_rng(0)
    for n in ns:
        m = sd.half_space_model(radius=R, n_cells=n, width=3.0 * A_H, materials=MATS)
        Fop = m.compliance_operator
        x = rng.standard_normal(Fop.shape[0])
        t_fft, _ = _median_time(lambda Fop=Fop, x=x: Fop @ x)
        tracemalloc.start()
        _ = Fop @ x
        mem_fft = (tracemalloc.get_traced_memory()[1]
                   + sum(v.nbytes for v in Fop._hat.values())) / 2**20
        tracemalloc.stop()
        S = m.stiffness_operator(rtol=1e-10)
        xr = rng.standard_normal(S.shape[0])
        t_cg, _ = _median_time(lambda S=S, xr=xr: S @ xr)
        it = int(np.median(S.iterations))
        if n <= dense_max:
            F = m.dense_compliance()
            t_dense, _ = _median_time(lambda F=F, x=x: F @ x)
            err = np.abs(F @ x - Fop @ x).max() / np.abs(F @ x).max()
            t0 = time.perf_counter()
            K = m.stiffness
            t_build = time.perf_counter() - t0
            t_kd, _ = _median_time(lambda K=K, xr=xr: K @ xr)
            errk = np.abs(K @ xr - S @ xr).max() / np.abs(K @ xr).max()
            dense = (f"{1e3 * t_dense:.2f} | {t_dense / t_fft:.1f} | {mem_fft:.1f} | "
                     f"{F.nbytes / 2**20:.0f} | {1e3 * t_cg:.1f} ({it}) | {1e3 * t_kd:.2f} | "
                     f"{t_build:.2f} |  (FFT-dense: {err:.1e}, K: {errk:.1e})")
            del F, K
        else:
            nb = (3 * n * n) ** 2 * 8 / 2**20
            dense = f"- | - | {mem_fft:.1f} | ({nb:.0f}) | {1e3 * t_cg:.1f} ({it}) | - | - |"
        print(f"| {n} | {n * n} | {3 * n * n} | {1e3 * t_fft:.2f} | {dense}")


CASES = {
    # similar materials (nu = 0, Mindlin exact), constant P, Q oscillating at 0.5 f P, window 2.4 a
    "similar": dict(mats=((E, 0.0), (E, 0.0)), P1=0.0, X=0.5, Y=0.0, width=2.4, cycles=4),
    # rigid sphere on nu = 0.3 (beta = 0.29), P = P0 (1 + 0.3 cos(2 pi t + 0.6)), elliptical Q
    "coupled": dict(mats=((E, 0.3), (np.inf, 0.0)), P1=0.3, X=0.4, Y=0.2, width=2.6, cycles=2),
}


def _case_model(case, n, f=0.5):
    c = CASES[case]
    a = float(cont.hertz_radius(P * (1 + c["P1"]), R, E / 2))
    return sd.half_space_model(radius=R, n_cells=n, width=c["width"] * a, friction=f,
                               materials=c["mats"]), c, f


def run_one(case, n, engine, S, out_file, cycles=None):
    """One run in this process (CPU, wall, peak RSS of the process); arrays saved to ``out_file``."""
    import json
    import resource

    from shakedown.models.half_space.matrix_free import fretting_cycles_fft, path_fft
    from shakedown.studies import half_space as hs

    m, c, f = _case_model(case, n)
    c = dict(c, cycles=cycles or c["cycles"])
    t = (np.arange(S) + 1) / S
    Qx, Qy = c["X"] * f * P * np.cos(2 * np.pi * t), c["Y"] * f * P * np.sin(2 * np.pi * t)
    Ps = P + c["P1"] * P * np.cos(2 * np.pi * t + 0.6)
    tol = 1e-9 if case == "similar" else 1e-14
    c0, w0 = time.process_time(), time.perf_counter()
    info = {}
    if engine == "fft":
        q0 = p0 = None
        if m.beta != 0:
            q0, p0 = path_fft(m, [(0.0, 0.0, P)])[-1]
        out = fretting_cycles_fft(m, P, Qx, Qy, P_samples=Ps, max_cycles=c["cycles"], tol=tol,
                                  q0=q0, p0=p0)
        W, q, p = out["W"], out["q"][-1], out["p"][-1]
        it = np.array(out["iterations"])
        info = dict(its_median=float(np.median(it)), its_max=int(it.max()),
                    passes=float(np.median(out["passes"])), residual=out["residual"])
    else:
        start = hs.static_path(m, [(0.0, 0.0, P)])[-1]
        run = sd.solve_cycles(m.system, m.load_cycle(P0=P, P1=c["P1"] * P, Qx=c["X"] * f * P,
                                                     Qy=c["Y"] * f * P, phase=0.6), 1.0,
                              initial_slip=start[0].slip, initial_gap=start[0].gap,
                              steps_per_cycle=S, max_cycles=c["cycles"], tol=tol)
        W = np.asarray(run.dissipation)
        tab = run.steady_table.sort_values(["t", "node"])
        qr = tab[["q_x", "q_y"]].to_numpy().reshape(-1, m.n_cells - 1, 2)[-1]
        pr = tab["p"].to_numpy().reshape(-1, m.n_cells - 1)[-1]
        q, p = hs.full_reactions(m, qr, pr, Qx[-1], Qy[-1], Ps[-1])
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    np.savez(out_file, W=W, q=q, p=p)
    print(json.dumps(dict(case=case, n=n, engine=engine, cpu=cpu, wall=wall, rss=rss,
                          cycles=len(W), load=os.getloadavg()[0], **info)))


def matrix_free(ns, case="similar", S=40, dense_max=24, reps=3, reps_max=64, cycles=None):
    """Dense cone engine and matrix-free steps side by side, each run in its own process (peak RSS
    per run): CPU time (robust to the shared machine's load), wall time, agreement.  The FFT runs
    are repeated ``reps`` times up to ``n = reps_max`` (median and, in brackets, the worst); the
    dense runs once."""
    import json
    import subprocess
    import sys
    import tempfile

    print(f"case {case}: {CASES[case]}; S = {S} steps per cycle")
    print("| n | cells | 2a/h | engine | cycles | W_last / W_MD - 1 | FISTA its (median, max) | passes "
          "| runs | CPU [s] (max) | wall [s] (max) | peak RSS [MB] | load | W_fft/W_dense - 1 "
          "| max dq/(f P), dp/P |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    tmp = tempfile.mkdtemp()
    for n in ns:
        m, c, f = _case_model(case, n)
        a = float(cont.hertz_radius(P, R, E / 2))
        res = {}
        for engine in (("dense", "fft") if n <= dense_max else ("fft",)):
            fn = os.path.join(tmp, f"{case}_{n}_{engine}.npz")
            cmd = [sys.executable, __file__, "one", "--case", case, "--n", str(n), "--engine",
                   engine, "--S", str(S), "--out", fn] + (["--cycles", str(cycles)] if cycles else [])
            runs = []
            for _ in range(reps if (engine == "fft" and n <= reps_max) else 1):
                line = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
                runs.append(json.loads(line.strip().splitlines()[-1]))
            r = dict(runs[0])
            for key in ("cpu", "wall", "rss", "load"):
                vals = [x[key] for x in runs]
                r[key], r[key + "_max"] = float(np.median(vals)), float(np.max(vals))
            r["reps"] = len(runs)
            res[engine] = (r, np.load(fn))
        for engine, (r, arr) in res.items():
            W = arr["W"]
            md = "-"
            if case == "similar":
                md = f"{W[-1] / float(cont.mindlin_deresiewicz_dissipation(c['X'] * f * P, P, f, a, cont.tangential_compliance_constant(c['mats']))) - 1:+.2e}"  # noqa: E501
            cmp = "- | -"
            if engine == "fft" and "dense" in res:
                d = res["dense"][1]
                k = min(len(W), len(d["W"]))
                cmp = (f"{np.max(np.abs(W[:k] / d['W'][:k] - 1)):.1e} | "
                       f"{np.abs(arr['q'] - d['q']).max() / (f * P):.1e}, "
                       f"{np.abs(arr['p'] - d['p']).max() / P:.1e}")
            its = f"{r['its_median']:.0f}, {r['its_max']}" if engine == "fft" else "-"
            passes = f"{r['passes']:.0f}" if engine == "fft" else "-"
            print(f"| {n} | {n * n} | {2 * a / m.h:.1f} | {engine} | {r['cycles']} | {md} | {its} | "
                  f"{passes} | {r['reps']} | {r['cpu']:.1f} ({r['cpu_max']:.1f}) | {r['wall']:.1f} "
                  f"({r['wall_max']:.1f}) | {r['rss']:.0f} | {r['load']:.1f} "
                  f"| {cmp} |", flush=True)


def lam2(ns, dense_max=24, X=0.3, Y=0.15):
    """Melan's lam2 of a fretting load (similar materials, nu = 0.3, window 2.4 a): matrix-free
    per-node construction against the dense cone engine on the contact-cell system (CPU times)."""
    from shakedown.models.half_space.bounds import contact_system_dense, fretting_lam2

    f = 0.5
    a = float(cont.hertz_radius(P, R, E_STAR))
    print(f"Q = lam ({X} f P cos, {Y} f P sin), P = {P}, f = {f}")
    print("| n | cells | contact cells | lam2 matrix-free | CG its | CPU [s] | lam2 dense cone engine "
          "[lower, upper] | CPU [s] (build + bounds) | rel. difference |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in ns:
        m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * a, friction=f, materials=MATS)
        c0 = time.process_time()
        mf = fretting_lam2(m, P, X * f * P, Y * f * P)
        c_mf = time.process_time() - c0
        dense = "- | - | -"
        if n <= dense_max:
            c0 = time.process_time()
            system, welded, _ = contact_system_dense(m, mf.contact)
            q0, p0 = welded(0.0, 0.0, P)
            ux, uy = welded(1.0, 0.0, P)[0] - q0, welded(0.0, 1.0, P)[0] - q0
            load = sd.LoadCycle.from_harmonics(q0, p0, q_cos=X * f * P * ux, q_sin=Y * f * P * uy)
            b = sd.shakedown_bounds(system, load, only=["lam2"])
            c_d = time.process_time() - c0
            dense = (f"{b.lam2:.8g} [{b.lam2_lower:.8g}, {b.lam2_upper:.8g}] | {c_d:.1f} | "
                     f"{mf.lam2 / b.lam2 - 1:+.1e}")
        print(f"| {n} | {n * n} | {int(mf.contact.sum())} | {mf.lam2:.8g} | {mf.cg_iterations} | "
              f"{c_mf:.2f} | {dense} |", flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["hertz", "operator", "matrix_free", "one", "lam2"])
    ap.add_argument("--ns", type=int, nargs="*", default=None)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--case", choices=sorted(CASES), default="similar")
    ap.add_argument("--dense-max", type=int, default=24)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--n", type=int)
    ap.add_argument("--engine", choices=["fft", "dense"])
    ap.add_argument("--S", type=int, default=40)
    ap.add_argument("--out")
    ap.add_argument("--cycles", type=int, default=None)
    a = ap.parse_args()
    if a.what == "one":
        run_one(a.case, a.n, a.engine, a.S, a.out, a.cycles)
        raise SystemExit
    print(f"# OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; "
          f"load: {os.getloadavg()}")
    if a.what == "hertz":
        hertz([15, 31] if a.quick else [15, 31, 63, 127, 255])
    elif a.what == "operator":
        operator(a.ns or ([8, 16] if a.quick else [8, 16, 24, 32, 48, 64, 128, 256]))
    elif a.what == "lam2":
        lam2(a.ns or [16, 24, 32, 48, 64, 128], dense_max=a.dense_max)
    else:
        matrix_free(a.ns or [16, 24, 32, 48, 64, 128], case=a.case, S=a.S, dense_max=a.dense_max,
                    reps=a.reps, cycles=a.cycles)
