"""Meshes of simple polygons: ear-clipping triangulation of the outline and the
:func:`polygon` builder (named boundaries per polygon side)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...model.errors import InputError
from .meshes import FEMesh, _segment_facets


def _ear_clip(P: np.ndarray) -> np.ndarray:
    """Triangulate a simple polygon (vertices counter-clockwise, shape (n, 2))."""
    idx = list(range(len(P)))
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    guard = 0
    while len(idx) > 3:
        guard += 1
        if guard > 10 * len(P) ** 2:
            raise InputError("polygon could not be triangulated: is it simple (no crossings)?")
        n = len(idx)
        best = None
        for k in range(n):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % n]
            a, b, c = P[i0], P[i1], P[i2]
            if cross(a, b, c) <= 0:
                continue
            inside = False
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                q = P[j]
                if cross(a, b, q) >= 0 and cross(b, c, q) >= 0 and cross(c, a, q) >= 0:
                    inside = True
                    break
            if not inside:
                # prefer the ear with the best smallest angle (better triangles)
                e = np.array([b - a, c - b, a - c])
                L = np.hypot(e[:, 0], e[:, 1])
                q = cross(a, b, c) / (L.max() ** 2)
                if best is None or q > best[0]:
                    best = (q, k)
        if best is None:
            raise InputError("polygon could not be triangulated: is it simple (no crossings)?")
        k = best[1]
        tris.append((idx[k - 1], idx[k], idx[(k + 1) % n]))
        idx.pop(k)
    tris.append(tuple(idx))
    return np.array(tris).T


def _check_simple(P: np.ndarray) -> None:
    """Raise if two non-adjacent sides of the polygon intersect."""
    n = len(P)

    def orient(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    for i in range(n):
        a, b = P[i], P[(i + 1) % n]
        for j in range(i + 1, n):
            if j == i or (j + 1) % n == i or (i + 1) % n == j:
                continue
            c, d = P[j], P[(j + 1) % n]
            if (orient(a, b, c) * orient(a, b, d) <= 0) and (orient(c, d, a) * orient(c, d, b) <= 0):
                raise InputError(
                    f"polygon is not simple: sides {i} and {j} intersect; give the vertices "
                    "in order around the boundary"
                )


def polygon(
    vertices,
    refine: int = 3,
    element: str = "P1",
    side_names: list[str] | None = None,
) -> FEMesh:
    """Triangle mesh of a simple polygon (ear clipping, then uniform refinement).

    Parameters
    ----------
    vertices : array_like, shape (n, 2)
        Polygon corners in order (either orientation); no self-intersections.
    refine : int
        Number of uniform refinements (each splits a triangle into 4).
    element : {"P1", "P2"}
    side_names : list of str, optional
        Names of the sides ``vertices[k] -> vertices[k + 1]``; default ``"side0"``, ...

    Returns
    -------
    FEMesh
        With one named boundary per side.

    Notes
    -----
    For graded or high-quality meshes of complex shapes write the mesh with an external
    mesher and read it with :func:`from_file`.
    """
    from skfem import MeshTri

    P = np.asarray(vertices, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 3 or not np.all(np.isfinite(P)):
        raise InputError(f"vertices must be a finite (n >= 3, 2) array; got shape {P.shape}")
    if element not in ("P1", "P2"):
        raise InputError(f"polygon meshes are triangular: element 'P1' or 'P2'; got {element!r}")
    n = len(P)
    names = side_names or [f"side{k}" for k in range(n)]
    if len(names) != n:
        raise InputError(f"side_names must have {n} entries (one per side); got {len(names)}")
    _check_simple(P)
    area2 = np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    if area2 == 0:
        raise InputError("polygon has zero area")
    order = np.arange(n) if area2 > 0 else np.arange(n)[::-1]
    t = order[_ear_clip(P[order])]
    mesh = MeshTri(P.T.copy(), t).refined(int(refine))
    fm = FEMesh(mesh, element, f"polygon with {n} sides, refined {refine} times")
    tags = {}
    for k, name in enumerate(names):
        seg = (P[k], P[(k + 1) % n])
        tags.setdefault(name, []).append(_segment_facets(mesh, seg, name))
    return replace(fm, mesh=mesh.with_boundaries(
        {k: np.unique(np.concatenate(v)) for k, v in tags.items()}))
