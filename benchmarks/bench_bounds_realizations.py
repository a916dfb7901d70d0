"""The bounds engine on many random realizations (issue 26): median, worst case, fallbacks.

Each realization runs in its own process (peak RSS per realization), one BLAS thread:

    OPENBLAS_NUM_THREADS=1 nohup python3 benchmarks/bench_bounds_realizations.py \\
        --kind crack --sizes 500,1000,2000 --count 20 --out /tmp/real.jsonl &
    python3 benchmarks/bench_bounds_realizations.py --report /tmp/real.jsonl

Kinds:

* ``crack``: ``crack_networks.sample_crack_set(N, density, half_length=1, min_spacing=0.1,
  rng=seed)``, ``kachanov_model(shear_modulus=1, poisson_ratio=0.25, friction)``,
  ``load_cycle(static=(-1, 0, -1), cyclic=(0, 1, 0))``; realization ``i`` takes density
  ``DENSITIES[i % 3]``, friction ``FRICTIONS[(i // 3) % 3]`` and seed ``SEED0 + i`` (seeds the
  tests do not use);
* ``issue``: the network of issue 26, ``sample_crack_set(N, density=0.1, rng=77)``, friction
  0.6, the same load (``--count 1``);
* ``dense``: ``bench_bounds.random_problem(N, seed, friction)`` (``K = M M^T + I``);
* ``fe``: the strip of ``bench_fe_bounds.py`` with ``N`` contact nodes (``fe.rectangle((N - 1)
  / 100, 0.1, N - 1, 8)``, held at its left end, bottom on the obstacle), dead load: top
  traction ``(0, -1)``; per realization (seed ``SEED0 + i``) the friction ``U(0.3, 0.9)`` and a
  cyclic top traction ``(a cos + c sin, p cos)`` with ``a ~ U(0.2, 0.6)``, ``p ~ U(-0.3, 0.3)``,
  ``c ~ U(0, 0.3)`` (unit load cases, condensed once and cached in ``/tmp/fe_bounds_cache``).

Per realization: the wall and CPU time of ``shakedown_bounds`` (default options; with one BLAS
thread the CPU time is the time on one unshared core), peak RSS, ``lam1``,
``lam2``, the stages' paths and fallbacks (:attr:`ShakedownBounds.stages`), and the checks by
HiGHS of :func:`check_with_highs` (the ``lam2`` LP, the LP deciding ``lam1`` and three random
rows' ``lam_high`` and ``lam_low``, each handed to HiGHS with the dense optimal basis as start
and HiGHS's tolerances at 1e-9), each compared to 1e-9
relative; and for the ``lam2`` LP and the LP deciding ``lam1`` the certified brackets of the
dense answer, HiGHS's reported point and HiGHS's final basis solved exactly, from exact residuals
(:func:`certified_bracket`: on ill-conditioned FE strips HiGHS's reported point violates rows by
2e-8 and its value is 1e-5 off, so raw values cannot decide).  Results are appended as JSON
lines; an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this repository's package

SEED0 = 5000
DENSITIES = (0.05, 0.1, 0.15)
FRICTIONS = (0.3, 0.6, 0.9)


def build(kind, n, i):

    if kind == "crack":
        import crack_networks as cn

        density, friction = DENSITIES[i % 3], FRICTIONS[(i // 3) % 3]
        cs = cn.sample_crack_set(n, density=density, half_length=1.0, min_spacing=0.1,
                                 rng=SEED0 + i)
        m = cn.kachanov_model(cs, shear_modulus=1.0, poisson_ratio=0.25, friction=friction)
        return m.system, m.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0)), \
            dict(density=density, friction=friction, seed=SEED0 + i)
    if kind == "issue":  # the network of issue 26 (n = 2000 there), i ignored
        import crack_networks as cn

        cs = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1, rng=77)
        m = cn.kachanov_model(cs, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
        return m.system, m.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0)), \
            dict(density=0.1, friction=0.6, seed=77)
    if kind == "dense":
        sys.path.insert(0, str(Path(__file__).parent))
        from bench_bounds import random_problem

        friction = FRICTIONS[i % 3]
        s, load = random_problem(n, seed=SEED0 + i, friction=friction)
        return s, load, dict(friction=friction, seed=SEED0 + i)
    if kind == "fe":
        from shakedown import fe

        rng = np.random.default_rng(SEED0 + i)
        friction = float(rng.uniform(0.3, 0.9))
        shear, press, rot = rng.uniform(0.2, 0.6), rng.uniform(-0.3, 0.3), rng.uniform(0.0, 0.3)
        # unit load cases (one condensation, cached), combined per realization
        loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shear": fe.Traction("top", (1.0, 0)),
                 "press": fe.Traction("top", (0.0, 1.0))}
        model = fe.FEModel(fe.rectangle((n - 1) / 100, 0.1, n - 1, 8), fe.isotropic(1.0, 0.3),
                           dirichlet={"left": "xy"}, contact=["bottom"], loads=loads,
                           friction=friction)
        cm = model.condense(cache_dir="/tmp/fe_bounds_cache")
        load = cm.load_cycle(static="dead", cyclic={"shear": shear, "press": press},
                             cyclic_sin={"shear": rot})
        return cm.system, load, dict(friction=friction, shear=float(shear), press=float(press),
                                     rot=float(rot), seed=SEED0 + i)
    raise ValueError(f"kind must be crack, issue, dense or fe; got {kind!r}")


#: HiGHS's primal and dual feasibility tolerances in the check (its default is 1e-7).
CHECK_TOL = 1e-9
#: Rows drawn per realization for the spot checks of lam_high and lam_low (up to N = 1000;
#: none above: each HiGHS check from a given basis factorizes it anew, ~20 s CPU at N = 2000).
SPOT_ROWS = 3
SPOT_MAX_N = 1000


class _NoBook:
    """What :func:`dense_path._min_start` records (nothing here)."""

    def record(self, ans):
        pass


def _dense_lp(cs):
    """The dense path's LP ``max e.x, A x <= b`` in ``x = (v, lam)`` (:mod:`.dense_path`)."""
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    return A, np.r_[cs.c, 0.0], np.r_[np.zeros(n), 1.0]


def _highs(ch):
    from shakedown.bounds.highs_path import HighsModel

    model = HighsModel(ch)
    h = model.lp._h
    for opt in ("primal_feasibility_tolerance", "dual_feasibility_tolerance"):
        h.setOptionValue(opt, CHECK_TOL)
    h.setOptionValue("time_limit", 300.0)
    return model


_SPLIT = 134217729.0  # 2^27 + 1 (Dekker's split of a double into two 26-bit halves)


def _split(a):
    c = _SPLIT * a
    hi = c - (c - a)
    return hi, a - hi


def exact_residual(A, x, b):
    """``A x - b`` correctly rounded: each product ``A_ij x_j`` as the exact sum of two doubles
    (Dekker's two-product), each row summed exactly by ``math.fsum`` (0.7 s at 1001 x 500).
    So a residual of 2.7e-15 is 2.7e-15, not rounding noise of the matrix product."""
    import math

    p = A * x[None, :]
    ah, al = _split(A)
    xh, xl = _split(x)
    err = ((ah * xh[None, :] - p) + ah * xl[None, :] + al * xh[None, :]) + al * xl[None, :]
    T = np.hstack([p, err, -np.asarray(b, float)[:, None]])
    return np.array([math.fsum(row) for row in T])


#: A bracket end counts when its certificate holds to this (relative, exact residuals; the
#: dense certificates hold to 5e-12 on the FE strips: multipliers of -5e-12 of the largest).
BRACKET_TOL = 1e-10


def certified_bracket(A, b, e, x, y, eq=()):
    """What the point ``x`` and multipliers ``y`` of ``max e.x, A x <= b`` (rows ``eq`` with
    equality) prove, from exact residuals: ``lo = e.x`` when ``x`` violates no row by more than
    :data:`BRACKET_TOL` of its scale ``||A_i|| |x|_inf + |b_i|`` (as the engine's
    :func:`~shakedown.bounds.certificates.kkt_residuals`; else ``-inf``), ``hi = b.y`` when
    ``y`` has the right signs (to :data:`BRACKET_TOL` of ``|y|_inf``) and ``A^T y = e`` to
    :data:`BRACKET_TOL` of ``max(max_j |A_:j|.|y|, |e|_inf)`` (weak duality; else ``inf``).
    The multiplier of the last row (``-lam <= 0``, ``b = 0``) is the dual's free choice
    ``max(0, -(m.y) - 1)``: it closes the ``lam`` column."""
    x, y = np.asarray(x, float), np.asarray(y, float).copy()
    eqm = np.zeros(len(b), bool)
    eqm[list(eq)] = True
    y[-1] = max(0.0, float(-(A[:-1, -1] @ y[:-1])) - 1.0)  # (A[:-1, -1] = -m)
    r = exact_residual(A, x, b)
    xs = max(float(np.abs(x).max()), 1.0)
    viol = np.where(eqm, np.abs(r), np.maximum(r, 0.0)) / (np.linalg.norm(A, axis=1) * xs
                                                          + np.abs(b))
    sign = float(np.max(np.where(eqm, 0.0, np.maximum(-y, 0.0)))) / max(np.abs(y).max(), 1e-300)
    st = exact_residual(A.T, y, e)
    stat = np.abs(st) / max(float((np.abs(A).T @ np.abs(y)).max()), float(np.abs(e).max()))
    primal, dual = float(viol.max()), max(sign, float(stat.max()))
    value, bound = float(e @ x), float(b @ y)
    return dict(value=value, bound=bound, primal=primal, dual=dual,
                lo=value if primal <= BRACKET_TOL else -np.inf,
                hi=bound if dual <= BRACKET_TOL else np.inf)


def compare_brackets(dense, highs, scale):
    """``conflict``: how far the two certified brackets are apart (0: they overlap, so the
    certificates do not contradict each other); ``width``: the dense bracket's width (0 to
    rounding: the dense answer is certified optimal); ``highs_off``: how far HiGHS's value
    lies outside the dense bracket (its claim that no certificate backs)."""
    conflict = max(0.0, highs["lo"] - dense["hi"], dense["lo"] - highs["hi"]) / scale
    width = (dense["hi"] - dense["lo"]) / scale
    off = max(0.0, highs["value"] - dense["hi"], dense["lo"] - highs["value"]) / scale
    return dict(conflict=conflict, width=width, highs_off=off)


def _basis_bracket(model, A, b, e, eq=()):
    """HiGHS's final basis solved here (LU of its rows, :class:`~shakedown.dense_lp.Tableau`):
    its exact basic solution and multipliers, bracketed like the others.  On the FE strips
    (seed 5003) HiGHS's reported ``x`` differs from its own basis's basic solution by 0.07,
    and that basis is feasible but 5e-7 short of the optimum (a multiplier of -1.3e-6)."""
    from shakedown import dense_lp

    T = model.tight_basis()
    if T is None:
        return None
    tab = dense_lp.Tableau(A, b, e, T)
    if tab.singular:
        return None
    y = np.zeros(len(b))
    y[tab.T0] = tab.y0 / tab.rownorm[tab.T0]
    return certified_bracket(A, b, e, tab.x0, y, eq=eq)


def _verify(model, T, sense, tight=()):
    """HiGHS started from the basis ``T`` (dense rows): its value, iterations, seconds, and
    its answer (``None`` if not checked)."""
    if T is None:  # no dense optimal basis to hand over: not checked (HiGHS cold is too slow)
        return np.nan, -1, 0.0, False, "no dense basis", None
    accepted = model.start_from(np.sort(T))
    t = time.perf_counter()
    ans = model.run(sense, tight=tight)
    v = float(ans.x[-1]) if ans.status == "optimal" else np.nan
    return v, int(ans.iterations), time.perf_counter() - t, bool(accepted), ans.status, ans


def check_with_highs(b, rng, on_partial=None):
    """Independent checks by HiGHS (nondimensional LPs, relative to ``max(1, lam2)``).

    Each LP is handed to HiGHS (tolerances :data:`CHECK_TOL`) with the dense path's optimal
    basis as its start; HiGHS computes that basis's primal and dual solution with its own
    factorization, checks optimality in its own terms and pivots on if it is not optimal (the
    iteration count says; 0 = the dense basis is HiGHS's optimum too).  Checked: the ``lam2`` LP
    (basis rebuilt from the result's certificate and state), the LP deciding ``lam1`` (``max
    lam`` with the limiting row tight; ``min lam`` when ``lam1 = 0``), and :data:`SPOT_ROWS`
    random rows' ``lam_high`` (equal where exact, ``>=`` the proven bound elsewhere, ``>= lam1``)
    and ``lam_low`` (equal).  The bases of the last three are found here by the dense dual
    simplex from the ``lam2`` basis (``max``) or the ``lam = 0`` vertex (``min``)."""
    from shakedown import dense_lp
    from shakedown.bounds.constraints import Scales
    from shakedown.bounds.dense_path import _min_start

    cs = b.constraints
    sc = Scales.of(cs)
    ch = sc.nondimensional(cs)
    n = ch.n_nodes
    A, bb, e = _dense_lp(ch)
    lf = sc.load_factor
    lam2 = b.lam2 / lf
    scale = max(1.0, abs(lam2))
    # the dense optimum's tight rows: the certificate's rows first, then the smallest slacks
    x = np.r_[b.state_at_lam2 / sc.slip, lam2]
    slack = (bb - A @ x) / (np.linalg.norm(A, axis=1) * max(1.0, np.abs(x).max()))
    y = b.certificate
    slack[: 2 * n][y > 1e-12 * max(np.abs(y).max(initial=0.0), 1e-300)] = -1.0
    T = np.sort(np.argsort(slack, kind="stable")[: n + 1])
    model = _highs(ch)
    v, it, s, ok, st, hans = _verify(model, T, "max")
    out = {"highs_lam2_s": s, "highs_lam2_iters": it, "highs_lam2_basis_accepted": ok,
           "highs_lam2_status": st, "dlam2": abs(v - lam2) / scale if st == "optimal" else np.nan}
    # certified brackets (exact residuals): the result's point and certificate, HiGHS's
    # point and row duals
    dense = certified_bracket(A, bb, e, x, np.r_[y * sc.force / lf, 0.0])
    out["lam2_dense"] = dense
    if st == "optimal":
        highs = certified_bracket(A, bb, e, hans.x, np.r_[hans.row_dual[: 2 * n], 0.0])
        out["lam2_highs"] = highs
        out.update({f"lam2_{k}": v for k, v in compare_brackets(dense, highs, scale).items()})
        out["lam2_highs_basis"] = _basis_bracket(model, A, bb, e)
    tab = dense_lp.Tableau(A, bb, e, T)
    starts = {"max": tab}

    def dense_basis(sense, k):
        if sense not in starts:  # the lam = 0 vertex, only when a min LP is checked
            starts[sense] = _min_start(A, bb, e, tab, 2 * n, _NoBook()) if not tab.singular \
                else None
        t = starts[sense]
        if t is None or t.singular:
            return None
        ans = dense_lp.batch_dual_simplex(t, [(k,)])[0]
        return ans if ans.status == "optimal" else None

    def one_row(sense, k, bracket=False):
        t = time.perf_counter()
        d = dense_basis(sense, k)
        v, it, s, ok, st, hans = _verify(model, None if d is None else d.basis, sense,
                                         tight=(k,))
        if bracket and sense == "max" and st == "optimal" and d is not None:
            dense = certified_bracket(A, bb, e, d.x, d.y, eq=(k,))
            highs = certified_bracket(A, bb, e, hans.x, np.r_[hans.row_dual[: 2 * n], 0.0],
                                      eq=(k,))
            out.update(lam1_dense=dense, lam1_highs=highs,
                       lam1_highs_basis=_basis_bracket(model, A, bb, e, eq=(k,)), **{
                f"lam1_{key}": val for key, val in compare_brackets(dense, highs, scale).items()})
        return v, it, time.perf_counter() - t, ok, st

    def diff(v, st, ref):
        """|v - ref| / scale; nan when HiGHS did not decide (time limit, no basis to check)."""
        if st not in ("optimal", "infeasible"):
            return np.nan
        if np.isnan(ref):  # never active: HiGHS must find the LP infeasible
            return 0.0 if st == "infeasible" else 1.0
        return abs(v - ref) / scale if st == "optimal" else 1.0

    k = b.limiting_constraint
    if k >= 0 and np.isfinite(b.lam1):
        sense, ref = ("max", b.lam1 / lf) if b.lam1 > 0 else ("min", b.lam_low[k] / lf)
        v, it, s, ok, st = one_row(sense, k, bracket=True)
        out.update(highs_lam1_s=s, highs_lam1_iters=it, highs_lam1_basis_accepted=ok,
                   highs_lam1_status=st, dlam1=diff(max(v, 0.0) if sense == "min" else v, st,
                                                    ref))
    if on_partial is not None:  # (lam2 and lam1 checked: kept if the spot rows do not finish)
        on_partial(out)
    spot = []
    lam1 = b.lam1 / lf
    for r in rng.choice(2 * n, size=min(SPOT_ROWS if n <= SPOT_MAX_N else 0, 2 * n),
                        replace=False):
        r = int(r)
        hi, lo = b.lam_high[r] / lf, b.lam_low[r] / lf
        vh, ith, sh, okh, sth = one_row("max", r)
        vl, itl, sl, okl, stl = one_row("min", r)
        exact = bool(b.lam_high_exact[r])
        if exact or np.isnan(hi):
            dh = diff(vh, sth, hi)
        elif sth == "optimal":  # a proven lower bound: HiGHS's value must not be below it
            dh = max(hi - vh, lam1 - vh, 0.0) / scale  # (nor below lam1)
        else:
            dh = np.nan
        dl = diff(max(vl, 0.0), stl, lo)
        spot.append(dict(row=r, exact=exact, dhigh=dh, dlow=dl, iters=[ith, itl],
                         seconds=sh + sl, accepted=[okh, okl], status=[sth, stl]))
    out["spot"] = spot
    d = [x for r in spot for x in (r["dhigh"], r["dlow"]) if not np.isnan(x)]
    out["dspot"] = max(d, default=0.0)
    out["spot_unchecked"] = int(sum(np.isnan(x) for r in spot for x in (r["dhigh"], r["dlow"])))
    return out


def calibrate():
    """CPU seconds of a fixed dense workload like the engine's (products with a 4000 x 2000
    matrix, 64 MB, and a 1000 x 1000 LU): measured beside each realization, its ratio to the
    smallest value of a run tells how much a loaded machine inflates the CPU time."""
    import scipy.linalg as sla

    rng = np.random.default_rng(0)
    G, x, M = rng.standard_normal((4000, 2000)), rng.standard_normal(2000), \
        rng.standard_normal((1000, 1000))
    c = time.process_time()
    for _ in range(20):
        x = G.T @ (G @ x) / 4000.0
    for _ in range(3):
        sla.lu_factor(M)
    return time.process_time() - c


def one(kind, n, i, check=True):
    import shakedown as sd

    system, load, params = build(kind, n, i)
    calib = calibrate()
    t, c = time.perf_counter(), time.process_time()
    b = sd.shakedown_bounds(system, load)
    sec, cpu = time.perf_counter() - t, time.process_time() - c
    rec = dict(kind=kind, n=n, i=i, **params, seconds=sec, cpu_seconds=cpu,
               rss_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
               lam1=b.lam1, lam2=b.lam2, limiting=b.limiting_label, n_lps=b.n_lps,
               fallbacks=sum(s.fallbacks for s in b.stages),
               stages=[s.to_dict() for s in b.stages],
               # outside the stages: the constraints and the safe state (Chebyshev centre)
               unstaged_seconds=b.solve_time - sum(s.seconds for s in b.stages),
               residual=max(b.residuals.values()),
               load=os.getloadavg()[0], calib_cpu=(calib + calibrate()) / 2)
    print(json.dumps(rec), flush=True)  # (kept by the driver if the check does not finish)
    if not check:
        return
    c = time.process_time()

    def partial(out):
        print(json.dumps({**rec, **out, "check_cpu_seconds": time.process_time() - c}),
              flush=True)

    rec.update(check_with_highs(b, np.random.default_rng(SEED0 + 7919 * n + i), partial))
    rec["check_cpu_seconds"] = time.process_time() - c
    print(json.dumps(rec), flush=True)


def drive(args):
    done = set()
    out = Path(args.out)
    if out.exists():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done.add((r["kind"], r["n"], r["i"]))
    for n in [int(v) for v in args.sizes.split(",")]:
        for i in range(args.first, args.first + args.count):
            if (args.kind, n, i) in done:
                continue
            env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
                       NUMBA_NUM_THREADS="1")
            try:
                p = subprocess.run([sys.executable, __file__, "--one", args.kind, str(n), str(i)]
                                   + (["--no-check"] if args.no_check else []),
                                   capture_output=True, text=True, env=env, timeout=args.timeout)
                stdout, stderr, rc = p.stdout, p.stderr, p.returncode
            except subprocess.TimeoutExpired as exc:  # (the child is killed)
                stdout, stderr, rc = exc.stdout or "", f"timeout after {args.timeout} s", -9
                stdout = stdout.decode() if isinstance(stdout, bytes) else stdout
            lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
            if not lines:
                line = json.dumps(dict(kind=args.kind, n=n, i=i, error=stderr[-2000:]))
            else:
                rec = json.loads(lines[-1])
                if "dlam2" not in rec or "spot" not in rec:  # the check did not finish
                    rec["check_error"] = stderr[-2000:] or f"exit status {rc}"
                line = json.dumps(rec)
            with out.open("a") as f:
                f.write(line + "\n")


def _fallback_stages(rs):
    """``stage: LPs`` over the realizations (the stages that fell back)."""
    count = {}
    for r in rs:
        for st in r["stages"]:
            if st["fallbacks"]:
                count[st["stage"]] = count.get(st["stage"], 0) + st["fallbacks"]
    return ", ".join(f"{k}: {v}" for k, v in count.items()) or "none"


def scaled(rs, cmin):
    """The worst CPU time times ``cmin / calib_cpu`` (the load's inflation taken out, as far
    as the calibration workload measures it); '-' without calibration."""
    v = [r["cpu_seconds"] * cmin / r["calib_cpu"] for r in rs if "calib_cpu" in r]
    return f"{max(v):.3g} ({len(v)})" if v else "-"


def _cert_summary(rs):
    """Certified brackets (the records with them): ``dense certified / checked; HiGHS's point
    certified; worst conflict; worst HiGHS value outside the dense bracket`` over the lam2 and
    lam1 LPs."""
    pairs = [(r[f"{q}_dense"], r.get(f"{q}_highs"), r.get(f"{q}_conflict"),
              r.get(f"{q}_highs_off")) for r in rs for q in ("lam2", "lam1")
             if f"{q}_dense" in r]
    if not pairs:
        return "-"
    tight = sum(1 for d, *_ in pairs if np.isfinite(d["lo"]) and np.isfinite(d["hi"]))
    hc = sum(1 for _, h, *_ in pairs if h and np.isfinite(h["lo"]) and np.isfinite(h["hi"]))
    conflict = max((c for *_, c, _ in pairs if c is not None), default=np.nan)
    off = max((o for *_, o in pairs if o is not None), default=np.nan)
    return f"{tight}/{len(pairs)}; {hc}/{len(pairs)}; {conflict:.1e}; {off:.1e}"


def report(paths):
    rows = [json.loads(ln) for p in paths for ln in Path(p).read_text().splitlines()]
    keys = sorted({(r["kind"], r["n"]) for r in rows})
    print("| kind | N | realizations | median CPU s | worst CPU s | median wall s | worst wall s | "
          "worst CPU s scaled by the calibration | worst peak RSS GB | "
          "fallbacks: LPs (realizations; stages) | worst diff to HiGHS: "
          "lam2 / lam1 LP / spot rows | HiGHS pivots from the dense bases (max) | load | "
          "errors | certified brackets (lam2, lam1 LPs): dense / HiGHS's point / worst "
          "conflict / worst HiGHS value outside the dense bracket |")
    print("| --- " * 15 + "|")
    cal = [r["calib_cpu"] for r in rows if "calib_cpu" in r]
    cmin = min(cal, default=np.nan)
    for kind, n in keys:
        rs = [r for r in rows if r["kind"] == kind and r["n"] == n and "error" not in r]
        err = sum(1 for r in rows if r["kind"] == kind and r["n"] == n and "error" in r)
        if not rs:
            print(f"| {kind} | {n} | 0 | | | | | | | | | | | {err} |")
            continue
        s = np.array([r["cpu_seconds"] for r in rs])
        w = np.array([r["seconds"] for r in rs])
        fb = [r["fallbacks"] for r in rs]
        ck = [r for r in rs if "dlam2" in r]
        unchecked = len(rs) - len(ck)

        def worst(key, ck=ck):
            vals = [r[key] for r in ck if key in r and not np.isnan(r[key])]
            miss = sum(1 for r in ck if key not in r or np.isnan(r[key]))
            text = f"{max(vals):.1e}" if vals else "-"
            return text + (f" ({miss} undecided)" if miss and vals else "")

        piv = max((max([r["highs_lam2_iters"], r.get("highs_lam1_iters", 0)]
                       + [max(d["iters"]) for d in r.get("spot", [])]) for r in ck), default=0)
        loads = [r["load"] for r in rs]
        print(f"| {kind} | {n} | {len(rs)} | {np.median(s):.3g} | {s.max():.3g} "
              f"(i = {rs[int(np.argmax(s))]['i']}) | {np.median(w):.3g} | {w.max():.3g} | "
              f"{scaled(rs, cmin)} | {max(r['rss_gb'] for r in rs):.2f} | "
              f"{sum(fb)} ({sum(1 for f in fb if f)}; {_fallback_stages(rs)}) | "
              f"{worst('dlam2')} / {worst('dlam1')} / {worst('dspot')}"
              f"{f' ({unchecked} not checked)' if unchecked else ''} | {piv} | "
              f"{min(loads):.1f}-{max(loads):.1f} | {err} | {_cert_summary(ck)} |")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kind", default="crack")
    ap.add_argument("--sizes", default="500,1000,2000")
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--out", default="bounds_realizations.jsonl")
    ap.add_argument("--timeout", type=float, default=3600.0, help="wall seconds per realization")
    ap.add_argument("--first", type=int, default=0, help="first realization index")
    ap.add_argument("--no-check", action="store_true",
                    help="time the bounds only (no HiGHS check: 20-40 s CPU per LP at N = 2000)")
    ap.add_argument("--one", nargs=3, metavar=("KIND", "N", "I"))
    ap.add_argument("--report", metavar="JSONL", nargs="+")
    a = ap.parse_args()
    if a.one:
        one(a.one[0], int(a.one[1]), int(a.one[2]), check=not a.no_check)
    elif a.report:
        report(a.report)
    else:
        drive(a)
