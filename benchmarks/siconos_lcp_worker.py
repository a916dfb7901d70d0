"""Solve a batch of LCPs with Siconos numerics (run under Debian's ``/usr/bin/python3``).

Siconos (Debian package ``python3-siconos``) is importable only by the system interpreter with
its own numpy, so :mod:`benchmarks.bench_evolution` writes the LCPs to an ``.npz`` and runs this
script in a subprocess.  It uses numpy and ``siconos.numerics`` only (not ``shakedown``).

Usage::

    /usr/bin/python3 benchmarks/siconos_lcp_worker.py IN.npz OUT.npz [--solvers lemke,pivot]

Input ``IN.npz``: ``M``, shape (m, m) (one matrix for every problem) or (k, m, m); ``Q``, shape
(k, m).  Problem ``i``: find ``z >= 0`` with ``w = M z + Q[i] >= 0`` and ``z . w = 0``.

Output ``OUT.npz``, for every solver name ``s``: ``s_z`` (k, m), ``s_info`` (k,) (0 = solved,
as returned by ``linearComplementarity_driver``), ``s_time`` (k,) [s] (the driver call only),
``s_build`` (k,) [s] (``sn.LCP(M, q)`` and ``sn.SolverOptions``), ``s_iter`` (k,) (pivots /
iterations reported by the solver), ``s_error`` (k,) (Siconos' own LCP error); plus
``solvers`` (names) and ``versions`` (numpy and Python versions).

Solvers (``--solvers``): ``lemke`` (``SICONOS_LCP_LEMKE``, lexicographic Lemke on a dense
tableau), ``pivot`` (``SICONOS_LCP_PIVOT``, the generic pivoting solver, its default pivoting
rule), ``pivot_lumod`` (``SICONOS_LCP_PIVOT_LUMOD``, Lemke with LU updates), ``newton_fb``
(``SICONOS_LCP_NEWTON_FB_FBLSA``, Fischer-Burmeister Newton with line search), ``enum``
(``SICONOS_LCP_ENUM``, all ``2^m`` complementary bases: small ``m`` only).
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

import numpy as np

SOLVERS = {
    "lemke": "SICONOS_LCP_LEMKE",
    "pivot": "SICONOS_LCP_PIVOT",
    "pivot_lumod": "SICONOS_LCP_PIVOT_LUMOD",
    "newton_fb": "SICONOS_LCP_NEWTON_FB_FBLSA",
    "enum": "SICONOS_LCP_ENUM",
}


def solve_batch(M, Q, solver, tol=1e-12):
    """Solve every problem of the batch with one Siconos solver; see the module docstring."""
    import siconos.numerics as sn

    sid = getattr(sn, SOLVERS[solver])
    k, m = Q.shape
    Z = np.zeros((k, m))
    info = np.zeros(k, int)
    t_solve = np.zeros(k)
    t_build = np.zeros(k)
    iters = np.zeros(k, int)
    err = np.zeros(k)
    for i in range(k):
        Mi = np.ascontiguousarray(M if M.ndim == 2 else M[i])
        t0 = time.perf_counter()
        problem = sn.LCP(Mi, np.ascontiguousarray(Q[i]))
        options = sn.SolverOptions(sid)
        options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        if solver == "enum":
            options.iparam[sn.SICONOS_LCP_IPARAM_ENUM_USE_DGELS] = 0
        z = np.zeros(m)
        w = np.zeros(m)
        t1 = time.perf_counter()
        info[i] = sn.linearComplementarity_driver(problem, z, w, options)
        t2 = time.perf_counter()
        t_build[i], t_solve[i] = t1 - t0, t2 - t1
        Z[i] = z
        iters[i] = options.iparam[sn.SICONOS_IPARAM_ITER_DONE]
        err[i] = options.dparam[sn.SICONOS_DPARAM_RESIDU]
    return dict(z=Z, info=info, time=t_solve, build=t_build, iter=iters, error=err)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("infile")
    ap.add_argument("outfile")
    ap.add_argument("--solvers", default="lemke")
    ap.add_argument("--tol", type=float, default=1e-12,
                    help="Siconos tolerance (its LCP error check; iterative solvers' target)")
    args = ap.parse_args(argv)
    data = np.load(args.infile)
    M, Q = np.asarray(data["M"], float), np.asarray(data["Q"], float)
    names = [s for s in args.solvers.split(",") if s]
    unknown = sorted(set(names) - set(SOLVERS))
    if unknown:
        raise SystemExit(f"unknown solver(s) {unknown}; choose from {sorted(SOLVERS)}")
    out = {"solvers": np.array(names),
           "versions": np.array([f"python {platform.python_version()}",
                                 f"numpy {np.__version__}"])}
    for name in names:
        res = solve_batch(M, Q, name, args.tol)
        out.update({f"{name}_{key}": val for key, val in res.items()})
        print(f"{name}: {int(np.sum(res['info'] != 0))} of {len(Q)} not solved, median "
              f"{np.median(res['time']) * 1e3:.4g} ms", file=sys.stderr, flush=True)
    np.savez(args.outfile, **out)


if __name__ == "__main__":
    main()
