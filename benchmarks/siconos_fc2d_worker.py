"""Solve a batch of 2-D frictional contact problems with Siconos FC2D NSGS (Debian python3).

Siconos (Debian package ``python3-siconos``) imports only under ``/usr/bin/python3``, so
:mod:`benchmarks.bench_step` writes the problems to an ``.npz`` and runs this script in a
subprocess.  numpy and ``siconos.numerics`` only (not ``shakedown``).

Usage::

    /usr/bin/python3 benchmarks/siconos_fc2d_worker.py IN.npz OUT.npz [--tol 1e-14] [--warm]

Input ``IN.npz``: ``M`` (m, m) with ``m = 2 nc`` (contact ``i``: rows ``2i`` normal, ``2i+1``
tangential), ``Q`` (k, m), ``mu`` (nc,).  Problem ``j``: ``u = M r + Q[j]``, ``r`` in the
Coulomb cone of each contact, ``u`` and ``r`` satisfying Coulomb's law (Siconos'
FrictionContactProblem, dimension 2).  ``--warm``: problem ``j`` starts from the reactions of
problem ``j - 1`` (a time-stepping warm start), else from zero.

Output ``OUT.npz``: ``r``, ``u`` (k, m), ``info`` (k,) (0 = converged), ``time`` (k,) [s] (the
``fc2d_driver`` call only), ``iters`` (k,), ``error`` (k,) (Siconos' own residual).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("inp")
    ap.add_argument("out")
    ap.add_argument("--tol", type=float, default=1e-14)
    ap.add_argument("--max-iter", type=int, default=200000)
    ap.add_argument("--warm", action="store_true")
    a = ap.parse_args()
    import siconos.numerics as sn

    data = np.load(a.inp)
    M, Q, mu = (np.ascontiguousarray(data[k], float) for k in ("M", "Q", "mu"))
    k, m = Q.shape
    R, U = np.zeros((k, m)), np.zeros((k, m))
    info, times, iters, err = (np.zeros(k, int), np.zeros(k), np.zeros(k, int), np.zeros(k))
    r_prev = np.zeros(m)
    for j in range(k):
        prob = sn.FrictionContactProblem(2, m // 2, M, Q[j].copy(), mu)
        so = sn.SolverOptions(sn.SICONOS_FRICTION_2D_NSGS)
        so.dparam[sn.SICONOS_DPARAM_TOL] = a.tol
        so.iparam[sn.SICONOS_IPARAM_MAX_ITER] = a.max_iter
        r = r_prev.copy() if a.warm else np.zeros(m)
        u = np.zeros(m)
        t0 = time.perf_counter()
        info[j] = sn.fc2d_driver(prob, r, u, so)
        times[j] = time.perf_counter() - t0
        iters[j] = so.iparam[sn.SICONOS_IPARAM_ITER_DONE]
        err[j] = so.dparam[sn.SICONOS_DPARAM_RESIDU]
        R[j], U[j] = r, u
        r_prev = r
    np.savez(a.out, r=R, u=U, info=info, time=times, iters=iters, error=err)


if __name__ == "__main__":
    main()
