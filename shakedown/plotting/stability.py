"""Plots of the stability check: growth rates s(mu) with returning points, modes, convergence.

Every function takes ``ax=None`` (a new figure is made) and returns the axes.
"""

from __future__ import annotations

import numpy as np


def _ax(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.5, 4))
    return ax


def plot_lam_mu(curves, ax=None, *, mu=None, growth=None, show_support=True, mu_star=None,
                friction=None):
    """Growth rate ``s`` against friction ``mu`` on every MCEIP branch (seed 000 Figs. 9, 12).

    The growth rate is ``lam`` in the Python API (``curves.lam``); the plot calls it ``s`` so
    that ``lam`` stays the load factor.  Only what is drawn gets a legend entry.

    Parameters
    ----------
    curves : LamMuCurves
    mu : float, optional
        The friction of ``growth`` (vertical dash-dot line).
    growth : GrowthRates, optional
        Growth rates to mark (black dots).
    show_support : bool
        Overdraw in black dots where the mode is a partial-slip mode (some slip nodes unload).
    mu_star : float, optional
        Critical friction ``mu*`` of the quasi-static problem (vertical red line).
    friction : float, optional
        The system's actual friction (vertical grey line).
    """
    ax = _ax(ax)
    n_slip = curves.nodes.size
    drew_partial = False
    for b, br in enumerate(curves.branches):
        style = "-" if br.lam.size >= 2 else "."
        ax.plot(br.mu, br.lam, style, color=f"C{b % 10}", lw=1.5, ms=4,
                label=f"branch {b + 1}")
        if show_support:
            partial = np.array([len(s) < n_slip for s in br.supports])
            if partial.any():
                drew_partial = True
                ax.plot(np.where(partial, br.mu, np.nan), np.where(partial, br.lam, np.nan),
                        ":", color="k", lw=2.5, alpha=0.6)
    if drew_partial:
        ax.plot([], [], ":", color="k", lw=2.5, alpha=0.6, label="partial slip (nodes unload)")
    for k, rp in enumerate(curves.returning_points):
        ax.plot(rp.mu, rp.lam, "s", mfc="none", mec="r", ms=9,
                label="returning point" if k == 0 else None)
        ax.annotate(f"mu = {rp.mu:.4g}", (rp.mu, rp.lam), textcoords="offset points",
                    xytext=(6, 6), fontsize=8, color="r")
    if mu_star is not None and np.isfinite(mu_star):
        ax.axvline(mu_star, color="tab:red", lw=1.2, label=f"critical friction mu* = {mu_star:.4g}")
    if friction is not None:
        ax.axvline(friction, color="0.4", lw=1.2, ls="--", label=f"actual friction {friction:.4g}")
    if mu is not None and (friction is None or not np.isclose(mu, friction)):
        ax.axvline(mu, color="0.5", lw=0.8, ls="-.", label=f"mu = {mu:.4g}")
    if growth is not None and growth.lam.size:
        ax.plot(np.full(growth.lam.size, growth.mu), growth.lam, "ko", ms=5,
                label=f"growth rates at mu = {growth.mu:.4g}")
    ax.set_xlabel("friction coefficient mu [-]")
    ax.set_ylabel("growth rate s [1/time]")
    ax.set_ylim(bottom=0)
    ax.set_title("divergence growth rates s(mu) (MCEIP branches)", fontsize=10)
    ax.legend(fontsize=7, loc="best")
    return ax


def plot_mode(result, coordinates=None, ax=None, *, label=None):
    """The mode ``x = chi v'`` of an :class:`MCEIPResult` and where the cone unloads.

    ``x`` is scaled to ``max |x| = 1``.  The cone unloading ``y`` is zero where a node slips;
    it is marked (scaled to its own maximum) only at the slip nodes that unload in the mode,
    so rounding noise of ``y`` on the support is never drawn as a shape.

    ``coordinates`` (shape (N, 2) or (N,), e.g. ``cm.node_coordinates``) gives the abscissa of
    the slip nodes [length] (default: their number, from 1).
    """
    ax = _ax(ax)
    if not result.found:
        ax.text(0.5, 0.5, f"no solution ({result.status})", ha="center", transform=ax.transAxes)
        return ax
    if coordinates is None:
        s = result.nodes.astype(float) + 1
        xlabel = "slip node (numbered from 1)"
    else:
        c = np.asarray(coordinates, float)
        s = c[result.nodes, 0] if c.ndim == 2 else c[result.nodes]
        xlabel = "position of the contact node along the boundary [length]"
    order = np.argsort(s)
    ax.plot(s[order], result.mode[order], "o-", ms=3,
            label=label or "slip rate x (scaled to max |x| = 1)")
    unload = np.setdiff1d(np.arange(result.nodes.size), result.support)
    if unload.size:
        y = result.y[unload]
        ax.plot(s[unload], y / (np.abs(y).max() or 1.0), "s", mfc="none", ms=5,
                label="unloading nodes: y / max y (x = 0 there)")
    else:
        ax.plot([], [], " ", label="every slip node slips in the mode (no unloading)")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("mode shape [-]")
    title = f"critical mode at mu* = {result.mu:.4g}"
    if result.lam > 0:
        title += f", growth rate s = {result.lam:.4g}"
    ax.set_title(title, fontsize=10)
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
    ax.set_ylabel("mu_n [-]")
    ax.legend(fontsize=7)
    return ax


def plot_convergence(n_per_edge, mu_h, ax=None, *, reference=None, label="mu*_h"):
    """``mu*_h`` against nodes per edge (seed 000 Fig. 6, right)."""
    ax = _ax(ax)
    ax.plot(n_per_edge, mu_h, "o-", label=label)
    if reference is not None:
        ax.axhline(reference, color="r", ls="--", lw=0.8, label=f"reference {reference:g}")
    ax.set_xlabel("nodes per edge")
    ax.set_ylabel("critical friction mu*_h [-]")
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
    ax.set_xlabel("t [cycles]")
    ax.set_ylabel("critical friction factor alpha* [-]")
    ax.legend(fontsize=7)
    return ax
