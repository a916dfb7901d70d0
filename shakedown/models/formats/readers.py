"""Read matrices and vectors from Matrix Market (``.mtx``), MATLAB (``.mat``), ``.npz`` and CSV.

Every reader returns a float array (dense, or ``scipy.sparse`` CSR for :func:`read_matrix` with
``sparse=True``) and raises :class:`ModelFileError` naming the file and what is wrong with it
-- the line and column for text files, the variable for containers -- without quoting the
file's content.  Nothing is unpickled (``.npz`` is read with ``allow_pickle=False``).

Formats
-------
``.mtx``
    Matrix Market (``%%MatrixMarket matrix coordinate|array real|integer ...``, any symmetry),
    1-based indices as the format defines them; one matrix per file.
``.mat``
    MATLAB up to v7.2 (``save -v7``; v7.3 HDF5 files are refused with that hint); the variable
    is named by ``variable`` (required when the file holds several).  Sparse matrices allowed.
``.npz``
    NumPy archive; the array is named by ``variable`` (required when it holds several).
``.csv``
    Numbers separated by commas, one matrix row per line; lines starting with ``#`` are
    comments; no header.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...model.errors import InputError
from ...model.limits import check_array_size, check_file_size

#: File suffixes each reader accepts.
SUFFIXES = (".mtx", ".mat", ".npz", ".csv")


class ModelFileError(InputError):
    """A model or load file that cannot be read: the message names the file and the problem."""


def _path(path) -> Path:
    p = Path(path)
    if p.suffix.lower() not in SUFFIXES:
        raise ModelFileError(
            f"{p}: unknown file type {p.suffix!r}; use one of {', '.join(SUFFIXES)}")
    if not p.is_file():
        raise ModelFileError(f"{p}: no such file")
    try:
        check_file_size(p, "model file")  # before anything is read or hashed
    except InputError as exc:
        raise ModelFileError(str(exc)) from None
    return p


def _npy_header(f, version):
    """``(shape, fortran_order, dtype)`` of an ``.npy`` header (any format version)."""
    try:
        from numpy.lib._format_impl import _read_array_header  # numpy >= 2
    except ImportError:  # pragma: no cover - numpy 1.x
        from numpy.lib.format import _read_array_header
    return _read_array_header(f, version)


def _npz_member(p: Path, data, name: str) -> None:
    """Refuse an ``.npz`` member whose header declares more than the member holds or than the
    machine can hold, before numpy allocates it."""
    import zipfile

    try:
        with zipfile.ZipFile(p) as z:
            info = z.getinfo(name + ".npy")
            with z.open(info) as f:
                version = np.lib.format.read_magic(f)
                shape, _, dtype = _npy_header(f, version)
                header_bytes = f.tell()
    except (KeyError, ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
        raise ModelFileError(f"{p}: array {name!r} has an unreadable header "
                             f"({type(exc).__name__})") from None
    count = int(np.prod(shape, dtype=object))
    try:
        check_array_size(p, f"array {name!r} (shape {shape})", count, dtype.itemsize)
    except InputError as exc:
        raise ModelFileError(str(exc)) from None
    if count * dtype.itemsize > info.file_size - header_bytes:
        raise ModelFileError(f"{p}: array {name!r} declares shape {shape} ({count * dtype.itemsize} "
                             f"bytes) but holds only {info.file_size - header_bytes} bytes: a damaged file")


def _csv_rows(p: Path) -> list[list[float]]:
    rows = []
    with open(p, newline="", encoding="utf-8", errors="replace") as f:
        for line_no, row in enumerate(csv.reader(f), start=1):
            if not row or (row[0].lstrip().startswith("#")) or all(not c.strip() for c in row):
                continue
            values = []
            for col, cell in enumerate(row, start=1):
                try:
                    values.append(float(cell))
                except ValueError:
                    raise ModelFileError(
                        f"{p}: line {line_no}, column {col}: not a number "
                        f"({'empty' if not cell.strip() else 'text'}); a CSV matrix holds "
                        "numbers only, comma separated, no header") from None
            if rows and len(values) != len(rows[0]):
                raise ModelFileError(
                    f"{p}: line {line_no} has {len(values)} columns, the first row "
                    f"{len(rows[0])}")
            rows.append(values)
    if not rows:
        raise ModelFileError(f"{p}: holds no numbers")
    return rows


def _container(p: Path, variable: str | None):
    """The array named ``variable`` of a ``.mat`` / ``.npz`` file."""
    if p.suffix.lower() == ".npz":
        try:
            data = np.load(p, allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - zip, pickle and format errors
            raise ModelFileError(f"{p}: not a readable .npz archive ({type(exc).__name__})") from None
        with data:
            names = list(data.files)
            name = _pick(p, variable, names)
            _npz_member(p, data, name)
            try:
                return np.array(data[name])
            except ValueError:
                raise ModelFileError(f"{p}: array {name!r} holds Python objects; only numeric "
                                     "arrays are read (no pickles)") from None
    import scipy.io

    try:
        data = scipy.io.loadmat(p)
    except NotImplementedError:
        raise ModelFileError(f"{p}: MATLAB v7.3 (HDF5) files are not supported; save with "
                             "save(..., '-v7')") from None
    except Exception as exc:  # noqa: BLE001 - scipy.io raises many types
        raise ModelFileError(f"{p}: not a readable MATLAB file ({type(exc).__name__})") from None
    names = [k for k in data if not k.startswith("__")]
    return data[_pick(p, variable, names)]


def container_names(path) -> list[str]:
    """Names of the arrays in a ``.mat`` / ``.npz`` file."""
    p = _path(path)
    if p.suffix.lower() == ".npz":
        try:
            with np.load(p, allow_pickle=False) as data:
                return list(data.files)
        except Exception as exc:  # noqa: BLE001
            raise ModelFileError(f"{p}: not a readable .npz archive ({type(exc).__name__})") from None
    import scipy.io

    try:
        return [w[0] for w in scipy.io.whosmat(p)]
    except NotImplementedError:
        raise ModelFileError(f"{p}: MATLAB v7.3 (HDF5) files are not supported; save with "
                             "save(..., '-v7')") from None
    except Exception as exc:  # noqa: BLE001
        raise ModelFileError(f"{p}: not a readable MATLAB file ({type(exc).__name__})") from None


def read_array(path, variable: str) -> np.ndarray:
    """The real array ``variable`` (any shape, dense) of a ``.mat`` / ``.npz`` file."""
    p = _path(path)
    value = _numeric(p, f"variable {variable!r}", _container(p, variable))
    value = value.toarray() if sp.issparse(value) else value
    return _finite(p, f"variable {variable!r}", value)


def _pick(p: Path, variable, names: list[str]) -> str:
    if variable is None:
        if len(names) == 1:
            return names[0]
        raise ModelFileError(f"{p}: holds {len(names)} variables ({', '.join(names)}); name the "
                             "one to read")
    if variable not in names:
        raise ModelFileError(f"{p}: has no variable {variable!r}; it holds "
                             f"{', '.join(names) or 'none'}")
    return variable


def _mtx(p: Path):
    import scipy.io

    with open(p, "rb") as f:
        head = f.readline(200)
        size_line = b"%"
        while size_line.startswith(b"%") or not size_line.strip():
            size_line = f.readline(400)
            if not size_line:
                break
    if not head.lower().startswith(b"%%matrixmarket"):
        raise ModelFileError(f"{p}: line 1: not a Matrix Market header (expected "
                             "'%%MatrixMarket matrix ...')")
    words = head.lower().split()
    if b"pattern" in words or b"complex" in words:
        field = "pattern" if b"pattern" in words else "complex"
        raise ModelFileError(f"{p}: line 1: a Matrix Market {field} file holds no real values "
                             "(a pattern file would be read as a matrix of ones); write the "
                             "matrix as 'real' or 'integer'")
    try:
        dims = [int(w) for w in size_line.split()]
    except ValueError:
        dims = []
    if len(dims) not in (2, 3) or min(dims) < 0:
        raise ModelFileError(f"{p}: the size line must hold 'rows cols' (array) or "
                             "'rows cols entries' (coordinate) as integers >= 0")
    entries = dims[2] if len(dims) == 3 else dims[0] * dims[1]
    try:
        check_array_size(p, f"the size line ({' '.join(map(str, dims))})", entries, 16)
        check_array_size(p, "the size line's rows", dims[0], 8)
    except InputError as exc:
        raise ModelFileError(str(exc)) from None
    if entries > p.stat().st_size:  # every entry takes at least 2 bytes of text
        raise ModelFileError(f"{p}: the size line declares {entries} entries but the file has "
                             f"only {p.stat().st_size} bytes: a damaged or truncated file")
    try:
        return scipy.io.mmread(p)
    except Exception as exc:  # noqa: BLE001
        raise ModelFileError(f"{p}: not a readable Matrix Market file ({type(exc).__name__}); "
                             "expected a real or integer matrix") from None


def _numeric(p: Path, what, value):
    if sp.issparse(value):
        value = value.tocsr()
        if not np.issubdtype(value.dtype, np.number) or np.iscomplexobj(value.data):
            raise ModelFileError(f"{p}: {what} must be real numbers; got {value.dtype}")
        return value.astype(float)
    arr = np.asarray(value)
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr) or arr.dtype == bool:
        raise ModelFileError(f"{p}: {what} must be real numbers; got dtype {arr.dtype}")
    return arr.astype(float)


def _finite(p: Path, what, arr):
    data = arr.data if sp.issparse(arr) else arr
    if not np.all(np.isfinite(data)):
        raise ModelFileError(f"{p}: {what} has non-finite entries (nan or inf)")
    return arr


def read_matrix(path, variable: str | None = None, *, sparse: bool = False):
    """A real 2-D matrix from a ``.mtx``, ``.mat``, ``.npz`` or ``.csv`` file.

    Parameters
    ----------
    path : path-like
    variable : str, optional
        Name of the matrix in a ``.mat`` / ``.npz`` file (optional when it holds one).
    sparse : bool
        Return ``scipy.sparse`` CSR (for a full FE stiffness); default a dense ndarray.

    Returns
    -------
    ndarray or scipy.sparse.csr_matrix, shape (m, n)
        In the file's units (e.g. force / length for a stiffness).

    Raises
    ------
    ModelFileError
        Missing file, unknown type, unreadable content, a missing variable, not 2-D, not
        real, or non-finite entries.
    """
    p = _path(path)
    suffix = p.suffix.lower()
    what = f"variable {variable!r}" if variable else "the matrix"
    if suffix == ".csv":
        value = np.array(_csv_rows(p))
    elif suffix == ".mtx":
        value = _mtx(p)
    else:
        value = _container(p, variable)
    value = _numeric(p, what, value)
    if value.ndim != 2:
        raise ModelFileError(f"{p}: {what} must be a 2-D matrix; got shape {value.shape}")
    _finite(p, what, value)
    if sparse:
        return sp.csr_matrix(value)
    if sp.issparse(value):
        try:
            check_array_size(p, f"{what} as a dense {value.shape} array",
                             value.shape[0] * value.shape[1])
        except InputError as exc:
            raise ModelFileError(str(exc)) from None
        return value.toarray()
    return value


def read_vector(path, variable: str | None = None, *, size: int | None = None) -> np.ndarray:
    """A real vector (a one-row or one-column matrix, or a 1-D array) from a file.

    ``size``, when given, is checked.  Same formats and errors as :func:`read_matrix`.
    """
    p = _path(path)
    what = f"variable {variable!r}" if variable else "the vector"
    if p.suffix.lower() in (".csv", ".mtx"):
        m = read_matrix(p)
    else:
        m = _numeric(p, what, _container(p, variable))
        m = m.toarray() if sp.issparse(m) else m
    if m.ndim == 2 and 1 in m.shape:
        m = m.ravel()
    if m.ndim != 1:
        raise ModelFileError(f"{p}: {what} must be a vector (one row or column); got shape "
                             f"{m.shape}")
    _finite(p, what, m)
    if size is not None and m.shape[0] != size:
        raise ModelFileError(f"{p}: {what} has {m.shape[0]} entries; expected {size}")
    return m
