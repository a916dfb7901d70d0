"""Kachanov crack-network benchmarks: assembly speed, accuracy against exact and BEM references.

Usage::

    python benchmarks/bench_kachanov.py            # everything (about 6 minutes on 2 cores)
    python benchmarks/bench_kachanov.py --quick    # smaller sizes
    python benchmarks/bench_kachanov.py --write-reference   # also data/reference CSV
    python benchmarks/bench_kachanov.py --only wstar       # section 5 alone (about 3 minutes)

Sections
--------
1. Assembly time (median of repeats) of the transmission factors + K for n = 100, 1000, 5000,
   next to a baseline: the same averages by 16-point Gauss-Legendre quadrature of the pointwise
   field (vectorised numpy, the straightforward method; not exact for close pairs).
2. Two collinear cracks: mean-opening amplification of Kachanov (uniform / elliptic weights)
   and the BEM (n_modes 4, 8, 16, 32) against the exact elliptic-integral solution.
3. Kachanov vs BEM on the same random sets (N = 100): time, relative error of the interaction
   (off-diagonal K) and of lam1, lam2 (shakedown.shakedown_bounds) against the BEM with 24 modes.
4. Smallest eigenvalue of Kachanov's symmetrised K.
5. Steady dissipation W* (``shakedown.solve_cycles``, implicit, 64 steps per period, from the
   zero initial state) of Kachanov and of the 8/16-mode BEM against the 24-mode BEM on the sets
   of section 3, at 1.2, 1.5 and 2 times the reference lam2, with the time (model build + bounds
   + cycles) of each model.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import crack_networks as cn  # noqa: E402
import shakedown as sd  # noqa: E402
from crack_networks.bem import collinear_exact_amplification  # noqa: E402


def median_time(fn, repeats):
    times = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def quadrature_factors(cracks, n_gauss=16, chunk=100):
    """Baseline: uniform line averages by Gauss-Legendre quadrature of the pointwise field."""
    n = cracks.n_cracks
    x, w = np.polynomial.legendre.leggauss(n_gauss)
    out = np.zeros((n, n, 2, 2))
    t, nn = cracks.tangents, cracks.normals
    for i0 in range(0, n, chunk):
        sl = slice(i0, min(n, i0 + chunk))
        pts = cracks.centres[sl, None, None, :] + (
            cracks.half_lengths[sl, None, None, None] * x[None, None, :, None]
            * t[sl, None, None, :]
        )  # (I, 1, q, 2)
        for d in range(2):  # unit normal, unit shear load
            from crack_networks.fields import _rotate_stress, _to_local, mode_stress_local

            zeta = _to_local(pts, cracks.centres[None, :, None, :],
                             cracks.half_lengths[None, :, None], cracks.angles[None, :, None])
            with np.errstate(all="ignore"):
                loc = mode_stress_local(zeta, 1)[..., 0, d, :]
            s = _rotate_stress(loc, cracks.angles[None, :, None])  # (I, J, q, 3)
            ni = nn[sl, None, None, :]
            ti = t[sl, None, None, :]
            Tx = s[..., 0] * ni[..., 0] + s[..., 1] * ni[..., 1]
            Ty = s[..., 1] * ni[..., 0] + s[..., 2] * ni[..., 1]
            out[sl, :, 0, d] = 0.5 * np.sum(w * (Tx * ni[..., 0] + Ty * ni[..., 1]), axis=-1)
            out[sl, :, 1, d] = 0.5 * np.sum(w * (Tx * ti[..., 0] + Ty * ti[..., 1]), axis=-1)
    idx = np.arange(n)
    out[idx, idx] = 0.0
    return out


def section_assembly(sizes, lines):
    lines.append("## 1. Assembly time\n")
    lines.append(
        "Median wall time [s]. `closed form` = `cn.transmission_factors` (exact line averages); "
        "`K` = + stiffness assembly (`kachanov_model(..., validate=False)`); `system` = + the "
        "`DiscreteSystem` (its Cholesky check of the 2N x 2N K); `quadrature` = baseline, "
        "16-point Gauss-Legendre averages of the pointwise field (same run).\n"
    )
    lines.append("| n | closed form | K | system | quadrature (baseline) | baseline / closed form |"
                 " max abs diff closed vs quadrature |")
    lines.append("|---|---|---|---|---|---|---|")
    for n in sizes:
        cs = cn.sample_crack_set(n, density=0.1, rng=1)
        rep = 5 if n <= 1000 else 1
        t_tf, Lam = median_time(lambda cs=cs: cn.transmission_factors(cs), rep)
        t_K, _ = median_time(lambda cs=cs: cn.kachanov_model(cs, validate=False), rep)
        if n <= 1000:
            t_sys, _ = median_time(lambda cs=cs: cn.kachanov_model(cs).system, max(1, rep // 2))
            sys_txt = f"{t_sys:.3g}"
        else:
            sys_txt = "not run (10000 x 10000 Cholesky)"
        if n <= 1000:
            t_q, Lq = median_time(lambda cs=cs: quadrature_factors(cs), max(1, rep // 2))
            diff = float(np.abs(Lq - Lam).max())
            q_txt, ratio, d_txt = f"{t_q:.3g}", f"{t_q / t_tf:.1f}", f"{diff:.2e}"
        else:
            q_txt = ratio = d_txt = "not run"
        lines.append(f"| {n} | {t_tf:.3g} | {t_K:.3g} | {sys_txt} | {q_txt} | {ratio} | {d_txt} |")
        print(lines[-1], flush=True)
    lines.append("")


def section_collinear(gaps, lines, write_reference):
    lines.append("## 2. Two collinear cracks: mean-opening amplification\n")
    lines.append(
        "Exact: `collinear_exact_amplification` (Westergaard, elliptic integrals). Entries: "
        "relative error `|model / exact - 1|`; the BEM times are for one model (2 cracks).\n"
    )
    hdr = "| gap / a | exact | Kachanov (uniform) | Kachanov (elliptic) | BEM 4 | BEM 8 | BEM 16 | BEM 32 |"
    lines.append(hdr)
    lines.append("|---|---|---|---|---|---|---|---|")
    rows = []
    for g in gaps:
        cs = cn.CrackSet([[-(1 + g / 2), 0.0], [1 + g / 2, 0.0]], [1.0, 1.0], [0.0, 0.0])
        ex = float(collinear_exact_amplification(g))

        def amp(m):
            return float(m.mean_discontinuities((0.0, 0.0, 1.0))[0, 0] / m.compliance[0])

        vals = [amp(cn.kachanov_model(cs)), amp(cn.kachanov_model(cs, weighting="elliptic"))]
        vals += [amp(cn.bem_model(cs, n_modes=m)) for m in (4, 8, 16, 32)]
        rows.append((g, ex, *vals))
        errs = " | ".join(f"{abs(v / ex - 1):.2e}" for v in vals)
        lines.append(f"| {g:g} | {ex:.10f} | {errs} |")
        print(lines[-1], flush=True)
    lines.append("")
    if write_reference:
        path = ROOT / "data" / "reference" / "two_collinear_cracks.csv"
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(
                "# Two equal collinear cracks (half-length a, tip gap g) under remote tension s: "
                "mean opening / isolated mean opening (pi a (1-nu) s / (2 mu)), plane strain.\n"
                "# exact: Westergaard Z = s (z^2 - d^2)/sqrt((z^2-b^2)(z^2-c^2)), b = g/2, "
                "c = b + 2a, d^2 = c^2 E(k)/K(k), k^2 = 1 - b^2/c^2 (scipy.special.ellipe/ellipk"
                "); amplification = 4((b^2+c^2)/2 - d^2)/(c-b)^2 (crack_networks.bem."
                "collinear_exact_amplification; see Tada, Paris & Irwin, The Stress Analysis of "
                "Cracks Handbook, two collinear cracks).\n"
                "# kachanov_uniform: Kachanov 1987 line averages (crack_networks.kachanov_model); "
                "bem32: Galerkin DD model with 32 modes (crack_networks.bem_model).\n"
            )
            fh.write("gap_over_a,exact,kachanov_uniform,kachanov_elliptic,bem32\n")
            for r in rows:
                fh.write(f"{r[0]:.6g},{r[1]:.12f},{r[2]:.12f},{r[3]:.12f},{r[7]:.12f}\n")
        print("wrote", path)


def section_network(n, densities, seeds, lines):
    lines.append(f"## 3. Kachanov vs BEM on random sets (N = {n}, min_spacing 0.1)\n")
    lines.append(
        "Reference: BEM with 24 modes. `K err` = ||K - K_ref|| / ||K_ref|| over the off-diagonal "
        "blocks (symmetrised K); `lam` errors are relative. Loads: seed 002 s.4.1, f = 0.6. "
        "Times: model construction incl. the DiscreteSystem, median of 3 (BEM 24: 1 run). "
        "W* is not compared: `shakedown.solve_cycles` did not exist when this was run.\n"
    )
    lines.append("| density | seed | model | time [s] | K err | lam1 | lam2 | lam1 err | lam2 err |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    off = ~np.kron(np.eye(n), np.ones((2, 2))).astype(bool)
    for rho in densities:
        for seed in seeds:
            cs = cn.sample_crack_set(n, density=rho, rng=seed)
            t_ref, ref = median_time(lambda cs=cs: cn.bem_model(cs, n_modes=24), 1)
            bref = sd.shakedown_bounds(ref.system, ref.load_cycle(), adjacency=False)
            Kref = ref.stiffness
            models = [
                ("Kachanov uniform", lambda cs=cs: cn.kachanov_model(cs), 3),
                ("Kachanov elliptic", lambda cs=cs: cn.kachanov_model(cs, weighting="elliptic"), 3),
                ("BEM 2", lambda cs=cs: cn.bem_model(cs, n_modes=2), 3),
                ("BEM 4", lambda cs=cs: cn.bem_model(cs, n_modes=4), 3),
                ("BEM 8", lambda cs=cs: cn.bem_model(cs, n_modes=8), 3),
                ("BEM 16", lambda cs=cs: cn.bem_model(cs, n_modes=16), 1),
            ]
            for name, build, rep in models:
                t, m = median_time(build, rep)
                b = sd.shakedown_bounds(m.system, m.load_cycle(), adjacency=False)
                kerr = np.linalg.norm((m.stiffness - Kref)[off]) / np.linalg.norm(Kref[off])
                lines.append(
                    f"| {rho} | {seed} | {name} | {t:.3g} | {kerr:.2e} | {b.lam1:.6f} | "
                    f"{b.lam2:.6f} | {abs(b.lam1 / bref.lam1 - 1):.2e} | "
                    f"{abs(b.lam2 / bref.lam2 - 1):.2e} |"
                )
                print(lines[-1], flush=True)
            lines.append(
                f"| {rho} | {seed} | BEM 24 (reference) | {t_ref:.3g} | 0 | {bref.lam1:.6f} | "
                f"{bref.lam2:.6f} | 0 | 0 |"
            )
            print(lines[-1], flush=True)
    lines.append("")


WSTAR_FACTORS = (1.2, 1.5, 2.0)


def _wstar_runs(build, lams, steps, max_cycles):
    """Build a model, its bounds and steady W* at each load factor, timing each part."""
    t0 = time.perf_counter()
    m = build()
    system = m.system
    load = m.load_cycle()
    t1 = time.perf_counter()
    b = sd.shakedown_bounds(system, load, adjacency=False)
    t2 = time.perf_counter()
    runs = []
    for lam in lams:
        t = time.perf_counter()
        r = sd.solve_cycles(system, load, lam, method="implicit", steps_per_cycle=steps,
                            max_cycles=max_cycles)
        runs.append((float(m.normalised_dissipation(r.steady_dissipation)), r.status,
                     r.n_cycles, time.perf_counter() - t))
    return dict(t_build=t1 - t0, t_bounds=t2 - t1, t_cycles=sum(x[3] for x in runs), bounds=b,
                runs=runs)


def section_wstar(n, densities, seeds, lines, steps=64, max_cycles=200):
    lines.append(f"## 5. Steady dissipation W*: Kachanov and BEM 8/16 vs BEM 24 (N = {n})\n")
    lines.append(
        "Same crack sets as section 3 (min_spacing 0.1, f = 0.6, seed 002 s.4.1 load: static "
        "(-1, 0, -1), cyclic (0, 1, 0) p0 = 1). `shakedown.solve_cycles(system, load, lam, "
        f"method='implicit', steps_per_cycle={steps}, max_cycles={max_cycles})` from the zero "
        "initial state, at the *same* load factors for every model: lam = c lam2_ref, c = "
        f"{', '.join(f'{c:g}' for c in WSTAR_FACTORS)}, lam2_ref = lam2 of the 24-mode BEM. "
        "W* = W mu / (4 (1 - nu) p0^2 abar^2) (MODEL.md s.7, `.normalised_dissipation`). "
        "`err` = |W*/W*_ref - 1|. Times (single runs): `build` = model + DiscreteSystem, "
        "`bounds` = shakedown_bounds, `cycles` = the three solve_cycles runs, `total` = the sum. "
        "The time discretisation (64 steps) is the same for every model, so the errors are "
        "model errors only.\n"
    )
    hdr = " | ".join(f"W* ({c:g} lam2) | err" for c in WSTAR_FACTORS)
    lines.append(f"| density | seed | model | {hdr} | build [s] | bounds [s] | cycles [s] | "
                 "total [s] | periods to steady |")
    lines.append("|---|---|---|" + "---|---|" * len(WSTAR_FACTORS) + "---|---|---|---|---|")
    summary = {}
    for rho in densities:
        for seed in seeds:
            cs = cn.sample_crack_set(n, density=rho, rng=seed)
            ref_build = lambda cs=cs: cn.bem_model(cs, n_modes=24)  # noqa: E731
            # reference bounds first (the load factors depend on them), then its runs
            t0 = time.perf_counter()
            ref_model = ref_build()
            ref_model.system  # noqa: B018
            t_ref_build = time.perf_counter() - t0
            lam2 = sd.shakedown_bounds(ref_model.system, ref_model.load_cycle(),
                                       adjacency=False).lam2
            lams = [c * lam2 for c in WSTAR_FACTORS]
            ref = _wstar_runs(lambda m=ref_model: m, lams, steps, max_cycles)
            ref["t_build"] = t_ref_build
            wref = [x[0] for x in ref["runs"]]
            models = [
                ("Kachanov uniform", lambda cs=cs: cn.kachanov_model(cs)),
                ("Kachanov elliptic", lambda cs=cs: cn.kachanov_model(cs, weighting="elliptic")),
                ("BEM 8", lambda cs=cs: cn.bem_model(cs, n_modes=8)),
                ("BEM 16", lambda cs=cs: cn.bem_model(cs, n_modes=16)),
            ]
            results = [(name, _wstar_runs(build, lams, steps, max_cycles))
                       for name, build in models]
            results.append(("BEM 24 (reference)", ref))
            for name, r in results:
                cells = []
                for (w, status, _, _), w0 in zip(r["runs"], wref, strict=True):
                    err = abs(w / w0 - 1)
                    flag = "" if status == "periodic" else f" ({status})"
                    cells.append(f"{w:.6g}{flag} | " + ("0" if "reference" in name
                                                             else f"{err:.2e}"))
                    summary.setdefault(name, []).append(err)
                total = r["t_build"] + r["t_bounds"] + r["t_cycles"]
                periods = "/".join(str(x[2]) for x in r["runs"])
                lines.append(f"| {rho} | {seed} | {name} | {' | '.join(cells)} | "
                             f"{r['t_build']:.3g} | {r['t_bounds']:.3g} | {r['t_cycles']:.3g} | "
                             f"{total:.3g} | {periods} |")
                print(lines[-1], flush=True)
    lines.append("")
    lines.append("Max / median relative error of W* over all sets and load factors:\n")
    lines.append("| model | max err | median err |")
    lines.append("|---|---|---|")
    for name, errs in summary.items():
        if "reference" in name:
            continue
        lines.append(f"| {name} | {max(errs):.2e} | {float(np.median(errs)):.2e} |")
    lines.append("")


def section_spd(lines):
    lines.append("## 4. Smallest eigenvalue of Kachanov's symmetrised K\n")
    lines.append("N = 200, half-length uniform in [0.05, 1], min_spacing 0 (the hardest case).\n")
    lines.append("| density | seed | min eig / k0 | asymmetry ||K-K^T||/||K|| |")
    lines.append("|---|---|---|---|")
    for rho in (0.1, 0.5, 1.0):
        for seed in (0, 1):
            cs = cn.sample_crack_set(200, density=rho, half_length=(0.05, 1.0), min_spacing=0.0,
                                     rng=seed)
            m = cn.kachanov_model(cs, validate=False)
            lines.append(f"| {rho} | {seed} | {m.min_eigenvalue / m.self_stiffness:.3f} | "
                         f"{m.asymmetry.relative_norm:.3e} |")
            print(lines[-1], flush=True)
    lines.append("")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--write-reference", action="store_true")
    ap.add_argument("--output", default=None, help="write the markdown tables here")
    ap.add_argument("--only", default=None,
                    choices=("assembly", "collinear", "network", "spd", "wstar"),
                    help="run one section only (wstar = section 5, W* vs the BEM)")
    args = ap.parse_args()

    def want(name):
        return args.only is None or args.only == name

    lines = [
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}.\n"
    ]
    sizes = (100, 300) if args.quick else (100, 1000, 5000)
    if want("assembly"):
        section_assembly(sizes, lines)
    gaps = (2.0, 1.0, 0.5, 0.2, 0.1, 0.05)
    if want("collinear"):
        section_collinear(gaps, lines, args.write_reference)
    n_net, dens, seeds = (40, (0.1,), (1,)) if args.quick else (100, (0.05, 0.1, 0.2), (1, 2))
    if want("network"):
        section_network(n_net, dens, seeds, lines)
    if want("spd"):
        section_spd(lines)
    if want("wstar"):
        section_wstar(n_net, dens, seeds, lines)
    text = "\n".join(lines)
    if args.output:
        Path(args.output).write_text(text, encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
