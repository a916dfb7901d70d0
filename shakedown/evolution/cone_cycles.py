"""The cyclic driver for ``dim = 3`` systems: implicit steps of the cone law (MODEL.md s.8).

:func:`solve_cycles_3d` is what :func:`shakedown.solve_cycles` runs for a 3-D system: the same
period loop, steady-state test (period 1 and 2), dissipation per period, energy identity,
permanently stuck nodes and :class:`~.cycle_results.CycleRun` result as in 2-D, with the step of
:class:`~.cone_step.ConeStepSolver`.  Slips and tangential reactions have shape (..., N, 2).

Scales (as in 2-D, with Euclidean norms per node): ``F`` is the largest welded reaction
component over the run's time grid; the state change between two states is
``max_i (k_i |dv_i| + C_ii |dw_i|) / F`` with ``k_i`` the node's tangential stiffness (the
mean of its two diagonal entries of ``A``).  A node *slips* in the steady orbit when its slip
path in contact, ``sum |dv_i|`` over the orbit's steps, exceeds ``SHAKEDOWN_FACTOR * tol *
F / k_i``.

Warm start: step ``j`` of period ``c >= 2`` starts the Newton method from the increment and gaps
of step ``j`` of period ``c - 1`` (the orbit being approached repeats them), period 1 from the
previous step's.  From period 4 on, the start is extrapolated along the approach: ``U_{c-1} +
rho (U_{c-1} - U_{c-2})`` per step, with ``rho`` the least-squares ratio of the last two
period-to-period changes of the increments (in force units, :func:`_predictor`), clipped to
``[0, RHO_MAX]`` (0: the plain start).  Only where the Newton method starts changes: every step
is still solved to the same tolerance and verified, so the answers are those of the plain start
to the step's tolerance.  Products with ``K`` are reused: a step's base reactions ``(q_w + A v,
p_w + B^T v)`` are the previous step's reactions minus its gaps' share plus the change of the
welded load, and the reactions ``r_b + K u_0`` of a warm start come from the stored ``K U =
r - r_b`` of the periods it combines; the equilibrium of every step is then checked once per
period against base reactions recomputed from the slips (one matrix product per period).

Acceleration (``anderson_memory > 0``, off by default): the start of the next period is the
Anderson (type II) combination of the last ``anderson_memory + 1`` period starts ``x`` and their
one-period images ``P(x)`` (the update :func:`~.anderson._anderson` of
:func:`shakedown.steady_cycle`) instead of ``P(x)`` itself, reset to the plain image when the
state change grows.  The steady test is unchanged (a simulated period whose end differs from its
start by at most ``tol``), so the recorded orbit is a simulated steady period; what may differ
from plain cycling is the path, and, where the steady state is not unique (locked-in slips of
nodes that never slip), which steady state is reached.  Period 2 is tested only after a plain
period.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..model.errors import InputError, ShapeError
from ..model.threads import single_blas_thread
from ..model.validation import check_count, check_load_factor, check_same_nodes
from .anderson import _anderson
from .cone_step import ConeStepSolver
from .cone_tables import table_3d
from .cycle_results import SHAKEDOWN_FACTOR, CycleRun, _energy, _outcome
from .events import CycleRecord
from .step_types import SEPARATED


class _FlatLoad:
    """The load with tangential arrays flattened to (..., 2N) (system order), for
    :func:`~.cycle_results._energy`."""

    def __init__(self, load):
        self.load = load

    def evaluate(self, t, lam):
        q, p = self.load.evaluate(t, lam)
        return q.reshape(q.shape[:-2] + (-1,)), p


def _states_in(name, value, n, k=None):
    x = np.array(value, dtype=float)
    if x.ndim == 2 and x.shape == (n, 2):
        x = x[None]
    if x.ndim != 3 or x.shape[1:] != (n, 2):
        raise ShapeError(f"{name} of a 3-D system must have shape ({n}, 2) or (n_states, {n}, 2);"
                         f" got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be finite")
    return x


def _check(system, load, lam, initial_slip, initial_gap, method, steps, max_cycles, tol):
    n = system.n_nodes
    check_same_nodes(system, load)
    if getattr(load, "dim", 3) != 3:
        raise ShapeError(f"a 3-D system needs a 3-D load (q0 of shape ({n}, 2)); got a 2-D load")
    lam = check_load_factor(lam, load)
    if method != "implicit":
        raise InputError(f"method={method!r} is not available for dim = 3 (the exact event path "
                         "of a cone law is not piecewise affine); use method='implicit'")
    steps = check_count("steps_per_cycle", steps, 2)
    max_cycles = check_count("max_cycles", max_cycles, 1)
    tol = float(tol)
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a positive number (e.g. 1e-10); got {tol}")
    batch = initial_slip is not None and np.ndim(initial_slip) == 3
    V0 = np.zeros((1, n, 2)) if initial_slip is None else _states_in("initial_slip",
                                                                     initial_slip, n)
    k = V0.shape[0]
    if initial_gap is None:
        W0 = np.zeros((k, n))
    else:
        g = np.array(initial_gap, dtype=float)
        if g.shape == (n,):
            g = np.repeat(g[None], k, axis=0)
        if g.shape != (k, n) or not np.all(np.isfinite(g)) or np.any(g < 0):
            raise InputError(f"initial_gap must be finite, >= 0, of shape ({n},) or ({k}, {n}); "
                             f"got shape {np.shape(initial_gap)}")
        W0 = g
    return lam, V0, W0, steps, max_cycles, tol, batch


def solve_cycles_3d(system, load, lam, initial_slip=None, initial_gap=None,
                    method="implicit", steps_per_cycle=200, max_cycles=200, tol=1e-10, *,
                    progress=None, record_history=False, solver=None, feas_tol=None,
                    anderson_memory=0):
    """:func:`shakedown.solve_cycles` for a ``dim = 3`` system (same parameters and result).

    ``initial_slip`` has shape (N, 2) or (n_states, N, 2) (a list of runs then); ``method`` must
    be ``"implicit"``; ``solver`` a :class:`~.cone_step.ConeStepSolver` of the same system.
    In the result, ``final_slip`` is (N, 2), ``cycle_start_slips`` (n_cycles + 1, N, 2), the
    steady table has columns ``slip_x, slip_y, q_x, q_y`` instead of ``slip, q``, states are
    ``stick / slip / separation``; ``final_active_sets`` holds the last period's Newton
    pieces (steps, N).  ``anderson_memory``: periods remembered by the steady-state accelerator
    (0: plain cycling, the default; see the module docstring).
    """
    lam, V0, W0, n_steps, max_cycles, tol, batch = _check(
        system, load, lam, initial_slip, initial_gap, method, steps_per_cycle, max_cycles, tol)
    if isinstance(anderson_memory, bool) or not isinstance(anderson_memory, (int, np.integer)) \
            or anderson_memory < 0:
        raise InputError(f"anderson_memory must be an integer >= 0 (0: plain cycling, e.g. 5); "
                         f"got {anderson_memory!r}")
    if solver is None:
        solver = ConeStepSolver(system) if feas_tol is None else ConeStepSolver(
            system, feas_tol=feas_tol)
    elif getattr(solver, "system", None) is not system:
        raise InputError("solver was built for another system; pass solver=None")
    with single_blas_thread():
        runs = [_run(system, solver, load, lam, v0, w0, n_steps, max_cycles, tol, progress,
                     record_history, int(anderson_memory)) for v0, w0 in zip(V0, W0, strict=True)]
    return runs if batch else runs[0]


def _change(d, F, v1, w1, v0, w0):
    dv = np.hypot(*(v1 - v0).T)
    return float(np.max(d.kT * dv + d.kN * np.abs(w1 - w0), initial=0.0) / F)


#: Largest ratio of the geometric approach used by the warm-start extrapolation.
RHO_MAX = 0.95


def _predictor(U_hist, d, KU_hist=None):
    """Warm starts (steps, N, 3) of the next period from the increments of the last periods
    ``U_hist`` (oldest first, each (steps, N, 3)): the last one alone with fewer than three,
    else ``U1 + rho (U1 - U2)`` with ``rho = <U1 - U2, U2 - U3> / |U2 - U3|^2`` (slips scaled by
    ``k_T``, gaps by ``C_ii``: force units) clipped to ``[0, RHO_MAX]``.  With ``KU_hist`` (the
    products ``K U`` of the same periods, node order) also the products of the warm starts, the
    same combination: ``(G, KG)``."""
    if KU_hist is not None:
        G = _predictor(U_hist, d)
        if G is None or len(U_hist) < 3 or G is U_hist[-1]:
            return G, (KU_hist[-1] if KU_hist else None)
        rho = _ratio(U_hist, d)
        return G, KU_hist[-1] + rho * (KU_hist[-1] - KU_hist[-2])
    if not U_hist:
        return None
    U1 = U_hist[-1]
    if len(U_hist) < 3:
        return U1
    rho = _ratio(U_hist, d)
    return U1 if rho == 0.0 else U1 + rho * (U1 - U_hist[-2])


def _ratio(U_hist, d):
    """The clipped ratio ``rho`` of :func:`_predictor` (three periods or more)."""
    U1 = U_hist[-1]
    s = np.column_stack([d.kT, d.kT, d.kN])
    a = (U1 - U_hist[-2]) * s
    b = (U_hist[-2] - U_hist[-3]) * s
    bb = float(np.sum(b * b))
    rho = float(np.sum(a * b)) / bb if bb > 0 else 0.0
    return min(max(rho, 0.0), RHO_MAX) if np.isfinite(rho) else 0.0


def _period(solver, c, v, w, qg, pg, U_prev, st0, KU_prev=None):
    """One period of implicit steps from ``(v, w)`` with warm starts ``U_prev`` (steps, N, 3)
    (None: each step from the previous one) and their products ``KU_prev`` with ``K`` (node
    order; None: computed by the steps); a CycleRecord (3-D shapes), the increments ``U`` and
    their products ``K U`` (steps, N, 3) (``r - r_b`` of the steps)."""
    n_steps, n = pg.shape
    V = np.empty((n_steps + 1, n, 2))
    Q = np.empty_like(V)
    Wg, P = np.empty((n_steps + 1, n)), np.empty((n_steps + 1, n))
    st = np.empty((n_steps + 1, n), np.int8)
    act = np.empty((n_steps, n), np.int8)
    U = np.empty((n_steps, n, 3))
    R = np.empty((n_steps, n, 3))
    RB = np.empty((n_steps, n, 3))
    scales = np.empty(n_steps)
    V[0], Wg[0] = v, w
    st[0] = st0  # the state of the previous period's last step (as in 2-D)
    r0 = solver.base(v, qg[-1], pg[-1])  # the load at t = 0 (= t = 1 of the grid)
    r0 += (solver.data.Kn[:, 2::3] @ w).reshape(n, 3)
    Q[0], P[0] = r0[:, :2], r0[:, 2]
    guess = None if U_prev is None else U_prev[-1]
    Wd = 0.0
    worst = 0.0
    statuses: dict[str, int] = {}
    Kn = solver.data.Kn
    rb = solver.base(v, qg[0], pg[0])
    for j in range(n_steps):
        g = U_prev[j] if U_prev is not None else guess
        ku = KU_prev[j] if KU_prev is not None else None
        u, r, s, name, it, res, F = solver.solve_raw(rb, g, equilibrium=False, ku0=ku)
        ok = res.worst <= solver.feas_tol
        key = ("unique" if solver.well_posed else "solved") if ok else "failed"
        statuses[key] = statuses.get(key, 0) + 1
        worst = max(worst, res.worst)
        V[j + 1] = V[j] + u[:, :2]
        Wg[j + 1], Q[j + 1], P[j + 1] = u[:, 2], r[:, :2], r[:, 2]
        st[j + 1] = solver.kinematic_states(u, F)
        act[j], U[j], R[j], RB[j], scales[j] = s, u, r, rb, F
        Wd -= float(np.sum(r[:, :2] * u[:, :2]))
        guess = u
        if ok and j + 1 < n_steps:  # the next base from this step's reactions (exact below)
            rb = r.copy()
            rb[:, :2] += qg[j + 1] - qg[j]
            rb[:, 2] += pg[j + 1] - pg[j]
            sep = np.flatnonzero(u[:, 2])
            if sep.size:  # minus the gaps' reactions (B w, C w) of this step
                rb -= (Kn[:, 3 * sep + 2] @ u[sep, 2]).reshape(n, 3)
        if not ok:
            t = c - 1 + (j + 1) / n_steps
            rec = CycleRecord(np.zeros(0), V[:j + 2], Wg[:j + 2], Q[:j + 2], P[:j + 2],
                              st[:j + 2], Wd, ok=False, max_residual=worst, statuses=statuses,
                              message=f"step {j + 1} of period {c} (t = {t:.6g}): failed: "
                                      f"no verified solution (residual {res.worst:.3g})")
            return rec, U, None
    # equilibrium of every step of the period by products with K (node order), from the base
    # reactions recomputed from the slips (the steps took them from the previous step's)
    KU = R - RB  # K U of each step (for the next periods' warm starts)
    Vf = V[:-1].reshape(n_steps, -1)
    RB[:, :, :2] = qg + (Vf @ solver.A.T).reshape(n_steps, n, 2)
    RB[:, :, 2] = pg + Vf @ solver.Bt.T
    eq = np.abs(RB.reshape(n_steps, -1) + U.reshape(n_steps, -1) @ Kn - R.reshape(n_steps, -1))
    eq = eq.max(axis=1) / scales
    worst = max(worst, float(eq.max()))
    msg = ""
    if eq.max() > 10 * solver.feas_tol:
        k = int(np.argmax(eq))
        msg = (f"step {k + 1} of period {c}: equilibrium residual {eq[k]:.3g} > "
               f"{10 * solver.feas_tol:g} (recomputed with K)")
    t = c - 1 + np.arange(n_steps + 1) / n_steps
    rec = CycleRecord(t, V, Wg, Q, P, st, Wd, active_sets=act, n_steps=n_steps,
                      max_residual=worst, ok=not msg, message=msg, statuses=statuses)
    return rec, U, KU


def _run(system, solver, load, lam, v0, w0, n_steps, max_cycles, tol, progress, record_history,
         memory=0):
    t_start = time.perf_counter()
    tot0 = dict(solver.totals)
    d = solver.data
    grid = np.arange(1, n_steps + 1) / n_steps
    qg, pg = load.evaluate(grid, lam)
    F = float(max(np.abs(qg).max(), np.abs(pg).max()))
    F = F if F > 0 else 1.0
    v, w = v0.copy(), w0.copy()
    starts_v, starts_w = [v.copy()], [w.copy()]
    W_list, change, records, history = [], [], [], [] if record_history else None
    statuses: dict[str, int] = {}
    max_res, period, ok, fail_msg, U_hist, KU_hist = 0.0, 0, True, "", [], []
    st0 = np.where(w * d.kN > 0, SEPARATED, 0).astype(np.int8)
    X, G, jumped = [], [], False  # Anderson memory: period starts and their changes
    v_end = v.copy()
    for c in range(1, max_cycles + 1):
        guesses, products = _predictor(U_hist, d, KU_hist)
        rec, U, KU = _period(solver, c, v, w, qg, pg, guesses, st0, products)
        for k_, m_ in (rec.statuses or {}).items():
            statuses[k_] = statuses.get(k_, 0) + m_
        max_res = max(max_res, rec.max_residual)
        if not rec.ok:
            ok, fail_msg = False, rec.message
            break
        U_hist, KU_hist = (U_hist + [U])[-3:], (KU_hist + [KU])[-3:]
        records = (records + [rec])[-2:]
        if history is not None:
            history.append(rec)
        v, w, st0 = rec.v[-1].copy(), rec.w[-1].copy(), rec.states[-1].copy()
        v_end = v.copy()
        W_list.append(rec.dissipation)
        change.append(_change(d, F, v, w, starts_v[-1], starts_w[-1]))
        if progress is not None:
            progress(c, max_cycles, rec.dissipation)
        if change[-1] <= tol:
            period = 1
        elif c >= 2 and not jumped and _change(d, F, v, w, starts_v[-2], starts_w[-2]) <= tol:
            period = 2
        if period:
            starts_v.append(v.copy())
            starts_w.append(w.copy())
            break
        jumped = False
        if memory:
            if len(change) >= 2 and change[-1] > change[-2]:  # safeguard: restart the memory
                X, G = [], []
            X.append(starts_v[-1].ravel())
            G.append((v - starts_v[-1]).ravel())
            X, G = X[-memory - 1:], G[-memory - 1:]
            x = _anderson(X, G, v.ravel())
            if len(X) >= 2 and np.all(np.isfinite(x)):
                v, jumped = x.reshape(v.shape), True
                # the approach was interrupted: no extrapolation across
                U_hist, KU_hist = U_hist[-1:], KU_hist[-1:]
        starts_v.append(v.copy())
        starts_w.append(w.copy())
    return _finish_3d(system, solver, load, lam, n_steps, tol, F, records, history, period,
                      W_list, change, starts_v, starts_w, v_end, w, ok, fail_msg, statuses,
                      max_res, tot0, t_start, max_cycles)


def _finish_3d(system, solver, load, lam, n_steps, tol, F, records, history, period, W_list,
               change, starts_v, starts_w, v, w, ok, fail_msg, statuses, max_res, tot0,
               t_start, max_cycles):
    d = solver.data
    n_cycles = len(W_list)
    orbit = records[-period:] if period else records[-1:]
    if period:
        states = np.concatenate([r.states[1:] for r in orbit])
        V = np.concatenate([orbit[0].v] + [r.v[1:] for r in orbit[1:]])
        contact = states != SEPARATED
        travel = np.sum(np.hypot(*np.diff(V, axis=0).transpose(2, 0, 1)) * contact, axis=0)
        slipped = travel * d.kT / F > SHAKEDOWN_FACTOR * tol
        stuck = np.flatnonzero(~slipped & np.all(contact, axis=0))
        steady_W = float(np.mean([r.dissipation for r in orbit]))
        shook = not bool(np.any(slipped))
        flat = [_flat(r) for r in orbit]
        K = np.asarray(system.to_dense().K if getattr(system, "is_sparse", False) else system.K)
        diag = np.concatenate([np.repeat(d.kT, 2), d.kN])
        energy = _energy(flat, _FlatLoad(load), lam, diag, F, tol, K=K, implicit=True)
    else:
        stuck, steady_W, shook, energy = np.zeros(0, int), float("nan"), False, None
    status, msg = _outcome(period, n_cycles, shook, steady_W, ok, fail_msg, max_cycles, change,
                           tol, statuses)
    tot = {k: solver.totals[k] - tot0.get(k, 0) for k in solver.totals}
    stats = dict(n_steps=tot["steps"], n_events=0, rate_solves=0,
                 active_set_iterations=tot["iterations"], factorizations=tot["iterations"],
                 low_rank_updates=0, cache_hits=0, lemke_calls=0, enumerations=0,
                 newton_iterations=tot["iterations"], cold_restarts=tot["cold_restarts"],
                 gauss_seidel=tot["gauss_seidel"], wall_time=time.perf_counter() - t_start)
    run = CycleRun(
        dissipation=np.asarray(W_list, float), steady_dissipation=steady_W,
        shook_down=bool(shook), period=int(period), stuck_nodes=np.asarray(stuck, int),
        n_cycles=n_cycles, cycles_to_steady=n_cycles - period if period else -1,
        state_change=np.asarray(change, float), final_slip=np.asarray(v, float).copy(),
        final_gap=np.asarray(w, float).copy(), cycle_start_slips=np.asarray(starts_v),
        cycle_start_gaps=np.asarray(starts_w), steady_orbit=tuple(orbit),
        energy_identity=energy, status=status, message=msg, max_residual=float(max_res),
        step_statuses=dict(statuses), statistics=stats, method="implicit",
        steps_per_cycle=n_steps, lam=lam, tol=tol, force_scale=F, load=load,
        final_active_sets=records[-1].active_sets if records else None,
        history=table_3d(history) if history else None)
    return _trust_3d(run, system, load, orbit, solver)


def _flat(rec):
    """A record with the tangential arrays flattened to (points, 2N) (system order)."""
    k = rec.v.shape[0]
    return replace(rec, v=rec.v.reshape(k, -1), q=rec.q.reshape(k, -1))


def _trust_3d(run, system, load, orbit, solver):
    """Overflow as a failure; a shakedown whose smallest cone margin over the orbit is below what
    the load's sampling can hide flagged (``within_sampling_error``), as in 2-D."""
    from .sampling import non_finite_message

    numbers = (run.dissipation, run.final_slip, run.final_gap, [run.force_scale])
    if not all(np.all(np.isfinite(x)) for x in numbers) or (
            run.period and not np.isfinite(run.steady_dissipation)):
        return replace(run, status="non_finite", shook_down=False,
                       message=non_finite_message(run.force_scale, system) + "; " + run.message)
    err_q, err_p = load.sampling_error(run.steps_per_cycle)
    error = float(run.lam * max(err_q.max(initial=0.0), err_p.max(initial=0.0)))
    if not run.shook_down or error <= solver.feas_tol * run.force_scale or not orbit:
        return replace(run, sampling_error=error)
    d = solver.data
    S = np.column_stack([d.sx, d.sy])
    Q = np.concatenate([r.q for r in orbit])
    P = np.concatenate([r.p for r in orbit])
    contact = np.concatenate([r.w for r in orbit]) == 0
    margin = np.where(contact, (d.g * P - np.hypot(*(Q / S).transpose(2, 0, 1)))
                      * S.min(axis=1), np.inf).min(axis=0)
    fmax = system.friction_xy.max(axis=1)
    budget = run.lam * (1.0 + fmax) * np.maximum(err_q, err_p)
    short = np.flatnonzero(margin < budget)
    if short.size == 0:
        return replace(run, sampling_error=error)
    j = int(short[np.argmin(margin[short] - budget[short])])
    msg = (f"shook down on the load sampled at {run.steps_per_cycle} points per period, but node "
           f"{j + 1} keeps a cone margin of only {margin[j]:.3g}, below what the sampling can "
           f"hide ({budget[j]:.3g}): the verdict lies within the load's sampling error "
           f"({error:.3g}); rerun with more steps_per_cycle")
    return replace(run, sampling_error=error, within_sampling_error=True,
                   message=run.message + "; " + msg)


__all__ = ["solve_cycles_3d", "table_3d"]
