"""Helpers shared by the plotting modules: matplotlib imported lazily, a new axes when none is
given, units of axis labels (always in brackets), and one name and colour per extreme
constraint of a two-node system (the same in every picture)."""

from __future__ import annotations

import numpy as np

#: Placeholder units when a scene declares none (``[scene] force_unit``, ``length_unit``).
UNITS = {"force": "[force]", "length": "[length]", "energy": "[force x length]"}


def _unit(units, key, power: int = 1) -> str:
    """The unit of ``key`` (``"force"``, ``"length"``, ``"energy"``) in brackets: ``"[mm]"``.

    ``units`` maps keys to unit names with or without brackets (a scene declares ``"mm"``; the
    placeholders are ``"[length]"``); ``power = 2`` squares it: ``"[mm²]"``, ``"[(N mm)²]"``.
    """
    u = str((units or {}).get(key) or UNITS[key]).strip()
    if u.startswith("[") and u.endswith("]"):
        u = u[1:-1]
    if power != 1:
        base = f"({u})" if " " in u else u
        u = base + ("²" if power == 2 else f"^{power}")
    return f"[{u}]"


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _new_ax(ax, **kw):
    if ax is None:
        fig, ax = _plt().subplots(**kw)
    return ax


#: Seed 002's order and numerals of a two-node system's extreme constraints, with the package's
#: names: rows of ``G`` are ``I_1, I_2, II_1, II_2`` (``k``), the seed draws I, II (node 1),
#: III, IV (node 2).  Each has one colour in every picture.
SEED_ORDER = (0, 2, 1, 3)
_ROMAN = ("I", "II", "III", "IV")
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red")
#: Legend label of the shaded safe shakedown region.
SAFE_REGION = r"safe region $\mathcal{H}(\lambda)$"


def constraint_style(k: int, n_nodes: int = 2) -> tuple[str, str]:
    """``(colour, legend label)`` of the extreme constraint in row ``k`` of ``G`` (two nodes).

    The label names the constraint as the package does (``I_1``: node 1 slips backward when it
    pushes, ``II_1``: forward; nodes from 1) and as seed 002 does (I, II, III, IV).
    """
    r = SEED_ORDER.index(k)
    name = f"{'I' if k < n_nodes else 'II'}_{k % n_nodes + 1}"
    return _COLOURS[r], f"{name} extreme (seed {_ROMAN[r]})"


#: Legend suffix of an extreme line too far away to be framed with the rest of the picture.
OUTSIDE = ": outside the picture"


def frame_lines(G, b, lo, hi, pad: float = 0.08, max_growth: float = 2.0):
    """A view box ``(lo, hi)`` grown so that every line ``G_k . x = b_k`` crosses it, when
    that costs at most a factor ``max_growth`` in the box's size.

    A line that misses the box, or only passes within ``pad`` times the box size of its edge,
    gets the point of it nearest the box centre inside the box (with that margin), so no
    constraint is named in a legend and left outside the picture or on its frame.  A line so far
    away that framing it would shrink the rest of the picture more than ``max_growth`` times
    is left out and reported: its legend entry says so (:data:`OUTSIDE`).

    Parameters
    ----------
    G : ndarray, shape (m, 2)
        Normals of the lines (plot coordinates).
    b : ndarray, shape (m,)
        Offsets.
    lo, hi : ndarray, shape (2,)
        Corners of the box.

    Returns
    -------
    lo, hi : ndarray, shape (2,)
    outside : set of int
        The lines left outside the box.
    """
    lo, hi = np.array(lo, float), np.array(hi, float)
    size0 = np.maximum(hi - lo, 1e-300)
    outside = set()
    for k, (g, off) in enumerate(zip(np.asarray(G, float), np.asarray(b, float), strict=True)):
        nn = float(g @ g)
        if nn == 0:
            continue
        margin = pad * max(float(np.max(hi - lo)), 1e-12)
        inner = (lo + margin, hi - margin)  # not hugging an edge either
        corners = np.array([[x, y] for x in (inner[0][0], inner[1][0])
                            for y in (inner[0][1], inner[1][1])])
        side = corners @ g - off
        if side.min() <= 0 <= side.max():
            continue  # the line crosses the box already
        c = 0.5 * (lo + hi)
        p = c - g * (g @ c - off) / nn
        new_lo, new_hi = np.minimum(lo, p - margin), np.maximum(hi, p + margin)
        if np.max((new_hi - new_lo) / size0) > max_growth:
            outside.add(k)
            continue
        lo, hi = new_lo, new_hi
    return lo, hi, outside
