"""Why the dense interior point stops near a relative gap of 1e-8: an experiment.

The dense interior point (:mod:`shakedown.bounds.cones.dense_ipm`) solves each Newton system by
the normal equations ``G^T W^-2 G dx = r`` (size ``2N + 1``).  Here the same iteration (same
starting point, scaling, steps and stopping rule, ``IPM_TOL`` lowered to 1e-14) solves it in
the augmented form ``[[0, G^T], [G, -W^T W]] (dx, dz) = (bx, bz')`` by a dense LU with partial
pivoting after a symmetric equilibration (size ``2N + 1 + 3M + 1``, ``M`` cuts), and both are
compared with Clarabel on one relaxation (``initial_cuts(data, per)``) of the benchmark's random
coupled systems: relative error of the value, relative gap between the value and the bound the
multipliers prove (:func:`shakedown.bounds.cones.socp.dual_bound`, valid whatever their
residuals), the stationarity residual, CPU seconds.  The augmented matrix is dense here (cost
``~ (3M)^3``), so this is a diagnosis, not a solver:

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_ipm_augmented.py 12 8
    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_ipm_augmented.py 30 8
"""
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "bounds"))
from test_cone_dense_ipm import random_3d, random_load  # noqa: E402

import shakedown.bounds.cones.dense_ipm as di  # noqa: E402
from shakedown.bounds.cones.data import cone_data  # noqa: E402
from shakedown.bounds.cones.melan import initial_cuts  # noqa: E402
from shakedown.bounds.cones.rounds import SocpLog, margin_state  # noqa: E402
from shakedown.bounds.cones.socp import dual_bound, solve_cuts  # noqa: E402


class AugNewton(di._Newton):
    """The Newton system of :class:`dense_ipm._Newton` in augmented form (dense LU)."""

    def __init__(self, G, W, Winv, lm, sc, zc):
        self.G, self.W, self.lm = G, W, lm
        self.WT, self.WinvT = W.transpose(0, 2, 1), Winv.transpose(0, 2, 1)
        self.lmc, self.Wc, self.hc = np.sqrt(sc * zc), np.sqrt(sc / zc), zc / sc
        self.Hm = np.einsum("mab,mcb->mac", Winv, Winv)
        n, m = G.n, G.m
        nx = 2 * n + 1
        Gd = np.zeros((3 * m + 1, nx))
        r = np.arange(m)
        Gd[3 * r, : 2 * n] = -G.E[G.nodes]
        Gd[3 * r + 1, 2 * G.nodes] = -1
        Gd[3 * r + 2, 2 * G.nodes + 1] = -1
        Gd[3 * r, 2 * n] = -G.col[:, 0]
        Gd[3 * r + 1, 2 * n] = -G.col[:, 1]
        Gd[3 * r + 2, 2 * n] = -G.col[:, 2]
        Gd[3 * m, 2 * n] = 1.0
        WtW = np.einsum("mba,mbc->mac", W, W)  # W^T W per cone
        K = np.zeros((nx + 3 * m + 1,) * 2)
        K[:nx, nx:] = Gd.T
        K[nx:, :nx] = Gd
        for k in range(m):
            K[nx + 3 * k: nx + 3 * k + 3, nx + 3 * k: nx + 3 * k + 3] = -WtW[k]
        K[-1, -1] = -self.Wc ** 2
        # equilibrate symmetric
        d = 1 / np.sqrt(np.maximum(np.abs(K).max(axis=1), 1e-300))
        self.d = d
        self.lu = sla.lu_factor(d[:, None] * K * d[None, :])
        self.nx, self.Gd = nx, Gd

    def _once(self, bx_u, bx_l, bz, bzc, bs, bsc):
        G, n = self.G, self.G.n
        Wt = np.einsum("mab,mb->ma", self.WT, di._jdiv(self.lm, bs))
        tc = bsc / self.lmc
        rhs = np.concatenate([bx_u.reshape(-1), [bx_l], (bz - Wt).reshape(-1), [bzc - self.Wc * tc]])
        sol = self.d * sla.lu_solve(self.lu, self.d * rhs)
        dx = sol[: self.nx]
        dz = sol[self.nx: -1].reshape(-1, 3)
        dzc = sol[-1]
        ddu, ddl = dx[:-1].reshape(n, 2), dx[-1]
        gdx, gdc = G.apply(ddu, ddl)
        return [ddu, ddl, dz, dzc, bz - gdx, bzc - gdc]

def compare(n, per, seeds):
    orig = di._Newton
    di.IPM_TOL = 1e-14
    for seed in seeds:
        d = cone_data(random_3d(n, seed), random_load(n, 100 + seed))
        nodes, times = initial_cuts(d, per)
        ref = solve_cuts(d, nodes, times)
        u0, _ = margin_state(d, solver="dense", log=SocpLog())
        a1, b1 = d.periodic(times, nodes)
        for name, cls in (("normal", orig), ("augmented", AugNewton)):
            di._Newton = cls
            t = time.process_time()
            try:
                ans = di.solve_dense(d.E, nodes, a1, b1, d.a0, d.b0, u0=u0)
            finally:
                di._Newton = orig
            hi, res = dual_bound(d, nodes, times, ans.z, ans.y_cap)
            print(f"N={n} M={nodes.size} seed={seed} {name:9s} {ans.status} it={ans.iterations} "
                  f"(lam - clarabel)/lam={(ans.lam - ref.lam) / ref.lam:.2e} "
                  f"(bound - lam)/lam={(hi - ans.lam) / ans.lam:.2e} "
                  f"stationarity={res['stationarity']:.1e} cpu={time.process_time() - t:.2f}s",
                  flush=True)
        hc, _ = dual_bound(d, nodes, times, ref.z, ref.y_cap)
        print(f"N={n} M={nodes.size} seed={seed} clarabel  (bound - lam)/lam="
              f"{(hc - ref.lam) / ref.lam:.2e}", flush=True)


if __name__ == "__main__":
    compare(int(sys.argv[1]), int(sys.argv[2]), [0, 1, 2])
