"""Bodies, loads and their assembly with scikit-fem (stiffness, consistent mass, load vectors).

A *node* is a location carrying ``dim`` displacement DOFs ``(u_x, u_y[, u_z])``: the mesh
vertices, then (quadratic elements) one node per edge (3-D) or facet (2-D) at its mid-point.
Loads and prescribed displacements have ``dim`` components (a pair in 2-D, a triple in 3-D).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ...model.errors import InputError
from .assembly3d import _facet_normals_3d, _voigt_stiffness
from .loads import (  # noqa: F401 - re-exported: the loads' historical home
    LOAD_TYPES,
    BodyForce,
    Displacement,
    Pressure,
    Traction,
    load_key,
    normalize_loads,
)
from .materials import Material
from .meshes import FEMesh

# --------------------------------------------------------------------------- bodies


def _parse_dirichlet(dirichlet, dim: int = 2) -> dict[str, tuple[int, ...]]:
    """``["top"]`` or ``{"top": "xy", "left": "x"}`` -> name -> components (all by default)."""
    if dirichlet is None:
        return {}
    if isinstance(dirichlet, str):
        dirichlet = [dirichlet]
    axes = "xyz"[:dim]
    if isinstance(dirichlet, dict):
        items = dirichlet.items()
    else:
        items = [(name, axes) for name in dirichlet]
    out = {}
    for name, comp in items:
        if not (isinstance(comp, str) and comp and set(comp) <= set(axes)
                and len(set(comp)) == len(comp)):
            allowed = "'x', 'y' or 'xy'" if dim == 2 else "'x', 'y', 'z' or a combination " \
                "such as 'xz' or 'xyz'"
            raise InputError(
                f"dirichlet[{name!r}] must be {allowed} (held components); got {comp!r}"
            )
        out[str(name)] = tuple(i for i, c in enumerate(axes) if c in comp)
    return out


@dataclass(frozen=True, eq=False)
class Body:
    """One elastic body: a mesh, a material, held boundaries and loads.

    Parameters
    ----------
    mesh : FEMesh
    material : Material
    dirichlet : list of str or dict, optional
        Held boundaries: ``["top"]`` (every component) or ``{"left": "x"}`` (rollers; in 3-D
        also e.g. ``"z"`` or ``"xz"``).  Prescribed non-zero values come from
        :class:`Displacement` loads.
    loads : dict name -> load(s), optional
        Load cases (see :func:`normalize_loads`), with vectors of ``mesh.dim`` components.
    thickness : float
        Out-of-plane thickness (forces are per this thickness; 1 = per unit thickness); 2-D
        only (must stay 1 on a 3-D mesh).
    """

    mesh: FEMesh
    material: Material
    dirichlet: object = None
    loads: object = None
    thickness: float = 1.0
    _held: dict = field(init=False, repr=False, default=None)

    def __post_init__(self):
        if not isinstance(self.mesh, FEMesh):
            raise InputError(f"mesh must be an FEMesh (fe.rectangle, ...); got {self.mesh!r}")
        if not isinstance(self.material, Material):
            raise InputError(
                f"material must be a Material (fe.isotropic, ...); got {self.material!r}"
            )
        if not (np.isfinite(self.thickness) and self.thickness > 0):
            raise InputError(f"thickness must be > 0; got {self.thickness!r}")
        dim = self.mesh.dim
        if self.material.dim != dim:
            raise InputError(
                f"material is {self.material.dim}-D (plane = {self.material.plane!r}) but the mesh "
                f"is {dim}-D: use fe.isotropic(..., plane='3d') on a 3-D mesh and plane='strain' "
                "or 'stress' on a 2-D mesh")
        if dim == 3 and self.thickness != 1.0:
            raise InputError(f"thickness = {self.thickness!r} applies to 2-D bodies only; a 3-D "
                             "body has its own depth: leave thickness = 1")
        held = _parse_dirichlet(self.dirichlet, dim)
        for name in held:
            self.mesh.facets(name)  # raises on unknown / empty names
        object.__setattr__(self, "_held", held)
        object.__setattr__(self, "loads", normalize_loads(self.loads))
        for case, items in self.loads.items():
            for it in items:
                b = getattr(it, "boundary", None)
                if b is not None:
                    self.mesh.facets(b)
                v = getattr(it, "value", None)
                if isinstance(v, tuple) and len(v) != dim:
                    raise InputError(
                        f"load case {case!r}: {type(it).__name__}.value = {v} has {len(v)} "
                        f"components but the mesh is {dim}-D; give {dim} components")
                if isinstance(it, Displacement) and b not in held:
                    raise InputError(
                        f"load case {case!r}: Displacement on {b!r}, which is not a Dirichlet "
                        f"boundary (dirichlet = {sorted(held)}); add it to dirichlet"
                    )

    # ------------------------------------------------------------------ discretisation
    @property
    def dim(self) -> int:
        """Space dimension of the body (2 or 3)."""
        return self.mesh.dim

    @cached_property
    def basis(self):
        import skfem

        names = ({"P1": "ElementTriP1", "P2": "ElementTriP2", "Q1": "ElementQuad1"}
                 if self.dim == 2 else
                 {"P1": "ElementTetP1", "P2": "ElementTetP2", "Q1": "ElementHex1"})
        e = getattr(skfem, names[self.mesh.element])()
        if self.dim == 3 and self.mesh.element == "Q1":
            # 2 x 2 x 2 Gauss points (exact stiffness and mass of parallelepipeds; the usual full
            # integration of trilinear hexahedra) instead of scikit-fem's default 4 x 4 x 4
            return skfem.Basis(self.mesh.mesh, skfem.ElementVector(e), intorder=3)
        return skfem.Basis(self.mesh.mesh, skfem.ElementVector(e))

    @cached_property
    def node_dofs(self) -> np.ndarray:
        """DOF numbers ``(u_x, u_y[, u_z])`` of every node, shape (n_nodes, dim)."""
        b = self.basis
        parts = [b.nodal_dofs.T]
        for extra in (b.edge_dofs, b.facet_dofs):
            if extra.size:
                parts.append(extra.T)
        nd = np.vstack(parts).astype(np.int64)
        if nd.size != b.N:
            raise InputError(f"unsupported element layout ({b.N} DOFs, {nd.size} nodal)")
        return nd

    @property
    def n_dofs(self) -> int:
        return int(self.basis.N)

    @cached_property
    def node_coordinates(self) -> np.ndarray:
        """Coordinates of every node, shape (n_nodes, dim)."""
        return self.basis.doflocs[:, self.node_dofs[:, 0]].T.copy()

    def _facet_node_lists(self, facets: np.ndarray) -> list[np.ndarray]:
        """Per node slot of a facet, the node numbers over ``facets``: the vertices, then the
        mid-edge nodes (``P2`` in 3-D) or the mid-side nodes (``P2`` in 2-D)."""
        m = self.mesh.mesh
        facets = np.asarray(facets)
        slots = list(m.facets[:, facets])
        if self.basis.edge_dofs.size:
            slots += list(m.p.shape[1] + m.f2e[:, facets])
        elif self.basis.facet_dofs.size:
            slots.append(m.p.shape[1] + facets)
        return slots

    def facet_nodes(self, facets: np.ndarray) -> np.ndarray:
        """Nodes on the given facets (vertices, plus mid-side / mid-edge nodes for ``P2``),
        sorted."""
        return np.unique(np.concatenate(self._facet_node_lists(facets)))

    def boundary_nodes(self, name: str) -> np.ndarray:
        return self.facet_nodes(self.mesh.facets(name))

    def facet_normals(self, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outward unit normals (n_f, dim) and sizes (n_f,) of boundary facets (lengths in 2-D,
        areas in 3-D; the normal at the facet's centre)."""
        m = self.mesh.mesh
        if self.dim == 3:
            return _facet_normals_3d(m, np.asarray(facets))
        a, b = m.p[:, m.facets[0, facets]], m.p[:, m.facets[1, facets]]
        d = b - a
        L = np.hypot(d[0], d[1])
        n = np.vstack([d[1], -d[0]]) / L
        centre = m.p[:, m.t[:, m.f2t[0, facets]]].mean(axis=1)
        flip = np.sum(n * (0.5 * (a + b) - centre), axis=0) < 0
        n[:, flip] *= -1
        return n.T, L

    def node_normals(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Nodes of boundary ``name`` and their outward unit normals (n, dim).

        A node's normal is the length- (area-) weighted mean of the outward normals of the
        facets of ``name`` that touch it (the facet's own normal on plane faces).
        """
        facets = self.mesh.facets(name)
        nodes = self.facet_nodes(facets)
        fn, L = self.facet_normals(facets)
        acc = np.zeros((self.node_dofs.shape[0], self.dim))
        for slot in self._facet_node_lists(facets):
            np.add.at(acc, slot, fn * L[:, None])
        n = acc[nodes]
        n /= np.linalg.norm(n, axis=1)[:, None]
        return nodes, n

    @property
    def held(self) -> dict[str, tuple[int, ...]]:
        return self._held

    def held_dofs(self) -> dict[int, tuple[str, int]]:
        """DOF -> (boundary, component) of every held DOF."""
        out = {}
        for name, comps in self._held.items():
            for node in self.boundary_nodes(name):
                for c in comps:
                    out[int(self.node_dofs[node, c])] = (name, c)
        return out

    # ------------------------------------------------------------------ assembly
    def stiffness(self):
        """Stiffness matrix (sparse CSR, ``n_dofs x n_dofs``) [force / length]."""
        from skfem import BilinearForm, asm
        from skfem.helpers import sym_grad

        D = self.material.D * self.thickness
        pairs = ((0, 0), (1, 1), (0, 1)) if self.dim == 2 else \
            ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))  # Voigt order, engineering shear
        nv = len(pairs)

        @BilinearForm
        def form(u, v, w):
            e, f = sym_grad(u), sym_grad(v)
            eu = [e[i, j] * (1 if i == j else 2) for i, j in pairs]
            ev = [f[i, j] * (1 if i == j else 2) for i, j in pairs]
            return sum(D[i, j] * eu[j] * ev[i] for i in range(nv) for j in range(nv)
                       if D[i, j] != 0.0)

        with np.errstate(over="ignore", invalid="ignore"):  # reported below, in words
            if self.dim == 3:  # the same integrals, vectorised over the local basis pairs
                K = _voigt_stiffness(self.basis, D, pairs)
            else:
                K = asm(form, self.basis).tocsr()
        if not np.all(np.isfinite(K.data)):
            raise InputError(
                f"the stiffness matrix overflows (material D up to {np.abs(D).max():.3g}, "
                "times element geometry): the elastic constants are too large for floating "
                "point; express them in larger stress units")
        return K

    def mass(self):
        """Consistent mass matrix (sparse CSR) [mass]."""
        from skfem import BilinearForm, asm
        from skfem.helpers import dot

        rho = self.material.density * self.thickness

        @BilinearForm
        def form(u, v, w):
            return rho * dot(u, v)

        return asm(form, self.basis).tocsr()

    def load_vector(self, items) -> tuple[np.ndarray, dict[int, float]]:
        """External force vector (n_dofs,) and prescribed displacements {dof: value}."""
        from skfem import FacetBasis, LinearForm, asm

        f = np.zeros(self.n_dofs)
        prescribed: dict[int, float] = {}
        for it in items:
            if isinstance(it, BodyForce):
                val = it.value

                @LinearForm
                def body(v, w, val=val):
                    b = val(w.x) if callable(val) else val
                    return self.thickness * sum(b[i] * v[i] for i in range(self.dim))

                f += asm(body, self.basis)
            elif isinstance(it, (Traction, Pressure)):
                facets = self.mesh.facets(it.boundary)
                fb = FacetBasis(self.mesh.mesh, self.basis.elem, facets=facets)
                val, is_p = it.value, isinstance(it, Pressure)

                @LinearForm
                def surf(v, w, val=val, is_p=is_p):
                    t = val(w.x) if callable(val) else val
                    if is_p:
                        t = [-t * w.n[i] for i in range(self.dim)]
                    return self.thickness * sum(t[i] * v[i] for i in range(self.dim))

                f += asm(surf, fb)
            elif isinstance(it, Displacement):
                nodes = self.boundary_nodes(it.boundary)
                xy = self.node_coordinates[nodes].T
                val = np.asarray(it.value(xy) if callable(it.value) else it.value, float)
                val = np.broadcast_to(val.reshape(self.dim, -1), (self.dim, nodes.size))
                for c in self._held[it.boundary]:
                    for node, u in zip(nodes, val[c], strict=True):
                        prescribed[int(self.node_dofs[node, c])] = float(u)
        return f, prescribed

    def key(self) -> dict:
        """JSON-able description for the cache key (raises TypeError on callables)."""
        m = self.mesh.mesh
        import hashlib

        h = hashlib.sha256()
        for arr in (m.p, m.t):
            h.update(np.ascontiguousarray(arr).tobytes())
        for name in sorted(m.boundaries or {}):
            h.update(name.encode())
            h.update(np.ascontiguousarray(np.sort(m.boundaries[name])).tobytes())
        return {
            "mesh": h.hexdigest(),
            "mesh_type": type(m).__name__,
            "element": self.mesh.element,
            "material": self.material.key(),
            "dirichlet": {k: list(v) for k, v in sorted(self._held.items())},
            "loads": {k: [load_key(x) for x in v] for k, v in sorted(self.loads.items())},
            "thickness": float(self.thickness),
        }
