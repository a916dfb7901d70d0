"""The one way the package writes a file: new file, fsync, rename into place; links refused.

Every file the package writes (results, plots, manifests, the resolved scene, citations, caches,
stores) goes through :func:`write_atomic`, and every folder it creates through
:func:`make_folder`:

* the bytes go to a new file beside the target (``O_CREAT | O_EXCL | O_NOFOLLOW``), are
  fsync'd, and the new file is renamed over the target (``os.replace`` replaces a link itself,
  never what it points to), so a reader sees the old content or the new one, never a torn file;
* a symbolic link at *any level* of the path as given (the file, the output folder itself and
  each folder above it, relative paths from the working folder) is refused with
  :class:`~shakedown.model.errors.UnsafePathError` (an ``InputError``): shakedown never writes
  into a link's target.  Give the real folder (``realpath``) if a link is meant;
* an ``OSError`` of the disk (read-only folder, disk full, quota) becomes
  :class:`~shakedown.model.errors.OutputError` naming the file; nothing half-written is left.

Files are created with mode ``0666 & ~umask`` like ``open(path, "w")``.
"""

from __future__ import annotations

import contextlib
import errno
import os
import uuid
from pathlib import Path

from .errors import OutputError, UnsafePathError

__all__ = ["check_no_links", "make_folder", "write_atomic", "fsync_dir", "refuse_link"]


def _levels(path: Path) -> list[Path]:
    """``path`` and each folder above it, as given (``a/b/c`` -> ``a``, ``a/b``, ``a/b/c``)."""
    parts = path.parts
    return [Path(*parts[: i + 1]) for i in range(len(parts))]


def check_no_links(path, what: str = "file") -> Path:
    """``path`` as a Path; :class:`UnsafePathError` if it or any folder above it is a link.

    Parameters
    ----------
    path : str or Path
        As given (relative to the working folder, or absolute: every level is checked).
    what : str
        What the path is, for the message (``"output folder"``, ``"store"``, ``"file"``).
    """
    path = Path(path)
    for p in _levels(path):
        if p.is_symlink():
            raise UnsafePathError(
                f"{what} {path}: {p} is a symbolic link (to {os.readlink(p)}); shakedown does not "
                "write through links, so that it never overwrites a file elsewhere. Use a plain "
                f"folder (remove the link, or give its target {os.path.realpath(p)} instead)")
    return path


#: The old name (``shakedown.studies.safe_files.refuse_link``).
refuse_link = check_no_links


def make_folder(path, what: str = "output folder") -> Path:
    """Create folder ``path`` (with parents) after checking it for links; return it.

    Raises
    ------
    UnsafePathError
        A level of ``path`` is a symbolic link, or ``path`` is a file.
    OutputError
        The folder cannot be created (read-only disk, permissions).
    """
    path = check_no_links(path, what)
    if path.exists() and not path.is_dir():
        raise UnsafePathError(f"{what} {path} is a file, not a folder; remove it or choose "
                              "another folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _output_error(path, what, exc) from None
    return check_no_links(path, what)  # (a link planted while the folders were made)


def fsync_dir(path) -> None:
    """Make a rename in folder ``path`` durable (a no-op where the platform cannot)."""
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _output_error(path, what, exc: OSError) -> OutputError:
    why = {errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is exceeded",
           errno.EROFS: "the file system is read-only",
           errno.EACCES: "permission denied"}.get(exc.errno, exc.strerror or str(exc))
    return OutputError(f"cannot write {what} {path}: {why} ({type(exc).__name__}: {exc}); "
                       "nothing was half-written; free space or choose another output folder "
                       "(--out)")


def write_atomic(path, data, what: str = "file") -> Path:
    """Write ``data`` to ``path``: new file, fsync, rename into place; links refused.

    Parameters
    ----------
    path : str or Path
        The file; its folder must exist.
    data : bytes, str or callable
        The content (``str`` is written as UTF-8), or ``write(tmp_path)`` that writes the new
        file itself (a plot, a Parquet table).
    what : str
        What the file is, for messages.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    UnsafePathError
        ``path`` or a folder above it is a symbolic link, or ``path`` is a folder.
    OutputError
        The disk refused the write (nothing is left behind: the old file, if any, is intact).
    """
    path = check_no_links(path, what)
    if path.exists() and not path.is_file():
        raise UnsafePathError(f"refusing to write {what} {path}: it is not a regular file; "
                              "remove it or choose another output folder (--out)")
    tmp = path.with_name(f".tmp-{uuid.uuid4().hex[:12]}-{path.name}"[:255])
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(tmp, flags, 0o666 & ~_umask())
        try:
            with os.fdopen(fd, "wb") as fh:
                if callable(data):
                    fh.close()
                    data(tmp)
                    with open(tmp, "rb+") as again:
                        os.fsync(again.fileno())
                else:
                    fh.write(data.encode() if isinstance(data, str) else bytes(data))
                    fh.flush()
                    os.fsync(fh.fileno())
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise
    except OSError as exc:
        raise _output_error(path, what, exc) from None
    fsync_dir(path.parent)
    return path
