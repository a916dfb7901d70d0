"""Cross-check against an independent FE code: GetFEM (Debian python3-getfem, runs only under
the system interpreter /usr/bin/python3, so it is called in a subprocess).  Marked ``peers``:
run by ``python3 -m pytest -m peers`` (recorded in benchmarks/RESULTS_peers.md), skipped with that
reason in the default run, and skipped with the install command when GetFEM is missing."""

import json
import shutil
import subprocess

import numpy as np
import pytest

from shakedown import fe

GETFEM_SCRIPT = r'''
import json, sys
import getfem as gf
import numpy as np
d = json.load(sys.stdin)
m = gf.Mesh("ptND", np.array(d["p"], float), np.array(d["t"], int))
mfu = gf.MeshFem(m, 2)
mfu.set_fem(gf.Fem("FEM_PK(2,1)"))
mim = gf.MeshIm(m, gf.Integ("IM_TRIANGLE(2)"))
E, nu = d["E"], d["nu"]
md = gf.Model("real")
md.add_fem_variable("u", mfu)
md.add_initialized_data("lambda", [E * nu / ((1 + nu) * (1 - 2 * nu))])
md.add_initialized_data("mu", [E / (2 * (1 + nu))])
md.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
md.assembly("build_matrix")
K = md.tangent_matrix().full()
X = mfu.basic_dof_nodes()
n = X.shape[1]
comp = np.arange(n) % 2  # qdim 2: x, y dofs interleaved at each node
bottom = np.flatnonzero(np.abs(X[1]) < 1e-12)
top = np.flatnonzero(np.abs(X[1] - 1) < 1e-12)
bx = bottom[comp[bottom] == 0][np.argsort(X[0, bottom[comp[bottom] == 0]])]
by = bottom[comp[bottom] == 1][np.argsort(X[0, bottom[comp[bottom] == 1]])]
c = np.concatenate([bx, by])
i = np.setdiff1d(np.arange(n), np.concatenate([c, top]))
S = K[np.ix_(c, c)] - K[np.ix_(c, i)] @ np.linalg.solve(K[np.ix_(i, i)], K[np.ix_(i, c)])
print(json.dumps(S.tolist()))
'''


def getfem_condensed_square(mesh, E, nu):
    """GetFEM's condensed K of a unit square (top held, bottom contact) on the same mesh."""
    m = mesh.mesh
    res = subprocess.run(["/usr/bin/python3", "-c", GETFEM_SCRIPT], capture_output=True,
                         text=True, timeout=120,
                         input=json.dumps({"p": m.p.tolist(), "t": m.t.tolist(), "E": E,
                                           "nu": nu}))
    if res.returncode != 0:
        raise RuntimeError(res.stderr[-2000:])
    return np.array(json.loads(res.stdout.strip().splitlines()[-1]))


def _has_getfem():
    if shutil.which("/usr/bin/python3") is None:
        return False
    r = subprocess.run(["/usr/bin/python3", "-c", "import getfem"], capture_output=True)
    return r.returncode == 0


@pytest.mark.peers
def test_condensed_square_matches_getfem():
    if not _has_getfem():
        pytest.skip("GetFEM is unavailable under /usr/bin/python3: apt-get install python3-getfem")
    # seed 000 s.7.1 square: on the bottom t = +x, -n = +y, so (v, w) = (u_x, u_y) and our
    # K must equal GetFEM's plain Schur complement in (u_x of bottom nodes, u_y of them)
    mesh = fe.rectangle(1.0, 1.0, 10, 10, pattern="union-jack")
    cm = fe.FEModel(mesh, fe.isotropic(1.0, 0.3), dirichlet=["top"],
                    contact=["bottom"]).condense()
    Kg = getfem_condensed_square(mesh, 1.0, 0.3)
    # two assemblies of the same P1 matrices: round-off only
    np.testing.assert_allclose(cm.K, Kg, atol=1e-12 * np.abs(Kg).max())
