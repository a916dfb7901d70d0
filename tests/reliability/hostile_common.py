"""Shared pieces of the hostile-input suite (issue 24): scenes, a CLI runner, error matching.

Error classes are looked up by name so that the suite also runs (and counts its failures)
against code that predates them: a case that expects ``DamagedFileError`` accepts nothing else.
"""

from __future__ import annotations

import io
import os
from contextlib import redirect_stderr, redirect_stdout

import shakedown.model.errors as E

SCENE = """
[scene]
name = "hostile"
{units}
[model]
kind = "matrices"
A = {A}
B = [[0.2]]
C = [[3.0]]
friction = 0.4
[load]
q0 = [0.0]
p0 = [1.0]
q_cos = [1.0]
[analyses.bounds]
plots = false
"""

CYCLES_SCENE = SCENE.replace("[analyses.bounds]\nplots = false\n",
                             "[analyses.cycles]\nlam = 1.5\nsteps_per_cycle = 32\nplots = false\n")

CRACK_SCENE = """
[scene]
name = "cracks"
[model]
kind = "crack_network"
n_cracks = 4
density = 0.05
seed = {seed}
[load]
static = [-1.0, 0.0, -1.0]
cyclic = [0.0, 1.0, 0.0]
[analyses.sweep]
n_realisations = 1
lams = [0.5, 3.0]
n_states = 2
steps_per_cycle = 16
max_cycles = 40
n_workers = 1
plots = false
store_format = "{fmt}"
"""


def scene_text(A="[[2.0]]", units=""):
    return SCENE.format(A=A, units=units)


def error_class(name: str):
    """The package's error class ``name``, or a class nothing raises (older code)."""
    return getattr(E, name, type(f"Missing{name}", (Exception,), {}))


def run_cli(argv, stdout=None):
    """``(status, stdout text, stderr text)`` of ``shakedown argv`` run in this process; an
    exception escaping ``main`` (a raw traceback) is returned as status ``"raised <type>"``."""
    from shakedown.scenes.cli import main

    out, err = stdout or io.StringIO(), io.StringIO()
    try:
        with redirect_stdout(out), redirect_stderr(err):
            code = main(list(argv))
    except SystemExit as exc:  # argparse
        code = f"exit {exc.code}"
    except BaseException as exc:  # noqa: BLE001 - what escapes is the finding
        code = f"raised {type(exc).__name__}"
    text = out.getvalue() if isinstance(out, io.StringIO) else ""
    return code, text, err.getvalue()


def files_under(root):
    return sorted(os.path.relpath(os.path.join(d, f), root)
                  for d, _, fs in os.walk(root) for f in fs)


def snapshot(root):
    """``{relative path: bytes}`` of every file under ``root``."""
    out = {}
    for rel in files_under(root):
        with open(os.path.join(root, rel), "rb") as f:
            out[rel] = f.read()
    return out
