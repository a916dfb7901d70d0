"""The first ``shakedown run`` after installing against a warm one (issue 25), as a user meets it.

Every run writes into a fresh output folder (a folder with results would be resumed):

* ``cold`` (repeated): ``shakedown run`` (the built-in default scene) with an empty numba cache
  folder (``NUMBA_CACHE_DIR``: the cache of a fresh install), under the command's own policy
  (``SHAKEDOWN_KERNEL`` unset: steps in Python, the kernel compiled by a detached background
  process, :mod:`shakedown.evolution.kernel_warm`); that background compile is stopped after
  the run (by its pid, printed in the run's note), so that it does not load the next runs;
* ``warm`` (repeated): ``shakedown run`` again, loading what was compiled;
* with ``--baseline DIR`` (a source tree, e.g. ``git archive main | tar -x -C DIR``): the same
  cold and warm runs of that tree, alternated with this one's (side by side, at the same load).

The warm runs use a cache filled beforehand by one foreground compile per tree.  The stdout of
every run is compared with the first cold run of this tree (``wall_s`` left out).

Wall time and CPU time (user + system of the command and its worker processes, not of the
detached compile) per run, the load average before each run.  Usage::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_first_run_cli.py [--repeats 3] [--baseline DIR]
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _env(root: Path, cache: str, policy: str | None) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))
    env.pop("SHAKEDOWN_KERNEL", None)
    if policy:
        env["SHAKEDOWN_KERNEL"] = policy
    return env


def run_cli(root: Path, cache: str, out: str, policy: str | None = None) -> dict:
    """``shakedown run -o OUT`` of the tree ``root``; wall and CPU (the command and its worker
    processes: every waited-for descendant, not the detached background compile)."""
    env = _env(root, cache, policy)
    load = os.getloadavg()[0]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "shakedown", "run", "-o", out], env=env,
                       capture_output=True, text=True, check=True, cwd=out)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return dict(wall=wall, cpu=cpu, load=load, stdout=p.stdout, stderr=p.stderr)


def lock_of(root: Path) -> str:
    """The background compile's lock file of the tree ``root`` (its own ``lock_path``)."""
    return subprocess.run([sys.executable, "-c", "from shakedown.evolution.kernel_warm import "
                           "lock_path; print(lock_path())"], env=_env(root, "", None),
                          cwd=tempfile.gettempdir(), capture_output=True, text=True,
                          check=True).stdout.strip()


def stop_background(run: dict, root: Path) -> bool:
    """Stop the background compile a cold run started (its pid is in the run's note), wait for
    it to exit and remove its lock file (a process stopped by SIGTERM leaves it); whether there
    was one."""
    pid = re.search(r"\(pid (\d+)\)", run["stderr"])
    if not pid:
        return False
    try:
        os.kill(int(pid.group(1)), signal.SIGTERM)
        while os.path.exists(f"/proc/{pid.group(1)}"):
            time.sleep(0.2)
    except ProcessLookupError:
        pass
    lock = lock_of(root)
    if os.path.exists(lock):
        os.remove(lock)
    return True


def fill_cache(root: Path, cache: str) -> float:
    """Compile the kernel of ``root`` into ``cache`` in the foreground; its CPU seconds."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", "from shakedown.evolution.kernel_warm import warm_up; "
                    "warm_up()"], env=_env(root, cache, "compile"), check=True,
                   cwd=tempfile.gettempdir())  # not this folder: '' first on sys.path
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def _line(kind, name, r, same=None):
    extra = "" if same is None else f"; printed results the same as this tree's first cold: {same}"
    print(f"{time.strftime('%H:%M:%S')} {kind:4s} {name:8s} {r['wall']:6.1f} s wall "
          f"{r['cpu']:6.1f} s CPU  load {r['load']:.1f}{extra}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline", type=Path, default=None,
                    help="a source tree to measure side by side (e.g. an archive of main)")
    ap.add_argument("--skip-cold", action="store_true", help="only the warm runs")
    args = ap.parse_args()
    trees = [("this", ROOT)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    print(f"machine: {os.cpu_count()} cores, {os.uname().machine}, Python "
          f"{sys.version.split()[0]}; uptime: {os.popen('uptime').read().strip()}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        first = {}
        for k in range(0 if args.skip_cold else args.repeats):  # cold: an empty cache each
            # time, trees alternated
            for name, root in trees:
                cache = os.path.join(tmp, f"cold-{name}-{k}")
                out = os.path.join(tmp, f"out-cold-{name}-{k}")
                os.mkdir(cache)
                os.mkdir(out)
                r = run_cli(root, cache, out)
                stop_background(r, root)
                first.setdefault(name, _results(r))
                _line("cold", name, r, _results(r) == first[name])
        caches = {}
        for name, root in trees:
            caches[name] = os.path.join(tmp, f"warm-{name}")
            os.mkdir(caches[name])
            cpu = fill_cache(root, caches[name])
            print(f"{time.strftime('%H:%M:%S')} compile of {name} (foreground, the cache of its "
                  f"warm runs): {cpu:.1f} s CPU (load {os.getloadavg()[0]:.1f})", flush=True)
        for k in range(args.repeats):
            for name, root in trees:
                out = os.path.join(tmp, f"out-warm-{name}-{k}")
                os.mkdir(out)
                r = run_cli(root, caches[name], out)
                first.setdefault(name, _results(r))
                _line("warm", name, r, _results(r) == first[name])
        if len(first) == 2:
            print("printed results of this tree and the baseline the same:",
                  first["this"] == first["baseline"], flush=True)


def _results(r) -> str:
    """The printed results without the run's own seconds (``wall_s``) and the scene file's path
    (which names the source tree)."""
    text = r["stdout"].split("results written")[0]
    return "\n".join(line for line in text.splitlines()
                     if "wall_s" not in line and not line.startswith("scene: "))


if __name__ == "__main__":
    main()
