"""The generic sweep engine and its resumable store, under their old name.

``shakedown.store`` (0.1) and ``shakedown.studies.store`` keep importing every public name;
the code lives in :mod:`.tables` (stores), :mod:`.engine` (tasks, :func:`run_tasks`),
:mod:`.workers` (local processes, Dask) and :mod:`.progress`.
"""

from .engine import SECONDS, Task, TaskRun, run_tasks
from .progress import Progress
from .safe_files import refuse_link, write_atomic
from .tables import KEY, CsvStore, ParquetStore, open_store
from .workers import Workers

__all__ = ["KEY", "SECONDS", "CsvStore", "ParquetStore", "Progress", "Task", "TaskRun",
           "Workers", "open_store", "refuse_link", "run_tasks", "write_atomic"]
