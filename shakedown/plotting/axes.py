"""Helpers shared by the plotting modules: matplotlib imported lazily, a new axes when none is
given, and the placeholder units of axis labels."""

from __future__ import annotations

#: Placeholder units when a scene declares none (``[scene] force_unit``, ``length_unit``).
UNITS = {"force": "[force]", "length": "[length]", "energy": "[force x length]"}


def _unit(units, key):
    return (units or {}).get(key, UNITS[key])


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _new_ax(ax, **kw):
    if ax is None:
        fig, ax = _plt().subplots(**kw)
    return ax
