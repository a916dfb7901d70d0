"""Scene model kind ``"fe"``: elastic bodies (2-D or 3-D) condensed onto their contact nodes.

``[model]`` keys
    ``geometry`` : ``"rectangle"`` | ``"trapezoid"`` | ``"polygon"`` | ``"mesh_file"`` |
    ``"box"`` (3-D: ``size = [lx, ly, lz]``, ``cells = [nx, ny, nz]``, ``origin`` (optional),
    faces ``left``/``right``/``front``/``back``/``bottom``/``top``);
    rectangle: ``width``, ``height``; trapezoid: ``bottom_width``, ``top_width``, ``height``,
    ``top_offset`` (optional); both: ``nx``, ``ny`` (cells), ``pattern``; polygon:
    ``vertices`` ([[x, y], ...]), ``side_names``, ``refine``; mesh_file: ``file`` (beside
    the scene, read by meshio: Gmsh ``.msh``, VTK, XDMF, ...; linear triangles or
    quadrilaterals, or 3-D tetrahedra or hexahedra; the physical groups of its facet elements
    name the boundaries that ``contact``, ``dirichlet`` and the loads refer to) and
    ``boundaries`` ({name = [[x0, y0], [x1, y1]]} segments adding names; in 3-D
    {name = [[x0, y0, z0], [x1, y1, z1]]} boxes selecting the boundary facets inside);
    ``element`` : ``"P1"`` | ``"P2"`` | ``"Q1"`` (3-D: tetrahedra P1/P2, hexahedra Q1);
    ``material`` : table with ``type = "isotropic"`` (``E``, ``nu``) or
    ``"transversely_isotropic"`` (``E1``, ``E2``, ``nu12``, ``nu23``, ``G12``, ``theta_deg``),
    plus ``plane`` (``"strain"``/``"stress"``; a 3-D mesh implies ``"3d"``) and ``density``;
    ``dirichlet`` : list of boundary names (or {name = "x" | "y" | "xy"});
    ``contact`` : list of boundary names; ``periodic`` : [master, slave];
    ``friction`` : number or list of N; ``mass`` : bool (condense the mass);
    ``thickness`` : number; ``cache_dir`` : name of the on-disk cache folder, created inside
    the output folder (a second run with the same output folder reads the condensed model);
    ``sparse`` : true keeps the stiffness uncondensed (``FEModel.uncondensed()``: the cyclic
    runs never form the dense ``K``, for thousands of contact nodes; not with ``mass`` or
    ``cache_dir``);
    ``bodies`` : several bodies, an array of tables ``[[model.bodies]]`` each with the geometry
    keys above, ``element``, ``material``, ``dirichlet``, ``contact`` (rigid obstacle) and
    ``boundaries``; then ``interfaces = [[a, name_a, b, name_b], ...]`` joins boundaries of two
    bodies with matching nodes (relative slip and gap in body ``a``'s frame), and the
    model-level geometry keys are not used.
``[load]`` tables ``static``, ``cyclic`` (cos amplitude), ``cyclic_sin`` (sin amplitude), each
    with ``traction`` ({boundary = [t_x, t_y]}), ``pressure`` ({boundary = p}, compression
    positive), ``body_force`` ([b_x, b_y]), ``displacement`` ({dirichlet boundary = [u_x, u_y]});
    3-D vectors have three components.  With several bodies a key ``"k:name"`` names the
    boundary ``name`` of body ``k``; a plain ``name`` loads every body that has that boundary.

The builder returns ``(system, load_cycle, condensed_model)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...model.errors import InputError, SceneError

GEOMETRIES = ("rectangle", "trapezoid", "polygon", "mesh_file", "box")
MESH_KEYS = (
    "geometry", "width", "height", "bottom_width", "top_width", "top_offset", "nx", "ny",
    "pattern", "vertices", "side_names", "refine", "file", "boundaries", "element", "size",
    "cells", "origin",
)
BODY_KEYS = MESH_KEYS + ("material", "dirichlet", "contact")
MODEL_KEYS = BODY_KEYS + (
    "periodic", "friction", "mass", "thickness", "cache_dir", "sparse", "bodies", "interfaces",
)
GEOMETRY_KEYS = {
    "rectangle": ("width", "height", "nx", "ny"),
    "trapezoid": ("bottom_width", "top_width", "height", "nx", "ny"),
    "polygon": ("vertices",),
    "mesh_file": ("file",),
    "box": ("size", "cells"),
}
LOAD_TABLES = ("static", "cyclic", "cyclic_sin")
LOAD_KINDS = ("traction", "pressure", "body_force", "displacement")
ISO_KEYS = ("type", "E", "nu", "plane", "density")
TI_KEYS = ("type", "E1", "E2", "nu12", "nu23", "G12", "theta_deg", "plane", "density")


def _require(table: dict, keys, where: str):
    for k in keys:
        if k not in table:
            raise SceneError(f"[{where}] key {k!r} is missing (needed here)")


def _mesh(model: dict, scene_dir: Path, where: str = "model"):
    from ...models import fe

    geometry = model.get("geometry", "rectangle")
    if geometry not in GEOMETRIES:
        raise SceneError(f"[{where}] key 'geometry' = {geometry!r} is not allowed; "
                         f"allowed: {', '.join(GEOMETRIES)}")
    _require(model, GEOMETRY_KEYS[geometry], where)
    if geometry == "box":
        for key in ("size", "cells"):
            if not (isinstance(model[key], list) and len(model[key]) == 3):
                raise SceneError(f"[{where}] key {key!r} = {model[key]!r} must be a list of three "
                                 "numbers (x, y, z)")
        mesh = fe.box(*model["size"], *model["cells"], element=model.get("element", "Q1"),
                      origin=model.get("origin", (0.0, 0.0, 0.0)))
        return mesh.with_boundaries(model["boundaries"]) if model.get("boundaries") else mesh
    element = model.get("element", "P1")
    pattern = model.get("pattern", "union-jack")
    if geometry == "rectangle":
        return fe.rectangle(model["width"], model["height"], model["nx"], model["ny"],
                            element=element, pattern=pattern)
    if geometry == "trapezoid":
        return fe.trapezoid(model["bottom_width"], model["top_width"], model["height"],
                            model["nx"], model["ny"], top_offset=model.get("top_offset"),
                            element=element, pattern=pattern)
    if geometry == "polygon":
        return fe.polygon(model["vertices"], refine=int(model.get("refine", 3)),
                          element=element, side_names=model.get("side_names"))
    path = scene_dir / str(model["file"])
    return fe.from_file(path, element=model.get("element"), boundaries=model.get("boundaries"))


def _material(spec, dim: int = 2):
    from ...models import fe

    if not isinstance(spec, dict) or "type" not in spec:
        raise SceneError("[model] key 'material' must be a table with 'type' = 'isotropic' or "
                         f"'transversely_isotropic'; got {spec!r}")
    kind = spec["type"]
    allowed = {"isotropic": ISO_KEYS, "transversely_isotropic": TI_KEYS}.get(kind)
    if allowed is None:
        raise SceneError(f"[model.material] key 'type' = {kind!r} is not allowed; allowed: "
                         "isotropic, transversely_isotropic")
    for k in spec:
        if k not in allowed:
            raise SceneError(f"[model.material] key {k!r} is not allowed for type {kind!r}; "
                             f"allowed: {', '.join(allowed)}")
    extra = {k: spec[k] for k in ("plane", "density") if k in spec}
    if dim == 3:
        extra.setdefault("plane", "3d")
    if kind == "isotropic":
        _require(spec, ("E", "nu"), "model.material")
        return fe.isotropic(spec["E"], spec["nu"], **extra)
    _require(spec, TI_KEYS[1:7], "model.material")
    return fe.transversely_isotropic(spec["E1"], spec["E2"], spec["nu12"], spec["nu23"],
                                     spec["G12"], np.deg2rad(float(spec["theta_deg"])), **extra)


def _target(name: str, bodies) -> list[tuple[int, str]]:
    """``"k:name"`` -> body ``k``; a plain name -> every body with that boundary (body 0 when
    there is one body)."""
    if len(bodies) == 1 and ":" not in name:
        return [(0, name)]
    if ":" in name:
        k, _, bname = name.partition(":")
        if not (k.isdigit() and int(k) < len(bodies)):
            raise SceneError(f"[load] boundary key {name!r}: {k!r} is not a body index 0.."
                             f"{len(bodies) - 1}; write 'k:name'")
        return [(int(k), bname)]
    hits = [(k, name) for k, b in enumerate(bodies) if name in b["mesh"].boundary_names]
    if not hits:
        raise SceneError(f"[load] boundary {name!r} belongs to no body; write 'k:name' with one "
                         "of the bodies' boundary names")
    return hits


def _load_cases(load: dict, bodies=None) -> dict:
    """``{case: [load, ...]}`` (one body) or, with ``bodies``, ``{body: {case: [...]}}``."""
    from ...models import fe

    single = bodies is None
    per_body: list[dict] = [{} for _ in (bodies or [None])]
    for k in load:
        if k not in LOAD_TABLES:
            raise SceneError(f"[load] key {k!r} is not allowed for kind 'fe'; allowed tables: "
                             f"{', '.join(LOAD_TABLES)}")
    for name in LOAD_TABLES:
        table = load.get(name)
        if table is None:
            continue
        if not isinstance(table, dict):
            raise SceneError(f"[load] key {name!r} must be a table with keys "
                             f"{', '.join(LOAD_KINDS)}")
        for case in per_body:
            case[name] = []
        for kind, spec in table.items():
            if kind not in LOAD_KINDS:
                raise SceneError(f"[load.{name}] key {kind!r} is not allowed; allowed: "
                                 f"{', '.join(LOAD_KINDS)}")
            if kind == "body_force":
                for case in per_body:
                    case[name].append(fe.BodyForce(spec))
                continue
            if not isinstance(spec, dict):
                raise SceneError(f"[load.{name}] key {kind!r} must be a table "
                                 "{boundary = value}")
            cls = {"traction": fe.Traction, "pressure": fe.Pressure,
                   "displacement": fe.Displacement}[kind]
            for boundary, value in spec.items():
                targets = [(0, boundary)] if single else _target(boundary, bodies)
                for k, bname in targets:
                    per_body[k][name].append(cls(bname, value))
    return per_body[0] if single else per_body


def _bodies(model: dict, load: dict, scene_dir: Path):
    """The :class:`~shakedown.fe.Body` list of a ``bodies = [...]`` model."""
    from ...models import fe

    specs = model["bodies"]
    if not (isinstance(specs, list) and specs and all(isinstance(b, dict) for b in specs)):
        raise SceneError("[model] key 'bodies' must be an array of tables [[model.bodies]]")
    for key in MESH_KEYS + ("material", "dirichlet", "contact", "periodic"):
        if key in model:
            raise SceneError(f"[model] key {key!r} goes inside each [[model.bodies]] table when "
                             "'bodies' is given")
    built = []
    for k, spec in enumerate(specs):
        where = f"model.bodies[{k}]"
        for key in spec:
            if key not in BODY_KEYS:
                raise SceneError(f"[{where}] key {key!r} is not allowed; allowed: "
                                 f"{', '.join(BODY_KEYS)}")
        _require(spec, ("material",), where)
        mesh = _mesh(spec, scene_dir, where)
        built.append({"mesh": mesh, "spec": spec,
                      "material": _material(spec["material"], mesh.dim)})
    cases = _load_cases(load or {}, built)
    bodies = [fe.Body(b["mesh"], b["material"], dirichlet=b["spec"].get("dirichlet"),
                      loads={c: v for c, v in cases[k].items() if v})
              for k, b in enumerate(built)]
    contact = [(k, name) for k, b in enumerate(built) for name in b["spec"].get("contact", [])]
    interfaces = [tuple(it) for it in model.get("interfaces", [])]
    return bodies, contact, interfaces


def build(model: dict, load: dict, scene_dir: Path, cache_root: Path | None = None):
    """Build ``(DiscreteSystem, LoadCycle, CondensedModel)`` from the ``[model]``/``[load]`` tables.

    A relative ``cache_dir`` is resolved inside ``cache_root`` (the run's output folder, given by
    the scene runner) so that nothing is written outside it; without ``cache_root`` no cache is used.
    """
    from ...models import fe
    from ..output import check_plain_name

    for key in model:
        if key not in MODEL_KEYS:
            raise SceneError(f"[model] key {key!r} is not allowed for kind 'fe'; "
                             f"allowed: {', '.join(MODEL_KEYS)}")
    if "bodies" not in model:
        _require(model, ("material", "contact"), "model")
    try:
        if "bodies" in model:
            bodies, contact, interfaces = _bodies(model, load, Path(scene_dir))
            fem = fe.FEModel(bodies=bodies, contact=contact, interfaces=interfaces,
                             friction=model.get("friction", 0.0))
        else:
            mesh = _mesh(model, Path(scene_dir))
            material = _material(model["material"], mesh.dim)
            periodic = model.get("periodic")
            fem = fe.FEModel(
                mesh, material, dirichlet=model.get("dirichlet"), contact=model["contact"],
                loads=_load_cases(load or {}), friction=model.get("friction", 0.0),
                periodic=tuple(periodic) if periodic else None,
                thickness=float(model.get("thickness", 1.0)),
            )
        cache_dir = model.get("cache_dir")
        if cache_dir and cache_root is not None:
            # a plain folder name inside the output folder ('..' would leave it)
            name = check_plain_name(Path(str(cache_dir)).name, "[model] key 'cache_dir'")
            cache_path = Path(cache_root) / name
        else:
            cache_path = None
        sparse = model.get("sparse", False)
        if not isinstance(sparse, bool):
            raise SceneError(f"[model] key 'sparse' = {sparse!r} must be true or false")
        if sparse and (model.get("mass", False) or model.get("cache_dir")):
            raise SceneError("[model] key 'sparse' = true keeps the stiffness uncondensed: it "
                             "takes neither 'mass' nor 'cache_dir' (remove them, or 'sparse')")
        cm = fem.uncondensed() if sparse else fem.condense(mass=bool(model.get("mass", False)),
                                                            cache_dir=cache_path)
        cycle = cm.load_cycle(
            static="static" if "static" in cm.welded else None,
            cyclic="cyclic" if "cyclic" in cm.welded else None,
            cyclic_sin="cyclic_sin" if "cyclic_sin" in cm.welded else None,
        )
        system = cm.system
    except SceneError:
        raise
    except InputError as exc:
        raise SceneError(f"[model] (kind 'fe') {exc}") from None
    return system, cycle, cm


def resolved(model: dict, load: dict) -> tuple[dict, dict]:
    """``[model]`` and ``[load]`` with the unconditional defaults of :func:`build` filled in."""
    m = dict(model)
    if "bodies" in m:
        m["bodies"] = [_resolved_mesh(dict(b)) for b in m["bodies"]]
        m.setdefault("interfaces", [])
    else:
        _resolved_mesh(m)
    for key, value in (("friction", 0.0), ("mass", False), ("thickness", 1.0),
                       ("sparse", False)):
        m.setdefault(key, value)
    return m, dict(load)


def _resolved_mesh(m: dict) -> dict:
    geometry = m.setdefault("geometry", "rectangle")
    if geometry in ("rectangle", "trapezoid"):
        m.setdefault("element", "P1")
        m.setdefault("pattern", "union-jack")
    elif geometry == "polygon":
        m.setdefault("element", "P1")
        m.setdefault("refine", 3)
    elif geometry == "box":
        m.setdefault("element", "Q1")
        m.setdefault("origin", [0.0, 0.0, 0.0])
    return m
