"""Solve a batch of 3-D frictional contact problems with Siconos FC3D solvers (Debian python3).

Siconos (Debian package ``python3-siconos``) imports only under ``/usr/bin/python3``, so
:mod:`benchmarks.bench_cone_step` (and the ``peers`` test) write the problems to an ``.npz`` and
run this script in a subprocess.  numpy and ``siconos.numerics`` only (not ``shakedown``).

Usage::

    /usr/bin/python3 benchmarks/siconos_fc3d_worker.py IN.npz OUT.npz [--solvers nsgs,nsn_ac]
        [--tol 1e-12] [--warm]

Input ``IN.npz``: ``M`` (m, m) with ``m = 3 nc`` (contact ``i``: row ``3i`` normal, ``3i + 1``,
``3i + 2`` tangential), ``Q`` (k, m), ``mu`` (nc,).  Problem ``j``: ``u = M r + Q[j]`` with ``r``
in the Coulomb cone ``|r_T| <= mu r_N`` and Coulomb's law in De Saxce's form (Siconos'
FrictionContactProblem, dimension 3).  ``--warm``: problem ``j`` starts from the reactions of
problem ``j - 1`` (a time-stepping warm start), else from zero; ``--given``: problem ``j``
starts from ``R0[j]`` (k, m) of the input (e.g. the start another solver was given).

Output ``OUT.npz``: per solver name ``<s>_r``, ``<s>_u`` (k, m), ``<s>_info`` (k,) (0 =
converged), ``<s>_time`` (k,) [s] (wall time of the ``fc3d_driver`` call only), ``<s>_cpu`` (k,)
[s] (its process CPU time), ``<s>_iters``, ``<s>_error``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

SOLVERS = {
    "nsgs": "SICONOS_FRICTION_3D_NSGS",
    "nsn_ac": "SICONOS_FRICTION_3D_NSN_AC",
    "nsn_fb": "SICONOS_FRICTION_3D_NSN_FB",
    "nsn_nm": "SICONOS_FRICTION_3D_NSN_NM",
    "admm": "SICONOS_FRICTION_3D_ADMM",
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("inp")
    ap.add_argument("out")
    ap.add_argument("--solvers", default="nsgs,nsn_ac")
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--max-iter", type=int, default=100000)
    ap.add_argument("--warm", action="store_true")
    ap.add_argument("--given", action="store_true")
    a = ap.parse_args()
    import siconos.numerics as sn

    data = np.load(a.inp)
    M, Q, mu = (np.ascontiguousarray(data[k], float) for k in ("M", "Q", "mu"))
    k, m = Q.shape
    out = {}
    for name in a.solvers.split(","):
        sid = getattr(sn, SOLVERS[name])
        R, U = np.zeros((k, m)), np.zeros((k, m))
        info, times, iters, err = (np.zeros(k, int), np.zeros(k), np.zeros(k, int),
                                   np.zeros(k))
        cpu = np.zeros(k)
        r_prev = np.zeros(m)
        for j in range(k):
            prob = sn.FrictionContactProblem(3, m // 3, M, Q[j].copy(), mu)
            so = sn.SolverOptions(sid)
            so.dparam[sn.SICONOS_DPARAM_TOL] = a.tol
            so.iparam[sn.SICONOS_IPARAM_MAX_ITER] = a.max_iter
            r = (np.array(data["R0"][j], float) if a.given else r_prev.copy() if a.warm
                 else np.zeros(m))
            u = np.zeros(m)
            t0, c0 = time.perf_counter(), time.process_time()
            info[j] = sn.fc3d_driver(prob, r, u, so)
            times[j] = time.perf_counter() - t0
            cpu[j] = time.process_time() - c0
            iters[j] = so.iparam[sn.SICONOS_IPARAM_ITER_DONE]
            err[j] = so.dparam[sn.SICONOS_DPARAM_RESIDU]
            R[j], U[j] = r, u
            r_prev = r
        out.update({f"{name}_r": R, f"{name}_u": U, f"{name}_info": info,
                    f"{name}_time": times, f"{name}_cpu": cpu, f"{name}_iters": iters, f"{name}_error": err})
    np.savez(a.out, **out)


if __name__ == "__main__":
    main()
