"""Straight 2-D crack sets: :class:`CrackSet`, segment distances, CSV input/output.

A crack has a centre ``(x, y)``, a half-length ``a > 0`` and an angle ``alpha`` (radians from the
x axis); tangent ``t = (cos alpha, sin alpha)``, normal ``n = (-sin alpha, cos alpha)``.  Angles
``alpha`` and ``alpha + pi`` describe the same crack and give the same discrete system (both the
normal and the tangent flip, so gap, slip and reactions are unchanged).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from shakedown.model.errors import InputError, ShapeError

from .crack_files import CSV_COLUMNS, read_table, write_table

__all__ = ["CrackSet", "segment_distance", "load_csv", "save_csv", "KachanovAccuracyWarning",
           "TOUCH_RTOL", "KACHANOV_GAP_RATIO"]


#: Two cracks *touch* when their segment distance is at most ``TOUCH_RTOL * min(a_i, a_j)``
#: plus the rounding of the tip coordinates (``64 eps`` times their magnitude).  A T-junction
#: built from exact data leaves a distance of ~5e-17 a after rounding; a physical gap of 1e-9 a
#: is already far inside the range where no crack-interaction model is meaningful.
TOUCH_RTOL = 1e-9
#: Largest coordinate or half-length accepted: the neighbour search squares distances (a k-d
#: tree of centres at 1.3e154 overflowed with a bare ``ValueError``, found by the fuzz test).
MAX_LENGTH = 1e150

#: Kachanov's method is inaccurate for close pairs: for two collinear cracks its mean opening is
#: 0.7 % too large at a gap of 0.5 a, 2.7 % at 0.1 a, 3.7 % at 0.05 a against the exact
#: solution, and its W* of random sets is up to 5 % low (benchmarks/RESULTS_kachanov.md,
#: sections 2 and 5).  Pairs closer than ``KACHANOV_GAP_RATIO * min(a_i, a_j)`` get a warning.
KACHANOV_GAP_RATIO = 0.1


class KachanovAccuracyWarning(UserWarning):
    """Some cracks are so close that Kachanov's approximation errs by a few per cent or more."""


def segment_distance(p0, p1, q0, q1):
    """Distance between segments ``[p0, p1]`` and ``[q0, q1]`` (vectorised, shapes (..., 2)).

    Zero when the segments intersect or touch; otherwise the smallest of the four
    end-point-to-segment distances.
    """
    p0, p1, q0, q1 = (np.asarray(x, float) for x in (p0, p1, q0, q1))

    def point_seg(x, s0, s1):
        d = s1 - s0
        L2 = np.einsum("...i,...i->...", d, d)
        u = np.clip(np.einsum("...i,...i->...", x - s0, d) / np.where(L2 > 0, L2, 1.0), 0, 1)
        return np.linalg.norm(x - (s0 + u[..., None] * d), axis=-1)

    def cross(o, a, b):
        return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (
            b[..., 0] - o[..., 0]
        )

    d1, d2 = cross(q0, q1, p0), cross(q0, q1, p1)
    d3, d4 = cross(p0, p1, q0), cross(p0, p1, q1)
    crossing = (d1 * d2 < 0) & (d3 * d4 < 0)
    dist = np.minimum(
        np.minimum(point_seg(p0, q0, q1), point_seg(p1, q0, q1)),
        np.minimum(point_seg(q0, p0, p1), point_seg(q1, p0, p1)),
    )
    return np.where(crossing, 0.0, dist)


def _array(name, value, ndim, n=None):
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a real array; got {type(value).__name__}") from exc
    if ndim == 0 and arr.ndim == 0 and n is not None:
        arr = np.full(n, float(arr))
    want = (n, 2) if ndim == 2 else (n,)
    if arr.ndim != len(want) or (n is not None and arr.shape[0] != n) or (
        ndim == 2 and arr.shape[-1] != 2
    ):
        shape = "(N, 2)" if ndim == 2 else f"({n},)"
        raise ShapeError(f"{name} must have shape {shape}; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        k = int(np.argmax(~np.isfinite(arr.reshape(arr.shape[0], -1)).any(axis=1)))
        raise InputError(f"{name} must be finite; crack {k} has {name} = {arr[k]}")
    return arr


@dataclass(frozen=True, eq=False)
class CrackSet:
    """A set of ``N`` straight, non-intersecting cracks in the plane.

    Parameters
    ----------
    centres : array_like, shape (N, 2)
        Crack centres [length].
    half_lengths : array_like, shape (N,) or float
        Half-lengths ``a > 0`` [length].
    angles : array_like, shape (N,) or float
        Angles from the x axis [rad].

    Raises
    ------
    ShapeError, InputError
        Wrong shapes, non-finite values, non-positive half-lengths, or two cracks that
        intersect or touch (the message names the pair).

    Examples
    --------
    >>> import crack_networks as cn
    >>> cs = cn.CrackSet([[0.0, 0.0], [3.0, 0.0]], [1.0, 1.0], [0.0, 0.0])
    >>> cs.n_cracks, round(cs.min_distance(), 12)
    (2, 1.0)
    """

    centres: np.ndarray
    half_lengths: np.ndarray
    angles: np.ndarray

    def __post_init__(self):
        c = _array("centres", self.centres, 2)
        if c.ndim != 2:
            raise ShapeError(f"centres must have shape (N, 2); got shape {c.shape}")
        n = c.shape[0]
        if n == 0:
            raise InputError("a CrackSet needs at least one crack; got 0 centres")
        a = _array("half_lengths", self.half_lengths, 0, n)
        ang = _array("angles", self.angles, 0, n)
        if np.any(a <= 0):
            k = int(np.argmax(a <= 0))
            raise InputError(
                f"half_lengths must be > 0; crack {k} has half_length {a[k]!r} "
                "(remove zero-length cracks)"
            )
        big = max(float(np.abs(c).max()), float(a.max()))
        if big > MAX_LENGTH:
            raise InputError(
                f"centres and half_lengths must be at most {MAX_LENGTH:g} in magnitude (squared "
                f"distances must stay finite); got {big:.3g}: give them in other length units")
        for arr in (c, a, ang):
            arr.setflags(write=False)
        object.__setattr__(self, "centres", c)
        object.__setattr__(self, "half_lengths", a)
        object.__setattr__(self, "angles", ang)
        p0, p1 = self.tips
        rounding = 64 * np.finfo(float).eps * float(np.abs(np.vstack([p0, p1])).max())
        pairs, gaps = self.close_pairs(TOUCH_RTOL, atol=rounding)
        if pairs.size:
            i, j = pairs[0]
            raise InputError(
                f"cracks must not intersect or touch; cracks {i + 1} (centre ({c[i, 0]:.6g}, "
                f"{c[i, 1]:.6g})) and {j + 1} (centre ({c[j, 0]:.6g}, {c[j, 1]:.6g})) meet "
                f"(distance {gaps[0]:.3g}, at most "
                f"{TOUCH_RTOL:g} of the shorter half-length plus rounding). Move or shorten one "
                "of them"
            )

    # ------------------------------------------------------------------ geometry
    @property
    def n_cracks(self) -> int:
        """Number of cracks ``N``."""
        return self.centres.shape[0]

    def __len__(self) -> int:
        return self.n_cracks

    @cached_property
    def tangents(self) -> np.ndarray:
        """Unit tangents ``t``, shape (N, 2)."""
        return np.stack([np.cos(self.angles), np.sin(self.angles)], axis=-1)

    @cached_property
    def normals(self) -> np.ndarray:
        """Unit normals ``n`` (tangent rotated by +90 degrees), shape (N, 2)."""
        return np.stack([-np.sin(self.angles), np.cos(self.angles)], axis=-1)

    @property
    def tips(self) -> tuple[np.ndarray, np.ndarray]:
        """End points ``c - a t`` and ``c + a t``, each of shape (N, 2)."""
        d = self.half_lengths[:, None] * self.tangents
        return self.centres - d, self.centres + d

    @property
    def mean_half_length(self) -> float:
        """``abar``, the mean half-length [length]."""
        return float(self.half_lengths.mean())

    def bounding_box(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` over all crack tips."""
        p, q = self.tips
        pts = np.vstack([p, q])
        return (*pts.min(axis=0), *pts.max(axis=0))

    def density(self, area: float | None = None) -> float:
        """``rho = sum a^2 / area`` (default area: the bounding box of the tips)."""
        if area is None:
            x0, y0, x1, y1 = self.bounding_box()
            area = (x1 - x0) * (y1 - y0)
        return float(np.sum(self.half_lengths**2) / area)

    def neighbour_pairs(self, distance: float) -> np.ndarray:
        """Pairs ``(i, j)``, ``i < j``, whose segments are at most ``distance`` apart.

        Returns an int array of shape (P, 2), sorted.  Uses a k-d tree on the centres, then the
        exact segment-segment distance.
        """
        n = self.n_cracks
        if n < 2:
            return np.zeros((0, 2), dtype=int)
        tree = cKDTree(self.centres)
        r = 2.0 * float(self.half_lengths.max()) + float(distance)
        cand = tree.query_pairs(r, output_type="ndarray")
        if cand.size == 0:
            return np.zeros((0, 2), dtype=int)
        i, j = cand[:, 0], cand[:, 1]
        near = np.linalg.norm(self.centres[i] - self.centres[j], axis=1) <= (
            self.half_lengths[i] + self.half_lengths[j] + distance
        )
        cand = cand[near]
        p0, p1 = self.tips
        i, j = cand[:, 0], cand[:, 1]
        d = segment_distance(p0[i], p1[i], p0[j], p1[j])
        out = cand[d <= distance]
        out = np.sort(out, axis=1)
        return out[np.lexsort((out[:, 1], out[:, 0]))] if out.size else out

    def close_pairs(self, gap_ratio: float, atol: float = 0.0):
        """Pairs closer than ``gap_ratio * min(a_i, a_j) + atol`` and their distances.

        Returns
        -------
        pairs : ndarray of int, shape (P, 2)
            ``i < j`` (0-based), sorted.
        distances : ndarray, shape (P,)
            Segment distances [length].
        """
        a = self.half_lengths
        pairs = self.neighbour_pairs(gap_ratio * float(a.max()) + atol)
        if pairs.size == 0:
            return pairs, np.zeros(0)
        i, j = pairs[:, 0], pairs[:, 1]
        p0, p1 = self.tips
        d = segment_distance(p0[i], p1[i], p0[j], p1[j])
        keep = d <= gap_ratio * np.minimum(a[i], a[j]) + atol
        return pairs[keep], d[keep]

    def warn_if_close(self, gap_ratio: float = KACHANOV_GAP_RATIO, stacklevel: int = 2) -> int:
        """Warn (:class:`KachanovAccuracyWarning`) when pairs are closer than ``gap_ratio a``.

        Returns the number of such pairs.
        """
        import warnings

        pairs, d = self.close_pairs(gap_ratio)
        if pairs.size:
            k = int(np.argmin(d / np.minimum(self.half_lengths[pairs[:, 0]],
                                             self.half_lengths[pairs[:, 1]])))
            i, j = pairs[k]
            warnings.warn(
                f"{len(pairs)} crack pair(s) are closer than {gap_ratio:g} of the shorter "
                f"half-length (closest: cracks {i + 1} and {j + 1}, distance {d[k]:.3g}); "
                "Kachanov's approximation errs by several per cent there (2.7 % in the opening "
                "of two collinear cracks at 0.1 a, benchmarks/RESULTS_kachanov.md): use the BEM "
                "model (cn.bem_model) or sample with a larger min_spacing",
                KachanovAccuracyWarning, stacklevel=stacklevel,
            )
        return int(len(pairs))

    def distances(self) -> np.ndarray:
        """All pairwise segment distances, shape (N, N) (``inf`` on the diagonal)."""
        p0, p1 = self.tips
        d = segment_distance(p0[:, None], p1[:, None], p0[None], p1[None])
        np.fill_diagonal(d, np.inf)
        return d

    def min_distance(self) -> float:
        """Smallest segment-segment distance between two cracks (``inf`` for one crack)."""
        if self.n_cracks < 2:
            return float("inf")
        tree = cKDTree(self.centres)
        # the nearest segments need not have the nearest centres: widen the search radius
        dc, _ = tree.query(self.centres, k=2)
        r = float(dc[:, 1].min()) + 2.0 * float(self.half_lengths.max())
        pairs = tree.query_pairs(r, output_type="ndarray")
        p0, p1 = self.tips
        i, j = pairs[:, 0], pairs[:, 1]
        return float(segment_distance(p0[i], p1[i], p0[j], p1[j]).min())

    # ------------------------------------------------------------------ transformations
    def permuted(self, order) -> CrackSet:
        """The cracks reordered (``new[k] = old[order[k]]``)."""
        o = np.asarray(order, dtype=int)
        return CrackSet(self.centres[o], self.half_lengths[o], self.angles[o])

    def rotated(self, angle: float, origin=(0.0, 0.0)) -> CrackSet:
        """The set rotated rigidly by ``angle`` [rad] about ``origin``."""
        c, s = np.cos(angle), np.sin(angle)
        o = np.asarray(origin, float)
        x = self.centres - o
        xr = np.stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1]], axis=-1) + o
        return CrackSet(xr, self.half_lengths, self.angles + angle)

    def translated(self, shift) -> CrackSet:
        """The set shifted by ``shift`` (shape (2,))."""
        return CrackSet(self.centres + np.asarray(shift, float), self.half_lengths, self.angles)

    def scaled(self, factor: float) -> CrackSet:
        """The set scaled by ``factor > 0`` about the origin (lengths and positions)."""
        return CrackSet(self.centres * factor, self.half_lengths * factor, self.angles)

    def subset(self, indices) -> CrackSet:
        """The cracks ``indices`` only."""
        return self.permuted(indices)

    # ------------------------------------------------------------------ I/O and display
    def to_array(self) -> np.ndarray:
        """Columns ``x, y, half_length, angle``, shape (N, 4)."""
        return np.column_stack([self.centres, self.half_lengths, self.angles])

    def to_dataframe(self):
        """A pandas DataFrame with columns ``x, y, half_length, angle``."""
        import pandas as pd

        return pd.DataFrame(self.to_array(), columns=list(CSV_COLUMNS))

    def save_csv(self, path) -> None:
        """Write the set to a CSV file (see :func:`save_csv`)."""
        save_csv(self, path)

    @classmethod
    def from_csv(cls, path) -> CrackSet:
        """Read a set from a CSV file (see :func:`load_csv`)."""
        return load_csv(path)

    def plot(self, ax=None, **kwargs):
        """Draw the cracks (see :func:`crack_networks.plotting.plot_cracks`)."""
        from .plotting import plot_cracks

        return plot_cracks(self, ax=ax, **kwargs)

    def __repr__(self) -> str:
        a = self.half_lengths
        return (
            f"CrackSet(n_cracks={self.n_cracks}, half_length=[{a.min():.4g}..{a.max():.4g}], "
            f"mean {a.mean():.4g})"
        )


def save_csv(cracks: CrackSet, path) -> None:
    """Write ``cracks`` as CSV with header ``x,y,half_length,angle`` (angle in radians)."""
    write_table(cracks.to_array(), path)


def load_csv(path) -> CrackSet:
    """Read a crack set written by :func:`save_csv` (see :func:`.crack_files.read_table`).

    The file needs a header with the columns ``x, y, half_length`` and either ``angle``
    (radians) or ``angle_deg`` (degrees), in any order; other columns are ignored.
    """
    return CrackSet(*read_table(path))
