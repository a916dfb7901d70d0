"""Monte Carlo sweeps of frictional systems: any system over lam x initial states, and (under
their old names) the crack-network study of :mod:`.crack_study`.

Built on the generic engine of :mod:`.engine` (:class:`Task`, :func:`run_tasks`: resumable
store, local processes or Dask, progress), re-exported here.

* :func:`system_sweep` -- one :class:`~shakedown.DiscreteSystem` over load factors x initial
  slips (:func:`initial_slips`), one row per run (:func:`run_row`).
* :class:`SweepSpec`, :func:`run_sweep` -> :class:`SweepResult` -- the crack-network study
  (:mod:`.crack_study`), re-exported.

Determinism: every random draw comes from ``numpy.random.SeedSequence(seed, spawn_key=...)``
named by the task, never from a stream shared between tasks, so rows do not depend on the
number of workers or on the order in which tasks finish.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from ..model.errors import InputError
from .crack_study import SweepResult, lam_grid, realisation_model, run_sweep, study_tasks
from .engine import Task, TaskRun, run_tasks
from .runs import initial_slip, initial_slips, run_row
from .spec import SweepSpec, SystemSource
from .workers import Workers

__all__ = [
    "SweepSpec",
    "SystemSource",
    "Task",
    "TaskRun",
    "Workers",
    "run_tasks",
    "system_sweep",
    "initial_slip",
    "initial_slips",
    "run_row",
    "lam_grid",
    "SweepResult",
    "run_sweep",
    "realisation_model",
    "study_tasks",
]




def _system_task(system, load, lam, slip, solver):
    return run_row(system, load, lam, slip, solver)


def system_sweep(system, load, lams: Iterable[float], slips, store, *, solver: dict | None = None,
                 **run_options) -> pd.DataFrame:
    """Sweep one system over load factors x initial slips (any model, not only cracks).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lams : iterable of float
    slips : array_like, shape (n_states, N)
        Initial slips, e.g. from :func:`initial_slips`.
    store : path or store
    solver : dict, optional
        Keyword arguments of :func:`shakedown.solve_cycles` (``method``, ``steps_per_cycle``,
        ``max_cycles``, ``tol``).
    **run_options
        Passed to :func:`run_tasks` (``n_workers``, ``scheduler``, ``progress``, ...).

    Returns
    -------
    pandas.DataFrame
        One row per (lam, state): ``lam_index``, ``lam``, ``state`` and the columns of
        :func:`run_row`.  The system is pickled with every task: fine up to a few hundred nodes.
    """
    slips = np.atleast_2d(np.asarray(slips, float))
    if slips.shape[1] != system.n_nodes:
        raise InputError(f"slips must have shape (n_states, {system.n_nodes}); got {slips.shape}")
    solver = dict(solver or {})
    tasks = []
    for i, lam in enumerate(lams):
        for j, v in enumerate(slips):
            tasks.append(Task(f"l{i}-s{j}", _tagged, (_system_task, dict(
                lam_index=i, lam=float(lam), state=j)), dict(
                system=system, load=load, lam=float(lam), slip=v, solver=solver)))
    return run_tasks(tasks, store, **run_options).rows


def _tagged(func, tags: dict, **kwargs):
    row = dict(tags)
    row.update(func(**kwargs))
    return row
