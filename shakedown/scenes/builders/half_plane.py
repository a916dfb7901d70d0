"""Scene model kind ``"half_plane"``: two half-planes pressed by ``P(t)``, sheared by ``Q(t)``.

``[model]`` keys
    ``profile`` (``"hertz"`` default, ``"flat_rounded"``, ``"power"``, ``"samples"``),
    ``radius`` [length] (not for samples), ``flat_half_width``, ``exponent``, ``gap_x`` and
    ``gap_g`` (lists, profile ``"samples"``), ``n_nodes`` (odd, default 61), ``width`` [length]
    (default, Hertz only: ``2.4 a(P0 + |P1|)``), ``friction`` (default 0.5), ``E1``, ``nu1``,
    ``E2``, ``nu2`` (defaults 1.0, 0.3, 1.0, 0.3; ``E2 = inf`` is a rigid body 2).
``[load]`` keys
    ``P0`` (> 0), ``P1``, ``Q1`` [force per unit thickness], ``phase`` [rad] or ``phase_deg``:
    ``P(t) = P0 + lam P1 cos(2 pi t + phase)``, ``Q(t) = lam Q1 cos(2 pi t)``.

The third returned object is the :class:`shakedown.models.half_plane.HalfPlaneModel`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...model.errors import SceneError

MODEL_KEYS = {
    "profile": (str,), "radius": (int, float), "flat_half_width": (int, float),
    "exponent": (int, float), "gap_x": (list,), "gap_g": (list,), "n_nodes": (int,),
    "width": (int, float), "friction": (int, float), "E1": (int, float), "nu1": (int, float),
    "E2": (int, float), "nu2": (int, float),
}
LOAD_KEYS = {"P0": (int, float), "P1": (int, float), "Q1": (int, float),
             "phase": (int, float), "phase_deg": (int, float)}

#: The built-in scene of seed 002 s.4.2 (Figs. 12-13).
HERTZ_ELLIPSE = Path(__file__).resolve().parents[1] / "builtin" / "hertz_ellipse.toml"


def _check(table: dict, allowed: dict, name: str):
    for key, value in table.items():
        if key not in allowed:
            raise SceneError(f"[{name}] key {key!r} is not allowed for kind 'half_plane'; "
                                f"allowed: {', '.join(allowed)}")
        if isinstance(value, bool) or not isinstance(value, allowed[key]):
            want = " or ".join("list" if t is list else t.__name__ for t in allowed[key])
            raise SceneError(f"[{name}] key {key!r} = {value!r} must be a {want}")


def normal_load(load_table: dict, noun: str):
    """``(P0, P1, phase [rad])`` of a contact scene's ``[load]`` table (half-plane and
    half-space); ``noun`` names ``P0`` in the message when it is missing."""
    if "phase" in load_table and "phase_deg" in load_table:
        raise SceneError("[load] give 'phase' (radians) or 'phase_deg', not both")
    if "P0" not in load_table:
        raise SceneError(f"[load] key 'P0' ({noun} > 0) is required")
    P0 = float(load_table["P0"])
    P1 = float(load_table.get("P1", 0.0))
    phase = float(load_table.get("phase", np.deg2rad(load_table.get("phase_deg", 0.0))))
    return P0, P1, phase


def build_from_scene(model_table: dict, load_table: dict, base_dir=None):
    """``(DiscreteSystem, LoadCycle, HalfPlaneModel)`` from a scene's ``[model]``/``[load]`` tables.

    ``base_dir`` is accepted for the builder interface (no file is read).
    """
    from ...models.half_plane.continuum import hertz_half_width
    from ...models.half_plane.model import _materials, _positive, half_plane_model

    model_table = {k: v for k, v in model_table.items() if k != "kind"}
    _check(model_table, MODEL_KEYS, "model")
    _check(load_table, LOAD_KEYS, "load")
    P0, P1, phase = normal_load(load_table, "mean normal load")
    Q1 = float(load_table.get("Q1", 0.0))
    profile = model_table.get("profile", "hertz")
    mats = ((model_table.get("E1", 1.0), model_table.get("nu1", 0.3)),
            (model_table.get("E2", 1.0), model_table.get("nu2", 0.3)))
    kw = {}
    for key in ("radius", "flat_half_width", "exponent"):
        if key in model_table:
            kw[key] = float(model_table[key])
    if profile == "samples":
        if "gap_x" not in model_table or "gap_g" not in model_table:
            raise SceneError("[model] profile 'samples' needs the lists 'gap_x' and 'gap_g'")
        kw["gap_samples"] = (model_table["gap_x"], model_table["gap_g"])
    width = model_table.get("width")
    if width is None:
        if profile != "hertz" or "radius" not in kw:
            raise SceneError("[model] key 'width' is required unless profile = 'hertz' "
                                "with a 'radius' (then it defaults to 2.4 a(P0 + |P1|))")
        _positive("radius", kw["radius"])
        e_star, _ = _materials(mats)
        width = 2.4 * float(hertz_half_width(P0 + abs(P1), kw["radius"], e_star))
    m = half_plane_model(profile, n_nodes=model_table.get("n_nodes", 61), width=width,
                         friction=model_table.get("friction", 0.5), materials=mats, **kw)
    load = m.load_cycle(P0=P0, P1=P1, Q1=Q1, phase=phase)
    return m.system, load, m


#: The builder interface of ``shakedown.scenes`` (``build(model, load, scene_dir)``).
build = build_from_scene
