"""Quasi-static cyclic evolution: implicit steps or the exact event-driven path (MODEL.md s.4).

:func:`solve_cycles` simulates load periods from an initial state until the state at the start
of a period repeats (period ``T``) or repeats every second period (``2T``), and reports the
dissipation per period, the steady cycle, shakedown, the permanently stuck nodes and the energy
identity ``W = closed integral of u . d r_w``.

Scales (documented, used by every tolerance): the *force scale* ``F`` is the largest
``|q_w|, |p_w|`` over the load's time grid (1 if the load is identically zero); the state
change between two states is ``max_j (A_jj |dv_j| + C_jj |dw_j|) / F`` (dimensionless: the
largest change of a reaction a node's own stiffness would produce, relative to the load).
"""

from __future__ import annotations

import time

import numpy as np

from ..model.errors import InputError
from ..model.loading import LoadCycle
from ..model.system import DiscreteSystem
from ..model.validation import check_load_factor, check_same_nodes
from .complementarity import (
    FEAS_TOL,
    SEPARATED,
    STICK,
    StepSolver,
    _vec,
)
from .cycle_results import SHAKEDOWN_FACTOR, CycleRun, EnergyIdentity, _finish
from .events import CycleRecord, EventIntegrator


def _check_inputs(system, load, lam, initial_slip, initial_gap, method, steps_per_cycle,
                  max_cycles, tol):
    if not isinstance(system, DiscreteSystem):
        raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
    if not isinstance(load, LoadCycle):
        raise InputError(f"load must be a LoadCycle; got {type(load).__name__}")
    n = system.n_nodes
    check_same_nodes(system, load)
    lam = check_load_factor(lam)
    if method not in ("implicit", "events"):
        raise InputError(f"method must be 'implicit' or 'events'; got {method!r}")
    if isinstance(steps_per_cycle, bool) or int(steps_per_cycle) != steps_per_cycle \
            or steps_per_cycle < 2:
        raise InputError(f"steps_per_cycle must be an integer >= 2; got {steps_per_cycle!r}")
    if isinstance(max_cycles, bool) or int(max_cycles) != max_cycles or max_cycles < 1:
        raise InputError(f"max_cycles must be an integer >= 1; got {max_cycles!r}")
    try:
        tol = float(tol)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tol must be a positive number; got {tol!r}") from exc
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a positive number (e.g. 1e-10); got {tol}")
    v0 = np.zeros(n) if initial_slip is None else _vec("initial_slip", initial_slip, n)
    w0 = np.zeros(n) if initial_gap is None else _vec("initial_gap", initial_gap, n, nonneg=True)
    return lam, v0, w0, int(steps_per_cycle), int(max_cycles), tol


def _state_change(D, F, v1, w1, v0, w0):
    n = v1.shape[0]
    return float(np.max(D[:n] * np.abs(v1 - v0) + D[n:] * np.abs(w1 - w0), initial=0.0) / F)


def solve_cycles(system: DiscreteSystem, load: LoadCycle, lam: float, initial_slip=None,
                 initial_gap=None, method: str = "implicit", steps_per_cycle: int = 200,
                 max_cycles: int = 200, tol: float = 1e-10, *, progress=None,
                 record_history: bool = False, solver: StepSolver | None = None,
                 feas_tol: float | None = None) -> CycleRun:
    """Simulate load periods until the response is periodic (MODEL.md s.4).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lam : float
        Load factor (``>= 0``).
    initial_slip : array_like, shape (N,), optional
        Slips at ``t = 0`` (zeros by default) [length].
    initial_gap : array_like, shape (N,), optional
        Gaps at ``t = 0`` (zeros by default, ``>= 0``).  The step problem does not depend on the
        previous gap: it only seeds which nodes start separated.
    method : {"implicit", "events"}
        ``"implicit"``: step ``k = 1..steps_per_cycle`` of each period is the implicit step to
        ``t = k / steps_per_cycle``, the first from ``initial_slip`` with every node closed
        (unless ``initial_gap > 0``).  ``"events"``: the exact path for a load piecewise linear
        between samples (:mod:`shakedown.events`); a harmonic load is first replaced by
        ``load.to_samples(steps_per_cycle)`` (the run's ``load`` attribute and message say so).
        The initial state is brought to equilibrium by one implicit step at ``t = 0``.
    steps_per_cycle : int
        Implicit steps per period (``>= 2``); for events, the samples of a harmonic load.
    max_cycles : int
        Budget of simulated periods.
    tol : float
        Relative tolerance of the steady-state test (see the module docstring).
    progress : callable, optional
        ``progress(cycle_index, max_cycles, W_of_that_cycle)`` after every period.
    record_history : bool
        Keep every period's time series in ``history``.
    solver : StepSolver, optional
        Reuse a solver (its factor cache) across runs.  By default every call builds a fresh
        one, so that a run's result does not depend, even in the last bits, on which runs the
        process did before (the cache decides between an LU solve and a low-rank update).
    feas_tol : float, optional
        Feasibility tolerance of the steps (default :data:`FEAS_TOL`; builds a new solver).

    Returns
    -------
    CycleRun

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> load = sd.LoadCycle.from_samples([0.0], [1.0], [[1.0], [-1.0]], [[0.0], [0.0]])
    >>> run = sd.solve_cycles(s, load, 1.0, method="events")
    >>> run.period, round(run.steady_dissipation, 12)   # 4 f P (lam Q1 - f P) / k
    (1, 1.0)
    """
    lam, v0, w0, n_steps, max_cycles, tol = _check_inputs(
        system, load, lam, initial_slip, initial_gap, method, steps_per_cycle, max_cycles, tol)
    if solver is None:
        solver = StepSolver(system) if feas_tol is None else StepSolver(system, feas_tol=feas_tol)
    elif solver.system is not system:
        raise InputError("solver was built for another system; pass solver=None")
    t_start = time.perf_counter()
    totals0 = dict(solver.totals)
    note = ""
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
    dtol = solver.feas_tol * F / D

    step_statuses: dict[str, int] = {}
    max_res = 0.0
    ok, fail_msg = True, ""
    v, w = v0.copy(), w0.copy()
    prev_states = np.where(w0 > 0, SEPARATED, STICK).astype(np.int8)
    guess = prev_states.copy()
    W_jump = 0.0
    integrator = None
    if method == "events":
        integrator = EventIntegrator(solver, load, lam, F)
        q_w0, p_w0 = load.evaluate(0.0, lam)
        r = solver.solve(v, q_w0, p_w0, guess)
        step_statuses[r.status] = step_statuses.get(r.status, 0) + 1
        max_res = r.residual
        if not r.success:
            ok, fail_msg = False, f"no verified equilibrium at t = 0: {r.message}"
        else:
            W_jump = float(-(r.q @ r.slip_increment))
            v, w, guess = r.slip, r.gap, r.active_set
    else:
        qw_steps, pw_steps = qg, pg

    starts_v, starts_w = [v0.copy()], [w0.copy()]
    if method == "events" and ok:
        starts_v[0], starts_w[0] = v.copy(), w.copy()
    W_list, change = [], []
    records: list[CycleRecord] = []
    history = [] if record_history else None
    period = 0
    c = 0
    while ok and c < max_cycles:
        c += 1
        if method == "implicit":
            rec = _implicit_cycle(solver, c, v, w, prev_states, guess, qw_steps, pw_steps,
                                  load, lam, step_statuses)
        else:
            rec = integrator.cycle(c, v, w, prev_states, guess)
        max_res = max(max_res, rec.max_residual)
        if not rec.ok:
            ok, fail_msg = False, rec.message
            break
        records = (records + [rec])[-2:]
        if history is not None:
            history.append(rec)
        v, w = rec.v[-1].copy(), rec.w[-1].copy()
        prev_states = rec.states[-1]
        guess = rec.active_sets[-1] if rec.active_sets.ndim == 2 else rec.active_sets
        W_list.append(rec.dissipation + (W_jump if c == 1 else 0.0))
        change.append(_state_change(D, F, v, w, starts_v[-1], starts_w[-1]))
        starts_v.append(v.copy())
        starts_w.append(w.copy())
        if progress is not None:
            progress(c, max_cycles, rec.dissipation)
        if change[-1] <= tol:
            period = 1
            break
        if c >= 2 and _state_change(D, F, v, w, starts_v[-3], starts_w[-3]) <= tol:
            period = 2
            break

    return _finish(system, solver, load, lam, method, n_steps, tol, F, dtol, records, history,
                   period, W_list, change, starts_v, starts_w, v, w, ok, fail_msg, note,
                   step_statuses, max_res, totals0, t_start, integrator, max_cycles)


def _implicit_cycle(solver, c, v, w, prev_states, guess, qw, pw, load, lam, step_statuses):
    n_steps, n = qw.shape
    V = np.empty((n_steps + 1, n))
    Wg, Q, P = np.empty_like(V), np.empty_like(V), np.empty_like(V)
    st = np.empty((n_steps + 1, n), np.int8)
    act = np.empty((n_steps, n), np.int8)
    q0w, p0w = load.evaluate(0.0, lam)
    V[0], Wg[0] = v, w
    Q[0], P[0] = q0w + solver.A @ v + solver.B @ w, p0w + solver.Bt @ v + solver.C @ w
    st[0] = prev_states
    W = 0.0
    worst = 0.0
    scales = np.empty(n_steps)
    base = None  # the first step of a period computes its base from scratch
    for k in range(n_steps):
        r = solver.solve(v, qw[k], pw[k], guess, base=base, verify=False)
        step_statuses[r.status] = step_statuses.get(r.status, 0) + 1
        worst = max(worst, r.residual)
        if not r.success:
            rec = CycleRecord(np.zeros(0), V[:k + 1], Wg[:k + 1], Q[:k + 1], P[:k + 1],
                              st[:k + 1], W, ok=False, max_residual=worst,
                              message=f"step {k + 1} of period {c} (t = "
                              f"{c - 1 + (k + 1) / n_steps:.6g}): {r.status}: {r.message}")
            return rec
        W -= float(r.q @ r.slip_increment)
        v, guess = r.slip, r.active_set
        V[k + 1], Wg[k + 1], Q[k + 1], P[k + 1] = r.slip, r.gap, r.q, r.p
        st[k + 1] = r.states
        act[k] = r.active_set
        scales[k] = r.force_scale
        if k + 1 < n_steps:
            base = solver.next_base(r.q, r.p, r.gap, qw[k + 1] - qw[k], pw[k + 1] - pw[k])
    # every step's equilibrium (q, p) = r_w + K (v, w), checked independently for the whole
    # period by one matrix-matrix product (BLAS-3) instead of a matrix-vector product per step
    U = np.hstack([V[1:], Wg[1:]])
    E = np.hstack([qw - Q[1:], pw - P[1:]]) + U @ solver.K
    eq = np.abs(E).max(axis=1) / scales
    worst = max(worst, float(eq.max()))
    if not worst <= 10 * solver.feas_tol:
        k = int(np.argmax(eq))
        return CycleRecord(np.zeros(0), V, Wg, Q, P, st, W, ok=False, max_residual=worst,
                           message=f"step {k + 1} of period {c}: equilibrium residual "
                           f"{eq[k]:.3g} > {10 * solver.feas_tol:g} (recomputed with K)")
    t = c - 1 + np.arange(n_steps + 1) / n_steps
    return CycleRecord(t, V, Wg, Q, P, st, W, active_sets=act, n_steps=n_steps,
                       max_residual=worst)


__all__ = ["solve_cycles", "CycleRun", "EnergyIdentity", "FEAS_TOL", "SHAKEDOWN_FACTOR"]
