"""On-disk cache of condensed FE models, keyed by a hash of the model definition.

The key is the SHA-256 of a canonical JSON description of the model (mesh arrays hashed,
element, material stiffness, held/contact/interface/periodic boundaries, load cases, mass flag,
cache format version).  Files are ``<cache_dir>/fe-<key>.npz`` written atomically
by :func:`shakedown.model.safe_files.write_atomic` (temporary file + rename; a cache folder
that is, or lies under, a symbolic link is refused) and read with ``allow_pickle=False``:
nothing is unpickled.  A model condensed with mass also serves a request without mass.

Each file carries its own check (``_key``: the model key; ``_sha256``: the SHA-256 of every
array's name, dtype, shape and bytes): a file whose arrays were edited, truncated or copied
under another key's name is detected on reading, reported by a warning naming the file, and
computed again (then overwritten).
"""

from __future__ import annotations

import hashlib
import io
import json
import warnings
from pathlib import Path

import numpy as np

from ...model.safe_files import check_no_links, make_folder, write_atomic

#: Largest cache file read (bytes); a larger one is ignored (recomputed), never loaded.
MAX_CACHE_BYTES = 8 * 2**30


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


def checksum(key: str, arrays: dict) -> str:
    """SHA-256 (hex) of ``key`` and each array's name, dtype, shape and bytes (sorted by name)."""
    h = hashlib.sha256(key.encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"|{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def load(cache_dir, key: str, mass: bool) -> dict | None:
    """The cached arrays, or None (missing, unreadable, damaged, or without the requested mass).

    A file that fails its check (edited arrays, another key, no checksum) is reported by a
    ``RuntimeWarning`` naming it and treated as missing (the model is condensed again and the
    file rewritten).
    """
    path = check_no_links(path_for(cache_dir, key), "FE cache file")
    if not path.is_file():
        return None
    if path.stat().st_size > MAX_CACHE_BYTES:
        warnings.warn(f"FE cache file {path} is larger than {MAX_CACHE_BYTES} bytes: ignored "
                      "(the model is condensed again)", RuntimeWarning, stacklevel=3)
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception:  # noqa: BLE001 - zip, format, decoding errors: a damaged file
        arrays = None
    stored = arrays.pop("_sha256", None) if arrays is not None else None
    skey = arrays.pop("_key", None) if arrays is not None else None
    if (arrays is None or stored is None or skey is None or str(skey) != key
            or str(stored) != checksum(key, arrays)):
        warnings.warn(f"FE cache file {path} fails its check (edited, truncated or not written "
                      "by this version): ignored, the model is condensed again and the file "
                      "rewritten", RuntimeWarning, stacklevel=3)
        return None
    if mass and "M" not in arrays:
        return None
    if not mass:
        arrays.pop("M", None)
    return arrays


def save(cache_dir, key: str, arrays: dict) -> Path:
    """Write the arrays with their check, atomically; keeps an existing valid file that already
    has the mass."""
    folder = make_folder(cache_dir, "FE cache folder")
    path = path_for(folder, key)
    if path.is_file() and "M" not in arrays:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            old = load(folder, key, mass=True)
        if old is not None:
            return path
    buf = io.BytesIO()
    np.savez(buf, _key=np.array(key), _sha256=np.array(checksum(key, arrays)), **arrays)
    return write_atomic(path, buf.getvalue(), "FE cache file")
