"""Structured 3-D meshes for the FE condensation: boxes and extruded 2-D meshes.

Each returns an :class:`~shakedown.fe.meshes.FEMesh` whose boundaries are named after the
faces of the box: ``"left"``/``"right"`` (``x`` min/max), ``"front"``/``"back"`` (``y``
min/max) and ``"bottom"``/``"top"`` (``z`` min/max).  Elements: ``"Q1"`` trilinear hexahedra,
``"P1"``/``"P2"`` linear/quadratic tetrahedra (six per hexahedral cell, scikit-fem's split).
Meshes from Gmsh are read by :func:`~shakedown.fe.meshes.from_file`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...model.errors import InputError
from ...model.validation import check_count, check_positive, real_array
from .meshes import FEMesh

FACES = ("left", "right", "front", "back", "bottom", "top")


def _faces(mesh, lo, hi):
    tol = 1e-9 * float(np.max(np.asarray(hi) - np.asarray(lo)))
    tags = {}
    for axis, (a, b) in enumerate((("left", "right"), ("front", "back"), ("bottom", "top"))):
        tags[a] = lambda x, k=axis: np.abs(x[k] - lo[k]) < tol
        tags[b] = lambda x, k=axis: np.abs(x[k] - hi[k]) < tol
    return mesh.with_boundaries(tags)


def _origin(origin) -> np.ndarray:
    o = real_array("origin", origin)
    if o.shape != (3,) or not np.all(np.isfinite(o)):
        raise InputError(f"origin must be three finite numbers (x0, y0, z0) [length]; got "
                         f"{origin!r}")
    return o


def box(lx: float, ly: float, lz: float, nx: int, ny: int, nz: int, element: str = "Q1",
        origin=(0.0, 0.0, 0.0)) -> FEMesh:
    """Structured mesh of ``[x0, x0 + lx] x [y0, y0 + ly] x [z0, z0 + lz]``.

    Parameters
    ----------
    lx, ly, lz : float
        Side lengths [length].
    nx, ny, nz : int
        Number of cells along x, y, z (``nx + 1`` vertices along an x edge).
    element : {"Q1", "P1", "P2"}
        Trilinear hexahedra, or tetrahedra (linear / quadratic) from each cell split in six.
    origin : (float, float, float)
        The corner with the smallest coordinates.

    Returns
    -------
    FEMesh
        With boundaries ``"left"``, ``"right"``, ``"front"``, ``"back"``, ``"bottom"``,
        ``"top"``.

    Examples
    --------
    >>> from shakedown import fe
    >>> m = fe.box(1.0, 1.0, 0.5, 4, 4, 2)
    >>> m.dim, m.mesh.p.shape
    (3, (3, 75))
    """
    from skfem import MeshHex, MeshTet

    L = [check_positive(n, v, unit=" [length]") for n, v in (("lx", lx), ("ly", ly), ("lz", lz))]
    n = [int(check_count(f"{k} (number of cells)", v, 1)) for k, v in
         (("nx", nx), ("ny", ny), ("nz", nz))]
    if element not in ("Q1", "P1", "P2"):
        raise InputError(f"element must be 'Q1' (hexahedra), 'P1' or 'P2' (tetrahedra); got "
                         f"{element!r}")
    o = _origin(origin)
    axes = [o[k] + np.linspace(0.0, L[k], n[k] + 1) for k in range(3)]
    cls = MeshHex if element == "Q1" else MeshTet
    mesh = _faces(cls.init_tensor(*axes), o, o + np.array(L))
    return FEMesh(mesh, element, f"box {L[0]:g}x{L[1]:g}x{L[2]:g}, {n[0]}x{n[1]}x{n[2]} cells, "
                                 f"{element}")


def extrude(mesh2d: FEMesh, depth: float, n_layers: int) -> FEMesh:
    """Hexahedral mesh of a quadrilateral 2-D mesh extruded along ``z`` over ``[0, depth]``.

    The 2-D ``(x, y)`` stay the 3-D ``(x, y)``; every named boundary of the 2-D mesh becomes
    the face swept by its edges (same name), and ``"front"``/``"back"`` name the faces
    ``z = 0`` and ``z = depth`` (so the 2-D ``"bottom"``/``"top"`` keep their names).

    Parameters
    ----------
    mesh2d : FEMesh
        A ``Q1`` (quadrilateral) 2-D mesh.
    depth : float
        Extrusion length [length].
    n_layers : int
        Number of hexahedral layers along ``z``.

    Returns
    -------
    FEMesh
        ``Q1`` hexahedra.
    """
    from skfem import MeshHex

    if not isinstance(mesh2d, FEMesh) or mesh2d.dim != 2 or mesh2d.element != "Q1":
        raise InputError(f"mesh2d must be a 2-D Q1 (quadrilateral) FEMesh, e.g. "
                         f"fe.rectangle(..., element='Q1'); got {mesh2d!r}")
    d = check_positive("depth", depth, unit=" [length]")
    nl = int(check_count("n_layers", n_layers, 1))
    m = mesh2d.mesh
    nv = m.p.shape[1]
    z = np.linspace(0.0, d, nl + 1)
    p = np.vstack([np.tile(m.p, nl + 1), np.repeat(z, nv)])
    quads = m.t.copy()  # counter-clockwise a, b, c, d (clockwise ones are turned)
    P = m.p[:, quads]
    area2 = ((P[0, 1] - P[0, 0]) * (P[1, 3] - P[1, 0]) - (P[1, 1] - P[1, 0]) * (P[0, 3] - P[0, 0]))
    quads[[1, 3]] = np.where(area2 < 0, quads[[3, 1]], quads[[1, 3]])
    cells = []
    for k in range(nl):
        lo, hi = quads + k * nv, quads + (k + 1) * nv
        cells.append(np.vstack([lo, hi]))
    t = np.hstack(cells)
    # scikit-fem's hexahedron vertex order (MeshHex docs): 0 (0,0,0), 1 (0,0,1), 2 (0,1,0),
    # 3 (1,0,0), 4 (0,1,1), 5 (1,0,1), 6 (1,1,0), 7 (1,1,1) for (x, y, z) of the unit cube
    a, b, c, dd, a2, b2, c2, d2 = t
    t = np.vstack([a, a2, dd, b, d2, b2, c, c2])
    hexes = MeshHex(p, t)
    names = {}
    for name in mesh2d.boundary_names:
        f = m.facets[:, mesh2d.facets(name)]  # (2, n_edges) vertex pairs in 2-D
        keys = {tuple(sorted((int(i + k * nv), int(j + k * nv), int(i + (k + 1) * nv),
                              int(j + (k + 1) * nv)))) for i, j in f.T for k in range(nl)}
        all_f = np.sort(hexes.facets, axis=0)
        names[name] = np.flatnonzero([tuple(col) in keys for col in all_f.T])
    tol = 1e-9 * d
    names["front"] = lambda x: np.abs(x[2]) < tol
    names["back"] = lambda x: np.abs(x[2] - d) < tol
    return FEMesh(replace(hexes.with_boundaries(names)), "Q1",
                  f"extrusion of ({mesh2d.description}) over depth {d:g}, {nl} layers")
