"""Matplotlib helpers for crack networks (imported lazily; every function takes ``ax=None``)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_cracks", "plot_collinear_accuracy", "plot_stiffness_comparison"]


def _axes(ax, figsize=(5.0, 5.0)):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=figsize)
    return ax


def plot_cracks(cracks, ax=None, *, values=None, cmap="viridis", label=None, numbers=False,
                linewidth=1.5, colorbar=True):
    """Draw the cracks as segments.

    Parameters
    ----------
    cracks : CrackSet
    ax : matplotlib Axes, optional
    values : array_like, shape (N,), optional
        Colour each crack by a value (e.g. slip fraction); otherwise all black.
    numbers : bool
        Write each crack's index at its centre.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.collections import LineCollection

    ax = _axes(ax)
    p0, p1 = cracks.tips
    segs = np.stack([p0, p1], axis=1)
    lc = LineCollection(segs, linewidths=linewidth, label=label)
    if values is not None:
        lc.set_array(np.asarray(values, float))
        lc.set_cmap(cmap)
    else:
        lc.set_color("k")
    ax.add_collection(lc)
    if values is not None and colorbar:
        ax.figure.colorbar(lc, ax=ax)
    if numbers:
        for k, (x, y) in enumerate(cracks.centres):
            ax.annotate(str(k), (x, y), fontsize=6, ha="center", va="bottom")
    x0, y0, x1, y1 = cracks.bounding_box()
    pad = 0.05 * max(x1 - x0, y1 - y0, 1e-12)
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    return ax


def plot_collinear_accuracy(gaps, exact, curves: dict, ax=None):
    """Relative error of mean-opening amplifications against the exact solution vs tip gap.

    ``curves``: label -> amplification values at ``gaps`` (same shape).  Returns the Axes.
    """
    ax = _axes(ax, (5.5, 4.0))
    gaps = np.asarray(gaps, float)
    for label, amp in curves.items():
        err = np.abs(np.asarray(amp, float) / np.asarray(exact, float) - 1.0)
        ax.loglog(gaps, np.maximum(err, 1e-16), "o-", label=label)
    ax.set_xlabel("tip gap / a")
    ax.set_ylabel("|amplification / exact - 1|")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return ax


def plot_stiffness_comparison(K_approx, K_ref, ax=None, *, label="Kachanov"):
    """Scatter of off-diagonal stiffness entries of an approximate model against a reference."""
    ax = _axes(ax, (4.5, 4.5))
    n = K_ref.shape[0] // 2
    off = ~np.kron(np.eye(n), np.ones((2, 2))).astype(bool)
    x, y = np.asarray(K_ref)[off], np.asarray(K_approx)[off]
    ax.plot(x, y, ".", ms=3, label=label)
    lim = float(np.abs(np.concatenate([x, y])).max()) if x.size else 1.0
    ax.plot([-lim, lim], [-lim, lim], "k-", lw=0.8)
    ax.set_xlabel("reference K_ij")
    ax.set_ylabel(f"{label} K_ij")
    ax.set_aspect("equal")
    ax.legend()
    return ax
