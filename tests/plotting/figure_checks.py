"""Checks of a drawn figure read from its artists (what a reviewer checks by eye, issue 25):
legend entries match what is drawn inside the axes, axis labels carry units in brackets."""

from __future__ import annotations

import re

import numpy as np
from matplotlib.lines import AxLine, Line2D

from shakedown.plotting.axes import OUTSIDE

#: An axis label ends with its unit in brackets: "slip v [mm]", "load factor lam [-]".
UNIT = re.compile(r"\[[^\[\]]+\]\$?$")


def _box(ax):
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    return x0, x1, y0, y1


def _segment_in_box(p, q, box) -> bool:
    """Does the segment p-q meet the box (Liang-Barsky clipping)?"""
    x0, x1, y0, y1 = box
    t0, t1 = 0.0, 1.0
    d = q - p
    for pk, qk in ((-d[0], p[0] - x0), (d[0], x1 - p[0]), (-d[1], p[1] - y0), (d[1], y1 - p[1])):
        if pk == 0:
            if qk < 0:
                return False
        else:
            t = qk / pk
            if pk < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    return t0 <= t1


def visible(artist, ax) -> bool:
    """Whether a line (finite or infinite) shows at least one point inside the axes limits."""
    box = _box(ax)
    if isinstance(artist, AxLine):
        (ax_, ay), (bx, by) = artist.get_xy1(), artist.get_xy2()
        p, d = np.array([ax_, ay], float), np.array([bx - ax_, by - ay], float)
        big = 1e6 * (abs(box[1] - box[0]) + abs(box[3] - box[2]) + np.abs(p).max())
        return _segment_in_box(p - big * d / np.linalg.norm(d), p + big * d / np.linalg.norm(d), box)
    if isinstance(artist, Line2D):
        xy = np.column_stack([artist.get_xdata(), artist.get_ydata()]).astype(float)
        xy = xy[np.isfinite(xy).all(axis=1)]
        if len(xy) == 1:
            return _segment_in_box(xy[0], xy[0], box)
        return any(_segment_in_box(xy[i], xy[i + 1], box) for i in range(len(xy) - 1))
    return True  # patches, collections: drawn where they are


def legend_entries(ax) -> list[str]:
    leg = ax.get_legend()
    return [t.get_text() for t in leg.get_texts()] if leg is not None else []


def labelled_artists(*axes) -> dict:
    """label -> artist of every labelled line, patch and collection of the axes."""
    out = {}
    for ax in axes:
        for a in [*ax.lines, *ax.patches, *ax.collections]:
            lab = a.get_label()
            if lab and not lab.startswith("_"):
                out[lab] = (a, ax)
    return out


def check_legend_matches_drawn(ax, *more_axes):
    """Every legend entry is a labelled artist visible inside its axes, and every labelled
    artist is in the legend; no entry twice."""
    entries = legend_entries(ax)
    assert entries, "no legend"
    assert len(entries) == len(set(entries)), f"repeated legend entries: {entries}"
    drawn = labelled_artists(ax, *more_axes)
    assert set(entries) == set(drawn), (sorted(entries), sorted(drawn))
    for lab, (artist, where) in drawn.items():
        if lab.endswith(OUTSIDE):  # a proxy that says where the line is: nothing drawn
            assert not len(getattr(artist, "get_xdata", list)()), lab
            continue
        assert visible(artist, where), f"legend entry {lab!r} is drawn outside the axes"


def check_units(*axes):
    """Every non-empty axis label ends with its unit in brackets."""
    for ax in axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label:
                assert UNIT.search(label.strip()), f"axis label without a unit in brackets: {label!r}"
