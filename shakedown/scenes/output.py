"""Output folder and progress display shared by the command line and the analyses."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

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


#: The command's progress display (tqdm on stderr); the old name is kept.
Progress = ProgressDisplay
