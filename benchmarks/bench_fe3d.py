"""3-D FE condensation: time and memory against the number of contact nodes, condensed (dense
``K``) against uncondensed (sparse ``K_z``).

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_fe3d.py --n 4 8 12 16 24 --repeats 3

The body: a block ``1 x 1 x 0.25`` of ``n x n x max(2, n // 4)`` trilinear hexahedra (``Q1``;
``--element P1`` for tetrahedra, six per cell), E = 1, nu = 0.3, held at its top, its bottom on a
rigid obstacle: ``N = (n + 1)^2`` contact nodes, ``3 N`` contact unknowns; one load case (top
displaced by (0.01, 0, -0.01)).  Each measurement is a fresh subprocess (its peak RSS is its
own; a 2 x 2 x 2 model is built first, untimed, so that imports and first calls are not
counted): ``condensed`` = ``FEModel.condense()`` (assembly, boundary-layer LU of ``K_ii``, dense
Schur complement and welded reactions); ``uncondensed`` = ``FEModel.uncondensed()`` (assembly,
the checks of ``K_z`` (symmetry, one sparse LU, 1-norm condition estimate) and welded reactions)
and one product ``K @ x`` with a random ``x`` (one solve with ``K_ii``).  ``--check`` also
compares the two ``K`` (``system.K.toarray()``) in the uncondensed worker (not timed).
Printed: medians (and worst) of the model's wall-clock and CPU (process) time, peak RSS,
``nnz(K_z)`` and the dense ``K`` bytes.
Results: ``RESULTS_fe3d.md``, ``fe3d.json``.

``--assembly``: the 3-D stiffness assembly alone, ``Body.stiffness()`` (each local function's
strains once per element block) against scikit-fem's ``asm`` of the form ``eps(u) . D eps(v)``
(the per-pair form the 2-D bodies use), side by side in one process, median of ``--repeats``,
with the largest entry difference.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)  # this checkout's package, not an installed one


def model(n: int, element: str):
    from shakedown import fe

    mesh = fe.box(1.0, 1.0, 0.25, n, n, max(2, n // 4), element=element)
    return fe.FEModel(mesh, fe.isotropic(1.0, 0.3, plane="3d"), dirichlet=["top"],
                      contact=["bottom"], loads={"push": fe.Displacement("top", (0.01, 0, -0.01))},
                      friction=0.3)


def worker(n: int, kind: str, element: str, check: bool):
    warm = model(2, element)  # imports and first assembly (not timed)
    warm.condense() if kind == "condensed" else warm.uncondensed()
    m = model(n, element)
    t0, c0 = time.perf_counter(), time.process_time()
    if kind == "condensed":
        cm = m.condense()
        t1, c1 = time.perf_counter(), time.process_time()
        extra = {"dense_K_mb": cm.K.nbytes / 2**20, "nnz_Kz": None, "product_s": None}
    else:
        cm = m.uncondensed()
        t1, c1 = time.perf_counter(), time.process_time()
        x = np.random.default_rng(0).standard_normal(3 * cm.n_nodes)
        cm.system.K @ x
        extra = {"dense_K_mb": None, "nnz_Kz": int(cm.system.nnz),
                 "product_s": time.perf_counter() - t1}
        if check:
            dense = m.condense().K
            extra["max_rel_diff"] = float(np.abs(cm.system.K.toarray() - dense).max()
                                          / np.abs(dense).max())
    print(json.dumps({"n": n, "element": element, "kind": kind, "n_nodes": cm.n_nodes,
                      "dofs": cm.counts["n_full_dofs"], "model_s": t1 - t0, "model_cpu_s": c1 - c0,
                      "timings": cm.timings, **extra,
                      "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))


def assembly(ns, element, repeats):
    from skfem import BilinearForm, asm
    from skfem.helpers import sym_grad

    from shakedown import fe

    pairs = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
    for n in ns:
        body = fe.Body(fe.box(1.0, 1.0, 0.25, n, n, max(2, n // 4), element=element),
                       fe.isotropic(1.0, 0.3, plane="3d"))
        D = body.material.D
        _ = body.basis

        @BilinearForm
        def form(u, v, w, D=D):
            e, f = sym_grad(u), sym_grad(v)
            eu = [e[i, j] * (1 if i == j else 2) for i, j in pairs]
            ev = [f[i, j] * (1 if i == j else 2) for i, j in pairs]
            return sum(D[i, j] * eu[j] * ev[i] for i in range(6) for j in range(6)
                       if D[i, j] != 0.0)

        tv, tf = [], []
        for _ in range(repeats):
            t0 = time.process_time()
            K = body.stiffness()
            t1 = time.process_time()
            ref = asm(form, body.basis).tocsr()
            tf.append(time.process_time() - t1)
            tv.append(t1 - t0)
        diff = abs(K - ref).max() / abs(ref).max()
        print(f"assembly n={n:3d} {element} dofs={body.n_dofs:6d}: vectorised "
              f"{np.median(tv):7.3f} s CPU (worst {max(tv):.3f}), per-pair form "
              f"{np.median(tf):7.3f} s (worst {max(tf):.3f}), ratio {np.median(tf) / np.median(tv):5.1f}, "
              f"max|dK|/max|K| {diff:.1e}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[4, 8, 12, 16, 24])
    ap.add_argument("--element", default="Q1")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--json", default="benchmarks/fe3d.json")
    ap.add_argument("--worker", nargs=2)
    ap.add_argument("--assembly", action="store_true")
    a = ap.parse_args()
    if a.assembly:
        print(f"uptime: {os.popen('uptime').read().strip()}")
        assembly(a.n, a.element, a.repeats)
        print(f"uptime: {os.popen('uptime').read().strip()}")
        return
    if a.worker:
        worker(int(a.worker[0]), a.worker[1], a.element, a.check)
        return
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    rows = []
    print(f"uptime: {os.popen('uptime').read().strip()}")
    for n in a.n:
        for rep in range(a.repeats):
            for kind in ("condensed", "uncondensed"):  # side by side, alternating
                cmd = [sys.executable, __file__, "--worker", str(n), kind, "--element", a.element]
                if a.check and rep == 0:
                    cmd.append("--check")
                out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                r["repeat"] = rep
                rows.append(r)
        for kind in ("condensed", "uncondensed"):
            rs = [r for r in rows if r["n"] == n and r["kind"] == kind]
            t = [r["model_s"] for r in rs]
            cpu = [r["model_cpu_s"] for r in rs]
            mem = [r["peak_rss_mb"] for r in rs]
            print(f"n={n:3d} N={rs[0]['n_nodes']:5d} dofs={rs[0]['dofs']:6d} {kind:12s} "
                  f"model {np.median(t):7.2f} s (worst {max(t):7.2f}) CPU {np.median(cpu):7.2f} s "
                  f"(worst {max(cpu):7.2f}) peak RSS "
                  f"{np.median(mem):7.0f} MB (worst {max(mem):7.0f})"
                  + (f" dense K {rs[0]['dense_K_mb']:.1f} MB" if rs[0]["dense_K_mb"] else
                     f" nnz(K_z) {rs[0]['nnz_Kz']} K@x {np.median([r['product_s'] for r in rs]):.3f} s")
                  + (f" max|dK|/max|K| {rs[0]['max_rel_diff']:.1e}" if "max_rel_diff" in rs[0]
                     else ""), flush=True)
    print(f"uptime: {os.popen('uptime').read().strip()}")
    with open(a.json, "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
