"""Benchmark: critical friction mu* of the unit square (seed 000 s.7.1), three methods.

For 21..201 nodes per edge (P1, union-jack pattern, nu = 0.3, top held, bottom in contact,
every bottom node in impending slip with chi = -1):

* condensation time (shakedown.fe, for reference),
* the power iteration of seed 000 s.6 (shifted, raw iterates, tol 1e-10, no polishing),
* ARPACK (scipy eigs, 6 eigenvalues of largest |1/mu| of -K0^-1 K1, Cholesky of K0),
* the plain dense approach (scipy.linalg.eig of the pencil, QZ),

medians of ``--repeats`` runs measured side by side in the same process.

    python benchmarks/bench_stability.py [--sizes 21 41 81 121 161 201] [--repeats 5]
        [--out benchmarks/RESULTS_stability.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from shakedown import fe
from shakedown.stability import NodePartition, mceip_mu, slip_pencil


def median_time(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[21, 41, 81, 121, 161, 201])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default="benchmarks/RESULTS_stability.md")
    args = ap.parse_args(argv)
    rows = []
    for n in args.sizes:
        t0 = time.perf_counter()
        mesh = fe.rectangle(1.0, 1.0, n - 1, n - 1, element="P1", pattern="union-jack")
        cm = fe.FEModel(mesh, fe.isotropic(1.0, 0.3), dirichlet=["top"],
                        contact=["bottom"]).condense()
        t_cond = time.perf_counter() - t0
        part = NodePartition.all_slip(cm.n_nodes, -1.0)
        t_pen, pen = median_time(lambda cm=cm, part=part: slip_pencil(cm.K, part), args.repeats)
        t_pow, r_pow = median_time(
            lambda pen=pen: mceip_mu(pen, method="power", polish=False, polish_after=None,
                                     tol=1e-10), args.repeats)
        t_arp, r_arp = median_time(lambda pen=pen: mceip_mu(pen, method="linear-arpack"),
                                   args.repeats)
        t_den, r_den = median_time(lambda pen=pen: mceip_mu(pen, method="linear-dense"),
                                   args.repeats)
        row = dict(n=n, N=cm.n_nodes, t_cond=t_cond, t_pen=t_pen, t_pow=t_pow,
                   it_pow=r_pow.iterations, t_arp=t_arp, t_den=t_den, mu=r_den.mu,
                   d_pow=abs(r_pow.mu - r_den.mu) / r_den.mu,
                   d_arp=abs(r_arp.mu - r_den.mu) / r_den.mu,
                   ok=r_pow.found and r_arp.found and r_den.found and r_den.mode.min() > 0)
        rows.append(row)
        print(row, flush=True)
    lines = [
        "# Stability check: mu* of the unit square (seed 000 s.7.1)",
        "",
        "Command: `python " + " ".join(["benchmarks/bench_stability.py", "--sizes",
                                         *map(str, args.sizes), "--repeats",
                                         str(args.repeats)]) + "`",
        "",
        f"Machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}, numpy {np.__version__}.  Times are medians of "
        f"{args.repeats} runs [s], all methods in the same process on the same pencil.",
        "",
        "Mesh: P1 triangles, union-jack pattern, nu = 0.3, top held, bottom in contact, every "
        "bottom node in impending slip (chi = -1).  `pencil`: Schur complement onto the slip "
        "nodes and K0, K1 (already condensed K).  `power`: seed 000 s.6 iteration (shift "
        "c = 1/mu_n, raw iterates to tol 1e-10, each step one NNLS QP).  `ARPACK`: eigs on "
        "x -> -K0^-1 K1 x (k = 6).  `dense`: scipy.linalg.eig (QZ) of the full pencil.  "
        "Ratios are power / dense and ARPACK / dense.",
        "",
        "| nodes/edge | slip nodes | condensation | pencil | power (its) | ARPACK | dense | "
        "power/dense | ARPACK/dense | mu*_h | rel. diff power, ARPACK vs dense | x > 0 |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['n']} | {r['N']} | {r['t_cond']:.3f} | {r['t_pen']:.4f} | "
            f"{r['t_pow']:.4f} ({r['it_pow']}) | {r['t_arp']:.4f} | {r['t_den']:.4f} | "
            f"{r['t_pow'] / r['t_den']:.2f} | {r['t_arp'] / r['t_den']:.2f} | {r['mu']:.6f} | "
            f"{r['d_pow']:.1e}, {r['d_arp']:.1e} | {'yes' if r['ok'] else 'NO'} |"
        )
    lines.append("")
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
