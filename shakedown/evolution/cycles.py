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

import numpy as np

from ..model.errors import InputError
from ..model.loading import LoadCycle
from ..model.system import DiscreteSystem
from ..model.threads import single_blas_thread
from ..model.validation import check_count, check_load_factor, check_same_nodes
from .complementarity import (
    FEAS_TOL,
    StepSolver,
    _vec,
)
from .cycle_results import SHAKEDOWN_FACTOR, CycleRun, EnergyIdentity
from .multistate import run_states


def _check_inputs(system, load, lam, initial_slip, initial_gap, method, steps_per_cycle,
                  max_cycles, tol):
    if not isinstance(system, DiscreteSystem):
        raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
    if not isinstance(load, LoadCycle):
        raise InputError(f"load must be a LoadCycle; got {type(load).__name__}")
    n = system.n_nodes
    check_same_nodes(system, load)
    lam = check_load_factor(lam, load)
    if method not in ("implicit", "events"):
        raise InputError(f"method must be 'implicit' or 'events'; got {method!r}")
    steps_per_cycle = check_count("steps_per_cycle", steps_per_cycle, 2)
    max_cycles = check_count("max_cycles", max_cycles, 1)
    try:
        tol = float(tol)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tol must be a positive number; got {tol!r}") from exc
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a positive number (e.g. 1e-10); got {tol}")
    batch = initial_slip is not None and np.ndim(initial_slip) == 2
    if batch:
        rows = list(initial_slip)
        if not rows:
            raise InputError("initial_slip with shape (n_states, N) needs n_states >= 1; "
                             "got 0 rows")
        V0 = np.array([_vec(f"initial_slip[{i}]", v, n) for i, v in enumerate(rows)])
    else:
        V0 = (np.zeros(n) if initial_slip is None else _vec("initial_slip", initial_slip, n))
        V0 = V0[None, :]
    k = V0.shape[0]
    if initial_gap is None or np.ndim(initial_gap) == 1:
        w0 = (np.zeros(n) if initial_gap is None
              else _vec("initial_gap", initial_gap, n, nonneg=True))
        W0 = np.repeat(w0[None, :], k, axis=0)
    elif batch and np.shape(initial_gap) == (k, n):
        W0 = np.array([_vec(f"initial_gap[{i}]", g, n, nonneg=True)
                       for i, g in enumerate(initial_gap)])
    else:
        raise InputError(f"initial_gap must have shape ({n},) or, with initial_slip of shape "
                         f"({k}, {n}), ({k}, {n}); got {np.shape(initial_gap)}")
    return lam, V0, W0, int(steps_per_cycle), int(max_cycles), tol, batch


def _state_change(D, F, v1, w1, v0, w0):
    n = v1.shape[0]
    return float(np.max(D[:n] * np.abs(v1 - v0) + D[n:] * np.abs(w1 - w0), initial=0.0) / F)


def solve_cycles(system: DiscreteSystem, load: LoadCycle, lam: float, initial_slip=None,
                 initial_gap=None, method: str = "implicit", steps_per_cycle: int = 200,
                 max_cycles: int = 200, tol: float = 1e-10, *, progress=None,
                 record_history: bool = False, solver: StepSolver | None = None,
                 feas_tol: float | None = None, anderson_memory: int = 0) -> CycleRun:
    """Simulate load periods until the response is periodic (MODEL.md s.4).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lam : float
        Load factor (``>= 0``).
    initial_slip : array_like, shape (N,) or (n_states, N), optional
        Slips at ``t = 0`` (zeros by default) [length].  With shape (n_states, N) the states
        are run together (:mod:`shakedown.evolution.multistate`: one solver, one factor
        cache, states sharing an active set solved by one multi-right-hand-side solve) and a
        list of ``n_states`` CycleRun is returned; each equals an independent run to the
        solver tolerance.
    initial_gap : array_like, shape (N,) or (n_states, N), optional
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
    anderson_memory : int
        ``dim = 3`` only: periods remembered by the steady-state accelerator of
        :mod:`.cone_cycles` (Anderson mixing of the period starts; the steady test is unchanged).
        ``0`` (default): plain cycling.  For 2-D, use :func:`shakedown.steady_cycle`.

    Returns
    -------
    CycleRun, or list of CycleRun for a 2-D ``initial_slip``

    Notes
    -----
    A ``dim = 3`` system runs :func:`~.cone_cycles.solve_cycles_3d` (implicit steps of the cone
    law, :mod:`.cone_step`): slips of shape (N, 2), ``initial_slip`` (N, 2) or
    (n_states, N, 2), ``method="implicit"`` only.

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> load = sd.LoadCycle.from_samples([0.0], [1.0], [[1.0], [-1.0]], [[0.0], [0.0]])
    >>> run = sd.solve_cycles(s, load, 1.0, method="events")
    >>> run.period, round(run.steady_dissipation, 12)   # 4 f P (lam Q1 - f P) / k
    (1, 1.0)
    """
    if getattr(system, "dim", 2) == 3:  # the cone step and its driver (MODEL.md s.8)
        from .cone_cycles import solve_cycles_3d

        return solve_cycles_3d(system, load, lam, initial_slip, initial_gap, method,
                               steps_per_cycle, max_cycles, tol, progress=progress,
                               record_history=record_history, solver=solver, feas_tol=feas_tol,
                               anderson_memory=anderson_memory)
    if anderson_memory != 0:
        raise InputError(f"anderson_memory={anderson_memory!r} is for dim = 3 systems; for a 2-D "
                         "system use shakedown.steady_cycle(..., accelerator='anderson')")
    lam, V0, W0, n_steps, max_cycles, tol, batch = _check_inputs(
        system, load, lam, initial_slip, initial_gap, method, steps_per_cycle, max_cycles, tol)
    if solver is None:
        solver = StepSolver(system) if feas_tol is None else StepSolver(system, feas_tol=feas_tol)
    elif solver.system is not system:
        raise InputError("solver was built for another system; pass solver=None")
    with single_blas_thread():  # many small solves: see shakedown/model/threads.py
        runs = run_states(system, solver, load, lam, V0, W0, method, n_steps, max_cycles, tol,
                          progress=progress, record_history=record_history)
    return runs if batch else runs[0]


__all__ = ["solve_cycles", "CycleRun", "EnergyIdentity", "FEAS_TOL", "SHAKEDOWN_FACTOR"]
