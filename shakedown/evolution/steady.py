"""Steady cycles and uniqueness experiments (MODEL.md s.4; seed 002 sections 2-3).

* :func:`steady_cycle` -- the direct steady-cycle solver.  The map ``P`` from the slip state at
  the start of a load period to the state one period later is piecewise affine (within a fixed
  sequence of node states every step is an affine map).  A steady cycle is a fixed point of
  ``P`` (or of ``P o P``: a period-2T orbit).  Instead of iterating ``x <- P(x)`` until it stops
  moving (slow when the memory of the initial state fades geometrically, seed 002 Fig. 8) the
  solver identifies the affine piece ``P(x) = M x + c`` at the current state by finite
  differences and jumps to its fixed point, ``(I - M) x = c`` (a Newton step on the piecewise
  affine equation ``P(x) - x = 0``), safeguarded; then it verifies the answer by simulating
  from it with :func:`shakedown.solve_cycles`.
* :func:`uniqueness_study` (in :mod:`shakedown.evolution.uniqueness`) -- the
  evolution from many initial states (in parallel over local
  processes), with a verdict on the uniqueness of the steady dissipation and of the
  time-varying part of the steady response.

Only the slips are state: with every node closed at the start of a period the gaps of the
previous step do not enter the step problem, so ``P`` acts on ``v`` in ``R^N``.

Period-2 orbits: the solver looks for a fixed point of ``P o P`` when ``P`` has no attracting
fixed point.  No system with an attracting period-2 orbit was found by a random search (coupled
2- and 3-node systems, one or two harmonics, ``lam`` from 0.8 to 3 ``lam2``, implicit steps),
so this path is tested only on period-1 systems (where it must return the period-1 cycle).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.errors import InputError
from ..model.results import short_repr
from ..model.validation import check_count, check_positive
from .anderson import _anderson
from .steady_maps import (
    FD_STEP,
    _check_common,
    _check_slip,
    _newton_step,
    _PeriodMap,
    natural_slip_scale,
    sample_initial_slips,
    slip_measure,
    tangential_stiffness,
)

__all__ = [
    "SteadyCycle",
    "steady_cycle",
    "natural_slip_scale",
    "sample_initial_slips",
]


# ------------------------------------------------------------------ the direct solver
@dataclass(frozen=True)
class SteadyCycle:
    """Result of :func:`steady_cycle`.

    Attributes
    ----------
    slip : ndarray, shape (N,) or (N, 2) for a 3-D system
        Slip state at the start of the steady cycle (the fixed point) [slip units].
    steady_dissipation : float
        Dissipation per load period ``W`` of the steady cycle [force x slip]; for period 2, the
        mean over the two periods (``nan`` if not converged).
    period : int
        1 or 2 (load periods), 0 when no steady cycle was found.
    shook_down : bool
    stuck_nodes : ndarray of int
        Nodes that never slip in the steady cycle.
    n_evaluations : int
        Load periods simulated in all (period-map evaluations, verification included).
    n_iterations : int
        Newton (or Anderson) iterations.
    residual : float
        Verification residual of the final state: the change of state over ``period`` periods
        simulated from it, in the measure of :func:`solve_cycles` (``max_j A_jj |dv_j| / F``,
        ``F`` its force scale).
    status : str
        ``"converged"``, ``"not_converged"`` (budget exhausted; ``slip`` is the best state) or
        ``"cycling"`` (the plain-cycling fallback returned, see ``message``).
    message : str
    method : str
        ``"newton"`` or ``"anderson"``.
    residual_history : ndarray
        Scaled residual of every base evaluation, in order.
    spectral_radius : float
        Newton: spectral radius of the last identified affine piece's ``M`` on the slipping
        coordinates (< 1: an attracting cycle; nan for Anderson).
    run : CycleRun or None
        The verification run (``steady_table``, ``energy_identity``, ...).
    """

    slip: np.ndarray
    steady_dissipation: float
    period: int
    shook_down: bool
    stuck_nodes: np.ndarray
    n_evaluations: int
    n_iterations: int
    residual: float
    status: str
    message: str
    method: str
    residual_history: np.ndarray = field(repr=False)
    spectral_radius: float = float("nan")
    run: object = field(repr=False, default=None)

    def __repr__(self) -> str:
        return short_repr(self, ("status", "method", "period", "shook_down",
                                 "steady_dissipation", "n_evaluations", "n_iterations",
                                 "residual", "spectral_radius"),
                          {"n_nodes": int(np.size(self.slip))})

    def verdict(self, energy: str = "[force x length]") -> str:
        """The answer in plain sentences (:func:`shakedown.evolution.verdicts.steady_verdict`)."""
        from .verdicts import steady_verdict

        return steady_verdict(self, energy)

    @property
    def steady_table(self):
        """The steady cycle's time series (the verification run's ``steady_table``)."""
        return None if self.run is None else self.run.steady_table


def steady_cycle(system, load, lam: float, initial_slip=None, *, method: str = "implicit",
                 steps_per_cycle: int = 200, tol: float = 1e-10, period="auto",
                 accelerator: str = "auto", max_evaluations: int = 400, warmup: int = 1,
                 anderson_memory: int = 8, fd_step: float = FD_STEP):
    """Steady cycle as the fixed point of the one-period map, verified by simulation.

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lam : float
        Load factor (``>= 0``).
    initial_slip : array_like, shape (N,) (3-D: (N, 2)), optional
        Starting state (zeros by default).  Locked-in slips of nodes that stay stuck are kept,
        so the answer is the steady cycle reached from (near) this state.
    method, steps_per_cycle, tol
        Passed to :func:`shakedown.solve_cycles` (``tol`` is also the convergence tolerance of
        the scaled fixed-point residual).
    period : {"auto", 1, 2}
        Look for a fixed point of ``P`` (1), of ``P o P`` (2), or of ``P`` first and then of
        ``P o P`` ("auto").
    accelerator : {"auto", "newton", "anderson"}
        ``"newton"``: identify the affine piece (``N`` extra evaluations per iteration) and solve
        for its fixed point; ``"anderson"``: Anderson acceleration (one evaluation per
        iteration, better for large ``N``).  ``"auto"``: Newton for ``N <= 12``.
    max_evaluations : int
        Budget of simulated load periods (verification and fallback included).
    warmup : int
        Plain periods simulated first (at least 1; they settle the transient pieces cheaply).
    anderson_memory : int
    fd_step : float
        Finite-difference step in units of the slip scale.

    Returns
    -------
    SteadyCycle
        With ``status == "converged"`` the verification simulation from ``slip`` was found
        periodic by :func:`solve_cycles` itself.  Otherwise the remaining budget is spent on plain
        cycling and its outcome is reported (``status == "cycling"``).
    """
    dim = getattr(system, "dim", 2)
    n = system.n_nodes * (2 if dim == 3 else 1)  # 3-D: the map acts on flat slips (2N,)
    lam = _check_common(system, load, lam)
    x = np.zeros(n) if initial_slip is None else _check_slip("initial_slip", initial_slip,
                                                             system.n_nodes, dim)
    if period not in ("auto", 1, 2):
        raise InputError(f"period must be 'auto', 1 or 2; got {period!r}")
    if accelerator not in ("auto", "newton", "anderson"):
        raise InputError(f"accelerator must be 'auto', 'newton' or 'anderson'; got {accelerator!r}")
    check_count("max_evaluations", max_evaluations, 4)
    fd_step = check_positive("fd_step", fd_step, unit=" (in slip scales, e.g. 1e-4)")
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a positive number; got {tol}")
    acc = accelerator if accelerator != "auto" else ("newton" if n <= 12 else "anderson")
    kw = dict(method=method, steps_per_cycle=steps_per_cycle, tol=tol)
    P = _PeriodMap(system, load, lam, kw)
    scale = float(np.max(natural_slip_scale(system, load, lam)))
    budget = int(max_evaluations)
    history = []
    diag_a = tangential_stiffness(system)
    force = [None]

    def resid(x, y):
        # the state-change measure of solve_cycles: max_j A_jj |dv_j| / F (F: its force scale;
        # 3-D: |dv_j| Euclidean, A_jj the node's tangential stiffness)
        return float(np.max(diag_a * slip_measure(system, y - x))) / force[0]

    for i in range(max(int(warmup), 1)):  # at least one: it also gives the force scale
        x, run0 = P(x, 1)
        if i == 0:
            force[0] = float(run0.force_scale)
    periods = (1, 2) if period == "auto" else (int(period),)
    x_warm = x.copy()
    best = (np.inf, x)
    iterations = 0
    rho = float("nan")
    unstable = False
    for p in periods:
        x = best[1] if np.isfinite(best[0]) else x_warm
        y = P(x, p)[0]
        r = resid(x, y)
        history.append(r)
        X, G = [], []  # Anderson memory
        rho = float("nan")
        fails = 0

        def room(k, p=p):  # k more evaluations leave enough budget for the verification
            return P.count + k * p <= budget - 2 * p

        while r > tol and room(n + 2):
            iterations += 1
            accepted = False
            if acc == "newton":
                h = fd_step * max(scale, float(np.max(np.abs(x))))
                x_n, rho = _newton_step(P, x, y, p, h, scale)
                # damped step: within one affine piece the residual along the Newton direction
                # is (1 - t) r, so a shorter step that stays in the piece still makes progress
                for t in (1.0, 0.5, 0.25, 0.125):
                    if not room(1):
                        break
                    x_new = x + t * (x_n - x)
                    y_new = P(x_new, p)[0]
                    r_new = resid(x_new, y_new)
                    history.append(r_new)
                    if np.all(np.isfinite(y_new)) and r_new < r:
                        accepted = True
                        break
            else:
                X.append(x.copy())
                G.append(y - x)
                X, G = X[-anderson_memory - 1:], G[-anderson_memory - 1:]
                x_new = _anderson(X, G, y)
                y_new = P(x_new, p)[0]
                r_new = resid(x_new, y_new)
                history.append(r_new)
                accepted = bool(np.all(np.isfinite(y_new)) and r_new < r)
            if accepted:
                x, y, r = x_new, y_new, r_new
                continue
            # safeguard: no progress from this piece; plain periods (1, 2, 4, ... in a row) let
            # the transient settle before the next identification
            fails += 1
            X, G = [], []
            for _ in range(2 ** min(fails - 1, 6)):
                if not room(1):
                    break
                x, y = y, P(y, p)[0]
            r = resid(x, y)
            history.append(r)
        unstable = bool(r <= tol and rho > 1.0 + 1e-8)
        if unstable:  # a repelling fixed point: evolution would leave it; try the next period
            continue
        if r < best[0]:
            best = (r, x)
        if best[0] <= tol:
            break
    x = best[1]
    # verification: simulate from x; solve_cycles must itself find the cycle periodic
    verify_cycles = max(2 * max(periods) + 1, min(budget - P.count, 3 * max(periods)))
    run = P.run(x, verify_cycles)
    starts = np.asarray(run.cycle_start_slips)
    per = int(run.period) if np.isfinite(best[0]) else 0
    if per:
        x = starts[-per - 1]
        ver = resid(starts[-per - 1], starts[-1])
        status, msg = "converged", f"steady cycle of period {per} verified by simulation"
        if int(run.cycles_to_steady) > 0:
            msg += f" after {int(run.cycles_to_steady)} settling period(s)"
    else:
        ver = best[0]
        remaining = budget - P.count
        if remaining > 0:
            run = P.run(np.asarray(run.final_slip, float), remaining)
            per = int(run.period)
        status = "cycling" if per else "not_converged"
        why = ("only repelling fixed points were found" if unstable and not
               np.isfinite(best[0]) else f"fixed-point iteration stalled at residual "
               f"{best[0]:.3g} > tol {tol:g}")
        msg = (
            f"{why}; plain "
            f"cycling {'reached' if per else 'did not reach'} a steady cycle within "
            f"max_evaluations={budget}"
        )
        starts = np.asarray(run.cycle_start_slips)
        if per and len(starts) > per:
            ver = resid(starts[-per - 1], starts[-1])
        x = np.asarray(run.final_slip, float) if per == 0 else starts[max(len(starts) - per - 1, 0)]
    return SteadyCycle(
        slip=np.asarray(x, float).reshape(P.shape),
        steady_dissipation=float(run.steady_dissipation) if per else float("nan"),
        period=per,
        shook_down=bool(run.shook_down) if per else False,
        stuck_nodes=np.asarray(run.stuck_nodes, int) if per else np.zeros(0, int),
        n_evaluations=int(P.count),
        n_iterations=iterations,
        residual=float(ver),
        status=status,
        message=msg,
        method=acc,
        residual_history=np.asarray(history),
        spectral_radius=rho,
        run=run,
    )
