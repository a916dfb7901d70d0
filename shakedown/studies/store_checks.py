"""The checks a store carries in its files, and the repairs of a damaged store (issue 24).

Every Parquet part carries, in its schema metadata (key ``shakedown_check``), its row count,
its task keys and the SHA-256 of its content (:func:`content_digest`: column names, dtypes and
``pandas.util.hash_pandas_object`` of the rows).  Every block of rows appended to a CSV store
carries three leading columns (:data:`CSV_CHECK`): a block id, the block's row count and the
SHA-256 of the block's fields as written.

:func:`repair_parquet` and :func:`repair_csv` run when a store is opened (under its lock):

* a part that cannot be read or fails its check (cut, edited, a column renamed), or whose
  columns differ from the store's, is moved to ``damaged/`` inside the store: its tasks have
  no rows any more and run again;
* a part or block holding a task key already held by an earlier one (a copied part) is moved
  aside / cut out likewise (the earlier rows are kept);
* a CSV block with fewer rows than it declares (a cut file) or a wrong checksum, and lines
  that belong to no block (garbage), are cut out of the file.

Each repair is reported by a ``RuntimeWarning`` naming the file and what was done.  Parts and
files written before these checks existed are read as they are (their columns still checked).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import uuid
import warnings
from pathlib import Path

import pandas as pd

from ..model.errors import DamagedFileError
from ..model.safe_files import check_no_links, make_folder

__all__ = ["CSV_CHECK", "content_digest", "parquet_bytes", "read_part", "repair_parquet",
           "csv_block", "repair_csv", "damaged"]

KEY = "task_key"
#: Leading columns of a checked CSV store: block id, rows in the block, SHA-256 of its fields.
CSV_CHECK = ("_block", "_block_rows", "_block_sha256")
_META = b"shakedown_check"


def damaged(path, why: str) -> DamagedFileError:
    """The error for a store file that cannot be repaired."""
    return DamagedFileError(
        f"store file {path} is damaged: {why}; it cannot be repaired automatically: move it "
        "away (its tasks then run again) or start a fresh store")


def _warn(msg: str) -> str:
    warnings.warn(msg, RuntimeWarning, stacklevel=4)
    return msg


# ---------------------------------------------------------------------------- Parquet parts
def content_digest(df: pd.DataFrame) -> str:
    """SHA-256 (hex) of a table's column names, dtypes and rows (index ignored)."""
    h = hashlib.sha256()
    h.update(json.dumps([[str(c), str(t)] for c, t in df.dtypes.items()]).encode())
    if len(df):
        h.update(pd.util.hash_pandas_object(df, index=False).to_numpy().tobytes())
    return h.hexdigest()


def parquet_bytes(df: pd.DataFrame) -> bytes:
    """The Parquet file of ``df`` with its check in the schema metadata."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(df, preserve_index=False)
    check = {"rows": len(df), "sha256": content_digest(df),
             "keys": sorted(set(df[KEY].astype(str))) if KEY in df.columns else []}
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           _META: json.dumps(check).encode()})
    buf = io.BytesIO()
    pq.write_table(table, buf)
    return buf.getvalue()


def read_part(path) -> pd.DataFrame:
    """The rows of a part, checked; :class:`DamagedFileError` naming it if it fails."""
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
        df = table.to_pandas()
    except Exception as exc:  # noqa: BLE001 - arrow, thrift, OS and decoding errors
        raise damaged(path, f"not a readable Parquet file ({type(exc).__name__}: {exc})") from None
    raw = (table.schema.metadata or {}).get(_META)
    if raw is None:
        return df  # a part written before the checks: read as it is
    try:
        check = json.loads(raw)
        rows, digest = int(check["rows"]), str(check["sha256"])
    except (ValueError, KeyError, TypeError):
        raise damaged(path, "its check (schema metadata) is not readable") from None
    if len(df) != rows:
        raise damaged(path, f"{len(df)} rows where its check says {rows}")
    if content_digest(df) != digest:
        raise damaged(path, "its content does not match its SHA-256 (edited, or a column "
                      "renamed)")
    return df


def repair_parquet(parts: list[Path], folder: Path) -> list[str]:
    """Verify every part; move damaged and duplicated ones to ``folder/damaged``; the messages."""
    done: list[str] = []
    seen: dict[str, Path] = {}
    columns = None
    for p in parts:
        check_no_links(p, "store part")
        why = None
        try:
            df = read_part(p)
        except DamagedFileError as exc:
            why, df = str(exc).split(": ", 1)[1].split("; it cannot")[0], None
        if df is not None:
            cols = [c for c in df.columns]
            if columns is None:
                columns = cols
            elif cols != columns:
                why = f"its columns {cols} differ from the store's {columns}"
        if why is None and df is not None and KEY in df.columns:
            keys = set(df[KEY].astype(str))
            again = sorted(keys & set(seen))
            if again:
                why = (f"it repeats the rows of task {again[0]!r} held by {seen[again[0]].name} "
                       f"({len(again)} task(s)): a duplicate")
            else:
                seen.update(dict.fromkeys(keys, p))
        if why is not None:
            aside = make_folder(folder / "damaged", "store folder") / p.name
            p.replace(aside)
            done.append(_warn(f"store {folder}: part {p.name} {why}: moved to {aside}; its "
                              "tasks run again"))
    return done


# ---------------------------------------------------------------------------- CSV blocks
def _digest_rows(rows: list[list[str]]) -> str:
    h = hashlib.sha256()
    for fields in rows:
        h.update(("\x1f".join(fields) + "\x1e").encode("utf-8", "surrogateescape"))
    return h.hexdigest()


def csv_block(rows: list[dict], columns: list[str], header: bool) -> bytes:
    """The CSV lines of one appended block of ``rows`` with their check (and the header)."""
    text = pd.DataFrame(rows, columns=columns).to_csv(
        index=False, header=False, float_format="%.17g", lineterminator="\n")
    fields = list(csv.reader(io.StringIO(text)))
    block, digest = uuid.uuid4().hex[:12], _digest_rows(fields)
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    if header:
        w.writerow([*CSV_CHECK, *columns])
    for f in fields:
        w.writerow([block, len(fields), digest, *f])
    return out.getvalue().encode()


def repair_csv(data: bytes, path) -> tuple[bytes, list[str]]:
    """``(data without its damaged blocks, messages)``; ``data`` unchanged if all is well."""
    if not data:
        return data, []
    text = data.decode("utf-8", "surrogateescape")
    try:
        lines = list(csv.reader(io.StringIO(text)))
    except csv.Error as exc:
        raise damaged(path, f"not a readable CSV file ({exc})") from None
    if not lines or tuple(lines[0][:3]) != CSV_CHECK:
        return data, []  # a store written before the checks: read as it is
    header, body = lines[0], lines[1:]
    width = len(header)
    kcol = header.index(KEY) if KEY in header else None
    blocks: dict[str, list[list[str]]] = {}
    garbage = 0
    for f in body:
        if len(f) != width or not f[0]:
            garbage += 1
            continue
        blocks.setdefault(f[0], []).append(f)
    done, keep, seen = [], [], set()
    if garbage:
        done.append(f"{garbage} line(s) that belong to no block of rows: removed")
    for bid, rows in blocks.items():
        keys = sorted({r[kcol] for r in rows}) if kcol is not None else []
        try:
            declared = int(rows[0][1])
        except ValueError:
            declared = -1
        if declared != len(rows) or any(r[1] != rows[0][1] or r[2] != rows[0][2] for r in rows):
            done.append(f"block {bid} (task(s) {', '.join(keys[:3])}) has {len(rows)} of "
                        f"{declared} rows: removed, its tasks run again")
        elif _digest_rows([r[3:] for r in rows]) != rows[0][2]:
            done.append(f"block {bid} (task(s) {', '.join(keys[:3])}) does not match its "
                        "SHA-256 (edited): removed, its tasks run again")
        elif set(keys) & seen:
            done.append(f"block {bid} repeats the rows of task {sorted(set(keys) & seen)[0]!r}: "
                        "a duplicate, removed")
        else:
            seen.update(keys)
            keep.extend(rows)
            continue
    if not done:
        return data, []
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(header)
    w.writerows(keep)
    return (out.getvalue().encode("utf-8", "surrogateescape"),
            [_warn(f"store {path}: {m}") for m in done])
