"""Argument checks shared by the analyses (messages name the field, the value and the fix)."""

from __future__ import annotations

import numpy as np

from .errors import InputError, ShapeError


def check_same_nodes(system, load) -> None:
    """``load`` must have one entry per node of ``system``."""
    if load.n_nodes != system.n_nodes:
        raise ShapeError(
            f"load has {load.n_nodes} nodes but the system has {system.n_nodes}; build the "
            "LoadCycle with arrays of shape (N,)"
        )


def check_load_factor(lam) -> float:
    """A finite load factor ``lam >= 0`` as a float."""
    try:
        lam = float(lam)
    except (TypeError, ValueError) as exc:
        raise InputError(f"lam must be a number >= 0; got {lam!r}") from exc
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam must be a finite number >= 0; got {lam}")
    return lam


def check_node_vector(name: str, value, n: int, *, nonneg: bool = False,
                      what: str = "value") -> np.ndarray:
    """A finite array of shape ``(n,)`` (one ``what`` per node); ``nonneg`` forbids negatives."""
    try:
        x = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a real array of shape ({n},); got {value!r}") from exc
    if x.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},) (one {what} per node); got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be finite; got {x[~np.isfinite(x)][0]}")
    if nonneg and np.any(x < 0):
        j = int(np.argmax(x < 0))
        raise InputError(f"{name} must be >= 0 (nodes cannot penetrate); node {j} has {x[j]}")
    return x
