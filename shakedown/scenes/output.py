"""Output folder and progress display shared by the command line and the analyses."""

from __future__ import annotations

import json
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

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
            raise ValueError(
                f"output file name {name!r} must be a plain file name "
                "(letters, digits, '_', '-', '.'), without folders"
            )
        p = self.path / name
        self.written.append(p)
        return p

    def write_json(self, name: str, obj) -> Path:
        p = self.file(name)
        p.write_text(json.dumps(_finite(obj), indent=2, default=_json_default) + "\n")
        return p

    def write_table(self, name: str, table) -> Path:
        """Write a pandas DataFrame as CSV (``name`` ends in .csv) or Parquet (.parquet)."""
        p = self.file(name)
        if name.endswith(".parquet"):
            table.to_parquet(p, index=False)
        else:
            table.to_csv(p, index=False)
        return p

    def save_figure(self, name: str, fig, dpi: int = 120) -> Path:
        p = self.file(name)
        fig.savefig(p, dpi=dpi, bbox_inches="tight")
        import matplotlib.pyplot as plt

        plt.close(fig)
        return p


class Progress:
    """Progress display on stderr: a live line on a terminal, a few plain lines otherwise.

    Use as ``for item in progress(iterable, total=n, desc="cycles"): ...``.
    """

    def __init__(self, enabled: bool = True, stream=None):
        self.enabled = enabled
        self.stream = stream or sys.stderr

    def __call__(self, iterable, total: int | None = None, desc: str = ""):
        if total is None:
            try:
                total = len(iterable)
            except TypeError:
                total = None
        if not self.enabled:
            yield from iterable
            return
        tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        t0 = time.perf_counter()
        last_report = -1.0
        i = 0
        for i, item in enumerate(iterable, start=1):
            yield item
            now = time.perf_counter() - t0
            if tty or total is None or now - last_report > 5.0 or i == total:
                self.stream.write(self._line(desc, i, total, now) + ("\r" if tty else "\n"))
                self.stream.flush()
                last_report = now
        if tty:
            self.stream.write("\n")
            self.stream.flush()

    @staticmethod
    def _line(desc, i, total, elapsed):
        if total:
            eta = elapsed / i * (total - i) if i else float("nan")
            return f"{desc}: {i}/{total} ({100 * i / total:3.0f}%) {elapsed:6.1f} s, ~{eta:5.1f} s left"
        return f"{desc}: {i} {elapsed:6.1f} s"

    def log(self, message: str) -> None:
        if self.enabled:
            self.stream.write(message + "\n")
            self.stream.flush()
