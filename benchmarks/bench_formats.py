"""Condensing an exported full stiffness (condense_stiffness) against shakedown.fe's own path.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_formats.py --sizes 21 41 81 --repeat 3

For a unit square (P1, union-jack, plane strain, top held, bottom in contact, ``n`` nodes per
edge) the full stiffness is assembled with scikit-fem and written to Matrix Market, as a user
would get it from an FE code.  Timed, side by side in the same process (medians of
``--repeat``):

* ``read``: ``read_matrix(..., sparse=True)`` of the ``.mtx`` file;
* ``condense``: :func:`shakedown.models.formats.condense_stiffness` with the factorization it
  uses when scikit-fem is installed: shakedown.fe's boundary-layer-ordered LU, whose Schur
  correction needs only the factor's trailing block;
* ``superlu``: the same with its fallback (no scikit-fem): a plain SuperLU of ``K_ii`` and
  solves for the ``2n`` contact columns (the first version of this reader);
* ``fe``: ``FEModel.condense()`` of the same body (assembly + boundary-layer ordered LU +
  Schur complement from the factor's trailing block): the package's own path, the baseline.

The two reduced stiffnesses are compared (max difference relative to max |K|).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _median_time(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def run(n: int, repeat: int, folder: Path) -> dict:
    import scipy.io
    from skfem import Basis, ElementTriP1, ElementVector, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    from shakedown import fe
    from shakedown.models.formats import condense_stiffness, read_matrix

    mesh = fe.rectangle(1.0, 1.0, n - 1, n - 1, element="P1")
    basis = Basis(mesh.mesh, ElementVector(ElementTriP1()))
    K = asm(linear_elasticity(*lame_parameters(1.0, 0.3)), basis)
    p = mesh.mesh.p
    bottom = np.flatnonzero(np.isclose(p[1], 0.0))
    bottom = bottom[np.argsort(p[0, bottom])]
    top = np.flatnonzero(np.isclose(p[1], 1.0))
    dofs = basis.nodal_dofs
    path = folder / f"K{n}.mtx"
    scipy.io.mmwrite(path, K, precision=17, symmetry="symmetric")
    t_read, Kr = _median_time(lambda: read_matrix(path, sparse=True), repeat)
    from shakedown.models.formats import stiffness

    def condense():
        return condense_stiffness(Kr, dofs[0, bottom], dofs[1, bottom],
                                  fixed_dofs=dofs[:, top].ravel(), normal_sign=-1)

    t_cond, cs = _median_time(condense, repeat)
    shared = stiffness._factorize
    stiffness._factorize = lambda Kii, Kci, n_i: stiffness._SuperLU(Kii)
    try:
        t_plain, cs_plain = _median_time(condense, repeat)
    finally:
        stiffness._factorize = shared
    model = fe.FEModel(mesh, fe.isotropic(1.0, 0.3), dirichlet=["top"], contact=["bottom"])
    t_fe, cm = _median_time(lambda: model.condense(), repeat)
    diff = float(np.abs(cs.K - cm.K).max() / np.abs(cm.K).max())
    diff = max(diff, float(np.abs(cs_plain.K - cm.K).max() / np.abs(cm.K).max()))
    return dict(n=n, dofs=K.shape[0], contact_nodes=len(bottom), read=t_read, condense=t_cond,
                plain=t_plain, fe=t_fe, diff=diff, mtx_mb=path.stat().st_size / 2**20)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[21, 41, 81])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print("| nodes/edge | DOFs | contact nodes | .mtx (MB) | read (s) | condense_stiffness (s) "
          "| plain SuperLU (s) | FEModel.condense (s) | plain / condense | fe / condense "
          "| max rel. diff of K |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            r = run(n, args.repeat, Path(tmp))
            print(f"| {r['n']} | {r['dofs']} | {r['contact_nodes']} | {r['mtx_mb']:.2f} | "
                  f"{r['read']:.3f} | {r['condense']:.3f} | {r['plain']:.3f} | {r['fe']:.3f} | "
                  f"{r['plain'] / r['condense']:.2f} | {r['fe'] / r['condense']:.2f} | "
                  f"{r['diff']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
