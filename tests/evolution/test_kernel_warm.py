"""When the compiled kernel is used (``shakedown.evolution.kernel_warm``, issue 25).

No test here compiles the kernel: the signature tests record the argument types of the real
calls (the kernel's entry points replaced by recorders that hand every step back to Python)
and compare them with those of :func:`kernel_warm.kernel_args`, the arguments the background
compile (and ``warm_up``) compiles for; a cold cache is an empty ``NUMBA_CACHE_DIR`` in a
subprocess under ``SHAKEDOWN_KERNEL=background`` with the background compile replaced.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution import fast_period, kernel, kernel_warm
from shakedown.evolution.complementarity import StepSolver

pytestmark = pytest.mark.skipif(not kernel.HAVE_KERNEL, reason="numba kernel not available")


def small_run_inputs():
    s = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                          [[1.5, 0.2], [0.2, 1.5]], 0.7)
    load = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0],
                                       q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
    return s, load


class Recorder:
    """Stands in for a dispatcher: records the numba types of each call's arguments and
    answers as the kernel does when it hands the step back (march: ``j0``; _solve_set:
    False, the assignment left to Python)."""

    def __init__(self, disp, answer):
        self.disp, self.answer, self.sigs = disp, answer, set()

    def __call__(self, *args):
        self.sigs.add(tuple(self.disp.typeof_pyval(a) for a in args))
        return self.answer(args)


def test_real_calls_have_the_warm_up_signature(monkeypatch):
    """Every call of ``march`` and ``_solve_set`` in a run (a 2-node system whose diagonal
    comes from ``system.diagonal()``, a strided read-only view) has the argument types the
    background compile compiles for: one signature, so that a run loads what was compiled
    instead of compiling its own (the workers of the default scene did: 20 s each)."""
    d_march, d_solve_set = kernel.march, kernel._solve_set
    march = Recorder(d_march, lambda a: a[5])
    solve_set = Recorder(d_solve_set, lambda a: False)
    monkeypatch.setattr(fast_period._k, "march", march)
    monkeypatch.setattr(kernel, "_solve_set", solve_set)
    monkeypatch.setenv("SHAKEDOWN_KERNEL", "compile")
    s, load = small_run_inputs()
    sd.solve_cycles(s, load, 1.5, solver=StepSolver(s))
    m_args, s_args = kernel_warm.kernel_args(n=3)
    assert march.sigs and solve_set.sigs
    assert march.sigs == {tuple(d_march.typeof_pyval(a) for a in m_args)}
    assert solve_set.sigs == {tuple(d_solve_set.typeof_pyval(a) for a in s_args)}


def test_readonly_and_writable_normalise_layout_and_flags():
    a = np.arange(12.0).reshape(3, 4)
    d = np.diagonal(a)  # strided and read-only
    r = kernel_warm.readonly(d)
    assert r.flags.c_contiguous and not r.flags.writeable
    np.testing.assert_array_equal(r, d)
    w = kernel_warm.writable(r)
    assert w.flags.c_contiguous and w.flags.writeable
    x = np.zeros(3)
    assert kernel_warm.writable(x) is x  # no copy when it is one already
    assert kernel.march.typeof_pyval(kernel_warm.readonly(d)) == kernel.march.typeof_pyval(
        kernel_warm.readonly(np.ones(3)))


def test_policy_from_the_environment(monkeypatch):
    for value, expected in (("numpy", "off"), ("off", "off"), ("background", "background"),
                            ("BACKGROUND", "background"), ("compile", "compile"), ("", "compile")):
        monkeypatch.setenv("SHAKEDOWN_KERNEL", value)
        assert kernel_warm.policy() == expected
    monkeypatch.delenv("SHAKEDOWN_KERNEL")
    assert kernel_warm.policy() == "compile"
    monkeypatch.setenv("SHAKEDOWN_KERNEL", "numpy")
    assert not kernel_warm.kernel_enabled()


def test_lock_lets_one_compile_run(tmp_path, monkeypatch):
    path = str(tmp_path / "k.lock")
    assert kernel_warm._take_lock(path)
    assert not kernel_warm._take_lock(path)  # held
    old = os.path.getmtime(path) - 2 * kernel_warm.LOCK_STALE_SECONDS
    os.utime(path, (old, old))
    assert kernel_warm._take_lock(path)  # stale: its process died


COLD = r"""
import os, sys, json
import numpy as np
import shakedown as sd
from shakedown.evolution import kernel_warm
from shakedown.evolution.complementarity import StepSolver
started = []
kernel_warm.start_background_compile = lambda: started.append(1)
s = sd.DiscreteSystem([[1.0, -0.3], [-0.3, 1.0]], [[-0.3, 0.9], [0.4, -0.1]],
                      [[1.5, 0.2], [0.2, 1.5]], 0.7)
load = sd.LoadCycle.from_harmonics([0.1, -0.1], [1.0, 1.0], q_cos=[0.5, 0.0],
                                   q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])
solver = StepSolver(s)
run = sd.solve_cycles(s, load, 1.5, solver=solver)
from shakedown.evolution import kernel
print(json.dumps(dict(kernel=solver.kernel, started=len(started), W=run.steady_dissipation,
                      compiled=len(kernel.march.signatures) + len(kernel._solve_set.signatures),
                      steps=solver.totals["steps"])))
"""


def test_cold_cache_runs_in_python_and_compiles_nothing(tmp_path):
    """``SHAKEDOWN_KERNEL=background`` with an empty numba cache: the solver's steps run in
    Python (no compile in the process: no signature of the kernel), the background compile is
    asked for, and the answer is that of the Python step."""
    env = dict(os.environ, SHAKEDOWN_KERNEL="background", NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run([sys.executable, "-c", COLD], env=env, capture_output=True, text=True,
                         check=True, cwd=os.path.dirname(os.path.dirname(os.path.dirname(
                             os.path.abspath(__file__)))))
    import json
    d = json.loads(out.stdout.strip().splitlines()[-1])
    assert d["kernel"] is False and d["started"] == 1 and d["compiled"] == 0
    assert d["steps"] > 0
    s, load = small_run_inputs()
    ref = sd.solve_cycles(s, load, 1.5, solver=StepSolver(s, kernel=False))
    assert d["W"] == ref.steady_dissipation


CLI_COLD = r"""
import os, sys
from shakedown.evolution import kernel_warm
from shakedown.scenes import cli

class Proc:
    pid = 12345

def fake():
    kernel_warm._state["started"] = Proc()
    return Proc()

kernel_warm.start_background_compile = fake
rc = cli.main(sys.argv[1:])
print("policy after:", os.environ.get("SHAKEDOWN_KERNEL"))
sys.exit(rc)
"""


@pytest.mark.parametrize("quiet", [False, True])
def test_command_on_a_cold_cache_says_what_it_did(tmp_path, quiet):
    """``shakedown cycles`` with an empty numba cache: the steps run in Python, the background
    compile is started, and the user is told so on stderr (not with ``--quiet``); the
    command's policy does not outlive it."""
    env = {k: v for k, v in os.environ.items() if k != "SHAKEDOWN_KERNEL"}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    argv = ["cycles", "two_node_coupled", "-o", str(tmp_path / "out")] + (["-q"] if quiet else [])
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, "-c", CLI_COLD, *argv], env=env, capture_output=True,
                       text=True, cwd=root)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "policy after: None" in r.stdout
    said = "numba's cache did not hold the compiled kernel" in r.stderr
    assert said is not quiet
    if not quiet:
        assert "(pid 12345)" in r.stderr and "ran in Python" in r.stderr


@pytest.mark.skipif(not os.path.exists("/proc/self/autogroup"), reason="Linux autogroups only")
@pytest.mark.parametrize("own_session", [True, False])
def test_background_compile_lowers_its_own_autogroup_only(own_session):
    """A detached compile (a session of its own, hence an autogroup of its own) lowers its
    group's priority, so that it does not take half of the CPU from the command's workers; a
    process sharing a session (e.g. with a terminal) never changes that session's group."""
    code = ("from shakedown.evolution.kernel_warm import _lower_autogroup; "
            "print(_lower_autogroup()); print(open('/proc/self/autogroup').read().strip())")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    before = open("/proc/self/autogroup").read().strip()
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root,
                       start_new_session=own_session)
    assert r.returncode == 0, r.stderr[-2000:]
    done, group = r.stdout.split("\n")[:2]
    if own_session:
        assert done == "True" and group.endswith("nice 19")
    else:
        assert done == "False" and group == before
    assert open("/proc/self/autogroup").read().strip() == before
