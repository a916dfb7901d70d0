"""The generic sweep engine: tasks -> rows -> an append-only store, resumable and parallel.

:class:`Task` (a key, a picklable function, its arguments) and :func:`run_tasks`: runs the tasks
that the store does not hold yet on local processes (``n_workers``), in this process
(``n_workers=1``) or on a Dask cluster (``scheduler``), appends each task's rows to the store as
it finishes, shows progress on stderr, and returns every row in *task order* read back from the
store -- the same bit for bit whatever the number of workers and however often the run was
interrupted, provided each task is self-contained and deterministic.  Nothing here knows about
cracks or even about frictional systems (:mod:`shakedown.sweep` builds on it).

Stores
------
A sweep writes one or more *rows* (dicts of scalars: ``int``, ``float``, ``bool``, ``str``) per
finished task, each carrying the task's key in the column :data:`KEY`.  A store makes every
append durable before returning, so that a sweep killed at any moment (``kill -9`` included)
restarts from what is on disk: :meth:`keys` tells which tasks are done, and no row is ever
written twice because only unfinished tasks are run again.

Two formats:

* :class:`ParquetStore` -- a folder of Parquet parts, each written to a temporary name, fsync'd
  and renamed into place (a rename is atomic: a part is either complete or absent).  Keeps
  dtypes exactly.  Needs ``pyarrow``.
* :class:`CsvStore` -- one CSV file, appended and fsync'd row batch by row batch; a partial last
  line left by a kill is cut off when the store is reopened.  Floats are written with 17
  significant digits and parsed with pandas' round-trip converter, so they come back bit for bit.

Both take a lock file (``.lock``, holding the writer's pid) so that two processes never append
to the same store; a lock left by a dead process is taken over.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import io
import multiprocessing
import os
import sys
import time
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..model import citations
from ..model.errors import InputError, MissingDependencyError, SolverError
from ..model.progress import progress_bar

#: Name of the column holding each row's task key.
KEY = "task_key"


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):  # not supported on every platform / file system
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class _Lock:
    """An exclusive lock file holding the owner's pid; stale locks (dead pid) are taken over."""

    def __init__(self, path: Path):
        self.path = path
        self.held = False

    def acquire(self) -> None:
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                try:
                    pid = int(self.path.read_text().strip() or 0)
                except (OSError, ValueError):
                    pid = 0
                if pid and pid != os.getpid() and _pid_alive(pid):
                    raise InputError(
                        f"store {self.path.parent} is in use by process {pid} (lock file "
                        f"{self.path}); wait for it to finish, or use another store path"
                    ) from None
                with contextlib.suppress(FileNotFoundError):
                    self.path.unlink()
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(str(os.getpid()))
            self.held = True
            return
        raise InputError(f"could not take the lock file {self.path}; remove it if stale")

    def release(self) -> None:
        if self.held:
            with contextlib.suppress(FileNotFoundError):
                self.path.unlink()
            self.held = False


class _Store:
    """Common interface: ``keys()``, ``append(rows)``, ``read()``, context manager (lock)."""

    format = ""

    def __init__(self, path):
        self.path = Path(path)
        self._lock = _Lock(self._lock_path())

    def _lock_path(self) -> Path:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self):
        self._lock.acquire()
        self._repair()  # only the lock holder may clear what a killed writer left behind
        return self

    def _repair(self) -> None:
        pass

    def __exit__(self, *exc):
        self._lock.release()
        return False

    def keys(self) -> set[str]:
        """The task keys that have rows in the store."""
        df = self.read()
        return set(df[KEY].astype(str)) if KEY in df.columns else set()

    @staticmethod
    def _check_rows(rows: list[dict]) -> None:
        for row in rows:
            if KEY not in row:
                raise InputError(f"every row needs a {KEY!r} column; got columns {list(row)}")


class ParquetStore(_Store):
    """A folder of Parquet parts (``part-*.parquet``), one per append; atomic renames."""

    format = "parquet"

    def __init__(self, path):
        super().__init__(path)
        self.path.mkdir(parents=True, exist_ok=True)

    def _repair(self) -> None:
        for tmp in self.path.glob(".tmp-*"):  # debris of a write interrupted by a kill
            with contextlib.suppress(OSError):
                tmp.unlink()

    def _lock_path(self) -> Path:
        return self.path / ".lock"

    def parts(self) -> list[Path]:
        return sorted(self.path.glob("part-*.parquet"))

    def append(self, rows: list[dict]) -> None:
        """Write ``rows`` as one new part (fsync'd, then renamed into place)."""
        if not rows:
            return
        self._check_rows(rows)
        n = len(self.parts())
        name = f"part-{n:06d}-{uuid.uuid4().hex[:8]}.parquet"
        tmp = self.path / f".tmp-{name}"
        pd.DataFrame(rows).to_parquet(tmp, index=False)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, self.path / name)
        _fsync_dir(self.path)

    def read(self) -> pd.DataFrame:
        """Every row, parts in the order they were written."""
        parts = self.parts()
        if not parts:
            return pd.DataFrame(columns=[KEY])
        return pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True)


class CsvStore(_Store):
    """One CSV file; rows appended with ``fsync``; a torn last line is cut off on opening."""

    format = "csv"

    def __init__(self, path):
        super().__init__(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)

    def _lock_path(self) -> Path:
        return self.path.with_name(self.path.name + ".lock")

    def _repair(self) -> None:
        if not self.path.exists():
            return
        data = self.path.read_bytes()
        if data and not data.endswith(b"\n"):
            keep = data.rfind(b"\n") + 1  # 0 when even the header is torn
            with open(self.path, "r+b") as fh:
                fh.truncate(keep)
                fh.flush()
                os.fsync(fh.fileno())

    def _header(self) -> list[str] | None:
        if not self.path.exists() or self.path.stat().st_size == 0:
            return None
        with open(self.path, newline="") as fh:
            return next(csv.reader(fh), None)

    def append(self, rows: list[dict]) -> None:
        """Append ``rows`` (columns fixed by the first append) and fsync the file."""
        if not rows:
            return
        self._check_rows(rows)
        header = self._header()
        columns = header or list(dict.fromkeys(k for r in rows for k in r))
        extra = sorted({k for r in rows for k in r} - set(columns))
        if extra:
            raise InputError(
                f"rows have columns {extra} that the CSV store {self.path} does not have "
                f"({columns}); every task must return the same columns"
            )
        buf = io.StringIO()
        df = pd.DataFrame(rows, columns=columns)
        df.to_csv(buf, index=False, header=header is None, float_format="%.17g",
                  lineterminator="\n")
        with open(self.path, "a", newline="") as fh:
            fh.write(buf.getvalue())
            fh.flush()
            os.fsync(fh.fileno())

    def read(self) -> pd.DataFrame:
        if self._header() is None:
            return pd.DataFrame(columns=[KEY])
        data = self.path.read_bytes()
        data = data[: data.rfind(b"\n") + 1]  # a live writer's torn last line is not a row
        # pandas >= 3 parses floats exactly by default (and deprecates float_precision)
        exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
        return pd.read_csv(io.BytesIO(data), keep_default_na=False, na_values=[""],
                           dtype={KEY: str}, **exact)


def open_store(path, format: str | None = None) -> _Store:
    """A store at ``path``: ``format`` ``"parquet"`` (a folder) or ``"csv"`` (a file).

    ``format=None`` picks CSV when ``path`` ends with ``.csv``, otherwise Parquet when
    ``pyarrow`` is installed and CSV (``path/rows.csv``) when it is not.
    """
    path = Path(path)
    if format is None:
        if path.suffix == ".csv":
            format = "csv"
        else:
            try:
                import pyarrow  # noqa: F401
                format = "parquet"
            except ImportError:
                format, path = "csv", path / "rows.csv"
    if format == "parquet":
        return ParquetStore(path)
    if format == "csv":
        return CsvStore(path)
    raise InputError(f"store format must be 'parquet' or 'csv'; got {format!r}")


class Progress:
    """Tasks done / total with elapsed time and an estimate of the time left, on stderr.

    On a terminal the line is redrawn in place (at most every ``min_interval`` s); otherwise a
    line is printed at every 10 % step.  The estimate uses this session's rate only (tasks
    resumed from the store do not count as fast work).
    """

    def __init__(self, total: int, done: int = 0, desc: str = "sweep", stream=None,
                 min_interval: float = 0.5):
        self.total, self.resumed, self.done = int(total), int(done), int(done)
        self.desc = desc
        self.stream = sys.stderr if stream is None else stream
        self.min_interval = min_interval
        self.t0 = time.perf_counter()
        self._last = -1.0
        self._last_decile = -1
        self._last_done = -1
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._draw(force=True)

    def text(self) -> str:
        el = time.perf_counter() - self.t0
        new = self.done - self.resumed
        pct = 100.0 * self.done / self.total if self.total else 100.0
        s = f"{self.desc}: {self.done}/{self.total} tasks ({pct:.0f}%)"
        if self.resumed:
            s += f", {self.resumed} from the store"
        s += f" | {el:.1f} s"
        if 0 < new and self.done < self.total:
            s += f" | ~{el / new * (self.total - self.done):.0f} s left"
        return s

    def _draw(self, force: bool = False) -> None:
        now = time.perf_counter()
        if self._tty:
            if force or now - self._last >= self.min_interval:
                self.stream.write("\r" + self.text() + "\x1b[K")
                self.stream.flush()
                self._last = now
            return
        decile = int(10 * self.done / self.total) if self.total else 10
        if (force and self.done != self._last_done) or decile > self._last_decile:
            self.stream.write(self.text() + "\n")
            self.stream.flush()
            self._last_decile, self._last_done = decile, self.done

    def update(self, n: int = 1) -> None:
        self.done += n
        self._draw(force=self.done >= self.total and not self._tty)

    def close(self) -> None:
        if self._tty:
            self._draw(force=True)
            self.stream.write("\n")
            self.stream.flush()
        else:
            self._draw(force=True)


# ---------------------------------------------------------------------------------- engine
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


def _call(func, args, kwargs):
    """Run one task in a worker; returns ``(rows, seconds, citation keys used there)``."""
    t0 = time.perf_counter()
    out = func(*args, **kwargs)
    if isinstance(out, pd.DataFrame):
        rows = out.to_dict("records")
    elif isinstance(out, dict):
        rows = [out]
    else:
        rows = [dict(r) for r in out]
    return rows, time.perf_counter() - t0, citations.used()  # what to cite, from any worker


class Workers:
    """Where tasks run: this process, local processes, or a Dask cluster; reusable.

    Pass one to several :func:`run_tasks` calls to start the worker processes (or connect to
    the cluster) once.  Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    n_workers : int
        Local processes (``concurrent.futures.ProcessPoolExecutor``, started on first use);
        1 runs the tasks in this process.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``"tcp://host:8786"``) or a client: run on that cluster
        instead (``n_workers`` is then ignored).  A client passed in is not closed.
    mp_context : str
        Start method of the local processes (``"spawn"``: safe with threads in the parent;
        a script that starts processes needs the usual ``if __name__ == "__main__":`` guard).
    """

    def __init__(self, n_workers: int = 1, scheduler=None, mp_context: str = "spawn"):
        if scheduler is None and (not isinstance(n_workers, int | np.integer)
                                  or isinstance(n_workers, bool) or n_workers < 1):
            raise InputError(f"n_workers must be an integer >= 1; got {n_workers!r}")
        self.n_workers, self.scheduler, self.mp_context = int(n_workers), scheduler, mp_context
        self._pool = self._client = None
        self._own_client = False
        if scheduler is not None:
            try:
                import distributed
            except ImportError as exc:  # Dask is the one optional extra (issue 9)
                raise MissingDependencyError(
                    f"scheduler = {scheduler!r} needs Dask: pip install \"shakedown[parallel]\""
                ) from exc

            self._distributed = distributed
            if isinstance(scheduler, distributed.Client):
                self._client = scheduler
            else:
                self._client, self._own_client = distributed.Client(scheduler), True

    @property
    def kind(self) -> str:
        return "dask" if self._client is not None else (
            "inline" if self.n_workers == 1 else "processes")

    @property
    def slots(self) -> int:
        """Tasks that can run at once."""
        if self._client is not None:
            return sum(self._client.nthreads().values()) or 1
        return self.n_workers

    def submit(self, task: Task):
        if self._client is not None:
            return self._client.submit(_call, task.func, task.args, task.kwargs, pure=False)
        if self.n_workers == 1:
            fut = cf.Future()
            try:
                fut.set_result(_call(task.func, task.args, task.kwargs))
            except Exception as exc:  # noqa: BLE001 - reported by the caller with the task key
                fut.set_exception(exc)
            return fut
        if self._pool is None:
            ctx = multiprocessing.get_context(self.mp_context)
            self._pool = cf.ProcessPoolExecutor(max_workers=self.n_workers, mp_context=ctx)
        return self._pool.submit(_call, task.func, task.args, task.kwargs)

    def wait(self, futures, timeout: float) -> list:
        """The futures among ``futures`` that are done (waits up to ``timeout`` s for one)."""
        if self._client is not None:
            try:
                self._distributed.wait(futures, timeout=timeout, return_when="FIRST_COMPLETED")
            except TimeoutError:
                pass
            return [f for f in futures if f.done()]
        done, _ = cf.wait(futures, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return list(done)

    def cancel(self, futures) -> None:
        futures = [f for f in futures if not f.done()]
        if self._client is not None:
            if futures:
                self._client.cancel(futures)
            return
        for f in futures:
            f.cancel()

    def close(self, cancel: bool = False) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=not cancel, cancel_futures=cancel)
            self._pool = None
        if self._own_client:
            self._client.close()
            self._own_client = False

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *rest):
        self.close(cancel=exc_type is not None)
        return False


def _as_store(store) -> _Store:
    return store if isinstance(store, _Store) else open_store(store)


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
    mp_context: str = "spawn",
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
        :func:`shakedown.store.open_store`.  Rows already in it are not recomputed; keys in it
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
        :class:`~shakedown.errors.SolverError` naming the task, or record it in
        ``TaskRun.failed`` and go on (it is retried on the next call).
    mp_context : str
        Start method of the local processes (``"spawn"``: safe with threads in the parent;
        a script that calls this with ``n_workers > 1`` needs the usual
        ``if __name__ == "__main__":`` guard).
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
