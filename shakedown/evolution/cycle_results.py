"""Results of :func:`~.cycles.solve_cycles`: :class:`CycleRun`, the energy identity of the
steady orbit and the assembly of a run's tables (MODEL.md s.4).

Scales as in :mod:`.cycles`: ``F`` is the load's force scale, ``D`` the diagonal of ``K``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..model.loading import LoadCycle
from ..model.results import short_repr
from .cone_tables import table_3d
from .step_types import SEPARATED, STATE_NAMES

#: A node *slips* in the steady orbit when its total slip while in contact exceeds
#: ``SHAKEDOWN_FACTOR * tol * F / A_jj``.  An orbit approached geometrically is accepted once a
#: period changes the state by ``<= tol``; its remaining slip is a few times that (forward and
#: backward slips that cancel), hence the factor 10.
SHAKEDOWN_FACTOR = 10.0


@dataclass(frozen=True)
class EnergyIdentity:
    """``W`` against the closed integral of ``u . d r_w`` over the steady orbit.

    Attributes
    ----------
    dissipation : float
        ``W`` of the steady orbit (summed over its ``period`` load periods) [energy].
    closed_integral : float
        ``sum_k (u_{k-1} + u_k) / 2 . (r_w,k - r_w,k-1)`` over the orbit's points (exact for
        the event-driven path, whose ``u`` and ``r_w`` are affine between points; for implicit
        steps a trapezoidal estimate whose difference from ``W`` is the O(1/steps) error of the
        backward-Euler path).
    difference : float
        ``dissipation - closed_integral``.
    relative_difference : float
        ``|difference| / max(|W|, |integral|, F^2 sum_j 1 / A_jj * tol)`` (dimensionless).
    numerical_dissipation : float
        Energy lost by the time discretisation itself (0 for the event-driven path).  For
        implicit (backward-Euler) steps the exact discrete balance is, with ``r = r_w + K u``
        and ``p_k w_k = 0``,

            W = sum_k u_{k-1} . (r_w,k - r_w,k-1) - sum_k [ (u_k - u_{k-1})^T K (u_k - u_{k-1}) / 2
                + p_k . w_{k-1} ] - [u . r_w + u^T K u / 2]_start^end

        (the last bracket vanishes on a periodic orbit).  This is the sum in brackets: the
        ``O(1/steps)`` gap between ``W`` and the continuous closed integral.
    discrete_difference : float
        ``W`` minus the right-hand side of that balance: zero to solver tolerance for every
        step count (for the event path it equals ``difference``).
    discrete_relative_difference : float
        The same, scaled like ``relative_difference``.
    """

    dissipation: float
    closed_integral: float
    difference: float
    relative_difference: float
    numerical_dissipation: float = 0.0
    discrete_difference: float = float("nan")
    discrete_relative_difference: float = float("nan")


@dataclass(frozen=True, eq=False)
class CycleRun:
    """Result of :func:`solve_cycles`.

    Attributes
    ----------
    dissipation : ndarray, shape (n_cycles,)
        ``W`` of every simulated period [energy]: implicit, ``sum_k -q_k . (v_k - v_{k-1})``
        with the end-of-step ``q``; events, ``sum f_j p_j |dv_j|`` integrated exactly.  The
        work of bringing the initial state to equilibrium (events: a jump at ``t = 0``) is in
        period 1.
    steady_dissipation : float
        ``W`` per load period of the steady orbit (mean over its ``period`` periods, without
        the initial jump of the events method); nan if none.
    shook_down : bool
        A steady orbit was reached in which no node slips: the total slip of node ``j`` while in
        contact over the orbit is at most ``SHAKEDOWN_FACTOR * tol * F / A_jj``.
    period : int
        1 or 2 (load periods) or 0 (no steady orbit within ``max_cycles``).
    stuck_nodes : ndarray of int
        Nodes in contact throughout the steady orbit that never slip (same test as
        ``shook_down``):
        the permanently stuck set ``S0``; empty if no steady orbit.
    n_cycles : int
        Simulated periods.
    cycles_to_steady : int
        Periods simulated before the steady orbit began (``n_cycles - period``); -1 if none.
    state_change : ndarray, shape (n_cycles,)
        Change of state over each period (see the module docstring); period 1 is detected when
        it is ``<= tol``, period 2 when the change over two periods is.
    final_slip, final_gap : ndarray, shape (N,)
        State at the end of the last simulated period.
    cycle_start_slips, cycle_start_gaps : ndarray, shape (n_cycles + 1, N)
        State at ``t = 0, 1, ..., n_cycles`` (row 0: the initial state; events: after the
        equilibrium jump at ``t = 0``).
    steady_orbit : tuple of CycleRecord
        The records behind ``steady_table`` (internal; arrays per period).
    steady_table : pandas.DataFrame
        The steady orbit's time series, one row per (time, node): ``cycle``, ``t`` (absolute,
        cycles), ``node``, ``slip``, ``gap``, ``q``, ``p``, ``state`` (:data:`STATE_NAMES`, of the
        step / segment ending at ``t``); the first row of each node is the orbit's start.  If no
        steady orbit was reached, the last simulated period (``steady`` attribute False).
    energy_identity : EnergyIdentity or None
        Over the steady orbit (None if none).
    status : str
        ``"periodic"``, ``"not_converged"`` (no steady orbit within ``max_cycles``) or
        ``"step_failed"`` (a step / rate problem had no verified solution; the run stopped) or
        ``"non_finite"`` (the numbers overflowed: load factor or units too large).
    message : str
        Human-readable summary, including non-unique steps (friction above critical) if any.
    max_residual : float
        Largest complementarity residual of any step (dimensionless, see ``StepResult``).
    step_statuses : dict
        Count of steps per ``StepResult.status`` (implicit; events: the initial projection).
    statistics : dict
        ``n_steps`` (implicit steps, or event segments), ``n_events`` (segments), ``rate_solves``,
        ``active_set_iterations``,
        ``factorizations``, ``low_rank_updates``, ``cache_hits``, ``lemke_calls``,
        ``enumerations``, ``wall_time`` [s].
    method, steps_per_cycle, lam, tol, force_scale :
        The run's settings; ``load`` is the load actually simulated (events with a harmonic
        load: its ``to_samples(steps_per_cycle)`` interpolant).
    final_active_sets : ndarray or None
        Implicit: the state assignments of the last period's steps, shape (steps, N).
    history : pandas.DataFrame or None
        All periods' time series (``record_history=True``), same columns as ``steady_table``.
    sampling_error : float
        Largest error of the welded reactions the run saw, sampled at ``steps_per_cycle``
        points, against the given load [force] (closed form for harmonics; 0 for the event
        path of a sampled load), see :mod:`shakedown.evolution.sampling`.
    within_sampling_error : bool
        The run shook down, but the exact load breaks a stick constraint at its final state:
        the verdict lies within the sampling error (the message says where).
    sampling_note : str
        What the check against the exact load found ('' when nothing was needed): the flag
        with its advice, or how far the slips at the exact load's extreme times moved the
        final state when they settled the verdict.
    """

    dissipation: np.ndarray
    steady_dissipation: float
    shook_down: bool
    period: int
    stuck_nodes: np.ndarray
    n_cycles: int
    cycles_to_steady: int
    state_change: np.ndarray
    final_slip: np.ndarray
    final_gap: np.ndarray
    cycle_start_slips: np.ndarray
    cycle_start_gaps: np.ndarray
    steady_orbit: tuple = field(repr=False)
    energy_identity: EnergyIdentity | None
    status: str
    message: str
    max_residual: float
    step_statuses: dict
    statistics: dict
    method: str
    steps_per_cycle: int
    lam: float
    tol: float
    force_scale: float
    load: LoadCycle = field(repr=False)
    final_active_sets: np.ndarray | None = field(default=None, repr=False)
    history: object = field(default=None, repr=False)
    sampling_error: float = 0.0
    within_sampling_error: bool = False
    sampling_note: str = ""

    @cached_property
    def steady_table(self):
        """The steady orbit's time series as a DataFrame (built on first access from
        ``steady_orbit``; see the class docstring)."""
        return _table(self.steady_orbit)

    @property
    def success(self) -> bool:
        """A steady orbit was reached."""
        return self.status == "periodic"

    def __repr__(self) -> str:
        return short_repr(self, ("lam", "method", "steps_per_cycle", "status", "period",
                                 "shook_down", "steady_dissipation", "n_cycles",
                                 "cycles_to_steady", "within_sampling_error"),
                          {"n_nodes": int(np.shape(self.final_slip)[0]),
                           "n_stuck": int(np.size(self.stuck_nodes))})

    def verdict(self, energy: str = "[force x length]", study=None, bounds=None) -> str:
        """The answer in plain sentences (:func:`shakedown.evolution.verdicts.cycles_verdict`):
        shook down / cyclic slip with ``W`` in ``energy`` units / no steady state, and what the
        check against the exact load found."""
        from .verdicts import cycles_verdict

        return cycles_verdict(self, self.lam, energy, study, bounds)


def orbit_arrays(records):
    """``(v, w, states)`` of the orbit's points, shape (points, N): the first record whole,
    the later ones without their first row (it repeats the previous record's last)."""
    take = [(r if i == 0 else _Tail(r)) for i, r in enumerate(records)]
    return (np.concatenate([r.v for r in take]), np.concatenate([r.w for r in take]),
            np.concatenate([r.states for r in take]))


class _Tail:
    def __init__(self, rec):
        self.v, self.w, self.states = rec.v[1:], rec.w[1:], rec.states[1:]


def _table(records):
    import pandas as pd

    if records and records[0].v.ndim == 3:  # a 3-D run: (points, N, 2) slips
        return table_3d(records)

    frames = []
    for i, rec in enumerate(records):
        sl = slice(0, None) if i == 0 else slice(1, None)  # the orbit's points, no repeats
        t = rec.t[sl]
        K, n = rec.v[sl].shape
        frames.append(pd.DataFrame({
            "cycle": np.full(K * n, int(round(rec.t[-1])) if rec.t.size else 0),
            "t": np.repeat(t, n),
            "node": np.tile(np.arange(n), K),
            "slip": rec.v[sl].ravel(),
            "gap": rec.w[sl].ravel(),
            "q": rec.q[sl].ravel(),
            "p": rec.p[sl].ravel(),
            "state": pd.Categorical.from_codes(rec.states[sl].ravel().astype(int),
                                               categories=list(STATE_NAMES)),
        }))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(
        columns=["cycle", "t", "node", "slip", "gap", "q", "p", "state"])


def _energy(records, load, lam, D, F, tol, K=None, implicit=False):
    t = np.concatenate([records[0].t] + [r.t[1:] for r in records[1:]])
    u = np.concatenate([np.hstack([records[0].v, records[0].w])]
                       + [np.hstack([r.v[1:], r.w[1:]]) for r in records[1:]])
    qw, pw = load.evaluate(t, lam)
    rw = np.hstack([qw, pw])
    du, drw = np.diff(u, axis=0), np.diff(rw, axis=0)
    integral = float(np.sum(0.5 * (u[1:] + u[:-1]) * drw))
    W = float(sum(r.dissipation for r in records))
    if W != 0.0 and abs(W) < np.finfo(float).tiny:
        import warnings

        warnings.warn(f"the dissipation per cycle W = {W:.3g} is a subnormal number (below "
                      f"{np.finfo(float).tiny:.3g}): it has lost precision; express forces and "
                      "lengths in units nearer to the problem's size", RuntimeWarning, stacklevel=2)
    n = records[0].v.shape[1]
    floor = F * F * float(np.sum(1.0 / D[:n])) * tol
    scale = max(abs(W), abs(integral), floor)
    rel = abs(W - integral) / scale
    if not implicit or K is None:
        return EnergyIdentity(W, integral, W - integral, rel, 0.0, W - integral, rel)
    # exact backward-Euler balance (see EnergyIdentity): left-point load work, minus the
    # discretisation losses, minus the boundary terms of a not exactly closed orbit
    p = np.concatenate([records[0].p] + [r.p[1:] for r in records[1:]])
    gaps = u[:, n:]
    losses = 0.5 * float(np.sum((du @ K) * du)) + float(np.sum(p[1:] * gaps[:-1]))
    left = float(np.sum(u[:-1] * drw))
    boundary = (float(u[-1] @ rw[-1] + 0.5 * u[-1] @ K @ u[-1])
                - float(u[0] @ rw[0] + 0.5 * u[0] @ K @ u[0]))
    ddiff = W - (left - losses - boundary)
    return EnergyIdentity(W, integral, W - integral, rel, losses, ddiff, abs(ddiff) / scale)


def _outcome(period, n_cycles, shook, steady_W, ok, fail_msg, max_cycles, change, tol,
             step_statuses):
    """A cycle run's ``(status, message)`` (2-D and 3-D drivers alike)."""
    if period:
        status = "periodic"
        msg = (f"periodic with period {period} T after {n_cycles} period(s); "
               + ("shook down" if shook else f"steady W = {steady_W:.6g} per period"))
    elif ok:
        status = "not_converged"
        msg = (f"no steady orbit within {max_cycles} period(s); last state change "
               f"{change[-1]:.3g} > tol = {tol:g}" if change else "no period simulated")
    else:
        status, msg = "step_failed", f"stopped: {fail_msg}"
    bad = {k: m for k, m in step_statuses.items() if k != "unique"}
    if bad:
        msg += "; step statuses " + ", ".join(f"{k}: {m}" for k, m in sorted(bad.items()))
    return status, msg


def _finish(system, solver, load, lam, method, n_steps, tol, F, dtol, records, history, period,
            W_list, change, starts_v, starts_w, v, w, ok, fail_msg, note, step_statuses,
            max_res, totals0, t_start, integrator, max_cycles):
    n = system.n_nodes
    n_cycles = len(W_list)
    orbit = records[-period:] if period else records[-1:]
    if period:
        states = np.concatenate([r.states[1:] for r in orbit])
        V = np.concatenate([orbit[0].v] + [r.v[1:] for r in orbit[1:]])
        contact = states != SEPARATED
        # total slip in contact over the orbit, in units of F / A_jj (see the module docstring)
        travel = np.sum(np.abs(np.diff(V, axis=0)) * contact, axis=0) * solver.diag[:n] / F
        slipped = travel > SHAKEDOWN_FACTOR * tol
        stuck = np.flatnonzero(~slipped & np.all(contact, axis=0))
        steady_W = float(np.mean([r.dissipation for r in orbit]))
        shook = not bool(np.any(slipped))
        energy = _energy(orbit, load, lam, solver.diag, F, tol, K=system.K,
                         implicit=(method == "implicit"))
    else:
        stuck, steady_W, shook, energy = np.zeros(0, int), float("nan"), False, None
    status, msg = _outcome(period, n_cycles, shook, steady_W, ok, fail_msg, max_cycles, change,
                           tol, step_statuses)
    tot = {k: solver.totals[k] - totals0.get(k, 0) for k in solver.totals}
    stats = dict(
        n_steps=int(integrator.n_events if integrator else tot["steps"]),
        n_events=int(integrator.n_events) if integrator else 0,
        rate_solves=int(integrator.rate_solves) if integrator else 0,
        active_set_iterations=tot["iterations"], factorizations=tot["factorizations"],
        low_rank_updates=tot["updates"], cache_hits=tot["cache_hits"],
        lemke_calls=tot["lemke_calls"], enumerations=tot["enumerations"],
        wall_time=time.perf_counter() - t_start,
    )
    final_act = records[-1].active_sets if (records and method == "implicit") else None
    return CycleRun(
        dissipation=np.asarray(W_list, float),
        steady_dissipation=steady_W,
        shook_down=bool(shook),
        period=int(period),
        stuck_nodes=np.asarray(stuck, int),
        n_cycles=n_cycles,
        cycles_to_steady=n_cycles - period if period else -1,
        state_change=np.asarray(change, float),
        final_slip=np.asarray(v, float).copy(),
        final_gap=np.asarray(w, float).copy(),
        cycle_start_slips=np.asarray(starts_v),
        cycle_start_gaps=np.asarray(starts_w),
        steady_orbit=tuple(orbit),
        energy_identity=energy,
        status=status,
        message=note + msg,
        max_residual=float(max_res),
        step_statuses=dict(step_statuses),
        statistics=stats,
        method=method,
        steps_per_cycle=n_steps,
        lam=lam,
        tol=tol,
        force_scale=F,
        load=load,
        final_active_sets=final_act,
        history=_table(history) if history else None,
    )

