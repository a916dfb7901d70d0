"""Reading scene and manifest files as untrusted text: size, encoding and nesting checked.

:func:`read_text` checks the file's size before reading it and decodes it as UTF-8 (a UTF-16
file is named as such); :func:`parse_toml` turns every failure of the TOML parser (including
the recursion of deeply nested input) into a :class:`~shakedown.model.errors.SceneError`
naming the file, and refuses nesting deeper than :data:`~shakedown.model.limits.MAX_NESTING`.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..model.errors import InputError, SceneError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["read_text", "parse_toml"]


def read_text(path, what: str = "scene file") -> str:
    """The UTF-8 text of a scene or manifest file, size-checked first; :class:`SceneError`
    naming the file for a file too large, unreadable or not UTF-8 (e.g. UTF-16)."""
    from ..model.limits import MAX_SCENE_BYTES, check_file_size

    try:
        check_file_size(path, what, MAX_SCENE_BYTES)
        data = Path(path).read_bytes()
    except InputError as exc:
        raise SceneError(str(exc)) from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the {what} ({exc.strerror or exc})") from None
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError(f"{path}: the {what} is UTF-16 text; save it as UTF-8")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: the {what} is not UTF-8 text (byte {exc.start}: "
                         f"{exc.reason}); save it as UTF-8") from None


def parse_toml(text: str, label: str) -> dict:
    """``tomllib.loads(text)`` with every failure a :class:`SceneError` naming ``label``
    (deep nesting, which makes the parser recurse, included)."""
    from ..model.limits import MAX_NESTING, check_nesting

    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{label}: not valid TOML: {exc}") from exc
    except (RecursionError, MemoryError):
        raise SceneError(f"{label}: tables or lists nested too deeply (more than {MAX_NESTING} "
                         "levels) or too large to parse") from None
    try:
        check_nesting(label, raw)
    except InputError as exc:
        raise SceneError(str(exc)) from None
    return raw
