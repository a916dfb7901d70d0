"""On-disk cache of condensed FE models, keyed by a hash of the model definition.

The key is the SHA-256 of a canonical JSON description of the model (mesh arrays hashed,
element, material stiffness, held/contact/interface/periodic boundaries, load cases, mass flag,
cache format version).  Files are ``<cache_dir>/fe-<key>.npz`` written atomically
(temporary file + rename) and read with ``allow_pickle=False``: nothing is unpickled.
A model condensed with mass also serves a request without mass.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np


def model_hash(description: dict) -> str:
    """SHA-256 (hex) of a JSON-able description, mass flag excluded (stored separately)."""
    d = dict(description)
    d.pop("mass", None)
    text = json.dumps(d, sort_keys=True, separators=(",", ":"), default=_default)
    return hashlib.sha256(text.encode()).hexdigest()


def _default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON-able: {type(x).__name__}")


def path_for(cache_dir, key: str) -> Path:
    return Path(cache_dir) / f"fe-{key}.npz"


def load(cache_dir, key: str, mass: bool) -> dict | None:
    """The cached arrays, or None (missing, unreadable, or without the requested mass)."""
    path = path_for(cache_dir, key)
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError):
        return None
    if mass and "M" not in arrays:
        return None
    if not mass:
        arrays.pop("M", None)
    return arrays


def save(cache_dir, key: str, arrays: dict) -> Path:
    """Write the arrays atomically; keeps an existing file that already has the mass."""
    folder = Path(cache_dir)
    folder.mkdir(parents=True, exist_ok=True)
    path = path_for(folder, key)
    if path.is_file() and "M" not in arrays:
        old = load(folder, key, mass=True)
        if old is not None:
            return path
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".npz.tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
