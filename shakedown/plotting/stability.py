"""Plots of the stability check: lam(mu) curves with returning points, modes, convergence.

Every function takes ``ax=None`` (a new figure is made) and returns the axes.
"""

from __future__ import annotations

import numpy as np


def _ax(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.5, 4))
    return ax


def plot_lam_mu(curves, ax=None, *, mu=None, growth=None, show_support=True):
    """Growth rate ``lam`` against friction ``mu`` for every branch (seed 000 Figs. 9, 12).

    Parameters
    ----------
    curves : LamMuCurves
    mu : float, optional
        A friction to mark with a vertical line.
    growth : GrowthRates, optional
        Growth rates to mark (dots).
    show_support : bool
        Dashed line style where the mode is a partial-slip mode (some slip nodes unload).
    """
    ax = _ax(ax)
    n_slip = curves.nodes.size
    for b, br in enumerate(curves.branches):
        if br.lam.size < 2:
            ax.plot(br.mu, br.lam, ".", color=f"C{b % 10}", ms=3)
            continue
        ax.plot(br.mu, br.lam, "-", color=f"C{b % 10}", lw=1.5, label=f"branch {b}")
        if show_support:
            partial = np.array([len(s) < n_slip for s in br.supports])
            if partial.any():
                ax.plot(np.where(partial, br.mu, np.nan), np.where(partial, br.lam, np.nan),
                        ":", color="k", lw=2.5, alpha=0.5)
    for rp in curves.returning_points:
        ax.plot(rp.mu, rp.lam, "s", mfc="none", mec="r", ms=9)
        ax.annotate(f"{rp.kind}: mu = {rp.mu:.4g}", (rp.mu, rp.lam), textcoords="offset points",
                    xytext=(6, 6), fontsize=8, color="r")
    if mu is not None:
        ax.axvline(mu, color="0.5", lw=0.8, ls="--")
    if growth is not None:
        ax.plot(np.full(growth.lam.size, growth.mu), growth.lam, "ko", ms=5,
                label=f"lam at mu = {growth.mu:g}")
    ax.set_xlabel("friction coefficient mu")
    ax.set_ylabel("growth rate lam")
    ax.set_title("MCEIP branches (dotted: partial slip; squares: returning points)", fontsize=9)
    ax.legend(fontsize=7)
    return ax


def plot_mode(result, coordinates=None, ax=None, *, label=None):
    """The mode ``x = chi v'`` and the cone unloading ``y`` of an :class:`MCEIPResult`.

    ``coordinates`` (shape (N, 2) or (N,), e.g. ``cm.node_coordinates``) gives the abscissa of
    the slip nodes (default: their index).
    """
    ax = _ax(ax)
    if not result.found:
        ax.text(0.5, 0.5, f"no solution ({result.status})", ha="center", transform=ax.transAxes)
        return ax
    if coordinates is None:
        s = result.nodes.astype(float)
        xlabel = "slip node"
    else:
        c = np.asarray(coordinates, float)
        s = c[result.nodes, 0] if c.ndim == 2 else c[result.nodes]
        xlabel = "x"
    order = np.argsort(s)
    ymax = np.abs(result.y).max() or 1.0
    ax.plot(s[order], result.mode[order], "o-", ms=3, label=label or "slip x / max x")
    ax.plot(s[order], result.y[order] / ymax, "s--", ms=3, label="cone unloading y / max y")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_title(f"mode at mu = {result.mu:.6g}, lam = {result.lam:.4g}", fontsize=9)
    ax.legend(fontsize=7)
    return ax


def plot_power_history(result, ax=None, *, reference=None):
    """The power-iteration estimates ``mu_n`` (seed 000 Fig. 6, left)."""
    ax = _ax(ax)
    h = np.asarray(result.history)
    ax.plot(np.arange(1, h.size + 1), h, ".-", ms=3, label="power iteration mu_n")
    if reference is not None:
        ax.axhline(reference, color="r", ls="--", lw=0.8, label=f"reference {reference:.5g}")
    ax.set_xlabel("iteration n")
    ax.set_ylabel("mu_n")
    ax.legend(fontsize=7)
    return ax


def plot_convergence(n_per_edge, mu_h, ax=None, *, reference=None, label="mu*_h"):
    """``mu*_h`` against nodes per edge (seed 000 Fig. 6, right)."""
    ax = _ax(ax)
    ax.plot(n_per_edge, mu_h, "o-", label=label)
    if reference is not None:
        ax.axhline(reference, color="r", ls="--", lw=0.8, label=f"reference {reference:g}")
    ax.set_xlabel("nodes per edge")
    ax.set_ylabel("critical friction mu*_h")
    ax.legend(fontsize=7)
    return ax


def plot_cycle_margin(cycle_stability, ax=None):
    """The critical friction factor ``alpha* = mu*/f`` at the snapshots of a cycle."""
    ax = _ax(ax)
    tab = cycle_stability.table
    a = np.where(np.isfinite(tab["alpha"]), tab["alpha"], np.nan)
    ax.step(tab["t"], a, where="post", label="alpha* = mu* / f")
    ax.plot(tab["t"], a, "o", ms=3)
    ax.axhline(1.0, color="r", ls="--", lw=0.8, label="actual friction")
    ax.set_xlabel("t (cycles)")
    ax.set_ylabel("critical friction factor")
    ax.legend(fontsize=7)
    return ax
