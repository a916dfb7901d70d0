"""Two-node trajectories in ``v`` or ``tau = A v`` space over the constraint lines (seed 002
Figs. 2-8); re-exported by :mod:`shakedown.plotting.cycles`."""

from __future__ import annotations

import numpy as np

from ..model.errors import InputError
from .axes import OUTSIDE, SAFE_REGION, SEED_ORDER, _new_ax, _plt, _unit, constraint_style, frame_lines


def _lines(system, load, lam, times):
    from ..bounds.engine import extreme_constraints

    cs = extreme_constraints(system, load)
    extreme = cs.offsets(lam)
    inst = [cs.instantaneous(system, load, float(t), lam) for t in times]
    return cs.G, extreme, inst


def _path(table):
    """Slips of a time-series table in time order, shape (n_times, N)."""
    return table.pivot_table(index="t", columns="node", values="slip",
                             aggfunc="last").sort_index().to_numpy(float)


def _trajectory_arrays(trajectories):
    if trajectories is None:
        return []
    if hasattr(trajectories, "cycle_start_slips") or (
        isinstance(trajectories, np.ndarray) and trajectories.ndim == 2
    ):
        trajectories = [trajectories]
    out = []
    for tr in trajectories:
        if hasattr(tr, "cycle_start_slips"):
            tab = getattr(tr, "steady_table", None)
            hist = getattr(tr, "history", None)
            starts = np.asarray(tr.cycle_start_slips, float)
            if hist is not None and len(hist):  # the whole path (record_history=True)
                starts = _path(hist)
            loop = None
            if tab is not None and len(tab) and int(getattr(tr, "period", 1)) > 0:
                loop = _path(tab)
            out.append((starts, loop))
        else:
            arr = np.asarray(tr, float)
            if arr.ndim != 2 or arr.shape[1] != 2:
                raise InputError(f"a trajectory must have shape (n_points, 2); got {arr.shape}")
            out.append((None, arr))
    return out


def plot_trajectory(system, load, lam: float, trajectories=None, ax=None, *, space: str = "v",
                    times=(), extremes: bool = True, shade_safe: bool = True, labels=None,
                    units=None):
    """Two-node state trajectories over the moving constraint lines (seed 002 Figs. 2-8).

    The constraint lines are ``G_k . v = b_k`` with ``G = [A - F B^T; -(A + F B^T)]``
    (conventions, section 3: ``I_j``, then ``II_j``), named and coloured as in
    :func:`~shakedown.plotting.bounds.plot_constraints_2d`; in ``tau = A v`` space they are
    ``G_k A^-1 tau = b_k`` (for ``B = 0`` perpendicular to the axes, seed 002 Fig. 7).  The view
    box frames the trajectories, the safe region and a stretch of every extreme line.

    Parameters
    ----------
    system : DiscreteSystem
        Two nodes.
    load : LoadCycle
    lam : float
    trajectories : CycleRun, array (n_points, 2), or a list of them, optional
        A ``CycleRun`` is drawn as its whole path if it was run with ``record_history=True``
        (thin line), else as its cycle-start states (dots joined by a thin line: the approach
        to the steady state), and its steady loop (thick line); an array as a path.
    ax : matplotlib Axes, optional
    space : {"v", "tau"}
    times : sequence of float
        Also draw the instantaneous constraint lines at these times (cycles), thin solid.
    extremes : bool
        Draw the extreme positions of the 4 constraints, dashed (``I^E, II^E, III^E, IV^E``
        of the seed are ``I_1, II_1, I_2, II_2`` here, nodes numbered from 1).
    shade_safe : bool
        Shade the safe shakedown region ``H(lam)`` when it is a bounded non-empty polygon.
    labels : sequence of str, optional
        Legend labels of the trajectories.
    units : dict, optional
        ``{"force": ..., "length": ...}`` for the axis labels.

    Returns
    -------
    matplotlib Axes
    """
    if system.n_nodes != 2:
        raise InputError(f"plot_trajectory is for two-node systems; got N = {system.n_nodes}")
    if space not in ("v", "tau"):
        raise InputError(f"space must be 'v' or 'tau'; got {space!r}")
    system = system.to_dense()  # two nodes: the plot works on dense 2 x 2 blocks
    ax = _new_ax(ax)
    G, b_ext, b_inst = _lines(system, load, float(lam), times)
    T = np.eye(2) if space == "v" else system.A  # point map v -> plotted coordinates
    Gs = G if space == "v" else G @ np.linalg.inv(system.A)
    trajs = _trajectory_arrays(trajectories)
    pts = [np.zeros((1, 2))]
    colours = _plt().rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (starts, loop) in enumerate(trajs):
        c = colours[i % len(colours)]
        lab = labels[i] if labels is not None and i < len(labels) else f"trajectory {i + 1}"
        if starts is not None and len(starts):
            s = starts @ T.T
            ax.plot(s[:, 0], s[:, 1], color=c, lw=0.8, marker="o" if len(s) <= 300 else None,
                    ms=3, alpha=0.7)
            pts.append(s)
            lab_start = None
        else:
            lab_start = lab
        if loop is not None and len(loop):
            l_ = loop @ T.T
            l_ = np.vstack([l_, l_[:1]]) if starts is not None else l_
            ax.plot(l_[:, 0], l_[:, 1], color=c, lw=2.2, label=lab if lab_start is None else lab)
            pts.append(l_)
    # view box: trajectories and the safe region / line intersections
    from ..bounds.engine import _polygon_2d

    poly = _polygon_2d(G, b_ext) if extremes else np.zeros((0, 2))
    if len(poly):
        pts.append(poly @ T.T)
    for k in range(G.shape[0] if len(pts) == 1 else 0):  # nothing else to frame: corners
        for m in range(k + 1, G.shape[0]):
            M = np.array([G[k], G[m]])
            if abs(np.linalg.det(M)) > 1e-12 * np.abs(M).max() ** 2:
                pts.append((np.linalg.solve(M, [b_ext[k], b_ext[m]]) @ T.T)[None, :])
    allp = np.vstack(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.15 * max(float(np.max(hi - lo)), 1e-12)
    lo, hi = lo - pad, hi + pad
    outside = set()
    if extremes:  # every extreme line named in the legend crosses the picture, or says not
        lo, hi, outside = frame_lines(Gs, b_ext, lo, hi)
    if shade_safe and len(poly) >= 3:
        P = poly @ T.T
        ax.fill(P[:, 0], P[:, 1], color="0.85", zorder=0, label=SAFE_REGION)
    for k in SEED_ORDER:  # seed 002 order I, II (node 1), III, IV (node 2)
        colour, name = constraint_style(k)
        offs = ([b_ext[k]] if extremes else []) + [b[k] for b in b_inst]
        for i, b in enumerate(offs):
            dashed = extremes and i == 0
            if dashed and k in outside:
                ax.plot([], [], "--", color=colour, lw=1.2, label=name + OUTSIDE)
                continue
            _axline(ax, Gs[k], b, color=colour, ls="--" if dashed else "-",
                    lw=1.2 if dashed else 0.6, alpha=1.0 if dashed else 0.5,
                    label=name if dashed else None)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    if space == "v":
        ax.set_xlabel(f"$v_1$, slip of node 1 {_unit(units, 'length')}")
        ax.set_ylabel(f"$v_2$, slip of node 2 {_unit(units, 'length')}")
    else:
        ax.set_xlabel(rf"$\tau_1 = (A v)_1$ {_unit(units, 'force')}")
        ax.set_ylabel(rf"$\tau_2 = (A v)_2$ {_unit(units, 'force')}")
    # beside the axes: the lines and the region stay uncovered
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    return ax


def _axline(ax, g, b, **kw):
    """Infinite line ``g . x = b``."""
    g = np.asarray(g, float)
    p0 = g * b / float(g @ g)
    d = np.array([-g[1], g[0]])
    return ax.axline(tuple(p0), tuple(p0 + d), **kw)
