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
    equivalent: str = ""


def M(id, area, file, original, replacement, tests, what, equivalent=""):
    """One mutation; ``equivalent`` (a reason) marks a mutant that cannot change any result
    (it is run and reported, but left out of the kill rate)."""
    return Mutation(id, area, file, original, replacement, tuple(tests.split()), what, equivalent)


T_STEP = "tests/evolution/test_complementarity.py tests/evolution/test_step_self_checks.py"
T_BOUNDS = ("tests/bounds/test_bounds.py tests/bounds/test_bounds_oracles.py tests/bounds/test_lp.py "
            "tests/bounds/test_bounds_units.py")
T_EVO = "tests/evolution/test_evolution.py tests/evolution/test_study_outputs.py"
T_STEADY = "tests/evolution/test_steady.py tests/evolution/test_study_outputs.py"
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
    M("S4", "steps", "shakedown/evolution/active_set.py",
      "cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sp / ft, -np.inf)",
      "cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sm / ft, -np.inf)",
      T_STEP + " " + T_EVO,
      "rate problems (events): stick node violating the forward cone switched by the backward test"),
    M("S11", "steps", "shakedown/evolution/active_set.py",
      "np.add(fp, q, out=cand[FORWARD])",
      "np.subtract(fp, q, out=cand[FORWARD])",
      T_STEP, "step problems: stick node violating the forward cone switched by the backward test"),
    M("S5", "steps", "shakedown/evolution/active_set.py",
      "xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(-dv, 0) / ds[:n])",
      "xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(dv, 0) / ds[:n])",
      T_STEP, "verification pairs dv- with the wrong sign"),
    M("S6", "steps", "shakedown/evolution/complementarity.py",
      "eq = float(max(np.abs(r[:n] - q).max(), np.abs(r[n:] - p).max()) / scale)",
      "eq = float(np.abs(r[:n] - q).max() / scale)",
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
    M("E1", "evolution", "shakedown/evolution/cycle_results.py",
      "stuck = np.flatnonzero(~slipped & np.all(contact, axis=0))",
      "stuck = np.flatnonzero(~slipped)",
      T_EVO, "issue-15 bug 5: separated (open) nodes reported among the permanently stuck"),
    M("E2", "evolution", "shakedown/evolution/cycle_results.py",
      "steady_W = float(np.mean([r.dissipation for r in orbit]))",
      "steady_W = float(orbit[0].dissipation)",
      T_EVO, "steady W of a period-2 orbit from its first period only"),
    M("E3", "evolution", "shakedown/evolution/cycle_results.py",
      "shook = not bool(np.any(slipped))",
      "shook = not bool(np.all(slipped))",
      T_EVO, "shakedown when any node stops slipping"),
    M("E4", "evolution", "shakedown/evolution/cycle_results.py",
      "slipped = travel > SHAKEDOWN_FACTOR * tol",
      "slipped = travel > 1e6 * SHAKEDOWN_FACTOR * tol",
      T_EVO, "slip threshold of S0 a million times too loose"),
    # ------------------------------------------------------------------ events
    M("EV1", "events", "shakedown/evolution/events.py",
      "allowed[c, FORWARD] = f[c] * p[c] + q[c] <= ft",
      "allowed[c, FORWARD] = f[c] * p[c] - q[c] <= ft",
      T_EVO, "event path: forward slip allowed by the backward cone test"),
    M("EV2", "events", "shakedown/evolution/events.py",
      "W += float(np.sum(f[slip] * 0.5 * (p[slip] + p_new[slip]) * np.abs(dv[slip])))",
      "W += float(np.sum(f[slip] * p[slip] * np.abs(dv[slip])))",
      T_EVO, "event dissipation by the left-point rule (p varies along a segment)"),
    M("EV3", "events", "shakedown/evolution/events.py",
      "(p > ft) & (pr < 0), p / -pr,",
      "(p > ft) & (pr < 0), 2 * p / -pr,",
      T_EVO, "opening event overshot (time to p = 0 doubled)"),
    M("EV4", "events", "shakedown/evolution/events.py",
      "w_new[close] = 0.0",
      "w_new[close] = w_new[close]",
      T_EVO, "closing node keeps its round-off gap",
      equivalent="the next segment's classification zeroes every gap below its tolerance "
                 "(events.py: w[~open_] = 0.0) before it is used; only the recorded point of "
                 "the closing event keeps a gap below dtol, and it is classified as closing"),
    # ------------------------------------------------------------------ steady
    M("ST1", "steady", "shakedown/evolution/steady.py",
      "unstable = bool(r <= tol and rho > 1.0 + 1e-8)",
      "unstable = False",
      T_STEADY, "repelling fixed points accepted as steady cycles"),
    M("ST2", "steady", "shakedown/evolution/steady.py",
      "verify_cycles = max(2 * max(periods) + 1, min(budget - P.count, 3 * max(periods)))",
      "verify_cycles = 1",
      T_STEADY, "steady cycle not verified by simulation"),
    M("ST3", "steady", "shakedown/evolution/steady.py",
      "if r < best[0]:",
      "if r > best[0]:",
      T_STEADY, "keeps the worst candidate of the period search"),
    M("ST4", "steady", "shakedown/evolution/steady_maps.py",
      "force = f * np.abs(load.p0) + np.abs(load.q0) + float(lam) * (qmax + f * pmax)",
      "force = f * np.abs(load.p0) + np.abs(load.q0)",
      T_STEADY + " " + T_UNIQ, "natural slip scale ignores the periodic load"),
    # ------------------------------------------------------------------ uniqueness
    M("U1", "uniqueness", "shakedown/evolution/uniqueness.py",
      "w_tol = float(w_rtol) * max(",
      "w_tol = 1000 * float(w_rtol) * max(",
      T_UNIQ, "issue-15 bug 6: uniqueness verdict tolerance multiplied by 1000"),
    M("U2", "uniqueness", "shakedown/evolution/uniqueness.py",
      "rng_ = np.nanmax(h, axis=0) - np.nanmin(h, axis=0)",
      "rng_ = np.nanmax(h, axis=0) - np.nanmax(h, axis=0)",
      T_UNIQ, "time-varying spread always zero"),
    M("U3", "uniqueness", "shakedown/evolution/uniqueness.py",
      "return out - out.mean(axis=1, keepdims=True)",
      "return out",
      T_UNIQ, "locked-in slips counted as time-varying response"),
    M("U4", "uniqueness", "shakedown/evolution/uniqueness.py",
      "unique_dissipation=bool(steady.all() and spread <= w_tol),",
      "unique_dissipation=bool(spread <= w_tol),",
      T_UNIQ, "unsettled runs do not prevent a 'unique' verdict"),
    # ------------------------------------------------------------------ sweep / store
    M("W1", "sweep", "shakedown/studies/summary.py",
      'W_star_min=("W_star", "min"),',
      'W_star_min=("W_star", "first"),',
      T_SWEEP, "issue-15 bug 7: W*_min taken from the first initial state"),
    M("W2", "sweep", "shakedown/studies/summary.py",
      'W_star_max=("W_star", "max"),',
      'W_star_max=("W_star", "last"),',
      T_SWEEP, "W*_max taken from the last initial state"),
    M("W3", "sweep", "shakedown/studies/summary.py",
      "sd = x.std(ddof=1) if x.size > 1 else np.nan",
      "sd = x.std(ddof=0) if x.size > 1 else np.nan",
      T_SWEEP, "confidence band with the biased standard deviation"),
    M("W4", "sweep", "shakedown/studies/engine.py",
      "todo = [t for t in tasks if t.key not in done]",
      "todo = list(tasks)",
      T_SWEEP, "resume recomputes finished tasks (duplicate rows)"),
    M("W5", "sweep", "shakedown/studies/tables.py",
      'float_format="%.17g"',
      'float_format="%.12g"',
      T_SWEEP, "CSV store loses the last digits of floats"),
    M("W6", "sweep", "crack_networks/model.py",
      "4.0 * (1.0 - self.poisson_ratio) * p0**2 * abar**2",
      "4.0 * (1.0 - self.poisson_ratio) * p0**2 * abar",
      T_SWEEP, "W* normalised by abar instead of abar^2"),
    # ------------------------------------------------------------------ Kachanov
    M("K1", "kachanov", "crack_networks/model.py",
      "K4[:, 1, :, 1].copy(), K4[:, 1, :, 0].copy(), K4[:, 0, :, 1].copy(),",
      "K4[:, 1, :, 1].copy(), K4[:, 0, :, 1].copy(), K4[:, 1, :, 0].copy(),",
      T_KACH, "B and B^T blocks of the crack-network stiffness swapped"),
    M("K2", "kachanov", "crack_networks/kachanov.py",
      "(-k0 * (a[i0:i1, None] / a[None, :]))",
      "(-k0 * (a[None, :] / a[i0:i1, None]))",
      T_KACH, "interaction stiffness scaled by a_j / a_i instead of a_i / a_j"),
    M("K3", "kachanov", "crack_networks/kachanov.py",
      "k0 = 4.0 * shear_modulus / (np.pi * (1.0 - poisson_ratio))",
      "k0 = 4.0 * shear_modulus / (np.pi * (1.0 + poisson_ratio))",
      T_KACH, "self stiffness with (1 + nu)"),
    M("K4", "kachanov", "crack_networks/model.py",
      "Sn_x * t[:, 0] + Sn_y * t[:, 1]], axis=-1)",
      "-(Sn_x * t[:, 0] + Sn_y * t[:, 1])], axis=-1)",
      T_KACH, "resolved shear traction with the wrong sign"),
    # ------------------------------------------------------------------ FE
    M("F1", "fe", "shakedown/models/fe/assembled.py",
      "S = self.Kcc - self.lu.schur_correction(self.Kci.T)",
      "S = self.Kcc + self.lu.schur_correction(self.Kci.T)",
      T_FE, "static condensation with the wrong sign of the Schur correction"),
    M("F2", "fe", "shakedown/models/fe/condensed.py",
      "S = a.Kcc + s * a.Mcc - lu.schur_correction((a.Kci + s * a.Mci).T)",
      "S = a.Kcc + s * a.Mcc - lu.schur_correction((a.Kci + 0 * a.Mci).T)",
      T_FE + " tests/stability/test_stability_fe.py", "dynamic stiffness without the coupling mass"),
    M("F3", "fe", "shakedown/models/fe/materials.py",
      "return np.linalg.inv(S6[np.ix_(idx, idx)])",
      "return C6[np.ix_(idx, idx)]",
      T_FE, "plane stress computed as plane strain"),
    M("F4", "fe", "shakedown/models/fe/materials.py",
      "S[4, 4] = S[5, 5] = 1 / G12",
      "S[4, 4] = S[5, 5] = 2 / G12",
      T_FE + " tests/stability/test_stability_fe.py", "shear compliance doubled"),
    M("F5", "fe", "shakedown/models/fe/materials.py",
      "R = np.array([[c, -s], [s, c]])",
      "R = np.array([[c, s], [-s, c]])",
      T_FE + " tests/stability/test_stability_fe.py", "material axes turned by -theta"),
    # ------------------------------------------------------------------ stability
    M("T1", "stability", "shakedown/stability/pencil.py",
      "K1 = prof[:, None] * S_nt * chi[None, :]",
      "K1 = -prof[:, None] * S_nt * chi[None, :]",
      T_STAB, "friction pencil K1 with the wrong sign"),
    M("T2", "stability", "shakedown/stability/pencil.py",
      "K0 = chi[:, None] * S_tt * chi[None, :]",
      "K0 = S_tt",
      T_STAB, "K0 without the slip-direction signs"),
    M("T3", "stability", "shakedown/stability/result.py",
      "comp = float(np.abs(x * y).max() / norm)",
      "comp = 0.0",
      T_STAB, "eigen-answer verification ignores complementarity",
      equivalent="with x scaled to max x = 1, complementarity max_j x_j abs(y_j) / norm is at "
                 "most max(residual on the support, SUPPORT_RTOL = 1e-9 off it) < VERIFY_TOL = "
                 "1e-8: implied by the other two checks"),
    M("T4", "stability", "shakedown/stability/result.py",
      "sign = float(max(0.0, -x.min(), -yout.min(initial=0.0)))",
      "sign = float(max(0.0, -x.min()))",
      T_STAB, "eigen-answer verification ignores the sign of y off the support"),
    M("T5", "stability", "shakedown/stability/layer.py",
      "return float(Dm[0, 0] / abs(Dm[0, 1])), float(-np.sign(Dm[0, 1]))",
      "return float(Dm[0, 0] / abs(Dm[0, 1])), float(np.sign(Dm[0, 1]))",
      "tests/stability/test_stability_fe.py", "layer's unstable slip direction reversed"),
    # ------------------------------------------------------------------ bounds
    M("B1", "bounds", "shakedown/bounds/certificates.py",
      "comp = (np.abs(Y) * np.abs(np.minimum(r, 0.0))).max(axis=1) / ys",
      "comp = 0.0 * ys",
      T_BOUNDS, "issue-15 bug 3 (part): dense-LP certificate ignores complementarity"),
    M("B2", "bounds", "shakedown/bounds/certificates.py",
      "stat = np.abs(e[None, :] - Y @ A).max(axis=1) / np.maximum(ys, en)",
      "stat = 0.0 * ys",
      T_BOUNDS, "issue-15 bug 3 (part): dense-LP certificate ignores stationarity"),
    M("B3", "bounds", "shakedown/bounds/certificates.py",
      "stat = float(np.abs(e - A.T @ y).max(initial=0.0) / max(ys * rownorm.max(), en))",
      "stat = 0.0",
      T_BOUNDS, "kkt_residuals ignores stationarity"),
    M("B4", "bounds", "shakedown/bounds/certificates.py",
      "comp = float(np.max(np.abs(y) * np.abs(np.minimum(r, 0.0)), initial=0.0) / ys)",
      "comp = 0.0",
      T_BOUNDS, "kkt_residuals ignores complementarity"),
    M("B5", "bounds", "shakedown/bounds/outcome.py",
      "limiting = int(np.nanargmin(lam_high))",
      "limiting = int(np.nanargmax(lam_high))",
      T_BOUNDS, "lam1 from argmax instead of argmin of the activity intervals"),
    M("B6", "bounds", "shakedown/bounds/constraints.py",
      "mI, tI = load.periodic_min(-1.0, f)",
      "mI, tI = load.periodic_min(1.0, f)",
      T_BOUNDS, "extreme offset of I_j with the wrong sign of q"),
    M("B7", "bounds", "shakedown/bounds/constraints.py",
      "G = np.vstack([A - FBt, -(A + FBt)])",
      "G = np.vstack([A + FBt, -(A - FBt)])",
      T_BOUNDS, "constraint normals with the coupling sign swapped"),
    M("B8", "bounds", "shakedown/bounds/outcome.py",
      "if np.isfinite(lam2) and lam1 >= lam2 - tol:",
      "if np.isfinite(lam2):",
      T_BOUNDS, "lam1 always set to lam2"),
    M("B9", "bounds", "shakedown/model/loading.py",
      "amp = np.hypot(a[0], b[0])",
      "amp = np.abs(a[0]) + np.abs(b[0])",
      T_BOUNDS, "harmonic extreme |a| + |b| instead of sqrt(a^2 + b^2)"),
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
    ap.add_argument("--tests", help="run these tests (space-separated) instead of the listed ones")
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
            if args.tests:
                m = Mutation(**{**m.__dict__, "tests": tuple(args.tests.split())})
            outcome, dt, tail = run_one(m, copy, args.timeout)
            rows.append((m, outcome, dt, tail))
            print(f"{m.id:5s} {outcome:18s} {dt:6.1f} s  {m.what}  [{tail}]", flush=True)
    equiv = [r for r in rows if r[0].equivalent]
    counted = [r for r in rows if r[1].startswith(("killed", "survived")) and not r[0].equivalent]
    killed = sum(r[1].startswith("killed") for r in counted)
    stale = sum(r[1] == "stale" for r in rows)
    errors = [r for r in rows if r[1].startswith("error")]
    rate = killed / len(counted) if counted else float("nan")
    summary = (f"{len(rows)} mutations: {len(equiv)} equivalent (not counted); of the other "
               f"{len(counted)}: {killed} killed, {len(counted) - killed} survived; {stale} stale, "
               f"{len(errors)} errors; kill rate {100 * rate:.1f} %")
    print(summary)
    if args.markdown:
        lines = ["| id | area | file | mutation | outcome | first failing test | time [s] |",
                 "| --- | --- | --- | --- | --- | --- | --- |"]
        for m, outcome, dt, tail in rows:
            caught = tail if outcome.startswith("killed") else ""
            if m.equivalent:
                outcome += " (equivalent: " + m.equivalent + ")"
            lines.append(f"| {m.id} | {m.area} | `{m.file}` | {m.what} | {outcome} | {caught} | "
                         f"{dt:.1f} |")
        Path(args.markdown).write_text(summary + "\n\n" + "\n".join(lines) + "\n")
    return 0 if not errors else 2


if __name__ == "__main__":
    sys.exit(main())
