"""Several initial states of one system stepped together (issue 13/14; MODEL.md s.4).

:func:`run_states` is the period loop of :func:`~.cycles.solve_cycles` for ``k >= 1`` initial
states of the same system and load.  Implicit runs advance in lockstep, one step of every
state still running at a time: states whose previous active set is the same (typical: all
states share it once they reach the same steady orbit, and every shaken-down state has the
all-stick set) are solved together by :func:`solve_many` -- one pair of triangular solves with
``k`` right-hand sides on the cached factor (BLAS-3) and one matrix product for their reactions
-- and every step is verified as in the single-state path (the sign checks of the step problem
per state; the equilibrium of each period recomputed with ``K``).  A state whose guess is not
cached or violates a sign falls back to :meth:`StepSolver.solve` alone.  The states share the
solver (its factor cache) and the critical friction.  Results agree with independent runs to
the solver tolerance; they are bit-identical for the same batch in any process (the batch's
order of work is fixed), not bit-identical to independent runs (a triangular solve with several
right-hand sides rounds differently from one with one).

With the compiled kernel (:mod:`.fast_period`, the default when numba is available) each
state's period is marched by the kernel instead, one state after the other, sharing the
kernel's cache of assignment inverses; the lockstep Python path above runs with
``StepSolver(kernel=False)`` or ``SHAKEDOWN_KERNEL=numpy``.

Scales: the per-step force scale of :class:`StepResult`, the per-run force scale ``F`` of
:mod:`.cycles`.
"""

from __future__ import annotations

import time

import numpy as np

from ..model.errors import InputError
from . import fast_period
from .cycle_results import _finish
from .events import CycleRecord, EventIntegrator
from .sampling import trust
from .step_types import FORWARD, SEPARATED, STICK, StepResult, kinematic_states


def check_energy_scale(F: float, D: np.ndarray, tol: float) -> float:
    """The energy scale ``F^2 sum(1/D)`` of a run [force x length]; :class:`InputError` when its
    ``tol`` fraction underflows the normal double range (forces x 1e-150 with stiffness
    x 1e150: every dissipation would underflow to 0 or a subnormal number)."""
    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        energy = float(F) * float(F) * float(np.sum(1.0 / np.asarray(D, float)))
    if np.isfinite(energy) and not energy * tol >= np.finfo(float).tiny:  # (an overflow is
        # reported by the run's own checks, as a failed run)
        raise InputError(
            f"the forces (largest welded reaction {F:.3g} [force]) and the stiffness (diagonal "
            f"{float(np.min(D)):.3g}..{float(np.max(D)):.3g} [force/length]) give an energy "
            f"scale F^2/k = {energy:.3g} [force x length] outside the range of double precision "
            f"(its tol = {tol:g} fraction must be above {np.finfo(float).tiny:.3g}): express "
            "forces and lengths in units nearer to the problem's size")
    return energy


def _state_change(D, F, v1, w1, v0, w0):
    n = v1.shape[0]
    return float(np.max(D[:n] * np.abs(v1 - v0) + D[n:] * np.abs(w1 - w0), initial=0.0) / F)


def solve_many(solver, V, q_w, p_w, guesses, Q0, P0, bases=None, predictions=None):
    """One implicit step of several states with shared welded reactions.

    Parameters
    ----------
    solver : StepSolver
    V : ndarray, shape (k, N)
        Slips at the start of the step [length].
    q_w, p_w : ndarray, shape (N,)
        Welded reactions at the end of the step [force].
    guesses : ndarray of int8, shape (k, N)
        Each state's guess (its previous ``active_set``).
    Q0, P0 : ndarray, shape (k, N)
        ``q_w + A v``, ``p_w + B^T v`` of each state [force].
    bases : list, optional
        Each state's own base factor of the low-rank updates (updated in place): states on
        different paths then do not take each other's factor as the base of their updates.
    predictions : list, optional
        Each state's prediction (its assignment at this step in its previous period, or
        None), passed to :meth:`StepSolver.solve` for the states solved one by one.

    Returns
    -------
    list of StepResult
        As :meth:`StepSolver.solve` with ``verify=False`` would return them.  States with a
        common cached guess whose signs all hold are solved together; the others one by one.
    """
    k, n = V.shape
    out = [None] * k
    if k > 1 and solver.well_posed is True:  # the status of a verified answer is "unique"
        scales = np.maximum(max(np.abs(q_w).max(), np.abs(p_w).max()),
                            np.maximum(np.abs(Q0).max(axis=1), np.abs(P0).max(axis=1)))
        scales[scales <= 0] = 1.0
        groups: dict[bytes, list[int]] = {}
        for i in range(k):
            groups.setdefault(guesses[i].tobytes(), []).append(i)
        for key, idx in groups.items():
            if len(idx) > 1:  # a single state: the plain step is as cheap
                F = _group(solver, key, np.array(idx), V, q_w, p_w, guesses, Q0, P0, scales,
                           out)
                if bases is not None and F is not None:
                    for i in idx:
                        if out[i] is not None:
                            bases[i] = F
    for i in range(k):
        if out[i] is None:
            if bases is not None:
                solver._base = bases[i]
            out[i] = solver.solve(V[i], q_w, p_w, guesses[i], base=(Q0[i], P0[i]),
                                  verify=False,
                                  prediction=None if predictions is None else predictions[i])
            if bases is not None:
                bases[i] = solver._base
    return out


def _group(solver, key, idx, V, q_w, p_w, guesses, Q0, P0, scales, out):
    """Solve the states ``idx`` (same guess ``key``) on its cached factor; fill ``out``.

    Returns the factor used (None for the all-stick guess or when not cached)."""
    n = solver.n
    s = guesses[idx[0]]
    g = idx.size
    q0, p0 = Q0[idx], P0[idx]
    Z = np.zeros((g, 2 * n))
    if np.any(s != STICK):
        F = solver._cache.get(key)
        if F is None:
            return
        rhs = -np.hstack([q0[:, F.jv] + F.coef * p0[:, F.jv], p0[:, F.jw]])
        if solver.schur:  # the reactions come with the solve
            X, R = F.lu.solve_with_reactions(np.ascontiguousarray(rhs.T))
        elif solver.sparse:
            X = F.lu.solve(np.ascontiguousarray(rhs.T))
        else:
            X, info = solver._getrs(F.lu[0], F.lu[1], rhs.T, overwrite_b=True)
            if info != 0:
                return
        Z[:, F.free] = X.T
        if solver.schur:
            R = R.T
        else:
            kr = F.krows if F.krows is not None else solver.K[F.free]
            R = X.T @ kr
        q, p = q0 + R[:, :n], p0 + R[:, n:]
        solver._cache.move_to_end(key)
        solver._base = F
        hits = 1
    else:
        F = None
        q, p = q0.copy(), p0.copy()
        hits = 0
    ft = solver.feas_tol * scales[idx]
    dtol = ft[:, None] / solver.diag  # (g, 2N)
    dv, w = Z[:, :n], Z[:, n:]
    f = solver.f
    fp = f * p
    isS, isF, isO = s == STICK, s == FORWARD, s == SEPARATED
    # signs of the step problem (ActiveSet._violations_step), all states at once
    viol = np.where(isO, -np.inf, -p / ft[:, None])
    viol = np.maximum(viol, np.where(isS, np.maximum(-(fp + q), q - fp) / ft[:, None], -np.inf))
    back = np.where(isF, -dv, dv) / dtol[:, :n]
    back = np.where(isO, -w / dtol[:, n:], back)
    viol = np.maximum(viol, np.where(isS, -np.inf, back))
    good = viol.max(axis=1) <= 1.0
    # complementarity residual (StepSolver.residuals, step problem), per state
    ds = scales[idx, None] / solver.diag
    xs = np.hstack([w / ds[:, n:], np.maximum(dv, 0) / ds[:, :n], np.maximum(-dv, 0) / ds[:, :n]])
    ys = np.hstack([p, fp + q, fp - q]) / scales[idx, None]
    comp = np.abs(np.minimum(xs, ys)).max(axis=1)
    solver.totals["steps"] += int(good.sum())
    solver.totals["iterations"] += int(good.sum())
    solver.totals["cache_hits"] += hits * int(good.sum())
    for a, i in enumerate(idx):
        if not good[a]:
            continue
        out[i] = StepResult(
            slip=V[i] + dv[a], gap=w[a].copy(), slip_increment=dv[a].copy(), q=q[a], p=p[a],
            states=kinematic_states(dv[a], w[a], dtol[a]), active_set=s.copy(), success=True, status="unique",
            message="solved; unique (friction below critical)", residual=float(comp[a]),
            complementarity_residual=float(comp[a]), equilibrium_residual=float("nan"),
            force_scale=float(scales[i]), method="active_set", iterations=1,
            cache_hits=hits)
    return F


def _check_period(solver, c, V, Wg, Q, P, qw, pw, scales, worst):
    """Equilibrium of every step of a period by one matrix product; (worst, message)."""
    U = np.hstack([V[1:], Wg[1:]])
    E = np.hstack([qw - Q[1:], pw - P[1:]]) + U @ solver.K
    eq = np.abs(E).max(axis=1) / scales
    worst = max(worst, float(eq.max()))
    if worst <= 10 * solver.feas_tol:
        return worst, ""
    k = int(np.argmax(eq))
    return worst, (f"step {k + 1} of period {c}: equilibrium residual {eq[k]:.3g} > "
                   f"{10 * solver.feas_tol:g} (recomputed with K)")


class _Track:
    """The period loop's state of one initial state."""

    def __init__(self, v0, w0):
        self.v, self.w = v0.copy(), w0.copy()
        self.prev_states = np.where(w0 > 0, SEPARATED, STICK).astype(np.int8)
        self.guess = self.prev_states.copy()
        self.statuses: dict[str, int] = {}
        self.max_res = 0.0
        self.ok, self.fail_msg = True, ""
        self.W_jump = 0.0
        self.starts_v, self.starts_w = [v0.copy()], [w0.copy()]
        self.W_list, self.change, self.records = [], [], []
        self.history = None
        self.period = 0
        self.base = None  # the base factor of this state's low-rank updates
        self.last_act = None  # the kernel's assignments of the last period

    @property
    def running(self):
        return self.ok and self.period == 0


def _implicit_cycles(solver, c, tracks, qw, pw, load, lam):
    """Period ``c`` of every track in lockstep; one CycleRecord per track."""
    k = len(tracks)
    n_steps, n = qw.shape
    V = np.empty((k, n_steps + 1, n))
    Wg, Q, P = np.empty_like(V), np.empty_like(V), np.empty_like(V)
    st = np.empty((k, n_steps + 1, n), np.int8)
    act = np.empty((k, n_steps, n), np.int8)
    scales = np.empty((k, n_steps))
    q0w, p0w = load.evaluate(0.0, lam)
    for i, tr in enumerate(tracks):
        V[i, 0], Wg[i, 0], st[i, 0] = tr.v, tr.w, tr.prev_states
    R0 = np.hstack([V[:, 0], Wg[:, 0]]) @ solver.K
    Q[:, 0], P[:, 0] = q0w + R0[:, :n], p0w + R0[:, n:]
    guesses = np.array([tr.guess for tr in tracks], np.int8)
    # the first step's base from scratch: (A v, B^T v)
    R1 = (np.hstack([V[:, 0], np.zeros_like(V[:, 0])]) @ solver.K if solver.schur
          else V[:, 0] @ solver.K[:n])
    Q0, P0 = qw[0] + R1[:, :n], pw[0] + R1[:, n:]
    Wd = np.zeros(k)
    worst = np.zeros(k)
    alive = np.arange(k)
    fail = {}
    if fast_period.usable(solver):  # each state's period by the compiled kernel
        res = np.zeros(n_steps)
        for i, tr in enumerate(tracks):
            res[:] = 0.0
            Wd[i], guesses[i], failed = fast_period.run_period(
                solver, qw, pw, V[i, 0], guesses[i], V[i], Wg[i], Q[i], P[i], st[i], act[i],
                scales[i], res, tr.statuses, pred=tr.last_act)
            worst[i] = max(worst[i], float(res.max()))
            if failed is not None:
                fail[i] = failed
            else:
                tr.last_act = act[i]  # the next period's prediction (kernel's probe)
        alive = alive[:0]
    # each state's assignments of its previous period predict this one's (the kernel's probe,
    # StepSolver._probe): on a steady or settling orbit step j's assignment is the previous
    # period's, one solve with a cached factor instead of two from the previous step's guess
    pred = [tracks[i].last_act if solver.well_posed is True else None for i in range(k)]
    dqw, dpw = np.diff(qw, axis=0), np.diff(pw, axis=0)
    alive = [int(i) for i in alive]
    for j in range(n_steps if alive else 0):
        bases = [tracks[i].base for i in alive]
        ia = np.array(alive)  # one index array for the four gathers
        res = solve_many(solver, V[ia, j], qw[j], pw[j], guesses[ia], Q0[ia],
                         P0[ia], bases, [None if pred[i] is None else pred[i][j]
                                         for i in alive])
        for i, b in zip(alive, bases, strict=True):
            tracks[i].base = b
        keep = []
        for a, (i, r) in enumerate(zip(alive, res, strict=True)):
            statuses = tracks[i].statuses
            statuses[r.status] = statuses.get(r.status, 0) + 1
            if r.residual > worst[i]:
                worst[i] = r.residual
            if not r.success:
                fail[i] = (j, r)
                continue
            keep.append(a)
            Wd[i] -= float(r.q @ r.slip_increment)
            V[i, j + 1], Wg[i, j + 1], Q[i, j + 1], P[i, j + 1] = r.slip, r.gap, r.q, r.p
            st[i, j + 1], act[i, j], guesses[i] = r.states, r.active_set, r.active_set
            scales[i, j] = r.force_scale
            if j + 1 < n_steps:
                Q0[i], P0[i] = solver.next_base(r.q, r.p, r.gap, dqw[j], dpw[j])
        alive = [alive[a] for a in keep]
        if not alive:
            break
    recs = []
    for i in range(k):
        if i in fail:
            j, r = fail[i]
            recs.append(CycleRecord(
                np.zeros(0), V[i, :j + 1], Wg[i, :j + 1], Q[i, :j + 1], P[i, :j + 1],
                st[i, :j + 1], Wd[i], ok=False, max_residual=worst[i],
                message=f"step {j + 1} of period {c} (t = {c - 1 + (j + 1) / n_steps:.6g}): "
                        f"{r.status}: {r.message}"))
            continue
        w_i, msg = _check_period(solver, c, V[i], Wg[i], Q[i], P[i], qw, pw, scales[i],
                                 worst[i])
        t = c - 1 + np.arange(n_steps + 1) / n_steps
        if not msg:
            tracks[i].last_act = act[i]
        recs.append(CycleRecord(t, V[i], Wg[i], Q[i], P[i], st[i], Wd[i], active_sets=act[i],
                                n_steps=n_steps, max_residual=w_i, ok=not msg, message=msg))
    return recs


def run_states(system, solver, load, lam, V0, W0, method, n_steps, max_cycles, tol, *,
               progress=None, record_history=False):
    """The period loop of :func:`~.cycles.solve_cycles` for the rows of ``V0`` / ``W0``
    (validated, shape (k, N)); a list of ``k`` CycleRun."""
    t_start = time.perf_counter()
    totals0 = dict(solver.totals)
    note = ""
    exact_load = load
    if method == "events" and load.kind != "samples":
        load = load.to_samples(n_steps)
        note = (f"harmonic load replaced by its piecewise-linear interpolant through "
                f"{n_steps} samples (load.to_samples); ")
    grid = (np.arange(1, n_steps + 1) / n_steps if method == "implicit"
            else np.arange(load.n_samples) / load.n_samples)
    qg, pg = load.evaluate(grid, lam)
    F = float(max(np.abs(qg).max(), np.abs(pg).max()))
    F = F if F > 0 else 1.0
    D = solver.diag
    check_energy_scale(F, D, tol)
    dtol = solver.feas_tol * F / D
    tracks = [_Track(v0, w0) for v0, w0 in zip(V0, W0, strict=True)]
    integrator = None
    if method == "events":
        integrator = EventIntegrator(solver, load, lam, F)
        q_w0, p_w0 = load.evaluate(0.0, lam)
        for tr in tracks:
            r = solver.solve(tr.v, q_w0, p_w0, tr.guess)
            tr.statuses[r.status] = tr.statuses.get(r.status, 0) + 1
            tr.max_res = r.residual
            if not r.success:
                tr.ok, tr.fail_msg = False, f"no verified equilibrium at t = 0: {r.message}"
            else:
                tr.W_jump = float(-(r.q @ r.slip_increment))
                tr.v, tr.w, tr.guess = r.slip, r.gap, r.active_set
                tr.starts_v[0], tr.starts_w[0] = tr.v.copy(), tr.w.copy()
    for tr in tracks:
        tr.history = [] if record_history else None
    c = 0
    while c < max_cycles and any(tr.running for tr in tracks):
        c += 1
        run = [tr for tr in tracks if tr.running]
        if method == "implicit":
            recs = _implicit_cycles(solver, c, run, qg, pg, load, lam)
        else:
            recs = [integrator.cycle(c, tr.v, tr.w, tr.prev_states, tr.guess) for tr in run]
        for tr, rec in zip(run, recs, strict=True):
            _advance(tr, rec, c, D, F, tol, progress, max_cycles)
    runs = []
    for tr in tracks:
        with np.errstate(over="ignore", invalid="ignore"):  # overflow becomes status non_finite
            run = _finish(system, solver, load, lam, method, n_steps, tol, F, dtol, tr.records,
                          tr.history, tr.period, tr.W_list, tr.change, tr.starts_v, tr.starts_w,
                          tr.v, tr.w, tr.ok, tr.fail_msg, note, tr.statuses, tr.max_res, totals0,
                          t_start, integrator, max_cycles)
        orbit = tr.records[-tr.period:] if tr.period else []
        runs.append(trust(run, system, exact_load, orbit, solver))
    return runs


def _advance(tr, rec, c, D, F, tol, progress, max_cycles):
    """Book one simulated period of a track: records, W, state change, steady test."""
    tr.max_res = max(tr.max_res, rec.max_residual)
    if not rec.ok:
        tr.ok, tr.fail_msg = False, rec.message
        return
    tr.records = (tr.records + [rec])[-2:]
    if tr.history is not None:
        tr.history.append(rec)
    tr.v, tr.w = rec.v[-1].copy(), rec.w[-1].copy()
    tr.prev_states = rec.states[-1]
    tr.guess = rec.active_sets[-1] if rec.active_sets.ndim == 2 else rec.active_sets
    tr.W_list.append(rec.dissipation + (tr.W_jump if c == 1 else 0.0))
    tr.change.append(_state_change(D, F, tr.v, tr.w, tr.starts_v[-1], tr.starts_w[-1]))
    tr.starts_v.append(tr.v.copy())
    tr.starts_w.append(tr.w.copy())
    if progress is not None:
        progress(c, max_cycles, rec.dissipation)
    if tr.change[-1] <= tol:
        tr.period = 1
    elif c >= 2 and _state_change(D, F, tr.v, tr.w, tr.starts_v[-3], tr.starts_w[-3]) <= tol:
        tr.period = 2
