"""Output folder and progress display shared by the command line and the analyses."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from ..model.errors import UnsafePathError
from ..model.progress import ProgressDisplay

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
    """Create ``path`` by writing a new temporary file beside it and renaming it into place.

    ``write(tmp_path)`` writes the content.  A symbolic link at ``path`` is refused (its target
    is never touched), so is a folder; an interrupted write leaves the old file intact.

    Parameters
    ----------
    path : path-like
        Destination, inside an existing folder.
    write : callable
        ``write(tmp_path)``; the temporary file already exists (empty, mode 0600).

    Raises
    ------
    UnsafePathError
        ``path`` is a symbolic link or not a regular file.
    """
    import os
    import tempfile

    path = Path(path)
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise UnsafePathError(
            f"refusing to write {path}: it is a symbolic link or not a regular file; remove "
            "it or choose another output folder (--out)"
        )
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)  # atomic; replaces a file, never follows a link at `path`
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask


class OutputFolder:
    """A folder that analyses write into; file names may not leave it.

    Parameters
    ----------
    path : path-like
        Created (with parents) if missing.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.path.mkdir(parents=True, exist_ok=True)
        self.written: list[Path] = []

    def file(self, name: str) -> Path:
        """Path of ``name`` inside the folder (plain file names only)."""
        if not _SAFE_NAME.match(name) or name in (".", ".."):
            raise UnsafePathError(
                f"output file name {name!r} must be a plain file name "
                "(letters, digits, '_', '-', '.'), without folders"
            )
        p = self.path / name
        self.written.append(p)
        return p

    def write_json(self, name: str, obj) -> Path:
        text = json.dumps(_finite(obj), indent=2, default=_json_default) + "\n"
        return write_atomically(self.file(name), lambda p: p.write_text(text))

    def write_table(self, name: str, table) -> Path:
        """Write a pandas DataFrame as CSV (``name`` ends in .csv) or Parquet (.parquet)."""
        if name.endswith(".parquet"):
            return write_atomically(self.file(name), lambda p: table.to_parquet(p, index=False))
        return write_atomically(self.file(name), lambda p: table.to_csv(p, index=False))

    def save_figure(self, name: str, fig, dpi: int = 120) -> Path:
        import matplotlib.pyplot as plt

        fmt = Path(name).suffix.lstrip(".") or None
        try:
            return write_atomically(
                self.file(name), lambda p: fig.savefig(p, dpi=dpi, bbox_inches="tight",
                                                       format=fmt))
        finally:
            plt.close(fig)


#: The command's progress display (tqdm on stderr); the old name is kept.
Progress = ProgressDisplay
