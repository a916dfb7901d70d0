"""Where a study's tasks run: this process, local worker processes, or a Dask cluster.

Local worker processes
----------------------
* one BLAS thread each (:mod:`threadpoolctl`), and as many workers as cores by default: a
  study's tasks are many small dense solves, for which OpenBLAS threads in every one of
  several processes only fight over the cores (issue 13 measured the whole job 1.8x slower);
* they exit when the process that started them dies (``kill -9`` included): each worker
  watches its parent's pid and calls ``os._exit`` within :data:`WATCH_SECONDS` of the parent
  disappearing, so no orphan keeps its memory, and the multiprocessing resource tracker, whose
  last client is then gone, exits too.

Dask
----
A scheduler address makes the client connect to that host and *unpickle its replies*: it is
trusted like code.  :class:`Workers` accepts an address only from the caller; the scene
analysis takes it only from the command line (``--set scheduler=...``) or the environment
(``SHAKEDOWN_SCHEDULER``), never silently from a shared scene file.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import re
import threading
import time

import numpy as np

from ..model import citations
from ..model.errors import InputError, MissingDependencyError

__all__ = ["Workers", "WATCH_SECONDS", "call_task", "start_method"]

#: Period (s) at which a worker process checks that its parent is alive.
WATCH_SECONDS = 0.5
#: ``tcp://host:port`` (or tls, ucx, ws, wss, inproc) or ``host:port``.
_ADDRESS = re.compile(r"^((tcp|tls|ucx|ws|wss|inproc)://)?\[?[A-Za-z0-9_.:-]+\]?:\d{1,5}/?$")
_BLAS_LIMIT = None


def limit_blas_threads(n: int | None) -> None:
    """Limit the BLAS / OpenMP pools of this process to ``n`` threads (once; None: no-op)."""
    global _BLAS_LIMIT
    if n is None or _BLAS_LIMIT is not None:
        return
    from threadpoolctl import threadpool_limits

    _BLAS_LIMIT = threadpool_limits(limits=int(n))


def start_method(requested: str = "auto") -> str:
    """The start method of a local pool: ``requested`` unless it is ``"auto"``, which gives
    ``"fork"`` when the platform offers it and this process runs only its main thread (a fork
    copies no other thread, so no lock held by one can be inherited locked), else ``"spawn"``."""
    if requested != "auto":
        return requested
    if "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1:
        return "fork"
    return "spawn"


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(WATCH_SECONDS)
        if os.getppid() != parent:
            os._exit(1)  # the parent died: this worker's results have nowhere to go


def _worker_init(parent: int, blas_threads: int | None) -> None:
    limit_blas_threads(blas_threads)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True,
                     name="shakedown-parent-watch").start()


def call_task(func, args, kwargs, blas_threads=None):
    """Run one task; returns ``(rows, seconds, citation keys used there)`` (rows: dicts)."""
    import pandas as pd

    limit_blas_threads(blas_threads)
    t0 = time.perf_counter()
    out = func(*args, **kwargs)
    if isinstance(out, pd.DataFrame):
        rows = out.to_dict("records")
    elif isinstance(out, dict):
        rows = [out]
    else:
        rows = [dict(r) for r in out]
    return rows, time.perf_counter() - t0, citations.used()  # what to cite, from any worker


def check_scheduler(scheduler) -> None:
    """:class:`InputError` unless ``scheduler`` is None, a Dask client or an address."""
    if scheduler is None or not isinstance(scheduler, str):
        return
    if not _ADDRESS.match(scheduler.strip()):
        raise InputError(
            f"scheduler must be a Dask scheduler address such as 'tcp://127.0.0.1:8786' "
            f"(start one with `dask scheduler`); got {scheduler!r}")


class Workers:
    """Where tasks run: this process, local processes, or a Dask cluster; reusable.

    Pass one to several :func:`~shakedown.studies.engine.run_tasks` calls to start the worker
    processes (or connect to the cluster) once.  Use as a context manager, or call
    :meth:`close`.

    Parameters
    ----------
    n_workers : int
        Local processes (``concurrent.futures.ProcessPoolExecutor``, started on first use);
        1 runs the tasks in this process.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``"tcp://host:8786"``) or a client: run on that cluster
        instead (``n_workers`` is then ignored).  A client passed in is not closed.  Trusted
        like code (see the module docstring).
    mp_context : str
        Start method of the local processes.  ``"auto"`` (default): ``"fork"`` where the
        platform has it and this process runs no other thread when the pool starts (the
        workers then start in milliseconds, with this process's imports), else ``"spawn"``
        (safe with threads in the parent, but each worker imports the package again: about
        2.5 s of CPU); see :func:`start_method`.  A script that starts processes needs the usual
        ``if __name__ == "__main__":`` guard.
    blas_threads : int or None
        BLAS threads of each worker process (local or Dask); None leaves them alone.  The
        in-process executor (``n_workers=1``) never changes the caller's settings.
    connect_timeout : float
        Seconds to wait for a Dask scheduler.
    """

    def __init__(self, n_workers: int = 1, scheduler=None, mp_context: str = "auto",
                 blas_threads: int | None = 1, connect_timeout: float = 10.0):
        if scheduler is None and (not isinstance(n_workers, int | np.integer)
                                  or isinstance(n_workers, bool) or n_workers < 1):
            raise InputError(f"n_workers must be an integer >= 1; got {n_workers!r}")
        check_scheduler(scheduler)
        self.n_workers, self.scheduler, self.mp_context = int(n_workers), scheduler, mp_context
        self.blas_threads = blas_threads
        self._pool = self._client = None
        self._own_client = False
        if scheduler is not None:
            try:
                import distributed
            except ImportError as exc:  # Dask is the one optional extra (issue 9)
                raise MissingDependencyError(
                    f"scheduler = {scheduler!r} needs Dask ({exc}): pip install "
                    "\"shakedown[parallel]\"") from exc
            self._distributed = distributed
            if isinstance(scheduler, distributed.Client):
                self._client = scheduler
            else:
                try:
                    self._client = distributed.Client(scheduler, timeout=connect_timeout)
                except (OSError, TimeoutError) as exc:
                    raise InputError(
                        f"scheduler {scheduler!r}: no Dask scheduler answered within "
                        f"{connect_timeout:g} s ({type(exc).__name__}); start one "
                        "(`dask scheduler`) or leave scheduler empty to use local "
                        "processes") from None
                self._own_client = True

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

    def submit(self, task):
        if self._client is not None:
            return self._client.submit(call_task, task.func, task.args, task.kwargs,
                                       self.blas_threads, pure=False)
        if self.n_workers == 1:
            fut = cf.Future()
            try:
                fut.set_result(call_task(task.func, task.args, task.kwargs))
            except Exception as exc:  # noqa: BLE001 - reported by the caller with the task key
                fut.set_exception(exc)
            return fut
        self.start()
        return self._pool.submit(call_task, task.func, task.args, task.kwargs)

    def start(self) -> None:
        """Start the local worker processes now (else at the first task; no-op for the
        in-process and Dask executors).  :meth:`__enter__` calls it, before any progress
        display starts its thread, so that the ``"auto"`` start method can fork."""
        if self._pool is not None or self._client is not None or self.n_workers == 1:
            return
        from ..evolution.fast_period import warm_up

        warm_up()  # compile the kernel here once: the workers then load it from the cache
        ctx = multiprocessing.get_context(start_method(self.mp_context))
        self._pool = cf.ProcessPoolExecutor(
            max_workers=self.n_workers, mp_context=ctx, initializer=_worker_init,
            initargs=(os.getpid(), self.blas_threads))
        self._pool.submit(int).result()  # the processes start at the first submission

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
        self.start()
        return self

    def __exit__(self, exc_type, *rest):
        self.close(cancel=exc_type is not None)
        return False
