"""One BLAS thread around many small dense solves (issue 13/14).

A cyclic run makes thousands of small LAPACK/BLAS calls (the compiled kernel's inverses and
block updates, the Python step's LU solves).  With OpenBLAS's default of one thread per core,
each such call wakes the other threads, which costs far more than the call itself, above all
on a busy machine.  Measured on 2 cores with another job running: a 150-node run took 0.46 s
with the default threads and 0.018 s with one; at 1000 nodes, periods with warm caches cost
8.3 ms per step with the default threads and 0.82 ms with one.  :func:`single_blas_thread`
limits every loaded BLAS to one thread for the duration of a ``with`` block (about 10 us to
enter; the previous limits are restored on exit).  Parallelism belongs one level up: a study
runs one process per core (:mod:`shakedown.studies.workers`).
"""

from __future__ import annotations

import contextlib
from functools import lru_cache


@lru_cache(maxsize=1)
def _controller():
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - threadpoolctl is a core dependency
        return None
    return ThreadpoolController()


def single_blas_thread():
    """Context manager: one BLAS thread inside the ``with`` block."""
    c = _controller()
    return contextlib.nullcontext() if c is None else c.limit(limits=1, user_api="blas")


__all__ = ["single_blas_thread"]
