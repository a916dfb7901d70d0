"""shakedown: elastic systems with Coulomb friction under periodic loading.

Core objects: :class:`DiscreteSystem` (reduced stiffness and friction), :class:`LoadCycle`
(periodic welded reactions); analyses: :func:`shakedown_bounds` / :func:`safe_region`
(shakedown load factors ``lam1``, ``lam2`` by linear programming).
"""

import importlib.abc as _abc
import importlib.util as _util
import sys as _sys
from importlib import import_module as _import_module

from .model.errors import (
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
from .model.loading import LoadCycle
from .model.system import CriticalFriction, DiscreteSystem
from .model.version import __version__ as __version__

# analyses are imported lazily so that `import shakedown` stays light
_LAZY = {
    "shakedown_bounds": "bounds",
    "safe_region": "bounds",
    "ShakedownBounds": "bounds",
    "SafeRegion": "bounds",
    "solve_cycles": "evolution",
    "CycleRun": "evolution",
    "uniqueness_study": "evolution",
    "steady_cycle": "evolution",
    "UniquenessStudy": "evolution",
    "SteadyCycle": "evolution",
    "sample_initial_slips": "evolution",
    "solve_step": "evolution",
    "StepSolver": "evolution",
    "StepResult": "evolution",
    "STATE_NAMES": "evolution",
    "EnergyIdentity": "evolution",
    "stability": None,
    "fe": "models.fe",
    "plotting": None,
    "scenes": None,
    "gallery": None,
    "sweep": "studies.sweep",
    "half_plane_model": "models.half_plane",
    "half_space_model": "models.half_space",
    "UncondensedSystem": "model.uncondensed",
}

#: Modules that moved in the stage layout (0.2), by their old name: ``import shakedown.sweep``
#: and ``from shakedown.fe import FEModel`` keep working, silently (the old names are a contract).
_MOVED = {
    "errors": "model.errors",
    "validation": "model.validation",
    "system": "model.system",
    "loading": "model.loading",
    "lp": "bounds.lp",
    "dense_lp": "bounds.dense_lp",
    "complementarity": "evolution.complementarity",
    "lemke": "evolution.lemke",
    "events": "evolution.events",
    "steady": "evolution",  # 0.1 re-exported the uniqueness study here too
    "uniqueness": "evolution.uniqueness",
    "fe": "models.fe",
    "sweep": "studies.sweep",
    "store": "studies.store",
    "output": "scenes.output",
    "cli": "scenes.cli",
    "builders": "scenes.builders",
    "analyses": "scenes.analyses",
}


def __getattr__(name):
    if name in _LAZY:
        mod = _LAZY[name]
        if mod is None:
            return _import_module(f".{name}", __name__)
        if mod in ("models.fe", "studies.sweep"):
            return _import_module(f".{mod}", __name__)
        return getattr(_import_module(f".{mod}", __name__), name)
    raise AttributeError(f"module 'shakedown' has no attribute {name!r}")


class _MovedModules(_abc.MetaPathFinder, _abc.Loader):
    """Import ``shakedown.<old>`` (and its submodules) as the module at its new home.

    The module object is the real one (``sys.modules`` maps both names to it), so classes,
    functions and monkeypatching are shared; its ``__name__`` is the new one.
    """

    def find_spec(self, fullname, path=None, target=None):
        head, _, rest = fullname.partition(".")
        if head != __name__ or rest.partition(".")[0] not in _MOVED:
            return None
        return _util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        first, _, tail = module.__name__.split(".", 1)[1].partition(".")
        new = f"{__name__}.{_MOVED[first]}" + (f".{tail}" if tail else "")
        _sys.modules[module.__name__] = _import_module(new)


_sys.meta_path.insert(0, _MovedModules())

__all__ = [
    "DiscreteSystem",
    "CriticalFriction",
    "LoadCycle",
    "InputError",
    "MissingDependencyError",
    "ShapeError",
    "NotSymmetricError",
    "NotPositiveDefiniteError",
    "SceneError",
    "ShakedownError",
    "SolverError",
    "UnsafePathError",
    *_LAZY,
]
