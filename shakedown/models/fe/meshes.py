"""Meshes for the FE condensation: structured rectangles and trapezoids, polygons, files.

Every mesh is an :class:`FEMesh`: a scikit-fem mesh with *named boundaries* (sets of
boundary facets) and the element family used on it:

- ``"P1"``: linear triangles, ``"P2"``: quadratic triangles (straight-sided, nodes at the
  vertices and mid-sides), ``"Q1"``: bilinear quadrilaterals;
- in 3-D (:mod:`shakedown.fe.meshes3d`, or a file of tetrahedra or hexahedra): ``"P1"``/
  ``"P2"`` linear/quadratic tetrahedra (``P2``: nodes at the vertices and mid-edges),
  ``"Q1"`` trilinear hexahedra.

Structured meshes of a rectangle with ``nx x ny`` cells have ``nx + 1`` nodes along the
bottom edge for ``P1``/``Q1`` and ``2 nx + 1`` for ``P2``.  Triangle patterns per cell (corners
``a`` bottom-left, ``b`` bottom-right, ``c`` top-right, ``d`` top-left):

- ``"diagonal"``: diagonal ``a-c`` in every cell (``/``, scikit-fem's default);
- ``"anti-diagonal"``: diagonal ``b-d`` (``\\``);
- ``"union-jack"``: ``/`` where ``i + j`` is even, ``\\`` where odd (mirror-symmetric about
  the vertical centre line when ``nx`` is even);
- ``"crossed"``: both diagonals, an extra node at each cell centre (4 triangles per cell).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ...model.errors import InputError
from ...model.validation import check_count, check_positive, real_array

ELEMENTS = ("P1", "P2", "Q1")
PATTERNS = ("diagonal", "anti-diagonal", "union-jack", "crossed")


@dataclass(frozen=True, eq=False)
class FEMesh:
    """A scikit-fem mesh with named boundaries and the element family used on it.

    Attributes
    ----------
    mesh : skfem.Mesh
        ``MeshTri`` (``P1``, ``P2``) or ``MeshQuad`` (``Q1``) with ``mesh.boundaries``.
    element : {"P1", "P2", "Q1"}
    description : str
        How it was made (for reports), e.g. ``"rectangle 1x1, 10x10 cells, diagonal"``.
    """

    mesh: object
    element: str
    description: str = ""

    def __post_init__(self):
        if self.element not in ELEMENTS:
            raise InputError(f"element must be one of {ELEMENTS}; got {self.element!r}")
        kind = type(self.mesh).__name__
        if not kind.startswith(("MeshTri", "MeshQuad", "MeshTet", "MeshHex")):
            raise InputError(f"mesh must be a scikit-fem MeshTri, MeshQuad, MeshTet or MeshHex; "
                             f"got a {kind}")
        is_quad = kind.startswith(("MeshQuad", "MeshHex"))
        if is_quad != (self.element == "Q1"):
            raise InputError(
                f"element {self.element!r} does not fit a {kind}: use 'Q1' on quadrilateral "
                "and hexahedral meshes and 'P1'/'P2' on triangle and tetrahedral meshes"
            )

    @property
    def dim(self) -> int:
        """Space dimension (2 or 3)."""
        return int(self.mesh.p.shape[0])

    @property
    def boundary_names(self) -> tuple[str, ...]:
        """Names of the tagged boundaries."""
        return tuple(self.mesh.boundaries or {})

    def facets(self, name: str) -> np.ndarray:
        """Facet indices of the boundary ``name``; clear error for unknown or empty names."""
        b = self.mesh.boundaries or {}
        if name not in b:
            raise InputError(
                f"unknown boundary name {name!r}; this mesh has {sorted(b)}. Tag it with "
                "FEMesh.with_boundaries or pick one of those names"
            )
        f = np.asarray(b[name], dtype=np.int64)
        if f.size == 0:
            raise InputError(f"boundary {name!r} has no facets; check its definition")
        return f

    def with_boundaries(self, boundaries: dict) -> FEMesh:
        """A copy with more named boundaries.

        ``boundaries`` maps a name to a facet index array, to a callable of the facet midpoints
        ``x`` (shape (dim, n_facets)) returning booleans, or (2-D) to a segment
        ``((x0, y0), (x1, y1))`` (facets whose both end points lie on the segment), or (3-D)
        to a box ``((x0, y0, z0), (x1, y1, z1))`` (boundary facets whose vertices all lie in
        the closed axis-aligned box; a flat box selects a patch of a plane face).
        """
        tags = {}
        for name, spec in boundaries.items():
            if callable(spec) or (isinstance(spec, np.ndarray) and spec.dtype.kind in "iu"):
                tags[name] = spec
            elif self.dim == 3:
                tags[name] = _box_facets(self.mesh, spec, name)
            else:
                tags[name] = _segment_facets(self.mesh, spec, name)
        return replace(self, mesh=self.mesh.with_boundaries(tags))

    def with_element(self, element: str) -> FEMesh:
        """The same mesh with another element family (``P1`` <-> ``P2``)."""
        return replace(self, element=element)

    @property
    def diameter(self) -> float:
        p = self.mesh.p
        return float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))

    def __repr__(self) -> str:
        return (
            f"FEMesh({self.element}, {self.mesh.t.shape[1]} cells, {self.mesh.p.shape[1]} "
            f"vertices, boundaries {list(self.boundary_names)}; {self.description})"
        )


def _segment_facets(mesh, segment, name) -> np.ndarray:
    try:
        (x0, y0), (x1, y1) = np.asarray(segment, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"boundary {name!r} must be facet indices, a callable or a segment "
            f"((x0, y0), (x1, y1)); got {segment!r}"
        ) from exc
    a, b = np.array([x0, y0]), np.array([x1, y1])
    L = np.hypot(*(b - a))
    if L == 0:
        raise InputError(f"boundary segment {name!r} has zero length")
    tol = 1e-8 * max(L, float(np.ptp(mesh.p, axis=1).max()))
    bf = mesh.boundary_facets()
    ok = np.ones(bf.size, dtype=bool)
    for k in range(mesh.facets.shape[0]):
        P = mesh.p[:, mesh.facets[k, bf]]
        d = P - a[:, None]
        s = (d.T @ (b - a)) / L**2
        dist = np.abs(d[0] * (b - a)[1] - d[1] * (b - a)[0]) / L
        ok &= (dist <= tol) & (s >= -1e-9) & (s <= 1 + 1e-9)
    return bf[ok]


def _box_facets(mesh, box, name) -> np.ndarray:
    try:
        lo, hi = np.asarray(box, dtype=float)
        if lo.shape != (3,) or not np.all(np.isfinite([lo, hi])):
            raise ValueError
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"boundary {name!r} must be facet indices, a callable of the facet midpoints or a "
            f"box ((x0, y0, z0), (x1, y1, z1)); got {box!r}") from exc
    lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    tol = 1e-8 * float(np.ptp(mesh.p, axis=1).max())
    bf = mesh.boundary_facets()
    P = mesh.p[:, mesh.facets[:, bf]]  # (3, n_vertices_per_facet, n_boundary_facets)
    ok = np.all((P >= lo[:, None, None] - tol) & (P <= hi[:, None, None] + tol), axis=(0, 1))
    return bf[ok]


def _check_divisions(nx, ny):
    for name, n in (("nx", nx), ("ny", ny)):
        check_count(f"{name} (number of cells)", n, 1)
    return int(nx), int(ny)


def _structured(nx: int, ny: int, element: str, pattern: str):
    """Unit-square structured mesh (skfem) with boundaries bottom/top/left/right."""
    from skfem import MeshQuad, MeshTri

    if element not in ELEMENTS:
        raise InputError(f"element must be one of {ELEMENTS}; got {element!r}")
    if pattern not in PATTERNS:
        raise InputError(f"pattern must be one of {PATTERNS}; got {pattern!r}")
    X, Y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
    p = np.vstack([X.ravel(), Y.ravel()])
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    if element == "Q1":
        mesh = MeshQuad(p, np.vstack([a, b, c, d]))
    elif pattern == "crossed":
        centres = 0.25 * (p[:, a] + p[:, b] + p[:, c] + p[:, d])
        e = p.shape[1] + np.arange(a.size)
        p = np.hstack([p, centres])
        t = np.hstack([np.vstack(v) for v in ((a, b, e), (b, c, e), (c, d, e), (d, a, e))])
        mesh = MeshTri(p, t)
    else:
        I, J = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        if pattern == "diagonal":
            slash = np.ones(a.size, dtype=bool)
        elif pattern == "anti-diagonal":
            slash = np.zeros(a.size, dtype=bool)
        else:
            slash = ((I + J) % 2 == 0).ravel()
        t1 = np.where(slash, np.vstack([a, b, c]), np.vstack([a, b, d]))
        t2 = np.where(slash, np.vstack([a, c, d]), np.vstack([b, c, d]))
        mesh = MeshTri(p, np.hstack([t1, t2]))
    tol = 1e-9
    return mesh.with_boundaries({
        "bottom": lambda x: np.abs(x[1]) < tol,
        "top": lambda x: np.abs(x[1] - 1) < tol,
        "left": lambda x: np.abs(x[0]) < tol,
        "right": lambda x: np.abs(x[0] - 1) < tol,
    })


def rectangle(
    width: float,
    height: float,
    nx: int,
    ny: int,
    element: str = "P1",
    pattern: str = "diagonal",
    origin=(0.0, 0.0),
) -> FEMesh:
    """Structured mesh of ``[x0, x0 + width] x [y0, y0 + height]``.

    Parameters
    ----------
    width, height : float
        Side lengths [length].
    nx, ny : int
        Number of cells along x and y (``nx + 1`` vertices per horizontal edge).
    element : {"P1", "P2", "Q1"}
    pattern : {"diagonal", "anti-diagonal", "union-jack", "crossed"}
        Triangle pattern (ignored for ``Q1``), see the module docstring.
    origin : (float, float)
        Bottom-left corner.

    Returns
    -------
    FEMesh
        With boundaries ``"bottom"``, ``"top"``, ``"left"``, ``"right"``.

    Examples
    --------
    >>> from shakedown import fe
    >>> m = fe.rectangle(1.0, 1.0, 10, 10)       # 11 nodes per edge
    >>> m.mesh.p.shape
    (2, 121)
    """
    width = check_positive("width", width, unit=" [length]")
    height = check_positive("height", height, unit=" [length]")
    nx, ny = _check_divisions(nx, ny)
    m = _structured(nx, ny, element, pattern)
    o = real_array("origin", origin)
    if o.shape != (2,) or not np.all(np.isfinite(o)):
        raise InputError(f"origin must be two finite numbers (x0, y0) [length]; got {origin!r}")
    p = m.p * np.array([[width], [height]]) + o.reshape(2, 1)
    return FEMesh(replace(m, doflocs=p), element,
                  f"rectangle {width:g}x{height:g}, {nx}x{ny} cells, {pattern}")


def trapezoid(
    bottom_width: float,
    top_width: float,
    height: float,
    nx: int,
    ny: int,
    top_offset: float | None = None,
    element: str = "P1",
    pattern: str = "diagonal",
) -> FEMesh:
    """Structured mesh of a trapezoid with horizontal bottom and top sides.

    The bottom side is ``[0, bottom_width] x {0}``; the top side
    ``[top_offset, top_offset + top_width] x {height}`` (default: centred).  The unit
    square's structured mesh is mapped row by row.  Boundaries: ``"bottom"``, ``"top"``,
    ``"left"``, ``"right"``.
    """
    bw = check_positive("bottom_width", bottom_width, unit=" [length]")
    tw = check_positive("top_width", top_width, unit=" [length]")
    h = check_positive("height", height, unit=" [length]")
    nx, ny = _check_divisions(nx, ny)
    off = 0.5 * (bw - tw) if top_offset is None else float(top_offset)
    m = _structured(nx, ny, element, pattern)
    X, Y = m.p
    p = np.vstack([off * Y + X * (bw + (tw - bw) * Y), h * Y])
    return FEMesh(replace(m, doflocs=p), element,
                  f"trapezoid bottom {bw:g} top {tw:g} height {h:g}, {nx}x{ny} cells, {pattern}")


def from_file(path, element: str | None = None, boundaries: dict | None = None) -> FEMesh:
    """Read a mesh file through meshio (gmsh, vtk, xdmf, ...).

    Linear triangles or quadrilaterals (2-D), linear tetrahedra or hexahedra (3-D) are read;
    physical groups of the facet elements (lines in 2-D; triangles or quadrilaterals in 3-D)
    become named boundaries (scikit-fem's reader), named by the group's name.  A 2-D mesh
    stored with a zero z coordinate stays 2-D.  ``boundaries`` adds more names (see
    :meth:`FEMesh.with_boundaries`: segments in 2-D, boxes in 3-D).  ``element`` defaults to
    ``"P1"`` for triangles and tetrahedra and ``"Q1"`` for quadrilaterals and hexahedra.
    """
    from pathlib import Path

    from skfem import Mesh

    from ...model.limits import check_file_size

    if not Path(path).is_file():
        raise InputError(f"mesh file {str(path)!r} does not exist")
    check_file_size(path, "mesh file")
    import logging

    quiet = logging.getLogger("skfem.io.meshio")  # hexahedral facets are oriented below
    level = quiet.level
    quiet.setLevel(logging.ERROR)
    try:
        mesh = Mesh.load(str(path))
    except (Exception, SystemExit) as exc:  # meshio raises many types, and may call sys.exit
        # (RecursionError and MemoryError are Exceptions); the reader's message may quote the
        # file: name only the error's type
        raise InputError(f"could not read mesh file {str(path)!r} ({type(exc).__name__}); "
                         "give a mesh format meshio reads (gmsh .msh, .vtk, .xdmf)") from None
    finally:
        quiet.setLevel(level)
    name = type(mesh).__name__
    if name not in ("MeshTri1", "MeshQuad1", "MeshTet1", "MeshHex1"):
        raise InputError(
            f"mesh file {str(path)!r} holds a {name}; only linear triangles, quadrilaterals, "
            "tetrahedra or hexahedra are supported (store the mesh with linear elements and "
            "choose element='P2' for quadratic fields)"
        )
    if name in ("MeshTri1", "MeshQuad1") and mesh.p.shape[0] != 2:
        mesh = replace(mesh, doflocs=mesh.p[:2])
    element = element or ("Q1" if name in ("MeshQuad1", "MeshHex1") else "P1")
    fm = FEMesh(mesh, element, f"file {path}")
    if mesh.boundaries is None:
        fm = replace(fm, mesh=mesh.with_boundaries({}))
    return fm.with_boundaries(boundaries) if boundaries else fm
