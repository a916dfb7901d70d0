"""Pictures of 3-D cyclic runs (MODEL.md s.8): per node, the tangential reaction path inside
the friction cone over the steady cycle, and the slip trajectories in the ``(v_x, v_y)`` plane.

Every function takes ``ax=None`` / ``axs=None`` and returns what it drew on; matplotlib is
imported here, not by :mod:`shakedown`.

* :func:`plot_cone_paths` -- per node, ``q / p`` over the steady cycle inside the friction
  ellipse ``|diag(1/f_x, 1/f_y) q| <= p`` (a circle of radius ``f`` for isotropic friction):
  the normalised traction touches the ellipse where the node slips.
* :func:`plot_slip_trajectories` -- ``(v_x, v_y)`` of the nodes over the steady cycle.
"""

from __future__ import annotations

import numpy as np

from ..model.errors import InputError
from .axes import _new_ax, _plt, _unit

__all__ = ["plot_cone_paths", "plot_slip_trajectories", "busiest_nodes"]


def _table(run):
    tab = getattr(run, "steady_table", run)
    if tab is None or len(tab) == 0 or "q_x" not in tab:
        raise InputError("a 3-D run with a steady table (columns q_x, q_y, p) is needed; run "
                         "solve_cycles on a dim = 3 system until it is periodic")
    return tab


def busiest_nodes(run, k: int = 4) -> np.ndarray:
    """The ``k`` nodes with the longest slip path over the steady cycle (0-based), then the
    others in order; shape (min(k, N),)."""
    tab = _table(run)
    path = {}
    for j, g in tab.groupby("node"):
        path[int(j)] = float(np.hypot(np.diff(g["slip_x"]), np.diff(g["slip_y"])).sum())
    order = sorted(path, key=lambda j: (-path[j], j))
    return np.asarray(order[:k], int)


def plot_cone_paths(run, system, nodes=None, axs=None, max_nodes: int = 4):
    """Per node, the normalised tangential reaction ``q / p`` over the steady cycle inside the
    friction ellipse (points where the node slips in red, stick in grey, the start marked).

    Parameters
    ----------
    run : CycleRun
        A periodic run of a ``dim = 3`` system.
    system : DiscreteSystem
        The run's system (its ``friction_xy``).
    nodes : sequence of int, optional
        0-based nodes; default the ``max_nodes`` with the longest slip path.
    axs : sequence of Axes, optional
        One per node.

    Returns
    -------
    list of matplotlib Axes
    """
    tab = _table(run)
    nodes = busiest_nodes(run, max_nodes) if nodes is None else np.asarray(nodes, int)
    if axs is None:
        plt = _plt()
        fig, axs = plt.subplots(1, len(nodes), figsize=(3.2 * len(nodes), 3.4), squeeze=False)
        axs = list(axs[0])
        fig.subplots_adjust(wspace=0.35)
    th = np.linspace(0, 2 * np.pi, 181)
    for ax, j in zip(axs, nodes, strict=False):
        g = tab[tab["node"] == j]
        fx, fy = system.friction_xy[j]
        p = g["p"].to_numpy(float)
        ok = p > 1e-12 * max(np.abs(p).max(), 1e-300)
        x, y = g["q_x"].to_numpy(float)[ok] / p[ok], g["q_y"].to_numpy(float)[ok] / p[ok]
        slip = (g["state"].astype(str).to_numpy() == "slip")[ok]
        ax.plot(fx * np.cos(th), fy * np.sin(th), color="k", lw=1.0, label="friction cone")
        ax.plot(x, y, color="0.6", lw=0.8, zorder=1)
        ax.scatter(x[~slip], y[~slip], s=8, color="0.45", label="stick", zorder=2)
        ax.scatter(x[slip], y[slip], s=10, color="#d62728", label="slip", zorder=3)
        if x.size:
            ax.scatter(x[:1], y[:1], s=40, facecolor="none", edgecolor="k", zorder=4,
                       label="cycle start")
        lim = 1.15 * max(fx, fy, np.abs(x).max(initial=0), np.abs(y).max(initial=0))
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("q_x / p")
        ax.set_ylabel("q_y / p")
        ax.set_title(f"node {j + 1}", fontsize=9)
        ax.axhline(0, color="0.85", lw=0.5, zorder=0)
        ax.axvline(0, color="0.85", lw=0.5, zorder=0)
    if len(axs):
        axs[0].legend(fontsize=7, loc="lower left")
    return list(axs)


def plot_slip_trajectories(run, nodes=None, ax=None, max_nodes: int = 6, units=None):
    """Slip ``(v_x, v_y)`` of nodes over the steady cycle (one closed curve per slipping node, a
    point per stuck node), the cycle start marked.

    Parameters
    ----------
    run : CycleRun
        A periodic run of a ``dim = 3`` system.
    nodes : sequence of int, optional
        0-based nodes; default the ``max_nodes`` with the longest slip path.
    ax : Axes, optional
    units : dict, optional
        ``{"length": ...}`` for the axis labels.

    Returns
    -------
    matplotlib Axes
    """
    tab = _table(run)
    nodes = busiest_nodes(run, max_nodes) if nodes is None else np.asarray(nodes, int)
    ax = _new_ax(ax)
    for j in nodes:
        g = tab[tab["node"] == j]
        x, y = g["slip_x"].to_numpy(float), g["slip_y"].to_numpy(float)
        line, = ax.plot(x, y, lw=1.2, label=f"node {j + 1}")
        ax.scatter(x[:1], y[:1], s=30, color=line.get_color(), edgecolor="k", zorder=3)
    ax.set_aspect("equal", adjustable="datalim")
    length = _unit(units, "length")
    ax.set_xlabel(f"v_x {length}")
    ax.set_ylabel(f"v_y {length}")
    ax.legend(fontsize=7)
    ax.set_title("slip over the steady cycle (o: cycle start)", fontsize=9)
    return ax
