"""The study engine: tasks -> rows -> an append-only store, resumable and parallel.

:class:`Task` (a key, a picklable function, its arguments) and :func:`run_tasks`: runs the tasks
that the store does not hold yet on local processes (``n_workers``), in this process
(``n_workers=1``) or on a Dask cluster (``scheduler``) (:mod:`.workers`), appends each task's
rows to the store (:mod:`.tables`) as it finishes, shows progress on stderr, and returns every
row in *task order* read back from the store -- the same bit for bit whatever the number of
workers and however often the run was interrupted, provided each task is self-contained and
deterministic.  Nothing here knows about cracks or even about frictional systems.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..model import citations
from ..model.errors import InputError, SolverError
from ..model.progress import progress_bar
from . import tables
from .tables import KEY
from .workers import Workers

__all__ = ["SECONDS", "Task", "TaskRun", "run_tasks"]

#: Metadata column: wall time of the task that produced the row (s).  Not part of the results
#: (it differs from run to run); :func:`run_tasks` returns it separately.
SECONDS = "task_seconds"


@dataclass(frozen=True)
class Task:
    """One unit of work: ``func(*args, **kwargs)`` returning a row (dict) or a list of rows.

    ``key`` names the task in the store (unique within a sweep).  ``func`` must be picklable
    (a module-level function) when the sweep runs on processes or Dask.  Rows are dicts of
    scalars (``int``, ``float``, ``bool``, ``str``; ``nan`` for a missing number) with the same
    columns for every task of a sweep.
    """

    key: str
    func: Callable
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)


@dataclass(frozen=True)
class TaskRun:
    """Outcome of :func:`run_tasks`.

    Attributes
    ----------
    rows : pandas.DataFrame
        Every row of the given tasks, in task order (rows of one task in the order returned),
        with the key column ``task_key``; read back from the store.
    seconds : pandas.Series
        Wall time of each task (s), indexed by key (tasks resumed from the store included).
    n_tasks, n_resumed, n_run : int
        Tasks in the sweep, found done in the store, run in this call.
    failed : dict
        ``key -> message`` of tasks that raised (only with ``on_error="skip"``); they have no
        rows and run again on the next call.
    wall_seconds : float
    """

    rows: pd.DataFrame
    seconds: pd.Series
    n_tasks: int
    n_resumed: int
    n_run: int
    failed: dict
    wall_seconds: float


def _as_store(store) -> tables._Store:
    return store if isinstance(store, tables._Store) else tables.open_store(store)


def run_tasks(
    tasks: Sequence[Task],
    store,
    *,
    n_workers: int = 1,
    scheduler=None,
    workers: Workers | None = None,
    progress: bool = True,
    desc: str = "sweep",
    on_error: str = "raise",
    mp_context: str = "auto",
    max_in_flight: int | None = None,
    flush_interval: float = 0.0,
) -> TaskRun:
    """Run the tasks not yet in ``store``, appending their rows as they finish.

    Parameters
    ----------
    tasks : sequence of Task
        Unique keys.  Their order is the order of the returned rows.
    store : path or store
        A path (folder -> Parquet parts, ``*.csv`` -> CSV file) or an object from
        :func:`shakedown.studies.tables.open_store`.  Rows already in it are not recomputed; keys in it
        that are not in ``tasks`` are kept but not returned.
    n_workers : int
        Local processes (``concurrent.futures.ProcessPoolExecutor``); 1 runs in this process.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``"tcp://host:8786"``) or a client: run on that cluster
        instead of local processes (``n_workers`` is then ignored).
    workers : Workers, optional
        Reuse these workers (then ``n_workers``, ``scheduler``, ``mp_context`` are ignored).
    progress : bool
        Show tasks done / total and an estimate of the time left on stderr.
    on_error : {"raise", "skip"}
        A task that raises: stop (after saving every finished row) and raise
        :class:`~shakedown.SolverError` naming the task, or record it in
        ``TaskRun.failed`` and go on (it is retried on the next call).
    mp_context : str
        Start method of the local processes (default ``"auto"``: ``"fork"`` when this process
        runs no other thread, else ``"spawn"``; :func:`~shakedown.studies.workers.start_method`);
        a script that calls this with ``n_workers > 1`` needs the usual
        ``if __name__ == "__main__":`` guard.
    max_in_flight : int, optional
        Tasks submitted ahead of completion (default 2 per worker slot).
    flush_interval : float
        Seconds to buffer finished rows before appending them (0: append every task at once).

    Returns
    -------
    TaskRun

    Notes
    -----
    An interrupted call (Ctrl-C, a ``KeyboardInterrupt`` raised by a task, ``kill -9``) loses at
    most the tasks that were running (and, with ``flush_interval > 0``, the buffered rows);
    calling again with the same tasks and store finishes the sweep with every row exactly once.
    """
    if on_error not in ("raise", "skip"):
        raise InputError(f"on_error must be 'raise' or 'skip'; got {on_error!r}")
    if workers is None and scheduler is None and (
            not isinstance(n_workers, int | np.integer) or isinstance(n_workers, bool)
            or n_workers < 1):
        raise InputError(f"n_workers must be an integer >= 1; got {n_workers!r}")
    tasks = list(tasks)
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):
        dup = pd.Series(keys)[pd.Series(keys).duplicated()].iloc[0]
        raise InputError(f"task keys must be unique; {dup!r} appears more than once")
    t_start = time.perf_counter()
    st = _as_store(store)
    with st:
        done = st.keys()
        todo = [t for t in tasks if t.key not in done]
        n_resumed = len(tasks) - len(todo)
        failed: dict[str, str] = {}
        if todo:
            own = workers is None
            if own:
                workers = Workers(min(n_workers, len(todo)) if scheduler is None else 1,
                                  scheduler, mp_context)
                workers.start()  # before the progress display's thread (start_method)
            ok = False
            try:
                _execute(todo, st, workers, progress, desc, on_error, max_in_flight,
                         flush_interval, len(tasks), n_resumed, failed)
                ok = True
            finally:
                if own:
                    workers.close(cancel=not ok)
        rows = st.read()
    rows = rows[rows[KEY].astype(str).isin(set(keys))] if len(rows) else rows
    order = {k: i for i, k in enumerate(keys)}
    if len(rows):
        pos = rows[KEY].astype(str).map(order)
        rows = rows.iloc[np.argsort(pos.to_numpy(), kind="stable")].reset_index(drop=True)
    seconds = (rows.groupby(KEY, sort=False)[SECONDS].first() if SECONDS in rows.columns
               else pd.Series(dtype=float))
    rows = rows.drop(columns=[SECONDS], errors="ignore")
    return TaskRun(rows=rows, seconds=seconds, n_tasks=len(tasks), n_resumed=n_resumed,
                   n_run=len(todo) - len(failed), failed=failed,
                   wall_seconds=time.perf_counter() - t_start)


def _execute(todo, st, backend, progress, desc, on_error, max_in_flight, flush_interval,
             n_total, n_resumed, failed):
    window = max_in_flight or (1 if backend.kind == "inline" else 2 * backend.slots)
    bar = progress_bar(n_total, desc=desc, initial=n_resumed, unit="task") if progress else None
    buffer: list[dict] = []
    last_flush = time.perf_counter()
    pending: dict = {}
    queue = iter(todo)
    cancel = True
    try:
        exhausted = False
        while True:
            while not exhausted and len(pending) < window:
                task = next(queue, None)
                if task is None:
                    exhausted = True
                    break
                pending[backend.submit(task)] = task.key
            if not pending:
                break
            for fut in backend.wait(list(pending), timeout=0.5):
                key = pending.pop(fut)
                try:
                    rows, secs, cited = fut.result()
                    citations.register(*cited)
                except BrokenProcessPool as exc:
                    raise SolverError(
                        f"a worker process died while running task {key!r} (killed, out of "
                        "memory, or a script that starts processes without the `if __name__ "
                        "== '__main__':` guard that the 'spawn' start method needs); the rows "
                        f"of every finished task are saved in {st.path}: run again to resume",
                        partial=st.path) from exc
                except Exception as exc:  # noqa: BLE001
                    if on_error == "raise":
                        raise SolverError(
                            f"sweep task {key!r} raised {exc!r}; the rows of every finished "
                            f"task are saved in {st.path}: fix the cause and run again to "
                            "resume", partial=st.path) from exc
                    failed[key] = repr(exc)
                    rows = []
                for r in rows:
                    r[KEY] = key
                    r[SECONDS] = secs
                buffer.extend(rows)
                if bar:
                    bar.update(1)
            now = time.perf_counter()
            if buffer and now - last_flush >= flush_interval:
                st.append(buffer)
                buffer, last_flush = [], now
        cancel = False
    finally:
        if buffer:
            st.append(buffer)
        if cancel:
            backend.cancel(list(pending))
        if bar:
            bar.close()
