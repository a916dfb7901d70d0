"""Bodies, loads and their assembly with scikit-fem (stiffness, consistent mass, load vectors).

A *node* is a location carrying two displacement DOFs ``(u_x, u_y)``: the mesh vertices,
then (``P2``) one node per facet at its mid-point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ...model.errors import InputError
from .materials import Material
from .meshes import FEMesh

# --------------------------------------------------------------------------- loads


def _pair(name: str, value) -> tuple[float, float] | object:
    if callable(value):
        return value
    try:
        v = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a pair (x, y) of numbers; got {value!r}") from exc
    if v.shape != (2,) or not np.all(np.isfinite(v)):
        raise InputError(f"{name} must be a finite pair (x, y); got {value!r}")
    return (float(v[0]), float(v[1]))


@dataclass(frozen=True)
class Traction:
    """Surface traction on a named boundary [force / length^2 x thickness = force / length].

    ``value``: ``(t_x, t_y)`` in the global frame, or a callable ``f(x) -> (2, ...)`` of the
    points ``x`` (shape (2, ...)); callables make the model uncacheable.
    """

    boundary: str
    value: object

    def __post_init__(self):
        object.__setattr__(self, "value", _pair("Traction.value", self.value))


@dataclass(frozen=True)
class Pressure:
    """Normal pressure on a named boundary (positive = pushing into the body, along ``-n``)."""

    boundary: str
    value: float

    def __post_init__(self):
        if not callable(self.value):
            v = float(self.value)
            if not np.isfinite(v):
                raise InputError(f"Pressure.value must be finite; got {self.value!r}")
            object.__setattr__(self, "value", v)


@dataclass(frozen=True)
class BodyForce:
    """Body force per unit volume ``(b_x, b_y)`` [force / length^3], or a callable of ``x``."""

    value: object
    body: int | None = None  # None: every body

    def __post_init__(self):
        object.__setattr__(self, "value", _pair("BodyForce.value", self.value))


@dataclass(frozen=True)
class Displacement:
    """Prescribed displacement ``(u_x, u_y)`` on a named *Dirichlet* boundary [length]."""

    boundary: str
    value: object

    def __post_init__(self):
        object.__setattr__(self, "value", _pair("Displacement.value", self.value))


LOAD_TYPES = (Traction, Pressure, BodyForce, Displacement)


def normalize_loads(loads) -> dict[str, tuple]:
    """``None`` | load | list of loads | dict name -> load(s)  ->  dict name -> tuple of loads."""
    if loads is None:
        return {}
    if isinstance(loads, LOAD_TYPES):
        loads = {"load": [loads]}
    elif isinstance(loads, (list, tuple)):
        loads = {"load": list(loads)}
    if not isinstance(loads, dict):
        raise InputError(
            f"loads must be a load, a list of loads or a dict name -> load(s); got {loads!r}"
        )
    out = {}
    for name, case in loads.items():
        items = [case] if isinstance(case, LOAD_TYPES) else list(case)
        for it in items:
            if not isinstance(it, LOAD_TYPES):
                raise InputError(
                    f"load case {name!r}: {it!r} is not one of Traction, Pressure, BodyForce, "
                    "Displacement"
                )
        out[str(name)] = tuple(items)
    return out


def load_key(load) -> dict:
    """JSON-able description of a load; raises if it holds a callable (not cacheable)."""
    d = {"type": type(load).__name__}
    for k, v in load.__dict__.items():
        if callable(v):
            raise TypeError("callable load")
        d[k] = v
    return d


# --------------------------------------------------------------------------- bodies


def _parse_dirichlet(dirichlet) -> dict[str, tuple[int, ...]]:
    """``["top"]`` or ``{"top": "xy", "left": "x"}`` -> name -> components."""
    if dirichlet is None:
        return {}
    if isinstance(dirichlet, str):
        dirichlet = [dirichlet]
    if isinstance(dirichlet, dict):
        items = dirichlet.items()
    else:
        items = [(name, "xy") for name in dirichlet]
    out = {}
    for name, comp in items:
        if comp not in ("x", "y", "xy"):
            raise InputError(
                f"dirichlet[{name!r}] must be 'x', 'y' or 'xy' (held components); got {comp!r}"
            )
        out[str(name)] = tuple(i for i, c in enumerate("xy") if c in comp)
    return out


@dataclass(frozen=True, eq=False)
class Body:
    """One elastic body: a mesh, a material, held boundaries and loads.

    Parameters
    ----------
    mesh : FEMesh
    material : Material
    dirichlet : list of str or dict, optional
        Held boundaries: ``["top"]`` (both components) or ``{"left": "x"}`` (rollers).
        Prescribed non-zero values come from :class:`Displacement` loads.
    loads : dict name -> load(s), optional
        Load cases (see :func:`normalize_loads`).
    thickness : float
        Out-of-plane thickness (forces are per this thickness; 1 = per unit thickness).
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
        held = _parse_dirichlet(self.dirichlet)
        for name in held:
            self.mesh.facets(name)  # raises on unknown / empty names
        object.__setattr__(self, "_held", held)
        object.__setattr__(self, "loads", normalize_loads(self.loads))
        for case, items in self.loads.items():
            for it in items:
                b = getattr(it, "boundary", None)
                if b is not None:
                    self.mesh.facets(b)
                if isinstance(it, Displacement) and b not in held:
                    raise InputError(
                        f"load case {case!r}: Displacement on {b!r}, which is not a Dirichlet "
                        f"boundary (dirichlet = {sorted(held)}); add it to dirichlet"
                    )

    # ------------------------------------------------------------------ discretisation
    @cached_property
    def basis(self):
        from skfem import Basis, ElementQuad1, ElementTriP1, ElementTriP2, ElementVector

        e = {"P1": ElementTriP1, "P2": ElementTriP2, "Q1": ElementQuad1}[self.mesh.element]()
        return Basis(self.mesh.mesh, ElementVector(e))

    @cached_property
    def node_dofs(self) -> np.ndarray:
        """DOF numbers ``(u_x, u_y)`` of every node, shape (n_nodes, 2)."""
        b = self.basis
        parts = [b.nodal_dofs.T]
        if b.facet_dofs.size:
            parts.append(b.facet_dofs.T)
        nd = np.vstack(parts).astype(np.int64)
        if nd.size != b.N:
            raise InputError(f"unsupported element layout ({b.N} DOFs, {nd.size} nodal)")
        return nd

    @property
    def n_dofs(self) -> int:
        return int(self.basis.N)

    @cached_property
    def node_coordinates(self) -> np.ndarray:
        """Coordinates of every node, shape (n_nodes, 2)."""
        return self.basis.doflocs[:, self.node_dofs[:, 0]].T.copy()

    def facet_nodes(self, facets: np.ndarray) -> np.ndarray:
        """Nodes on the given facets (vertices, plus mid-side nodes for ``P2``), sorted."""
        m = self.mesh.mesh
        nodes = [m.facets[:, facets].ravel()]
        if self.basis.facet_dofs.size:
            nodes.append(m.p.shape[1] + np.asarray(facets))
        return np.unique(np.concatenate(nodes))

    def boundary_nodes(self, name: str) -> np.ndarray:
        return self.facet_nodes(self.mesh.facets(name))

    def facet_normals(self, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outward unit normals (n_f, 2) and lengths (n_f,) of boundary facets."""
        m = self.mesh.mesh
        a, b = m.p[:, m.facets[0, facets]], m.p[:, m.facets[1, facets]]
        d = b - a
        L = np.hypot(d[0], d[1])
        n = np.vstack([d[1], -d[0]]) / L
        centre = m.p[:, m.t[:, m.f2t[0, facets]]].mean(axis=1)
        flip = np.sum(n * (0.5 * (a + b) - centre), axis=0) < 0
        n[:, flip] *= -1
        return n.T, L

    def node_normals(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Nodes of boundary ``name`` and their outward unit normals (n, 2).

        A node's normal is the length-weighted mean of the outward normals of the facets of
        ``name`` that touch it (the facet's own normal on straight sides).
        """
        facets = self.mesh.facets(name)
        nodes = self.facet_nodes(facets)
        fn, L = self.facet_normals(facets)
        m = self.mesh.mesh
        acc = np.zeros((self.node_dofs.shape[0], 2))
        for k in range(m.facets.shape[0]):
            np.add.at(acc, m.facets[k, facets], fn * L[:, None])
        if self.basis.facet_dofs.size:
            acc[m.p.shape[1] + facets] += fn * L[:, None]
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

        @BilinearForm
        def form(u, v, w):
            e, f = sym_grad(u), sym_grad(v)
            eu = (e[0, 0], e[1, 1], 2 * e[0, 1])
            ev = (f[0, 0], f[1, 1], 2 * f[0, 1])
            return sum(D[i, j] * eu[j] * ev[i] for i in range(3) for j in range(3))

        with np.errstate(over="ignore", invalid="ignore"):  # reported below, in words
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
                    return self.thickness * (b[0] * v[0] + b[1] * v[1])

                f += asm(body, self.basis)
            elif isinstance(it, (Traction, Pressure)):
                facets = self.mesh.facets(it.boundary)
                fb = FacetBasis(self.mesh.mesh, self.basis.elem, facets=facets)
                val, is_p = it.value, isinstance(it, Pressure)

                @LinearForm
                def surf(v, w, val=val, is_p=is_p):
                    t = val(w.x) if callable(val) else val
                    if is_p:
                        t = (-t * w.n[0], -t * w.n[1])
                    return self.thickness * (t[0] * v[0] + t[1] * v[1])

                f += asm(surf, fb)
            elif isinstance(it, Displacement):
                nodes = self.boundary_nodes(it.boundary)
                xy = self.node_coordinates[nodes].T
                val = np.asarray(it.value(xy) if callable(it.value) else it.value, float)
                val = np.broadcast_to(val.reshape(2, -1), (2, nodes.size))
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
