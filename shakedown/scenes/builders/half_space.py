"""Scene model kind ``"half_space"``: two half-spaces (sphere on flat) pressed by ``P(t)``, sheared
by ``(Q_x(t), Q_y(t))``: a 3-D system (MODEL.md s.8.5).

``[model]`` keys
    ``profile`` (``"sphere"`` default, ``"ellipsoid"``, ``"flat_rounded"``, ``"height_map"``),
    ``radius`` [length] (sphere; edge radius of flat_rounded), ``radii`` (``[R_x, R_y]``,
    ellipsoid), ``flat_radius`` [length] (flat_rounded), ``heights`` (``n x n`` nested list,
    height_map), ``n_cells`` (cells per side, default 15), ``width`` [length] (default, sphere
    only: ``2.4 a(P0 + |P1|)``), ``friction`` (default 0.5), ``E1``, ``nu1``, ``E2``, ``nu2``
    (defaults 1.0, 0.3, 1.0, 0.3; ``E2 = inf`` is a rigid body 2).
``[load]`` keys
    ``P0`` (> 0), ``P1``, ``Qx``, ``Qy`` [force], ``phase`` [rad] or ``phase_deg``:
    ``P(t) = P0 + lam P1 cos(2 pi t + phase)``, ``Q_x = lam Qx cos 2 pi t``, ``Q_y = lam Qy sin 2 pi t``.

The third returned object is the :class:`shakedown.models.half_space.HalfSpaceModel`.
"""

from __future__ import annotations

from pathlib import Path

from ...model.errors import InputError, SceneError
from .half_plane import _check as _check_kind
from .half_plane import normal_load

MODEL_KEYS = {
    "profile": (str,), "radius": (int, float), "radii": (list,), "flat_radius": (int, float),
    "heights": (list,), "n_cells": (int,), "width": (int, float), "friction": (int, float),
    "E1": (int, float), "nu1": (int, float), "E2": (int, float), "nu2": (int, float),
}
LOAD_KEYS = {"P0": (int, float), "P1": (int, float), "Qx": (int, float), "Qy": (int, float),
             "phase": (int, float), "phase_deg": (int, float)}

#: The built-in fretting scene (sphere on flat, oscillating tangential load).
SPHERE_FRETTING = Path(__file__).resolve().parents[1] / "builtin" / "sphere_fretting.toml"


def _check(table, allowed, name):
    try:
        _check_kind(table, allowed, name)
    except SceneError as e:
        raise SceneError(str(e).replace("kind 'half_plane'", "kind 'half_space'")) from None


def build_from_scene(model_table: dict, load_table: dict, base_dir=None):
    """``(DiscreteSystem, LoadCycle, HalfSpaceModel)`` from a scene's ``[model]``/``[load]`` tables.

    ``base_dir`` is accepted for the builder interface (no file is read).
    """
    from ...models.half_plane.model import _positive
    from ...models.half_space.continuum import hertz_radius
    from ...models.half_space.influence import material_constants
    from ...models.half_space.model import DENSE_MAX_CELLS, half_space_model

    model_table = {k: v for k, v in model_table.items() if k != "kind"}
    _check(model_table, MODEL_KEYS, "model")
    _check(load_table, LOAD_KEYS, "load")
    P0, P1, phase = normal_load(load_table, "mean normal force")
    profile = model_table.get("profile", "sphere")
    mats = ((model_table.get("E1", 1.0), model_table.get("nu1", 0.3)),
            (model_table.get("E2", 1.0), model_table.get("nu2", 0.3)))
    kw = {k: model_table[k] for k in ("radius", "radii", "flat_radius", "heights") if k in model_table}
    width = model_table.get("width")
    try:
        if width is None:
            if profile != "sphere" or "radius" not in kw:
                raise SceneError("[model] key 'width' is required unless profile = 'sphere' with a "
                                 "'radius' (then it defaults to 2.4 a(P0 + |P1|))")
            e_star = material_constants(mats)[0]
            width = 2.4 * float(hertz_radius(_positive("P0", P0) + abs(P1),
                                             _positive("radius", kw["radius"]), e_star))
        m = half_space_model(profile, n_cells=model_table.get("n_cells", 15), width=width,
                             friction=model_table.get("friction", 0.5), materials=mats, **kw)
        if m.n_cells > DENSE_MAX_CELLS:  # no dense system: the matrix-free fretting analysis only
            return _TooLarge(m, "system"), _TooLarge(m, "load"), m
        load = m.load_cycle(P0=P0, P1=P1, Qx=load_table.get("Qx", 0.0), Qy=load_table.get("Qy", 0.0),
                            phase=phase)
    except SceneError:
        raise
    except InputError as e:
        raise SceneError(f"[model]/[load] of kind 'half_space': {e}") from None
    return m.system, load, m


def _dense_max():
    from ...models.half_space.model import DENSE_MAX_CELLS

    return DENSE_MAX_CELLS


class _TooLarge:
    """Stands for the dense system (or its load) of a model above ``DENSE_MAX_CELLS`` cells: any
    use raises a :class:`SceneError` that names the size and what runs at it."""

    def __init__(self, model, what):
        self._model, self._what = model, what

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise SceneError(
            f"[model] n_cells = {self._model.n} gives {self._model.n_cells} cells, above "
            f"DENSE_MAX_CELLS = {_dense_max()}: no dense {self._what} is built; only the "
            "'fretting' analysis (matrix-free FFT steps) runs at this size (or lower n_cells)")


#: The builder interface of ``shakedown.scenes`` (``build(model, load, scene_dir)``).
build = build_from_scene
