"""The first ``shakedown run`` after installing against a warm one (issue 25), as a user meets it.

Every run writes into a fresh output folder (a folder with results would be resumed):

* ``cold`` (repeated): ``shakedown run`` (the built-in default scene) with an empty numba cache
  folder (``NUMBA_CACHE_DIR``: the cache of a fresh install), under the command's own policy
  (``SHAKEDOWN_KERNEL`` unset: steps in Python, the kernel compiled by a detached background
  process, :mod:`shakedown.evolution.kernel_warm`); the background compile of every cold run
  but the last is stopped (by its pid, printed in the run's note);
* ``background``: the script waits for the last one to finish (its lock file gone) and reports
  its CPU time (read from ``/proc`` while it runs, Linux only);
* ``warm`` (repeated): ``shakedown run`` again, loading what was compiled;
* with ``--baseline``: also ``SHAKEDOWN_KERNEL=compile`` with an empty cache (the behaviour
  before issue 25: the kernel compiled in the foreground before the workers start).

Wall time and CPU time (user + system of the command and its worker processes, not of the
detached compile) per run, the load average before each run.  Usage::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_first_run_cli.py [--repeats 3] [--baseline]
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_cli(cache: str, out: str, policy: str | None) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env.pop("SHAKEDOWN_KERNEL", None)
    if policy:
        env["SHAKEDOWN_KERNEL"] = policy
    load = os.getloadavg()[0]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "shakedown", "run", "-o", out], env=env,
                       capture_output=True, text=True, check=True, cwd=out)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return dict(wall=wall, cpu=cpu, load=load, stdout=p.stdout, stderr=p.stderr)


def lock_path() -> str:
    sys.path.insert(0, str(ROOT))
    from shakedown.evolution.kernel_warm import lock_path as path

    return path()


def wait_background(timeout: float = 3600.0) -> float | None:
    """Wait for the background compile (its lock file); its CPU seconds, None if none ran."""
    path = lock_path()
    cpu, t0 = None, time.time()
    while os.path.exists(path) and time.time() - t0 < timeout:
        cpu = max(cpu or 0.0, _compile_cpu())
        time.sleep(0.5)
    return cpu


def _compile_cpu() -> float:
    """CPU seconds of the running background compile (found in /proc by its command line)."""
    tick = os.sysconf("SC_CLK_TCK")
    for pid in os.listdir("/proc"):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            if b"kernel_warm import main" in cmd:
                f = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
                return (int(f[11]) + int(f[12])) / tick
        except (OSError, IndexError, ValueError):
            continue
    return 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cache = os.path.join(tmp, "numba")
        for k in range(args.repeats):  # cold: an empty cache each time
            shutil.rmtree(cache, ignore_errors=True)
            os.mkdir(cache)
            out = os.path.join(tmp, f"cold{k}")
            os.mkdir(out)
            cold = run_cli(cache, out, None)
            pid = re.search(r"\(pid (\d+)\)", cold["stderr"])
            last = k == args.repeats - 1
            if pid and not last:  # the background compile this run started: stopped (only
                try:  # the last one is waited for; it may have finished during the run)
                    os.kill(int(pid.group(1)), signal.SIGTERM)
                    while os.path.exists(f"/proc/{pid.group(1)}"):
                        time.sleep(0.2)
                except ProcessLookupError:
                    pass
                if os.path.exists(lock_path()):
                    os.remove(lock_path())
            print(f"{time.strftime('%H:%M:%S')} cold: {cold['wall']:.1f} s wall, "
                  f"{cold['cpu']:.1f} s CPU (load {cold['load']:.1f}; the note printed: "
                  f"{pid is not None})", flush=True)
        bg = wait_background()
        print(f"{time.strftime('%H:%M:%S')} background compile of the last cold run: "
              f"{bg if bg is None else round(bg, 1)} s CPU (load {os.getloadavg()[0]:.1f})",
              flush=True)
        for k in range(args.repeats):
            out = os.path.join(tmp, f"warm{k}")
            os.mkdir(out)
            warm = run_cli(cache, out, None)
            same = _results(cold) == _results(warm)
            print(f"{time.strftime('%H:%M:%S')} warm: {warm['wall']:.1f} s wall, "
                  f"{warm['cpu']:.1f} s CPU (load {warm['load']:.1f}); printed results the same "
                  f"as cold: {same}", flush=True)
        for k in range(args.repeats if args.baseline else 0):
            shutil.rmtree(cache, ignore_errors=True)
            os.mkdir(cache)
            out = os.path.join(tmp, f"base{k}")
            os.mkdir(out)
            base = run_cli(cache, out, "compile")
            print(f"{time.strftime('%H:%M:%S')} baseline (SHAKEDOWN_KERNEL=compile, cold): "
                  f"{base['wall']:.1f} s wall, {base['cpu']:.1f} s CPU (load "
                  f"{base['load']:.1f})", flush=True)


def _results(r) -> str:
    """The printed results without the run's own seconds (``wall_s``)."""
    text = r["stdout"].split("results written")[0]
    return "\n".join(line for line in text.splitlines() if "wall_s" not in line)


if __name__ == "__main__":
    main()
