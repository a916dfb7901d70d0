"""Loads of FE bodies: tractions, pressures, body forces and prescribed displacements, with
``dim`` components (a pair in 2-D, a triple in 3-D), and load cases (dicts name -> loads)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model.errors import InputError

# --------------------------------------------------------------------------- loads


def _pair(name: str, value) -> tuple[float, ...] | object:
    """A finite pair ``(x, y)`` (2-D) or triple ``(x, y, z)`` (3-D), or a callable."""
    if callable(value):
        return value
    try:
        v = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a pair (x, y) of numbers (a triple (x, y, z) in 3-D); "
                         f"got {value!r}") from exc
    if v.shape not in ((2,), (3,)) or not np.all(np.isfinite(v)):
        raise InputError(f"{name} must be a finite pair (x, y) (a triple (x, y, z) in 3-D); got "
                         f"{value!r}")
    return tuple(float(x) for x in v)


@dataclass(frozen=True)
class Traction:
    """Surface traction on a named boundary [force / length^2 x thickness = force / length in
    2-D; force / length^2 in 3-D].

    ``value``: ``(t_x, t_y)`` (``(t_x, t_y, t_z)`` in 3-D) in the global frame, or a callable
    ``f(x) -> (dim, ...)`` of the points ``x`` (shape (dim, ...)); callables make the model
    uncacheable.
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
    """Body force per unit volume ``(b_x, b_y[, b_z])`` [force / length^3], or a callable of
    ``x``."""

    value: object
    body: int | None = None  # None: every body

    def __post_init__(self):
        object.__setattr__(self, "value", _pair("BodyForce.value", self.value))


@dataclass(frozen=True)
class Displacement:
    """Prescribed displacement ``(u_x, u_y[, u_z])`` on a named *Dirichlet* boundary [length]."""

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
