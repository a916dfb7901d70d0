"""Every public module imports on its own, in any order (no import cycles), and the lazy names resolve."""

import functools
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import pytest

MODULES = [
    "shakedown", "shakedown.model", "shakedown.bounds", "shakedown.bounds.lp", "shakedown.bounds.dense_lp",
    "shakedown.evolution", "shakedown.evolution.complementarity", "shakedown.evolution.lemke",
    "shakedown.evolution.events", "shakedown.evolution.cycles", "shakedown.evolution.steady",
    "shakedown.evolution.uniqueness", "shakedown.studies.store", "shakedown.studies.sweep",
    "shakedown.scenes", "shakedown.scenes.cli", "shakedown.scenes.output", "shakedown.gallery",
    "shakedown.stability", "shakedown.models.fe", "shakedown.plotting", "shakedown.plotting.bounds",
    "shakedown.plotting.cycles", "shakedown.plotting.sweep", "shakedown.plotting.stability",
    "crack_networks",
]

#: Module paths of version 0.1, before the stage layout: they must keep importing, as the same
#: module objects, with no warning.
OLD_PATHS = {
    "shakedown.system": "shakedown.model.system", "shakedown.loading": "shakedown.model.loading",
    "shakedown.errors": "shakedown.model.errors", "shakedown.validation": "shakedown.model.validation",
    "shakedown.lp": "shakedown.bounds.lp", "shakedown.dense_lp": "shakedown.bounds.dense_lp",
    "shakedown.complementarity": "shakedown.evolution.complementarity",
    "shakedown.lemke": "shakedown.evolution.lemke", "shakedown.events": "shakedown.evolution.events",
    "shakedown.steady": "shakedown.evolution", "shakedown.uniqueness": "shakedown.evolution.uniqueness",
    "shakedown.store": "shakedown.studies.store", "shakedown.sweep": "shakedown.studies.sweep",
    "shakedown.output": "shakedown.scenes.output", "shakedown.cli": "shakedown.scenes.cli",
    "shakedown.fe": "shakedown.models.fe", "shakedown.fe.condense": "shakedown.models.fe.condense",
    "shakedown.builders.matrices": "shakedown.scenes.builders.matrices",
    "shakedown.analyses.bounds": "shakedown.scenes.analyses.bounds",
}


def _old_path_code(old: str) -> str:
    return (f"import warnings; warnings.simplefilter('error'); import sys, importlib; "
            f"a = importlib.import_module({old!r}); b = importlib.import_module({OLD_PATHS[old]!r}); "
            f"assert a is b, (a, b); assert sys.modules[{old!r}] is b")


@functools.cache
def _fresh_imports() -> dict:
    """Every fresh-interpreter import check of this file, run once, as many at once as there are
    cores (each is a new interpreter importing the package: ~2 s); by code string."""
    codes = [f"import {m}" for m in MODULES] + [_old_path_code(old) for old in OLD_PATHS]
    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:
        runs = pool.map(lambda c: subprocess.run([sys.executable, "-c", c], capture_output=True,
                                                 text=True), codes)
        return dict(zip(codes, runs, strict=True))


@pytest.mark.parametrize("old", sorted(OLD_PATHS))
def test_old_module_paths_still_import(old):
    r = _fresh_imports()[_old_path_code(old)]
    assert r.returncode == 0, r.stderr


def test_public_names_of_version_0_1():
    code = ("import shakedown as sd; from shakedown.sweep import run_sweep, SweepSpec; "
            "from shakedown.fe import FEModel; from shakedown.bounds import extreme_constraints; "
            "from shakedown.scenes import build, load_scene; "
            "assert sd.sweep.run_sweep is run_sweep and sd.fe.FEModel is FEModel; "
            "assert callable(sd.solve_cycles) and callable(sd.shakedown_bounds) and sd.stability.mceip_mu")
    r = subprocess.run([sys.executable, "-W", "error", "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("module", MODULES)
def test_module_imports_first(module):
    r = _fresh_imports()[f"import {module}"]
    assert r.returncode == 0, r.stderr


def test_lazy_public_names_resolve():
    import shakedown as sd

    for name in sd.__all__:
        assert getattr(sd, name) is not None, name


def test_shakedown_does_not_import_crack_networks_or_fe():
    code = ("import sys, shakedown; import shakedown.scenes.files, shakedown.bounds; "
            "assert 'crack_networks' not in sys.modules and 'skfem' not in sys.modules")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
