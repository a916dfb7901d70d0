"""Load histories from CSV records: measured welded reactions, resampled to one period.

A record is a CSV file with a header row naming its columns: ``t`` (time, any unit, strictly
increasing, any sampling, uneven allowed) and, for each contact node ``j = 1..N`` (numbered
from 1), ``q_j`` and ``p_j``: the welded reactions (MODEL.md s.1: reaction of the obstacle on
the body, ``p`` compression positive) [force].  Columns may come in any order; extra columns
are refused (a misspelt name would otherwise be ignored).

One period ``[t_start, t_start + period]`` of the record (it must cover it) is resampled at
``n_samples`` equally spaced times by linear interpolation; the :class:`~shakedown.LoadCycle`
is ``r_w(t) = r0 + lam * r1(t)`` with ``r0`` the mean of the resampled period and ``r1`` the
rest (so ``lam = 1`` is the record, and ``lam`` scales its oscillation about the mean).

The stated error: the periodic piecewise-linear load the analyses see is compared with the
record at every record time in the period (and with the record's end of period against its
start, the periodicity mismatch); the largest difference, relative to the record's largest
``|q|, |p|``, is :attr:`RecordFit.relative_error`.  Reading refuses a fit worse than
``max_error`` and names the ``n_samples`` that would do.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...model.errors import InputError
from ...model.limits import check_array_size, check_file_size
from ...model.loading import LoadCycle
from ...model.validation import check_count, check_positive
from .readers import ModelFileError

_COLUMN = re.compile(r"^([qp])_([1-9][0-9]*)$")


@dataclass(frozen=True)
class RecordFit:
    """How well the resampled period matches the record.

    Attributes
    ----------
    path : str
    n_nodes, n_samples, n_record_samples : int
        Contact nodes; samples of the load cycle; record samples inside the period.
    t_start, period : float
        The period taken from the record [the record's time unit].
    max_error : float
        Largest ``|r_record - r_resampled|`` over the period's record samples, including the
        periodicity mismatch ``|r(t_start + period) - r(t_start)|`` [force].
    scale : float
        Largest ``|q|``, ``|p|`` of the record in the period [force].
    """

    path: str
    n_nodes: int
    n_samples: int
    n_record_samples: int
    t_start: float
    period: float
    max_error: float
    scale: float

    @property
    def relative_error(self) -> float:
        """``max_error / scale`` (0 for an all-zero record)."""
        return self.max_error / self.scale if self.scale > 0 else 0.0

    def message(self) -> str:
        return (f"{self.path}: {self.n_record_samples} record samples over one period "
                f"[{self.t_start:g}, {self.t_start + self.period:g}] resampled to "
                f"{self.n_samples} samples; largest difference {self.max_error:.3g} "
                f"({self.relative_error:.2e} of the largest reaction)")


def _read(p: Path) -> tuple[list[str], np.ndarray]:
    if p.suffix.lower() != ".csv":
        raise ModelFileError(f"{p}: a load record must be a .csv file; got {p.suffix!r}")
    if not p.is_file():
        raise ModelFileError(f"{p}: no such file")
    try:
        check_file_size(p, "load record")
    except InputError as exc:
        raise ModelFileError(str(exc)) from None
    rows, header = [], None
    with open(p, newline="", encoding="utf-8", errors="replace") as f:
        for line_no, row in enumerate(csv.reader(f), start=1):
            if not row or row[0].lstrip().startswith("#") or all(not c.strip() for c in row):
                continue
            if header is None:
                header = [c.strip() for c in row]
                continue
            if len(row) != len(header):
                raise ModelFileError(f"{p}: line {line_no} has {len(row)} columns; the header "
                                     f"has {len(header)}")
            try:
                rows.append([float(c) for c in row])
            except ValueError:
                col = next(i for i, c in enumerate(row, 1) if not _is_float(c))
                raise ModelFileError(f"{p}: line {line_no}, column {col} "
                                     f"({header[col - 1]!r}): not a number") from None
    if header is None or not rows:
        raise ModelFileError(f"{p}: no header and data rows (expected columns t, q_1, p_1, ...)")
    return header, np.array(rows)


def _is_float(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


def _columns(p: Path, header: list[str]) -> tuple[int, np.ndarray, np.ndarray]:
    if "t" not in header:
        raise ModelFileError(f"{p}: the header has no time column 't' (expected t, q_1, p_1, ...)")
    if len(set(header)) != len(header):
        raise ModelFileError(f"{p}: the header names a column twice")
    found = {}
    for i, name in enumerate(header):
        if name == "t":
            continue
        m = _COLUMN.match(name)
        if m is None:
            raise ModelFileError(f"{p}: header column {i + 1} is not 't', 'q_<node>' or "
                                 "'p_<node>' (nodes numbered from 1)")
        found[(m.group(1), int(m.group(2)))] = i
    n = max((j for _, j in found), default=0)
    if n > len(header):  # (before listing the missing columns: q_1000000000)
        kind, j = max(found, key=lambda kj: kj[1])
        raise ModelFileError(f"{p}: column '{kind}_{j}' names node {j}, but the record has "
                             f"only {len(header) - 1} data columns (q_j and p_j of nodes "
                             f"1..{(len(header) - 1) // 2} at most)")
    missing = [f"{k}_{j}" for j in range(1, n + 1) for k in "qp" if (k, j) not in found]
    if n == 0 or missing:
        raise ModelFileError(f"{p}: columns missing: {', '.join(missing) or 'q_1, p_1'} (every "
                             f"node 1..{max(n, 1)} needs q_j and p_j)")
    qi = np.array([found[("q", j)] for j in range(1, n + 1)])
    pi = np.array([found[("p", j)] for j in range(1, n + 1)])
    return n, qi, pi


def read_load_record(path, period: float, *, n_samples: int = 256, t_start: float | None = None,
                     max_error: float = 1e-2) -> tuple[LoadCycle, RecordFit]:
    """The :class:`~shakedown.LoadCycle` of one period of a CSV record (module docstring).

    Parameters
    ----------
    path : path-like
        The CSV record (columns ``t``, ``q_1``, ``p_1``, ..., ``q_N``, ``p_N``).
    period : float
        Period of the loading [the record's time unit].
    n_samples : int
        Equally spaced samples of the load cycle (>= 2).
    t_start : float, optional
        Start of the period taken (default: the record's first time).
    max_error : float
        Largest accepted :attr:`RecordFit.relative_error`.

    Returns
    -------
    (LoadCycle, RecordFit)

    Raises
    ------
    ModelFileError
        Unreadable file, bad header, non-increasing time, a record shorter than the period,
        or a resampling error above ``max_error``.
    """
    p = Path(path)
    try:
        period = check_positive("period", period)
        n_samples = check_count("n_samples", n_samples, 2)
    except InputError as exc:
        raise ModelFileError(f"{p}: {exc}") from None
    header, data = _read(p)
    n, qi, pi = _columns(p, header)
    try:  # the resampled period and its copies (about 6 arrays of n_samples x 2N)
        check_array_size(p, f"n_samples = {n_samples} x {2 * n} columns", 6 * n_samples * 2 * n)
    except InputError as exc:
        raise ModelFileError(str(exc)) from None
    t = data[:, header.index("t")]
    if not np.all(np.isfinite(data)):
        raise ModelFileError(f"{p}: holds non-finite numbers (nan or inf)")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise ModelFileError(f"{p}: time must increase strictly; data row {k + 2} does not")
    t0 = float(t[0]) if t_start is None else float(t_start)
    # a record ending at t0 + period up to round-off (relative 1e-9 of the period) covers it
    if t0 < t[0] or t0 + period > t[-1] + 1e-9 * period:
        raise ModelFileError(f"{p}: the record covers t = {t[0]:g}..{t[-1]:g}; one period "
                             f"[{t0:g}, {t0 + period:g}] must lie inside it")
    r = np.concatenate([data[:, qi], data[:, pi]], axis=1)  # (n_record, 2N)
    ts = t0 + period * np.arange(n_samples) / n_samples
    samples = np.stack([np.interp(ts, t, r[:, k]) for k in range(2 * n)], axis=1)
    inside = (t >= t0) & (t <= t0 + period)
    tau = np.concatenate([t[inside], [t0 + period]])
    ref = np.concatenate([r[inside], [np.array([np.interp(t0 + period, t, r[:, k])
                                                for k in range(2 * n)])]])
    ext = np.concatenate([samples, samples[:1]])  # periodic: closes back to the first sample
    tt = np.concatenate([ts, [t0 + period]])
    fitted = np.stack([np.interp(tau, tt, ext[:, k]) for k in range(2 * n)], axis=1)
    scale = float(np.abs(r[inside]).max()) if inside.any() else 0.0
    fit = RecordFit(path=str(p), n_nodes=n, n_samples=n_samples,
                    n_record_samples=int(inside.sum()), t_start=t0, period=period,
                    max_error=float(np.abs(fitted - ref).max()), scale=scale)
    if fit.relative_error > max_error:
        raise ModelFileError(
            f"{fit.message()}: above the accepted {max_error:g}; raise n_samples (the record "
            f"has {fit.n_record_samples} samples in the period), check the period, or accept "
            "more with max_error")
    r0 = samples.mean(axis=0)
    r1 = samples - r0
    cycle = LoadCycle.from_samples(r0[:n], r0[n:], r1[:, :n], r1[:, n:])
    return cycle, fit
