"""Plots of cyclic evolutions (seed 002 Figs. 2, 5-8).

Every function takes ``ax=None`` (a new figure is made) and returns the axes it drew on.
matplotlib is imported here, not by :mod:`shakedown`.

* :func:`plot_dissipation` -- ``W`` per cycle (optionally on a log scale, or the distance to the
  steady value, which shows geometric convergence as a straight line).
* :func:`plot_steady_cycle` -- slips and reactions of the steady cycle against time.
* :func:`plot_node_states` -- node x time image of the node states.
* :func:`plot_trajectory` -- two-node trajectories in ``v`` space or ``tau = A v`` space over the
  constraint lines ``I_j``, ``II_j`` of MODEL.md s.3 (extreme positions dashed).
* :func:`plot_uniqueness` -- steady ``W`` of every initial state of a uniqueness study.
"""

from __future__ import annotations

import numpy as np

from ..model.errors import InputError
from .axes import _new_ax, _plt, _unit
from .trajectory import plot_trajectory

__all__ = [
    "plot_dissipation",
    "plot_steady_cycle",
    "plot_node_states",
    "plot_trajectory",
    "plot_uniqueness",
    "STATE_ORDER",
]

#: Display order (and colour index) of node-state labels; unknown labels are appended.
STATE_ORDER = ("stick", "slip", "slip+", "forward", "slip-", "backward", "open", "separation")
_STATE_COLOURS = {
    "stick": "#d9d9d9", "slip": "#d62728", "slip+": "#d62728", "forward": "#d62728", "slip-": "#1f77b4",
    "backward": "#1f77b4", "open": "#2ca02c", "separation": "#2ca02c",
}


def _dissipation_array(run):
    W = getattr(run, "dissipation", run)
    try:
        W = np.asarray(W, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(
            "plot_dissipation needs a CycleRun or an array of W per cycle; got "
            f"{type(run).__name__}"
        ) from exc
    if W.ndim != 1:
        raise InputError(f"W per cycle must be 1-D; got shape {W.shape}")
    return W


def plot_dissipation(run, ax=None, *, log: bool = False, relative: bool = False, units=None,
                     **line_kw):
    """Dissipation per cycle ``W_k`` against the cycle number ``k = 1, 2, ...``.

    Parameters
    ----------
    run : CycleRun or array_like, shape (n_cycles,)
    ax : matplotlib Axes, optional
    log : bool
        Logarithmic ``W`` axis (cycles with ``W <= 0`` are not shown).
    relative : bool
        Plot ``|W_k - W_steady|`` instead (``W_steady`` from ``run.steady_dissipation``, else the
        last cycle): geometric convergence (seed 002 Fig. 8) is a straight line on a log axis.
    units : dict, optional
        ``{"energy": ...}`` unit of ``W`` for the axis label (default ``[force x length]``).
    **line_kw
        Passed to ``ax.plot``.

    With at most three cycles the values are drawn as labelled bars (a lone dot says
    nothing); cycle numbers are integers.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.ticker import MaxNLocator

    W = _dissipation_array(run)
    ax = _new_ax(ax)
    k = np.arange(1, W.size + 1)
    y = W
    label = "W per cycle"
    if relative:
        ref = float(getattr(run, "steady_dissipation", np.nan))
        if not np.isfinite(ref):
            ref = float(W[-1]) if W.size else 0.0
        y = np.abs(W - ref)
        label = "|W - W_steady|"
        log = True
    if log:
        y = np.where(y > 0, y, np.nan)
    line_kw.setdefault("marker", "o")
    line_kw.setdefault("markersize", 3)
    if W.size <= 3 and not log:
        bars = ax.bar(k, y, width=0.5, color=line_kw.get("color", "C0"))
        ax.bar_label(bars, labels=[f"{v:.4g}" for v in y], fontsize=8)
        ax.set_xlim(0.3, max(W.size, 1) + 0.7)
        top = float(np.nanmax(np.abs(y))) if W.size and np.isfinite(y).any() else 0.0
        ax.set_ylim(0, top * 1.25 if top > 0 else 1.0)
        ax.set_xticks(k)
        if top == 0 and W.size:
            ax.plot(k, y, "o", color=line_kw.get("color", "C0"))
            ax.text(0.5, 0.5, "W = 0 in every cycle: no node slips", ha="center",
                    va="center", transform=ax.transAxes)
    else:
        ax.plot(k, y, **line_kw)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("cycle")
    ax.set_ylabel(f"{label} {_unit(units, 'energy')}")
    return ax


def _steady_frame(run, needs=("t", "node", "slip", "q", "p", "state")):
    table = getattr(run, "steady_table", run)
    if table is None or not hasattr(table, "columns"):
        raise InputError(
            "need a CycleRun / SteadyCycle with a steady_table, or that table (DataFrame with "
            f"columns t, node, slip, q, p, state); got {type(run).__name__}"
        )
    missing = set(needs) - set(table.columns)
    if missing:
        raise InputError(f"the steady table lacks columns {sorted(missing)}")
    if len(table) == 0:
        raise InputError("the steady table is empty: no steady cycle was reached")
    return table


_MAX_CURVES = 10


def _same_curves(tab, nodes) -> list[list[int]]:
    """The nodes grouped by identical (slip, q, p) histories, each group sorted, to the
    round-off of the table's own scales (1e-9 of the largest slip and reaction)."""
    wide = tab[tab["node"].isin(nodes)].pivot_table(index="node", columns="t",
                                                    values=["slip", "q", "p"], aggfunc="last")
    scales = [max(float(np.nanmax(np.abs(wide[c].to_numpy(float)), initial=0.0)), 1e-300)
              for c in ("slip", "q", "p")]
    rows = np.hstack([wide[c].to_numpy(float) / sc for c, sc in zip(("slip", "q", "p"),
                                                                      scales, strict=True)])
    groups, keys = [], []
    for j, row in zip(wide.index.to_numpy(int), rows, strict=True):
        for g, key in zip(groups, keys, strict=True):
            if np.allclose(row, key, rtol=0, atol=1e-9, equal_nan=True):
                g.append(int(j))
                break
        else:
            groups.append([int(j)])
            keys.append(row)
    return groups


def _nodes_label(group) -> str:
    """``node 7`` or ``nodes 7, 54`` (numbered from 1)."""
    names = [str(j + 1) for j in group]
    if len(names) == 1:
        return f"node {names[0]}"
    return "nodes " + (", ".join(names) if len(names) <= 4 else f"{names[0]}, ..., {names[-1]}")


def plot_steady_cycle(run, ax=None, *, nodes=None, units=None):
    """Slips (top) and reactions ``q`` (solid), ``p`` (dashed) (bottom) over the steady cycle.

    Parameters
    ----------
    run : CycleRun, SteadyCycle or DataFrame
        Anything with a ``steady_table`` (columns ``t, node, slip, q, p``), or that table.
    ax : sequence of two Axes, optional
    nodes : sequence of int, optional
        Nodes to draw (0-based, as in the table; all by default).  Nodes whose slips and
        reactions coincide over the cycle (mirror nodes of a symmetric model) are drawn as one
        curve named after all of them; of more than 10 curves, the 10 that slip most in contact
        are drawn.  Legends number nodes from 1.
    units : dict, optional
        ``{"force": ..., "length": ...}`` for the axis labels.

    Returns
    -------
    ndarray of two Axes
    """
    tab = _steady_frame(run)
    all_nodes = np.unique(tab["node"].to_numpy(int))
    nodes = all_nodes if nodes is None else np.asarray(nodes, int)
    groups = _same_curves(tab, nodes)  # nodes whose curves coincide (a symmetric model) share one
    subset = ""
    if len(groups) > _MAX_CURVES:
        # the 10 curves that slip most while in contact (stuck nodes are flat lines, and the
        # slip of an open node moves without friction or reactions)
        contact = tab[tab["state"].astype(str).isin(["forward", "backward", "stick"])]
        slipping = contact if len(contact) else tab
        swing = slipping.groupby("node")["slip"].agg(lambda x: float(x.max() - x.min()))
        groups = sorted(groups, key=lambda g: -swing.get(g[0], 0.0))[:_MAX_CURVES]
        groups = sorted(groups)
        n_shown = sum(len(g) for g in groups)
        subset = f" (the {n_shown} of {all_nodes.size} nodes that slip most in contact)"
    if ax is None:
        fig, ax = _plt().subplots(2, 1, sharex=True, figsize=(6.4, 5.6))
    ax = np.asarray(ax).ravel()
    if ax.size != 2:
        raise InputError(f"plot_steady_cycle needs two axes; got {ax.size}")
    colours = _plt().rcParams["axes.prop_cycle"].by_key()["color"]
    for i, group in enumerate(groups):
        sub = tab[tab["node"] == group[0]].sort_values("t")
        c = colours[i % len(colours)]
        name = _nodes_label(group)
        ax[0].plot(sub["t"], sub["slip"], color=c, label=name)
        ax[1].plot(sub["t"], sub["q"], color=c, label=f"q {name}")
        ax[1].plot(sub["t"], sub["p"], color=c, ls="--", label=f"p {name}")
    ax[0].set_ylabel(f"slip v {_unit(units, 'length')}")
    ax[1].set_ylabel(f"q (solid), p (dashed) {_unit(units, 'force')}")
    ax[0].set_title("steady cycle" + subset, fontsize=10)
    ax[1].set_xlabel("t [cycles]")
    ax[0].legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return ax


def plot_node_states(run, ax=None):
    """Node x time image of the node states over the steady cycle.

    Parameters
    ----------
    run : CycleRun, SteadyCycle or DataFrame
        Anything with a ``steady_table`` (columns ``t, node, state``), or that table.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    tab = _steady_frame(run, ("t", "node", "state"))
    tab = tab.assign(state=tab["state"].astype(str))
    labels = [s for s in STATE_ORDER if s in set(tab["state"])]
    labels += sorted(set(tab["state"]) - set(labels))
    code = {s: i for i, s in enumerate(labels)}
    grid = tab.assign(code=tab["state"].map(code)).pivot_table(
        index="node", columns="t", values="code", aggfunc="first"
    )
    t = grid.columns.to_numpy(float)
    grid.index = grid.index.astype(int) + 1  # nodes numbered from 1
    ax = _new_ax(ax)
    cmap = ListedColormap([_STATE_COLOURS.get(s, "#9467bd") for s in labels])
    dt = np.diff(t).min() if t.size > 1 else 1.0
    extent = (t[0] - dt, t[-1], grid.index.max() + 0.5, grid.index.min() - 0.5)
    ax.imshow(grid.to_numpy(float), aspect="auto", interpolation="nearest", cmap=cmap,
              vmin=-0.5, vmax=len(labels) - 0.5, extent=extent)
    ax.legend(handles=[Patch(color=cmap(i), label=s) for i, s in enumerate(labels)],
              fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    if len(grid.index) <= 20:
        ax.set_yticks(grid.index.to_numpy(int))
    ax.set_ylim(extent[2], extent[3])  # exactly the nodes: no empty rows below the last
    ax.set_xlabel("t [cycles]")
    ax.set_ylabel("node")
    ax.set_title("node states over the steady cycle", fontsize=10)
    return ax


def plot_uniqueness(study, ax=None, *, units=None):
    """Steady ``W`` of every initial state of a :class:`~shakedown.steady.UniquenessStudy`.

    Runs that shook down are drawn as open circles, runs in cyclic slip as dots, runs that did
    not reach a steady cycle as crosses at ``W = 0``.  Initial states are numbered from 1 (state
    1 is the zero slip; the study's table numbers them from 0).
    """
    tab = getattr(study, "table", study)
    if not hasattr(tab, "columns") or "steady_dissipation" not in tab.columns:
        raise InputError("plot_uniqueness needs a UniquenessStudy or its table")
    ax = _new_ax(ax)
    W = tab["steady_dissipation"].to_numpy(float)
    # initial states numbered from 1 as in everything a person reads (the table is 0-based)
    i = (tab["state"].to_numpy(int) if "state" in tab else np.arange(len(tab))) + 1
    sd_ = tab["shook_down"].to_numpy(bool)
    ok = np.isfinite(W)
    if (ok & sd_).any():  # a legend entry only for what is drawn
        ax.plot(i[ok & sd_], W[ok & sd_], "o", mfc="none", label="shook down")
    if (ok & ~sd_).any():
        ax.plot(i[ok & ~sd_], W[ok & ~sd_], ".", ms=8, label="cyclic slip")
    if (~ok).any():
        ax.plot(i[~ok], np.zeros((~ok).sum()), "x", label="no steady cycle")
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    top = float(np.nanmax(W, initial=0.0)) if ok.any() else 0.0
    # W >= 0 from 0: equal values are not blown up to rounding noise
    top = top if top > 0 else 1.0
    ax.set_ylim(-0.05 * top, 1.15 * top)  # markers at W = 0 drawn whole
    ax.ticklabel_format(axis="y", useOffset=False)
    cols = [c for c in tab.columns if str(c).startswith("initial_slip_")]
    zero = bool(cols) and np.allclose(tab[cols].to_numpy(float)[np.argmin(i)], 0.0)
    ax.set_xlabel(f"initial state{f' ({i.min()}: zero slip)' if zero else ''}")
    ax.set_ylabel(f"steady W per cycle {_unit(units, 'energy')}")
    ax.set_title("steady dissipation from each initial state", fontsize=10)
    ax.legend(fontsize="small")
    return ax
