"""Crack sets as CSV files: ``x, y, half_length, angle`` (radians) or ``angle_deg``.

Error messages name the failing line and column and what was expected, never the file's
content: a scene's ``file`` key may point at any readable file.
"""

from __future__ import annotations

import os

import numpy as np

from shakedown.model.errors import InputError, ShapeError

CSV_COLUMNS = ("x", "y", "half_length", "angle")


def write_table(table, path) -> None:
    """Write rows ``x, y, half_length, angle`` (shape (N, 4), radians) with a header."""
    np.savetxt(
        os.fspath(path), table, delimiter=",", header=",".join(CSV_COLUMNS),
        comments="", fmt="%.17g",
    )


def read_table(path):
    """Centres (N, 2), half-lengths (N,) and angles (N,) [rad] from a crack CSV file.

    The file needs a header with the columns ``x, y, half_length`` and either ``angle``
    (radians) or ``angle_deg`` (degrees), in any order; other columns are ignored.
    """
    # messages name the failing position and what was expected, never the file's content
    # (a scene's `file` key may point at any readable file)
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise InputError(f"crack file {path!r} does not exist or is not a file")
    try:
        with open(path, encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except (UnicodeDecodeError, OSError):
        raise InputError(f"crack file {path!r} is not a readable UTF-8 text file") from None
    header = [h.strip().lower() for h in (lines[0] if lines else "").split(",")]
    missing = [c for c in ("x", "y", "half_length") if c not in header]
    if missing or not ({"angle", "angle_deg"} & set(header)):
        need = missing + ([] if {"angle", "angle_deg"} & set(header) else ["angle or angle_deg"])
        raise InputError(
            f"crack file {path!r}: line 1 must have a header with columns x, y, half_length and "
            f"angle (radians) or angle_deg; missing: {', '.join(need)}"
        )
    rows = []
    for r, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != len(header):
            raise ShapeError(f"crack file {path!r}: line {r} has {len(cells)} columns but the "
                             f"header has {len(header)}")
        try:
            rows.append([float(x) for x in cells])
        except ValueError:
            col = next(k for k, x in enumerate(cells) if not _is_float(x))
            raise InputError(f"crack file {path!r}: line {r}, column {col + 1} "
                             f"({header[col]!r}) is non-numeric") from None
    data = np.array(rows, dtype=float).reshape(-1, len(header))
    col = {h: data[:, k] for k, h in enumerate(header)}
    angle = col["angle"] if "angle" in col else np.deg2rad(col["angle_deg"])
    return np.column_stack([col["x"], col["y"]]), col["half_length"], angle


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
