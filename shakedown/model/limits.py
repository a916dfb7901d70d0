"""Sizes checked before work: what a file may declare, and what the machine can hold.

A file can declare more than it holds (an ``.npz`` header with shape ``(10^9, 10^9)``, a Matrix
Market size line, ``n_samples = 10^8`` in a CSV load record) or be larger than memory.  The
readers check such declarations here *before* allocating, reading or hashing anything, and
raise :class:`~shakedown.model.errors.InputError` naming the file, the field, the value and the
limit.

Limits
------
:data:`MAX_FILE_BYTES`
    Largest model, load or scene file read (default 4 GiB; environment variable
    ``SHAKEDOWN_MAX_FILE_BYTES`` to change it).
:func:`max_array_bytes`
    Largest array built from a file: half the machine's physical memory.
:data:`MAX_NESTING`
    Deepest nesting of tables / lists in a scene (TOML) or manifest (JSON) file.
:data:`MAX_SCENE_BYTES`
    Largest scene or manifest file (text): 64 MiB.
"""

from __future__ import annotations

import os
from pathlib import Path

from .errors import InputError

#: Largest model / load file read, in bytes (``SHAKEDOWN_MAX_FILE_BYTES`` overrides).
MAX_FILE_BYTES = int(os.environ.get("SHAKEDOWN_MAX_FILE_BYTES", 4 * 2**30))
#: Largest scene / manifest file, in bytes.
MAX_SCENE_BYTES = 64 * 2**20
#: Deepest nesting of tables and lists in a scene or manifest file.
MAX_NESTING = 32


def physical_memory() -> int:
    """Bytes of physical memory (8 GiB where the platform does not tell)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 8 * 2**30


def max_array_bytes() -> int:
    """Largest array a file may make the package allocate: half the physical memory."""
    return physical_memory() // 2


def check_file_size(path, what: str = "file", limit: int | None = None) -> int:
    """The size of ``path`` in bytes; :class:`InputError` if above ``limit`` (default
    :data:`MAX_FILE_BYTES`).  Nothing is read."""
    limit = MAX_FILE_BYTES if limit is None else limit
    size = Path(path).stat().st_size
    if size > limit:
        raise InputError(f"{what} {path} is {size} bytes, more than the limit of {limit} bytes; "
                         "it is not read (set SHAKEDOWN_MAX_FILE_BYTES to allow larger files)")
    return size


def check_array_size(where, field: str, n_items: int, itemsize: int = 8) -> None:
    """:class:`InputError` if ``n_items`` numbers of ``itemsize`` bytes exceed
    :func:`max_array_bytes`; ``where`` (the file) and ``field`` are named."""
    need = int(n_items) * int(itemsize)
    limit = max_array_bytes()
    if n_items < 0 or need > limit:
        raise InputError(f"{where}: {field} declares {n_items} entries ({need} bytes), more than "
                         f"this machine can hold (limit {limit} bytes, half its memory)")


def nesting_depth(value, limit: int = MAX_NESTING) -> int:
    """Depth of nested dicts / lists in ``value`` (iterative: no recursion), up to ``limit + 1``."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        v, d = stack.pop()
        if d > deepest:
            deepest = d
            if deepest > limit:
                return deepest
        if isinstance(v, dict):
            stack.extend((x, d + 1) for x in v.values())
        elif isinstance(v, (list, tuple)):
            stack.extend((x, d + 1) for x in v)
    return deepest


def check_nesting(where, value, limit: int = MAX_NESTING) -> None:
    """:class:`InputError` if ``value`` nests tables / lists deeper than ``limit``."""
    if nesting_depth(value, limit) > limit:
        raise InputError(f"{where}: tables or lists nested more than {limit} levels deep; a "
                         "scene needs at most a few levels")
