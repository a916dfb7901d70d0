"""Anderson (type II) mixing of a fixed-point iteration ``x <- P(x)``: the update shared by
:func:`shakedown.steady_cycle` and the accelerator of the 3-D cyclic driver (:mod:`.cone_cycles`).
"""

from __future__ import annotations

import numpy as np


def _anderson(X, G, y):
    """Anderson (type II) update from iterates ``X`` and residuals ``G = P(X) - X``.

    Parameters
    ----------
    X, G : list of ndarray, each of shape (n,)
        The last ``m + 1`` iterates and their residuals (same units as the state).
    y : ndarray, shape (n,)
        ``P(X[-1])``, returned unchanged when fewer than two iterates are given.

    Returns
    -------
    ndarray, shape (n,)
        ``y - (dX + dG) gamma`` with ``gamma`` the least-squares solution of ``dG gamma = G[-1]``.
    """
    if len(X) < 2:
        return y
    dG = np.diff(np.array(G), axis=0).T  # (n, m)
    dX = np.diff(np.array(X), axis=0).T
    gamma = np.linalg.lstsq(dG, G[-1], rcond=1e-12)[0]
    return y - (dX + dG) @ gamma


__all__ = ["_anderson"]
