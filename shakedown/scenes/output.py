"""Output folder and progress display shared by the command line and the analyses."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import uuid
from pathlib import Path

import numpy as np

from ..model.errors import UnsafePathError
from ..model.progress import ProgressDisplay
from ..model.safe_files import check_no_links, fsync_dir, make_folder, write_atomic

_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else str(x)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, (set, tuple)):
        return list(obj)
    raise TypeError(f"cannot write {type(obj).__name__} to JSON")


def _finite(obj):
    """Replace non-finite floats by strings ('inf', 'nan') so the JSON is standard."""
    if isinstance(obj, dict):
        return {str(k): _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        return x if math.isfinite(x) else str(x)
    return obj


#: Characters a plain name may not contain: path separators, drive colons, NUL and controls.
_UNSAFE_CHARS = re.compile(r"[/\\:\x00-\x1f\x7f]")


def check_plain_name(name, what: str = "name") -> str:
    """``name`` if it is a plain name for a file or folder inside the output folder.

    Refused: empty names, ``.`` and ``..``, anything with a path separator (``/``, ``\\``), a
    drive colon or a control character, names starting with ``~`` or longer than 255
    characters.  Spaces and non-ASCII letters are fine.

    Raises
    ------
    UnsafePathError
    """
    text = str(name)
    if (not text or text.strip() in (".", "..") or _UNSAFE_CHARS.search(text)
            or text.startswith("~") or len(text) > 255 or text != text.strip()):
        raise UnsafePathError(
            f"{what} = {text!r} must be a plain name (no folders, no '/', '\\', ':', '..', "
            "no leading/trailing spaces, at most 255 characters): it names a folder inside "
            "the output folder, e.g. 'two_node_coupled'"
        )
    return text


def write_atomically(path, write) -> Path:
    """Create ``path`` by ``write(tmp_path)`` into a new file renamed into place (kept for the old
    name: :func:`shakedown.model.safe_files.write_atomic`, links refused at every level)."""
    return write_atomic(path, write)


class OutputFolder:
    """A folder that analyses write into; file names may not leave it.

    The folder and every level of its path are checked for symbolic links
    (:mod:`shakedown.model.safe_files`).  With ``staged=True`` (the ``shakedown`` command)
    result files are written into a hidden staging folder inside it and moved into place by
    :meth:`commit` once the run has succeeded; :meth:`discard` (a failed or refused run) removes
    them, so the folder is left as it was.  Stores and caches that must outlive a failed run
    (the sweep's ``sweep_store/``, the FE cache) live under :attr:`path` directly.

    Parameters
    ----------
    path : path-like
        Created (with parents) if missing.
    staged : bool
        Stage result files until :meth:`commit`.
    """

    def __init__(self, path, staged: bool = False):
        self.path = make_folder(path, "output folder")
        self.written: list[Path] = []
        self._staging = None
        if staged:
            self._staging = make_folder(self.path / f".staging-{uuid.uuid4().hex[:12]}",
                                        "staging folder")

    def file(self, name: str) -> Path:
        """Path of ``name`` inside the folder (plain file names only).

        While staged, the path where the file is written now (inside the staging folder);
        :attr:`written` lists the final paths."""
        if not _SAFE_NAME.match(name) or name in (".", ".."):
            raise UnsafePathError(
                f"output file name {name!r} must be a plain file name "
                "(letters, digits, '_', '-', '.'), without folders"
            )
        p = self.path / name
        self.written.append(p)
        return (self._staging / name) if self._staging is not None else p

    def write_bytes(self, name: str, data) -> Path:
        """Write ``data`` (bytes or str) to file ``name``."""
        return write_atomic(self.file(name), data, "result file")

    def write_text(self, name: str, text: str) -> Path:
        """Write ``text`` (UTF-8) to file ``name``."""
        return self.write_bytes(name, text)

    def write_json(self, name: str, obj) -> Path:
        text = json.dumps(_finite(obj), indent=2, default=_json_default) + "\n"
        return self.write_bytes(name, text)

    def write_table(self, name: str, table) -> Path:
        """Write a pandas DataFrame as CSV (``name`` ends in .csv) or Parquet (.parquet)."""
        if name.endswith(".parquet"):
            return write_atomic(self.file(name), lambda p: table.to_parquet(p, index=False))
        return write_atomic(self.file(name), lambda p: table.to_csv(p, index=False))

    def save_figure(self, name: str, fig, dpi: int = 120) -> Path:
        import matplotlib.pyplot as plt

        fmt = Path(name).suffix.lstrip(".") or None
        try:
            return write_atomic(
                self.file(name), lambda p: fig.savefig(p, dpi=dpi, bbox_inches="tight",
                                                       format=fmt))
        finally:
            plt.close(fig)

    def final(self, name: str) -> Path:
        """Where file ``name`` is now: staged (not yet committed) or in the folder."""
        if self._staging is not None and (self._staging / name).is_file():
            return self._staging / name
        return self.path / name

    def commit(self) -> list[Path]:
        """Move the staged files into the folder (each by one rename); the written paths."""
        if self._staging is not None:
            check_no_links(self.path, "output folder")
            for p in sorted(self._staging.iterdir()):
                target = check_no_links(self.path / p.name, "result file")
                if target.exists() and not target.is_file():
                    raise UnsafePathError(f"refusing to replace {target}: not a regular file")
                os.replace(p, target)
            fsync_dir(self.path)
            self._staging.rmdir()
            self._staging = None
        return sorted(set(self.written))

    def discard(self) -> None:
        """Remove the staged files (a failed or refused run): the folder is left as it was."""
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None


#: The command's progress display (tqdm on stderr); the old name is kept.
Progress = ProgressDisplay
