"""Half-space contact (issue 23): Hertz convergence and the FFT operator against the dense matrices.

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py hertz
      OPENBLAS_NUM_THREADS=1 python benchmarks/bench_half_space.py operator
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


def matrix_free(ns, S=40, X=0.5, dense_max=16):
    """Steady fretting cycle (Q oscillating at 0.5 f P, nu = 0, window 2.4 a) matrix-free, with the
    dense cone engine beside it up to ``dense_max``: CPU time (robust to the shared machine's load)
    and peak resident memory of this process."""
    import resource

    from shakedown.models.half_space.matrix_free import fretting_cycles_fft
    from shakedown.studies import half_space as hs

    mats = ((E, 0.0), (E, 0.0))
    a = float(cont.hertz_radius(P, R, E / 2))
    f = 0.5
    t = (np.arange(S) + 1) / S
    print("| n | cells | 2a/h | W / W_MD - 1 | cycles | FISTA iterations per step (median, max) "
          "| CPU [s] FFT | CPU [s] dense (build + run) | W_fft / W_dense - 1 | peak RSS [MB] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in ns:
        m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * a, friction=f, materials=mats)
        c0 = time.process_time()
        out = fretting_cycles_fft(m, P, X * f * P * np.cos(2 * np.pi * t), max_cycles=4, tol=1e-9)
        c_fft = time.process_time() - c0
        W_md = float(cont.mindlin_deresiewicz_dissipation(X * f * P, P, f, a,
                                                          cont.tangential_compliance_constant(mats)))
        dense = "- | -"
        if n <= dense_max:
            c0 = time.process_time()
            run, _ = hs.fretting_run(m, P, X * f * P, steps_per_cycle=S, max_cycles=4)
            c_dense = time.process_time() - c0
            dense = f"{c_dense:.1f} | {out['W'][-1] / run.steady_dissipation - 1:+.1e}"
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        it = np.array(out["iterations"])
        print(f"| {n} | {n * n} | {2 * a / m.h:.1f} | {out['W'][-1] / W_md - 1:+.2e} | {len(out['W'])} "
              f"| {int(np.median(it))}, {it.max()} | {c_fft:.1f} | {dense} | {rss:.0f} |", flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["hertz", "operator", "matrix_free"])
    ap.add_argument("--ns", type=int, nargs="*", default=None)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    print(f"# OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; "
          f"load: {os.getloadavg()}")
    if a.what == "hertz":
        hertz([15, 31] if a.quick else [15, 31, 63, 127, 255])
    elif a.what == "operator":
        operator(a.ns or ([8, 16] if a.quick else [8, 16, 24, 32, 48, 64, 128, 256]))
    else:
        matrix_free(a.ns or [16, 32, 64])
