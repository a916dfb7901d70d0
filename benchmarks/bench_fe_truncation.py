"""Why an FE interface is not made sparse by dropping small couplings (issue 14).

An FE strip (width 4, height 1, P1, isotropic E = 1, nu = 0.3, top fixed, bottom on the
obstacle, weight as the static load and a horizontal body force as the cyclic one, f = 0.5)
is condensed on its ``nx + 1`` bottom nodes; its ``K`` is then truncated to the couplings
``|K_ij| >= rtol sqrt(K_ii K_jj)`` (a sparse system) and ``lam1``, ``lam2`` and the steady
dissipation at ``1.5 lam2`` are compared with the full system's.

    python3 benchmarks/bench_fe_truncation.py --nx 80 240
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.sparse as sp

import shakedown as sd
from shakedown import fe


def truncated(s, rtol):
    K = s.K
    d = np.sqrt(np.diag(K))
    mask = (np.abs(K) >= rtol * np.outer(d, d)) | np.eye(K.shape[0], dtype=bool)
    Kt = sp.csr_matrix(np.where(mask, K, 0.0))
    n = s.n_nodes
    return sd.DiscreteSystem(Kt[:n, :n], Kt[:n, n:], Kt[n:, n:], s.friction)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, nargs="+", default=[80, 240])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    a = ap.parse_args()
    print("| contact nodes | rtol | fill | lam1 rel. error | lam2 rel. error | W(1.5 lam2) rel. error |")
    print("|---|---|---|---|---|---|")
    for nx in a.nx:
        model = fe.FEModel(fe.rectangle(4.0, 1.0, nx, max(4, nx // 8)), fe.isotropic(1.0, 0.3),
                           dirichlet=["top"], contact=["bottom"], friction=0.5,
                           loads={"weight": fe.BodyForce((0.0, -1.0)),
                                  "push": fe.BodyForce((1.0, 0.0))})
        cm = model.condense()
        s = cm.system
        load = cm.load_cycle(static="weight", cyclic="push")
        b = sd.shakedown_bounds(s, load)
        lam = 1.5 * b.lam2
        W = sd.solve_cycles(s, load, lam, steps_per_cycle=32, max_cycles=100).dissipation[-1]
        for rtol in a.rtol:
            st = truncated(s, rtol)
            bt = sd.shakedown_bounds(st, load)
            Wt = sd.solve_cycles(st, load, lam, steps_per_cycle=32,
                                 max_cycles=100).dissipation[-1]
            print(f"| {s.n_nodes} | {rtol:g} | {st.nnz / (2 * s.n_nodes) ** 2:.3f} | "
                  f"{bt.lam1 / b.lam1 - 1:.2e} | {bt.lam2 / b.lam2 - 1:.2e} | {Wt / W - 1:.2e} |",
                  flush=True)


if __name__ == "__main__":
    main()
