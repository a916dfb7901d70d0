#!/usr/bin/env python3
"""Mutation check of the core numerics: do the tests catch small realistic bugs?

A hand-written list of mutations (:data:`MUTATIONS`); each is one file, an exact snippet of
its source, the replacement (a plausible bug), and the tests that should catch it.  For each
mutation the script copies the repository (tracked and untracked, non-ignored files) once into
a temporary folder -- never touching the working tree --, writes the mutated file there, runs
the listed tests against that copy (``PYTHONPATH`` set to it, ``CI=1`` so hypothesis is
derandomised) with a time limit, and restores the file.  A mutation is

* ``killed``   -- the tests fail (or time out: a mutation that makes a loop run forever is
                  caught by the time limit, reported as ``killed (timeout)``);
* ``survived`` -- the tests pass;
* ``stale``    -- its original snippet no longer occurs in the file (the code was rewritten):
                  skipped, not counted; update the snippet.

The kill rate is ``killed / (killed + survived)``.  Run by hand::

    python3 tools/mutation_check.py                 # all mutations
    python3 tools/mutation_check.py --only B1,S3    # a few, by id
    python3 tools/mutation_check.py --list          # the list, with stale ones marked
    python3 tools/mutation_check.py --markdown out.md

Record the last result in ``benchmarks/RESULTS_mutation.md`` (survivors explained).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutation:
    id: str
    area: str
    file: str
    original: str
    replacement: str
    tests: tuple
    what: str


def M(id, area, file, original, replacement, tests, what):
    return Mutation(id, area, file, original, replacement, tuple(tests.split()), what)


T_STEP = "tests/evolution/test_complementarity.py tests/evolution/test_step_self_checks.py"
T_BOUNDS = "tests/bounds/test_bounds.py tests/bounds/test_bounds_oracles.py tests/bounds/test_lp.py"
T_EVO = "tests/evolution/test_evolution.py tests/evolution/test_study_outputs.py"
T_STEADY = "tests/evolution/test_steady.py"
T_UNIQ = "tests/evolution/test_uniqueness.py tests/evolution/test_study_outputs.py"
T_SWEEP = "tests/studies/test_sweep.py tests/studies/test_sweep_outputs.py"
T_KACH = "tests/crack_networks/test_kachanov.py tests/crack_networks/test_kachanov_oracles.py"
T_FE = "tests/models/test_fe.py tests/models/test_fe_checks.py"
T_STAB = "tests/stability/test_stability.py tests/stability/test_stability_cycle.py"
T_SYS = "tests/model/test_system.py"

MUTATIONS = [
    # ------------------------------------------------------------------ steps (the 9 bugs first)
    M("S1", "steps", "shakedown/evolution/complementarity.py",
      "comp = self.residuals(z, q, p, allowed, forced, scale)",
      "comp = 0.0 * self.residuals(z, q, p, allowed, forced, scale)",
      T_STEP, "issue-15 bug 1: reported complementarity residual hard-wired to 0"),
    M("S2", "steps", "shakedown/evolution/lemke.py",
      "r = int(ties[z0_row[0]]) if z0_row.size else _lexmin_row(T, ties, entering, n)",
      "r = int(ties[z0_row[0]]) if z0_row.size else int(ties[0])",
      T_STEP, "issue-15 bug 2: Lemke without the lexicographic tie-breaking rule (first row)"),
    M("S3", "steps", "shakedown/evolution/lemke.py",
      "r = int(ties[z0_row[0]]) if z0_row.size else _lexmin_row(T, ties, entering, n)",
      "r = int(ties[z0_row[0]]) if z0_row.size else int(ties[-1])",
      T_STEP, "Lemke tie rule: last tied row"),
    M("S4", "steps", "shakedown/evolution/complementarity.py",
      "cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sp / ft, -np.inf)",
      "cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sm / ft, -np.inf)",
      T_STEP, "stick node violating the forward cone switched by the backward test"),
    M("S5", "steps", "shakedown/evolution/complementarity.py",
      "xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(-dv, 0) / ds[:n])",
      "xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(dv, 0) / ds[:n])",
      T_STEP, "verification pairs dv- with the wrong sign"),
    M("S6", "steps", "shakedown/evolution/complementarity.py",
      "eq = float(max(np.abs(qe - q).max(), np.abs(pe - p).max()) / scale)",
      "eq = float(np.abs(qe - q).max() / scale)",
      T_STEP, "equilibrium residual ignores the normal reactions"),
    M("S7", "steps", "shakedown/evolution/complementarity.py",
      "if sol.success and wp:",
      "if sol.success:",
      T_STEP, "step called unique above the critical friction"),
    M("S8", "steps", "shakedown/evolution/complementarity.py",
      "p0 = p_w + self.Bt @ v_prev",
      "p0 = p_w + self.B @ v_prev",
      T_STEP, "B instead of B^T in the normal reaction of the previous slips"),
    M("S9", "steps", "shakedown/model/system.py",
      "schur = self.A - self.B @ np.linalg.solve(self.C, self.B.T)",
      "schur = self.A",
      T_SYS, "issue-15 bug 4: sufficient critical-friction bound with A instead of the Schur complement"),
    M("S10", "steps", "shakedown/model/system.py",
      "node_bounds = np.where((diagB > 0) & (f > 0), np.diag(self.A) / (diagB * f), np.inf)",
      "node_bounds = np.where((diagB > 0) & (f > 0), np.diag(self.C) / (diagB * f), np.inf)",
      T_SYS, "single-node critical friction with C instead of A"),
    # ------------------------------------------------------------------ evolution, events, energy
    M("E1", "evolution", "shakedown/evolution/cycles.py",
      "stuck = np.flatnonzero(~slipped & np.all(contact, axis=0))",
      "stuck = np.flatnonzero(~slipped)",
      T_EVO, "issue-15 bug 5: separated (open) nodes reported among the permanently stuck"),
    M("E2", "evolution", "shakedown/evolution/cycles.py",
      "steady_W = float(np.mean([r.dissipation for r in orbit]))",
      "steady_W = float(orbit[0].dissipation)",
      T_EVO, "steady W of a period-2 orbit from its first period only"),
    M("E3", "evolution", "shakedown/evolution/cycles.py",
      "shook = not bool(np.any(slipped))",
      "shook = not bool(np.all(slipped))",
      T_EVO, "shakedown when any node stops slipping"),
    M("E4", "events", "shakedown/evolution/events.py",
      "<<E4>>", "<<E4>>",
      T_EVO, "placeholder"),
    # ------------------------------------------------------------------ bounds
    M("B1", "bounds", "shakedown/bounds/dense_lp.py",
      "comp = (np.abs(Y) * np.abs(np.minimum(r, 0.0))).max(axis=1) / ys",
      "comp = 0.0 * ys",
      T_BOUNDS, "issue-15 bug 3 (part): dense-LP certificate ignores complementarity"),
    M("B2", "bounds", "shakedown/bounds/dense_lp.py",
      "stat = np.abs(e[None, :] - Y @ A).max(axis=1) / ys",
      "stat = 0.0 * ys",
      T_BOUNDS, "issue-15 bug 3 (part): dense-LP certificate ignores stationarity"),
    M("B3", "bounds", "shakedown/bounds/dense_lp.py",
      "stat = float(np.abs(e - A.T @ y).max(initial=0.0) / max(ys * rownorm.max(), 1e-300))",
      "stat = 0.0",
      T_BOUNDS, "kkt_residuals ignores stationarity"),
    M("B4", "bounds", "shakedown/bounds/dense_lp.py",
      "comp = float(np.max(np.abs(y) * np.abs(np.minimum(r, 0.0)), initial=0.0) / ys)",
      "comp = 0.0",
      T_BOUNDS, "kkt_residuals ignores complementarity"),
]

# ---------------------------------------------------------------------------- running


def files_to_copy(root: Path) -> list[str]:
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=root,
                         capture_output=True, text=True, check=True).stdout.split("\n")
    return [f for f in out if f and (root / f).is_file()]


def make_copy(root: Path, dest: Path) -> None:
    for f in files_to_copy(root):
        target = dest / f
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(root / f, target)


def status_of(m: Mutation, root: Path) -> str:
    path = root / m.file
    if not path.exists() or m.original not in path.read_text():
        return "stale"
    return "ready"


def run_one(m: Mutation, copy: Path, timeout: float) -> tuple[str, float, str]:
    path = copy / m.file
    src = path.read_text()
    if m.original not in src:
        return "stale", 0.0, "original snippet not found"
    path.write_text(src.replace(m.original, m.replacement, 1))
    env = dict(os.environ, PYTHONPATH=str(copy), CI="1", OPENBLAS_NUM_THREADS="1",
               PYTHONDONTWRITEBYTECODE="1")
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-rf", "-p", "no:cacheprovider", *m.tests]
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, cwd=copy, env=env, capture_output=True, text=True,
                           timeout=timeout)
        dt = time.perf_counter() - t0
        lines = r.stdout.strip().splitlines()
        failed = [ln.split()[1] for ln in lines if ln.startswith("FAILED ")]
        tail = failed[0].split("::", 1)[-1] if failed else (lines or [""])[-1]
        if r.returncode == 0:
            outcome = "survived"
        elif r.returncode == 1:
            outcome = "killed"
        else:
            outcome = f"error (pytest exit {r.returncode})"
    except subprocess.TimeoutExpired:
        dt = time.perf_counter() - t0
        outcome, tail = "killed (timeout)", f"no result within {timeout:g} s"
    finally:
        path.write_text(src)
    return outcome, dt, tail


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", help="comma-separated mutation ids")
    ap.add_argument("--area", help="run only this area")
    ap.add_argument("--list", action="store_true", help="list the mutations and exit")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per mutation")
    ap.add_argument("--markdown", help="write the result table to this file")
    args = ap.parse_args(argv)
    muts = [m for m in MUTATIONS if "<<" not in m.original]
    if args.only:
        keep = set(args.only.split(","))
        muts = [m for m in muts if m.id in keep]
    if args.area:
        muts = [m for m in muts if m.area == args.area]
    if args.list:
        for m in muts:
            print(f"{m.id:5s} {m.area:11s} {status_of(m, ROOT):6s} {m.file}: {m.what}")
        return 0
    rows = []
    with tempfile.TemporaryDirectory(prefix="mutation_check_") as tmp:
        copy = Path(tmp) / "repo"
        make_copy(ROOT, copy)
        for m in muts:
            outcome, dt, tail = run_one(m, copy, args.timeout)
            rows.append((m, outcome, dt, tail))
            print(f"{m.id:5s} {outcome:18s} {dt:6.1f} s  {m.what}  [{tail}]", flush=True)
    counted = [r for r in rows if r[1].startswith(("killed", "survived"))]
    killed = sum(r[1].startswith("killed") for r in counted)
    stale = sum(r[1] == "stale" for r in rows)
    errors = [r for r in rows if r[1].startswith("error")]
    rate = killed / len(counted) if counted else float("nan")
    summary = (f"{len(rows)} mutations: {killed} killed, {len(counted) - killed} survived, "
               f"{stale} stale, {len(errors)} errors; kill rate {100 * rate:.1f} %")
    print(summary)
    if args.markdown:
        lines = ["| id | area | file | mutation | outcome | first failing test | time [s] |",
                 "| --- | --- | --- | --- | --- | --- | --- |"]
        for m, outcome, dt, tail in rows:
            caught = tail if outcome == "killed" else ""
            lines.append(f"| {m.id} | {m.area} | `{m.file}` | {m.what} | {outcome} | {caught} | "
                         f"{dt:.1f} |")
        Path(args.markdown).write_text(summary + "\n\n" + "\n".join(lines) + "\n")
    return 0 if not errors else 2


if __name__ == "__main__":
    sys.exit(main())
