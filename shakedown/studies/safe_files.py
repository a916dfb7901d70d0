"""Writing files without following symbolic links: new file, fsync, rename into place.

A study's store lives in a folder that other people's files may be linked into (a shared
output folder, a copied store).  Writing through a link would overwrite the file it points to,
so every write of :mod:`shakedown.studies` goes through :func:`write_atomic`: the bytes go to a
new file (``O_CREAT | O_EXCL | O_NOFOLLOW``) next to the target, are fsync'd, and the new file
is renamed over the target (``os.replace`` replaces a link itself, never what it points to).
A target or folder that *is* a link is refused with
:class:`~shakedown.model.errors.UnsafePathError` (an ``InputError``), so a linked
file is never silently replaced either.
"""

from __future__ import annotations

import contextlib
import os
import uuid
from pathlib import Path

from ..model.errors import UnsafePathError

__all__ = ["refuse_link", "write_atomic", "fsync_dir"]


def refuse_link(path, what: str = "file") -> Path:
    """``path`` as a Path; :class:`UnsafePathError` if it or its parent folder is a symbolic link.

    Parameters
    ----------
    path : str or Path
    what : str
        What the path is, for the message (``"store"``, ``"file"``).
    """
    path = Path(path)
    for p in (path, path.parent):
        if p.is_symlink():
            raise UnsafePathError(
                f"{what} {path}: {p} is a symbolic link (to {os.readlink(p)}); shakedown does not "
                "write through links, so that it never overwrites a file elsewhere. Use a plain "
                "folder (remove the link, or point the output somewhere else)")
    return path


def fsync_dir(path) -> None:
    """Make a rename in folder ``path`` durable (a no-op where the platform cannot)."""
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_atomic(path, data: bytes, what: str = "file") -> Path:
    """Write ``data`` to ``path``: new file, fsync, rename into place; links refused.

    Readers see the old content or the new one, never a torn file; a kill leaves at most a
    ``.tmp-*`` file behind (stores remove theirs when reopened).

    Returns
    -------
    Path
        ``path``.
    """
    path = refuse_link(path, what)
    tmp = path.with_name(f".tmp-{uuid.uuid4().hex[:12]}-{path.name}")
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    fd = os.open(tmp, flags, 0o644)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    fsync_dir(path.parent)
    return path
