"""Speed of the 3-D uniqueness bound (``DiscreteSystem.critical_friction()`` for ``dim = 3``).

Side by side in one process, per random coupled system (dense ``K = M M^T + 3N I``, ``f`` in
[0.2, 0.6] per direction): *baseline* -- the former computation, ``S = A - B C^-1 B^T`` formed
by ``cho_solve`` and a product, its smallest eigenvalue and ``lambda_max(F C F)`` by the dense
symmetric eigensolver (a tridiagonalisation of the ``2N`` and ``N`` matrices); *certified* --
:func:`shakedown.model.critical3d.sufficient_factor_3d`: the estimates by Lanczos (products
with ``S^-1`` through one Cholesky factor, and with ``F C F``) proven by Cholesky factorisations
of the shifted matrices.  CPU time (``time.process_time``, one thread: the one-core figure)
and wall time, the order of the two alternated per system, the load average with each row.

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
        python3 benchmarks/bench_3d_critical.py 500 1000 --seeds 0 1 2
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this repository's package
from shakedown.model.critical3d import sufficient_factor_3d  # noqa: E402


def baseline(A, B, C, friction_xy):
    """The former ``sufficient_factor_3d`` (dense eigensolver, estimates not proven)."""
    fmax = np.asarray(friction_xy, float).max(axis=1)
    S = A - B @ sla.cho_solve(sla.cho_factor(C), B.T)
    S = 0.5 * (S + S.T)
    s = float(sla.eigvalsh(S, subset_by_index=[0, 0])[0])
    FCF = fmax[:, None] * C * fmax[None, :]
    c = float(sla.eigvalsh(0.5 * (FCF + FCF.T), subset_by_index=[C.shape[0] - 1,
                                                                  C.shape[0] - 1])[0])
    return 2.0 * float(np.sqrt(s / c))


def system(n, seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    f = 0.2 + 0.4 * rng.random((n, 2))
    return (np.ascontiguousarray(K[: 2 * n, : 2 * n]), np.ascontiguousarray(K[: 2 * n, 2 * n:]),
            np.ascontiguousarray(K[2 * n:, 2 * n:]), f)


def timed(fn, *args):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args)
    return out, time.perf_counter() - t0, time.process_time() - c0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sizes", type=int, nargs="+")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--out", default="benchmarks/critical_3d_speed.json")
    a = ap.parse_args()
    rows = []
    for n in a.sizes:
        for seed in a.seeds:
            A, B, C, f = system(n, seed)
            order = ["baseline", "certified"] if seed % 2 == 0 else ["certified", "baseline"]
            row = dict(N=n, seed=seed, load=os.getloadavg()[0])
            for name in order:
                if name == "baseline":
                    val, wall, cpu = timed(baseline, A, B, C, f)
                else:
                    val, wall, cpu = timed(lambda *x: sufficient_factor_3d(*x)[0], A, B, C, f)
                row[name] = dict(factor=val, wall=wall, cpu=cpu)
            row["rel_diff"] = (row["baseline"]["factor"] - row["certified"]["factor"]) \
                / row["baseline"]["factor"]
            row["cpu_ratio"] = row["baseline"]["cpu"] / row["certified"]["cpu"]
            row["load_after"] = os.getloadavg()[0]
            rows.append(row)
            print(json.dumps(row), flush=True)
            with open(a.out, "w") as fh:
                json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
