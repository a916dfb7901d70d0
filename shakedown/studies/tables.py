"""Append-only row stores of a study: Parquet parts or one CSV file, resumable after a kill.

A study writes one or more *rows* (dicts of scalars: ``int``, ``float``, ``bool``, ``str``) per
finished task, each carrying the task's key in the column :data:`KEY`.  A store makes every
append durable before returning, so that a study killed at any moment (``kill -9`` included)
restarts from what is on disk: :meth:`keys` tells which tasks are done, and no row is ever
written twice because only unfinished tasks are run again.

Every write creates a new file and renames it into place (:func:`.safe_files.write_atomic`):
a file is either complete or absent, and a store, a part or a lock file that is a symbolic
link is refused instead of written through.

* :class:`ParquetStore` -- a folder of Parquet parts, one per append.  Keeps dtypes exactly.
  Needs ``pyarrow``.
* :class:`CsvStore` -- one CSV file, rewritten (old rows + new rows, renamed into place) at every
  append.  Floats are written with 17 significant digits and parsed with pandas' round-trip
  converter, so they come back bit for bit.  A torn last line (a file written by an older
  version, killed mid-append) is ignored by readers and cut by the next writer.

Every part / row block carries its own check (:mod:`.store_checks`): its row count, a
SHA-256 of its content and its task keys.  Opening a store (taking its lock) verifies it and
repairs what it can, saying so by a ``RuntimeWarning`` naming the file: a damaged part (cut,
edited, a column renamed, unreadable) is moved to ``damaged/`` and a damaged CSV block is cut
out, so that their tasks run again; a part that repeats rows of an earlier part (a copy) is
moved aside too.  What cannot be repaired (an unreadable CSV file without checks) is refused
with :class:`~shakedown.model.errors.DamagedFileError` naming the file.

Both take an exclusive lock (:mod:`filelock`, an OS lock released when its process dies, so a
killed writer's lock never blocks the next run) so that two processes never write one store.
"""

from __future__ import annotations

import abc
import contextlib
import csv
import io
import uuid
from pathlib import Path

import pandas as pd

from ..model.errors import InputError
from . import store_checks as _checks
from .safe_files import make_folder, refuse_link, write_atomic

__all__ = ["KEY", "ParquetStore", "CsvStore", "open_store"]

#: Name of the column holding each row's task key.
KEY = "task_key"


class _Store(abc.ABC):
    """Common interface: ``keys()``, ``append(rows)``, ``read()``, context manager (lock)."""

    format = ""

    def __init__(self, path):
        self.path = refuse_link(path, "store")
        self._lock = None

    @abc.abstractmethod
    def _lock_path(self) -> Path:
        """The lock file of this store."""

    def __enter__(self):
        from filelock import FileLock, Timeout

        path = refuse_link(self._lock_path(), "lock file of the store")
        lock = FileLock(str(path), timeout=0)
        try:
            lock.acquire()
        except Timeout:
            raise InputError(
                f"store {self.path} is in use by another process (lock file {path}); wait for "
                "it to finish, or use another store path") from None
        self._lock = lock
        self._repair()  # only the lock holder may clear what a killed writer left behind
        return self

    def _repair(self) -> None:
        for tmp in self._folder().glob(".tmp-*"):  # debris of a write interrupted by a kill
            with contextlib.suppress(OSError):
                tmp.unlink()

    @abc.abstractmethod
    def _folder(self) -> Path:
        """The folder holding the store's files (and the debris of interrupted writes)."""

    def __exit__(self, *exc):
        if self._lock is not None:
            self._lock.release()
            self._lock = None
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
        make_folder(self.path, "store")
        self.repairs: list[str] = []

    def _folder(self) -> Path:
        return self.path

    def _repair(self) -> None:
        super()._repair()
        self.repairs = _checks.repair_parquet(self.parts(), self.path)

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
        data = _checks.parquet_bytes(pd.DataFrame(rows))
        write_atomic(self.path / f"part-{n:06d}-{uuid.uuid4().hex[:8]}.parquet", data,
                     "store part")

    def read(self) -> pd.DataFrame:
        """Every row, parts in the order they were written."""
        parts = self.parts()
        if not parts:
            return pd.DataFrame(columns=[KEY])
        return pd.concat([_checks.read_part(refuse_link(p, "store part")) for p in parts],
                         ignore_index=True)


class CsvStore(_Store):
    """One CSV file, rewritten and renamed into place at every append."""

    format = "csv"

    def __init__(self, path):
        super().__init__(path)
        make_folder(self.path.parent, "store folder")
        self.repairs: list[str] = []

    def _folder(self) -> Path:
        return self.path.parent

    def _lock_path(self) -> Path:
        return self.path.with_name(self.path.name + ".lock")

    def _repair(self) -> None:
        super()._repair()
        data = self._bytes()
        if data and not data.endswith(b"\n"):
            data = data[: data.rfind(b"\n") + 1]
            write_atomic(self.path, data, "store")
        good, self.repairs = _checks.repair_csv(data, self.path)
        if good != data:
            write_atomic(self.path, good, "store")

    def _bytes(self) -> bytes:
        refuse_link(self.path, "store")
        return self.path.read_bytes() if self.path.exists() else b""

    def _header(self, data: bytes) -> list[str] | None:
        if b"\n" not in data:
            return None
        return next(csv.reader(io.StringIO(data[: data.find(b"\n") + 1].decode())), None)

    def append(self, rows: list[dict]) -> None:
        """Append ``rows`` (columns fixed by the first append): the file is rewritten with them
        and renamed into place."""
        if not rows:
            return
        self._check_rows(rows)
        data = self._bytes()
        data = data[: data.rfind(b"\n") + 1]
        header = self._header(data)
        columns = ([c for c in header if c not in _checks.CSV_CHECK] if header else
                   list(dict.fromkeys(k for r in rows for k in r)))
        extra = sorted({k for r in rows for k in r} - set(columns))
        if extra:
            raise InputError(
                f"rows have columns {extra} that the CSV store {self.path} does not have "
                f"({columns}); every task must return the same columns"
            )
        write_atomic(self.path, data + _checks.csv_block(rows, columns, header is None),
                     "store")

    def read(self) -> pd.DataFrame:
        data = self._bytes()
        data = data[: data.rfind(b"\n") + 1]  # a torn last line is not a row
        if self._header(data) is None:
            return pd.DataFrame(columns=[KEY])
        # pandas >= 3 parses floats exactly by default (and deprecates float_precision)
        exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
        try:
            df = pd.read_csv(io.BytesIO(data), keep_default_na=False, na_values=[""],
                             dtype={KEY: str}, **exact)
        except (ValueError, UnicodeDecodeError, csv.Error) as exc:  # pandas' ParserError too
            raise _checks.damaged(self.path, f"not a readable CSV table ({exc})") from None
        return df.drop(columns=[c for c in _checks.CSV_CHECK if c in df.columns])


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
