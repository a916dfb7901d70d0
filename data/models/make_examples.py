"""Write the example model files of ``data/models/`` (run from the repository root).

    python data/models/make_examples.py

Every file is derived from a model the package also builds another way, so the tests can
check that reading it gives the same system:

* ``two_node_K.mtx``, ``two_node_K.csv``: the reduced stiffness ``K = [[A, B], [B^T, C]]`` of
  the built-in scene ``two_node_coupled`` (Matrix Market, CSV);
* ``two_node.mat``: its blocks and friction under MATLAB-style names ``Ktt``, ``Ktn``,
  ``Knn``, ``mu`` (chosen in ``data/scenes/two_node_mat.toml``); ``two_node.npz``: the same
  as arrays ``A``, ``B``, ``C``, ``friction``;
* ``two_node_record.csv``: a "measured" record of the same scene's welded reactions at
  ``lam = 1``, sampled unevenly (jittered times, seeded) over 1.5 periods of 0.02 s;
* ``square_full_K.mtx``, ``square_dofs.csv``, ``square_force.mtx``: the full (every DOF)
  plane-strain stiffness of a unit square (P1, 4 x 4 cells, E = 1, nu = 0.3) as an FE code
  would export it, the 1-based DOFs of its bottom (contact) and top (support) nodes, and
  body-force vectors (static ``square_force.mtx``, cyclic ``square_shake.csv``);
* ``unit_square.msh``: that mesh as a Gmsh 2.2 file with physical groups ``bottom``,
  ``top``, ``left``, ``right`` (lines) and ``body`` (triangles), written by meshio.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

A = np.array([[1.0, -0.3], [-0.3, 1.0]])
B = np.array([[-0.3, 0.9], [0.4, -0.1]])
C = np.array([[1.5, 0.2], [0.2, 1.5]])
FRICTION = 0.7
#: welded reactions of two_node_coupled: r_w(t) = r0 + lam (r_cos cos 2 pi t + r_sin sin 2 pi t)
Q0, P0 = np.array([0.1, -0.1]), np.array([1.0, 1.0])
Q_COS, Q_SIN, P_COS = np.array([0.5, 0.0]), np.array([0.0, 0.5]), np.array([0.0, 0.3])
PERIOD = 0.02  # s: the record's time unit is seconds
SQUARE = dict(width=1.0, height=1.0, nx=4, ny=4, E=1.0, nu=0.3, body_force=(0.01, -0.02),
              shake=(0.005, 0.0))


def reduced_stiffness() -> np.ndarray:
    return np.block([[A, B], [B.T, C]])


def record(rng) -> np.ndarray:
    """``(t, q_1, p_1, q_2, p_2)`` rows: 1.5 periods, 300 samples at jittered times."""
    n = 300
    t = np.sort(np.concatenate([[0.0], rng.uniform(0, 1.5 * PERIOD, n - 1)]))
    ph = 2 * np.pi * t / PERIOD
    q = Q0[None] + np.cos(ph)[:, None] * Q_COS + np.sin(ph)[:, None] * Q_SIN
    p = P0[None] + np.cos(ph)[:, None] * P_COS
    return np.column_stack([t, q[:, 0], p[:, 0], q[:, 1], p[:, 1]])


def square_mesh():
    from shakedown import fe

    return fe.rectangle(SQUARE["width"], SQUARE["height"], SQUARE["nx"], SQUARE["ny"],
                        element="P1").mesh


def square_full():
    """Full stiffness, bottom/top node DOFs (0-based), static and cyclic body-force vectors."""
    from skfem import Basis, ElementTriP1, ElementVector, LinearForm, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = square_mesh()
    basis = Basis(mesh, ElementVector(ElementTriP1()))
    K = asm(linear_elasticity(*lame_parameters(SQUARE["E"], SQUARE["nu"])), basis)
    bx, by = SQUARE["body_force"]
    f = asm(LinearForm(lambda v, w: bx * v[0] + by * v[1]), basis)
    sx, sy = SQUARE["shake"]
    f1 = asm(LinearForm(lambda v, w: sx * v[0] + sy * v[1]), basis)
    y = mesh.p[1]
    bottom = np.flatnonzero(np.isclose(y, 0.0))
    bottom = bottom[np.argsort(mesh.p[0, bottom])]
    top = np.flatnonzero(np.isclose(y, SQUARE["height"]))
    dofs = basis.nodal_dofs  # (2, n_nodes): x and y DOF of each node
    return K, f, f1, dofs[:, bottom], dofs[:, top]


def write_msh(path: Path) -> None:
    import meshio

    mesh = square_mesh()
    pts = np.column_stack([mesh.p.T, np.zeros(mesh.p.shape[1])])
    tri = mesh.t.T
    groups = {"bottom": 1, "top": 2, "left": 3, "right": 4, "body": 5}
    lines, phys = [], []
    for name in ("bottom", "top", "left", "right"):
        facets = mesh.boundaries[name]
        lines.append(mesh.facets[:, facets].T)
        phys.append(np.full(len(facets), groups[name]))
    lines, phys = np.concatenate(lines), np.concatenate(phys)
    m = meshio.Mesh(
        pts, [("line", lines), ("triangle", tri)],
        cell_data={"gmsh:physical": [phys, np.full(len(tri), groups["body"])],
                   "gmsh:geometrical": [phys, np.full(len(tri), groups["body"])]},
        field_data={name: np.array([tag, 1 if name != "body" else 2])
                    for name, tag in groups.items()},
    )
    meshio.write(path, m, file_format="gmsh22", binary=False)


def main() -> None:
    import scipy.io

    K = reduced_stiffness()
    scipy.io.mmwrite(HERE / "two_node_K.mtx", K, precision=17,
                     comment=" reduced stiffness of two_node_coupled, order v1 v2 w1 w2")
    np.savetxt(HERE / "two_node_K.csv", K, delimiter=",", fmt="%.17g")
    scipy.io.savemat(HERE / "two_node.mat", {"Ktt": A, "Ktn": B, "Knn": C, "mu": FRICTION})
    np.savez(HERE / "two_node.npz", A=A, B=B, C=C, friction=np.full(2, FRICTION))
    rows = record(np.random.default_rng(20261123))
    np.savetxt(HERE / "two_node_record.csv", rows, delimiter=",", fmt="%.17g",
               header="t,q_1,p_1,q_2,p_2", comments="")
    Kf, f, f1, bottom, top = square_full()
    scipy.io.mmwrite(HERE / "square_full_K.mtx", Kf, precision=17, symmetry="symmetric",
                     comment=" unit square, P1 4x4, plane strain E=1 nu=0.3, every DOF")
    scipy.io.mmwrite(HERE / "square_force.mtx", f[:, None], precision=17,
                     comment=" body force (0.01, -0.02) per unit volume")
    np.savetxt(HERE / "square_shake.csv", f1, fmt="%.17g")  # cyclic body force (0.005, 0)
    with open(HERE / "square_dofs.csv", "w") as out:
        out.write("# 1-based DOFs: bottom nodes (left to right): x (tangential), y (normal); "
                  "top nodes: x, y (held)\n")
        out.write("bottom_x," + ",".join(str(d + 1) for d in bottom[0]) + "\n")
        out.write("bottom_y," + ",".join(str(d + 1) for d in bottom[1]) + "\n")
        out.write("top," + ",".join(str(d + 1) for d in top.T.ravel()) + "\n")
    write_msh(HERE / "unit_square.msh")


if __name__ == "__main__":
    main()
