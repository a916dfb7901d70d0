"""What every stage takes: :class:`DiscreteSystem`, :class:`LoadCycle`, argument checks, errors.

Imports nothing else from :mod:`shakedown`; every other package may import from here.
"""

from .errors import (
    InputError,
    MissingDependencyError,
    NotPositiveDefiniteError,
    NotSymmetricError,
    SceneError,
    ShakedownError,
    ShapeError,
    SolverError,
    UnsafePathError,
)
from .loading import LoadCycle
from .system import CriticalFriction, DiscreteSystem

__all__ = [
    "DiscreteSystem",
    "CriticalFriction",
    "LoadCycle",
    "InputError",
    "MissingDependencyError",
    "NotPositiveDefiniteError",
    "NotSymmetricError",
    "SceneError",
    "ShakedownError",
    "ShapeError",
    "SolverError",
    "UnsafePathError",
]
