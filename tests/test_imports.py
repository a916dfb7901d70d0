"""Every public module imports on its own, in any order (no import cycles), and the lazy names resolve."""

import subprocess
import sys

import pytest

MODULES = [
    "shakedown", "shakedown.system", "shakedown.loading", "shakedown.bounds", "shakedown.lp",
    "shakedown.dense_lp", "shakedown.complementarity", "shakedown.lemke", "shakedown.events",
    "shakedown.evolution", "shakedown.steady", "shakedown.uniqueness", "shakedown.store",
    "shakedown.sweep", "shakedown.scenes", "shakedown.cli", "shakedown.gallery", "shakedown.output",
    "shakedown.stability", "shakedown.fe", "shakedown.plotting", "shakedown.plotting.bounds",
    "shakedown.plotting.cycles", "shakedown.plotting.sweep", "shakedown.plotting.stability",
    "crack_networks",
]


@pytest.mark.parametrize("module", MODULES)
def test_module_imports_first(module):
    r = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_lazy_public_names_resolve():
    import shakedown as sd

    for name in sd.__all__:
        assert getattr(sd, name) is not None, name


def test_shakedown_does_not_import_crack_networks_or_fe():
    code = ("import sys, shakedown; import shakedown.scenes, shakedown.bounds; "
            "assert 'crack_networks' not in sys.modules and 'skfem' not in sys.modules")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
