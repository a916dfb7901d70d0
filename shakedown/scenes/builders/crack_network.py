"""Scene model kind ``"crack_network"``: a random (or given) crack set, Kachanov or BEM model.

``[model]`` keys
    Geometry, either sampled: ``n_cracks`` (int, default 100), ``density`` (default 0.1),
    ``half_length`` (number or ``[lo, hi]``, default 1.0), ``orientation`` (omit for uniform
    in ``[0, pi)``, a number or ``[lo, hi]``, radians), ``orientation_deg`` (the same in
    degrees), ``min_spacing`` (in units of half-length, default 0.1), ``seed`` (int, default 0);
    or ``file``: a CSV beside the scene with columns ``x, y, half_length, angle`` (radians) or
    ``angle_deg`` (see :func:`crack_networks.load_csv`).
    Material and model: ``shear_modulus`` (default 1.0), ``poisson_ratio`` (0.25),
    ``friction`` (0.6), ``symmetric`` (true; false is refused, a DiscreteSystem needs a
    symmetric K), ``method`` (``"kachanov"`` default, or ``"bem"``), ``weighting``
    (``"uniform"`` default or ``"elliptic"``, Kachanov only), ``n_modes`` (BEM, default 16),
    ``interaction_radius`` (Kachanov, uniform weighting: keep the interactions of pairs closer
    than this many ``a_i + a_j``; the system is then sparse and the cyclic runs and bounds use
    it without densifying; its error against the full interaction is in
    ``benchmarks/RESULTS_kachanov_assembly.md``).
``[load]`` keys
    ``static``, ``cyclic``: far-field stresses ``[sxx, sxy, syy]`` (tension positive) of
    ``S(t) = static + lam * cyclic * cos(2 pi t)``; defaults ``[-1, 0, -1]`` and ``[0, 1, 0]``
    (seed 002 s.4.1, MODEL.md s.7, ``p0 = 1``).

The third returned object is the :class:`crack_networks.KachanovModel` (or ``BEMModel``).
"""

from __future__ import annotations

from pathlib import Path

from ...model.errors import SceneError

MODEL_KEYS = {
    "n_cracks": (int,),
    "density": (int, float),
    "half_length": (int, float, list),
    "orientation": (int, float, list),
    "orientation_deg": (int, float, list),
    "min_spacing": (int, float),
    "seed": (int,),
    "file": (str,),
    "shear_modulus": (int, float),
    "poisson_ratio": (int, float),
    "friction": (int, float, list),
    "symmetric": (bool,),
    "method": (str,),
    "weighting": (str,),
    "n_modes": (int,),
    "interaction_radius": (int, float),
}
LOAD_KEYS = ("static", "cyclic")


def _check_types(table: dict, allowed: dict, name: str):
    for key, value in table.items():
        if key not in allowed:
            raise SceneError(
                f"[{name}] key {key!r} is not allowed for kind 'crack_network'; allowed: "
                f"{', '.join(allowed)}"
            )
        types = allowed[key]
        if isinstance(value, bool) and bool not in types:
            ok = False
        else:
            ok = isinstance(value, types)
        if not ok:
            want = " or ".join("list" if t is list else t.__name__ for t in types)
            raise SceneError(f"[{name}] key {key!r} = {value!r} must be a {want}")
        if key == "seed" and not 0 <= value < 2**128:  # numpy's seeds: integers >= 0
            raise SceneError(f"[{name}] key 'seed' = {value!r} must be an integer >= 0")


def _pair_or_number(key, value):
    if isinstance(value, list):
        if len(value) != 2 or not all(isinstance(v, (int, float)) for v in value):
            raise SceneError(f"[model] key {key!r} = {value!r} must be a number or [lo, hi]")
        return (float(value[0]), float(value[1]))
    return float(value)


def _stress(key, value):
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise SceneError(f"[load] key {key!r} = {value!r} must be a list [sxx, sxy, syy]")
    return tuple(float(v) for v in value)


def draws_realisations(model: dict) -> bool:
    """The sweep draws this model anew per realisation (random Kachanov crack sets from the
    sampling keys, one friction coefficient); a crack set read from a ``file``, the BEM model,
    per-crack friction or non-uniform weighting are swept as the one given system."""
    return ("file" not in model and model.get("method", "kachanov") == "kachanov"
            and model.get("weighting", "uniform") == "uniform"
            and not isinstance(model.get("friction"), list))


def build(model: dict, load: dict, scene_dir: Path):
    import numpy as np

    import crack_networks as cn

    _check_types(model, MODEL_KEYS, "model")
    for key in load:
        if key not in LOAD_KEYS:
            raise SceneError(
                f"[load] key {key!r} is not allowed for kind 'crack_network'; allowed: "
                f"{', '.join(LOAD_KEYS)} (far-field stresses [sxx, sxy, syy])"
            )
    if "file" in model:
        sampled = [k for k in ("n_cracks", "density", "half_length", "orientation",
                               "orientation_deg", "min_spacing", "seed") if k in model]
        if sampled:
            raise SceneError(
                f"[model] key 'file' cannot be combined with sampling keys {sampled}; "
                "give either a crack file or the sampling parameters"
            )
        path = Path(scene_dir) / model["file"]
        if not path.is_file():
            raise SceneError(f"[model] key 'file' = {model['file']!r}: no such file {path}")
        cracks = cn.load_csv(path)
    else:
        if "orientation" in model and "orientation_deg" in model:
            raise SceneError("[model] give 'orientation' (radians) or 'orientation_deg', not both")
        orientation = None
        if "orientation" in model:
            orientation = _pair_or_number("orientation", model["orientation"])
        elif "orientation_deg" in model:
            o = _pair_or_number("orientation_deg", model["orientation_deg"])
            orientation = tuple(np.deg2rad(o)) if isinstance(o, tuple) else float(np.deg2rad(o))
        cracks = cn.sample_crack_set(
            model.get("n_cracks", 100),
            density=float(model.get("density", 0.1)),
            half_length=_pair_or_number("half_length", model.get("half_length", 1.0)),
            orientation=orientation,
            min_spacing=float(model.get("min_spacing", 0.1)),
            rng=model.get("seed", 0),
        )
    if model.get("symmetric", True) is False:
        raise SceneError(
            "[model] key 'symmetric' = false is not supported in scenes: a DiscreteSystem needs "
            "a symmetric K (the default symmetrises Kachanov's K); use the Python API "
            "(crack_networks.kachanov_model(..., symmetric=False).stiffness_raw) for raw matrices"
        )
    method = model.get("method", "kachanov")
    common = dict(
        shear_modulus=float(model.get("shear_modulus", 1.0)),
        poisson_ratio=float(model.get("poisson_ratio", 0.25)),
        friction=model.get("friction", 0.6),
    )
    if method == "kachanov":
        if "n_modes" in model:
            raise SceneError("[model] key 'n_modes' only applies to method = 'bem'")
        net = cn.kachanov_model(cracks, weighting=model.get("weighting", "uniform"),
                                interaction_radius=model.get("interaction_radius"), **common)
    elif method == "bem":
        for key in ("weighting", "interaction_radius"):
            if key in model:
                raise SceneError(f"[model] key {key!r} only applies to method = 'kachanov'")
        net = cn.bem_model(cracks, n_modes=model.get("n_modes", 16), **common)
    else:
        raise SceneError(f"[model] key 'method' = {method!r} must be 'kachanov' or 'bem'")
    static = _stress("static", load.get("static", [-1.0, 0.0, -1.0]))
    cyclic = _stress("cyclic", load.get("cyclic", [0.0, 1.0, 0.0]))
    return net.system, net.load_cycle(static=static, cyclic=cyclic), net


def resolved(model: dict, load: dict) -> tuple[dict, dict]:
    """``[model]`` and ``[load]`` with every default that :func:`build` applies filled in."""
    m, ld = dict(model), dict(load)
    if "file" not in m:
        for key, value in (("n_cracks", 100), ("density", 0.1), ("half_length", 1.0),
                           ("min_spacing", 0.1), ("seed", 0)):
            m.setdefault(key, value)
    for key, value in (("shear_modulus", 1.0), ("poisson_ratio", 0.25), ("friction", 0.6),
                       ("symmetric", True), ("method", "kachanov")):
        m.setdefault(key, value)
    if m["method"] == "kachanov":
        m.setdefault("weighting", "uniform")
    elif m["method"] == "bem":
        m.setdefault("n_modes", 16)
    ld.setdefault("static", [-1.0, 0.0, -1.0])
    ld.setdefault("cyclic", [0.0, 1.0, 0.0])
    return m, ld
