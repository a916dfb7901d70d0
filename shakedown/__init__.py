"""shakedown: elastic systems with Coulomb friction under periodic loading.

Core objects: :class:`DiscreteSystem` (reduced stiffness and friction), :class:`LoadCycle`
(periodic welded reactions); analyses: :func:`shakedown_bounds` / :func:`safe_region`
(shakedown load factors ``lam1``, ``lam2`` by linear programming).
"""

from importlib import import_module as _import_module

from .errors import (
    InputError,
    NotPositiveDefiniteError,
    NotSymmetricError,
    SceneError,
    ShakedownError,
    ShapeError,
    SolverError,
)
from .loading import LoadCycle
from .system import CriticalFriction, DiscreteSystem

__version__ = "0.1.0"

# analyses are imported lazily so that `import shakedown` stays light
_LAZY = {
    "shakedown_bounds": "bounds",
    "safe_region": "bounds",
    "ShakedownBounds": "bounds",
    "SafeRegion": "bounds",
    "solve_cycles": "evolution",
    "CycleRun": "evolution",
    "uniqueness_study": "uniqueness",
    "steady_cycle": "steady",
    "UniquenessStudy": "uniqueness",
    "SteadyCycle": "steady",
    "sample_initial_slips": "steady",
    "solve_step": "complementarity",
    "StepSolver": "complementarity",
    "StepResult": "complementarity",
    "STATE_NAMES": "complementarity",
    "EnergyIdentity": "evolution",
    "stability": None,
    "fe": None,
    "plotting": None,
    "scenes": None,
    "gallery": None,
    "sweep": None,
    "half_plane_model": "models.half_plane",
}


def __getattr__(name):
    if name in _LAZY:
        mod = _LAZY[name]
        if mod is None:
            return _import_module(f".{name}", __name__)
        return getattr(_import_module(f".{mod}", __name__), name)
    raise AttributeError(f"module 'shakedown' has no attribute {name!r}")


__all__ = [
    "DiscreteSystem",
    "CriticalFriction",
    "LoadCycle",
    "InputError",
    "ShapeError",
    "NotSymmetricError",
    "NotPositiveDefiniteError",
    "SceneError",
    "ShakedownError",
    "SolverError",
    *_LAZY,
]
