"""Maps of a 3-D contact surface over a steady cycle: node states with traction arrows, the zone
that sticks for the whole cycle over the pressure, and the tangential force loop.

* :func:`patch_coordinates` -- the contact nodes' in-plane coordinates ``(N, 2)`` (a 3-D FE
  model: its nodes in the mean tangent frame; a model with ``xy``: those).
* :func:`plot_patch_states` -- stick / slip / separation of every node at one instant of the
  steady cycle, with the tangential reactions ``q`` as arrows.
* :func:`plot_stuck_zone` -- nodes stuck over the whole steady cycle, slipping at some instant,
  or open throughout, over the mean contact pressure.
* :func:`plot_force_loop` -- total tangential reaction ``sum_i q_i(t)`` against the cyclic load's
  phase ``lam cos(2 pi t)``, or the force through the contact against a prescribed displacement:
  the hysteresis loop of a joint; :func:`plot_loop_opening` the same loop with its straight-line
  fit removed (a stiff joint's loop is thin), :func:`loop_area` its area.

Every function takes ``ax=None`` (a new figure is made) and returns the axes it drew on; the
steady table is that of a 3-D :class:`~shakedown.evolution.cycle_results.CycleRun` (columns
``t, node, slip_x, slip_y, gap, q_x, q_y, p, state``).
"""

from __future__ import annotations

import numpy as np

from ..model.errors import InputError
from .axes import _new_ax, _plt, _unit

__all__ = ["patch_coordinates", "plot_patch_states", "plot_stuck_zone", "plot_force_loop",
           "plot_loop_opening", "loop_area", "STATE_COLOURS_3D"]

#: Colours of the 3-D node states.
STATE_COLOURS_3D = {"stick": "#7f7f7f", "slip": "#d62728", "separation": "#2ca02c"}
_COLUMNS = {"t", "node", "q_x", "q_y", "p", "state"}


def patch_coordinates(model) -> np.ndarray:
    """In-plane coordinates ``(N, 2)`` [length] of the contact nodes of ``model``.

    A 3-D FE model (``node_coordinates`` (N, 3), ``tangents`` (N, 2, 3)) is projected on the
    mean tangent frame ``(t_x, t_y)`` of its nodes (for a plane patch: the patch's own axes); a
    model with ``xy`` (N, 2) gives those.
    """
    xy = getattr(model, "xy", None)
    if xy is not None and np.shape(xy)[-1] == 2:
        return np.asarray(xy, float)
    X = getattr(model, "node_coordinates", None)
    T = getattr(model, "tangents", None)
    if X is None or T is None or np.ndim(T) != 3:
        raise InputError("patch maps need a 3-D model with node_coordinates and tangents "
                         f"(a 3-D FE model) or xy; got {type(model).__name__}")
    frame = np.asarray(T, float).mean(axis=0)  # (2, 3)
    frame /= np.linalg.norm(frame, axis=1)[:, None]
    return np.asarray(X, float) @ frame.T


def _table(run):
    tab = getattr(run, "steady_table", run)
    if tab is None or not hasattr(tab, "columns") or not _COLUMNS <= set(tab.columns):
        raise InputError("need a 3-D CycleRun with a steady table (columns t, node, q_x, q_y, p, "
                         f"state); got {type(run).__name__}")
    if len(tab) == 0:
        raise InputError("the steady table is empty: no steady cycle was reached")
    return tab


def _at(tab, t: float):
    """Rows of the recorded instant nearest to ``t`` (modulo one period), sorted by node."""
    times = np.unique(tab["t"].to_numpy(float))
    frac = times - np.floor(times[0])
    # a table holding both ends of the period: the end (a step's result) stands for both
    first = 1 if len(times) > 1 and abs(frac[-1] - frac[0] - 1.0) < 1e-9 else 0
    k = first + int(np.argmin(np.abs(((frac[first:] - t) + 0.5) % 1.0 - 0.5)))
    rows = tab[tab["t"] == times[k]].sort_values("node")
    return float(frac[k] % 1.0), rows


def _spacing(xy) -> float:
    """Mean node spacing of a patch [length]: sqrt(area of the bounding box / N)."""
    ext = np.ptp(xy, axis=0)
    area = float(np.prod(ext[ext > 0])) if np.any(ext > 0) else 1.0
    return float(np.sqrt(area / max(len(xy), 1))) or 1.0


def _square(ax, xy):
    ax.set_aspect("equal")
    span = np.ptp(xy, axis=0).max() if len(xy) > 1 else 1.0
    pad = 0.08 * span
    ax.set_xlim(xy[:, 0].min() - pad, xy[:, 0].max() + pad)
    ax.set_ylim(xy[:, 1].min() - pad, xy[:, 1].max() + pad)


def plot_patch_states(model, run, t: float, ax=None, *, units=None, scale=None, legend=True):
    """Node states at the recorded instant nearest to ``t`` [periods], with arrows of ``q``.

    Parameters
    ----------
    model : 3-D FE model or a model with ``xy``
        Gives the node positions (:func:`patch_coordinates`).
    run : CycleRun or its steady table
    t : float
        Instant in the period, ``0 <= t < 1``.
    scale : float, optional
        Force per unit of length on the map [force / length] (shared between panels when
        given); default: the largest ``|q|`` of the steady cycle spans 1.5 mean node spacings.
    legend : bool
        Draw the states' legend in the axes (``False`` for panels that share a figure legend).
    """
    tab = _table(run)
    xy = patch_coordinates(model)
    t_k, rows = _at(tab, t)
    nodes = rows["node"].to_numpy(int)
    ax = _new_ax(ax)
    states = rows["state"].astype(str).to_numpy()
    for s, colour in STATE_COLOURS_3D.items():  # every state in the legend, drawn or not
        m = states == s
        ax.scatter(*xy[nodes[m]].T, s=36, marker="s", color=colour, label=s, zorder=2)
    q = rows[["q_x", "q_y"]].to_numpy(float)
    if scale is None:
        qmax = float(np.hypot(tab["q_x"], tab["q_y"]).max()) or 1.0
        scale = qmax / (1.5 * _spacing(xy))
    ax.quiver(*xy[nodes].T, *q.T, angles="xy", scale_units="xy", scale=scale, color="black",
              width=0.004, zorder=3)
    _square(ax, xy)
    if legend:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    ax.set_title(f"t = {t_k:.3g} T", fontsize=10)
    ax.set_xlabel(f"x along t_x {_unit(units, 'length')}")
    ax.set_ylabel(f"y along t_y {_unit(units, 'length')}")
    return ax


def plot_stuck_zone(model, run, ax=None, *, units=None):
    """Nodes stuck over the whole steady cycle, slipping at some instant, or always open, drawn
    over the cycle's mean contact pressure (filled contours)."""
    tab = _table(run)
    xy = patch_coordinates(model)
    n = xy.shape[0]
    state = tab.pivot_table(index="node", columns="t", values="state", aggfunc="first")
    p_mean = tab.groupby("node")["p"].mean().reindex(range(n)).to_numpy(float)
    ax = _new_ax(ax)
    if n >= 3 and np.ptp(xy[:, 0]) > 0 and np.ptp(xy[:, 1]) > 0:
        # levels from 0: round-off (|p| ~ 1e-14 at open nodes) must not fall below the first
        pm = np.clip(np.nan_to_num(p_mean), 0.0, None)
        levels = np.linspace(0.0, max(float(pm.max()), 1e-300), 13)
        cs = ax.tricontourf(xy[:, 0], xy[:, 1], pm, levels=levels, cmap="Blues")
        _plt().colorbar(cs, ax=ax, label=f"mean p {_unit(units, 'force')}")
    S = state.reindex(range(n)).to_numpy(str)
    kinds = {
        "stuck all cycle": np.all(S == "stick", axis=1),
        "slips": np.any(S == "slip", axis=1),
        "open all cycle": np.all(S == "separation", axis=1),
    }
    kinds["stick / open"] = ~(kinds["stuck all cycle"] | kinds["slips"] | kinds["open all cycle"])
    style = {"stuck all cycle": ("s", "#404040"), "slips": ("o", "#d62728"),
             "open all cycle": ("x", "#2ca02c"), "stick / open": ("^", "#9467bd")}
    for name, m in kinds.items():
        if m.any():
            mk, c = style[name]
            ax.scatter(*xy[m].T, marker=mk, color=c, s=30, label=f"{name} ({int(m.sum())})",
                       zorder=3)
    _square(ax, xy)
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.25, 1.0), borderaxespad=0)
    ax.set_xlabel(f"x along t_x {_unit(units, 'length')}")
    ax.set_ylabel(f"y along t_y {_unit(units, 'length')}")
    ax.set_title("permanent stick zone over the steady cycle", fontsize=10)
    return ax


def _loop(run, lam, displacement):
    """``(x, F_x, F_y, xlabel, ylabel)`` of the steady cycle, closed (first instant repeated)."""
    tab = _table(run)
    tot = tab.groupby("t")[["q_x", "q_y"]].sum().sort_index()
    t = tot.index.to_numpy(float)
    if displacement is None:
        x = float(lam) * np.cos(2 * np.pi * t)
        fx, fy = tot["q_x"].to_numpy(float), tot["q_y"].to_numpy(float)
        names = ("cyclic load phase lam cos(2 pi t)", "sum q_x", "sum q_y", "total tangential reaction")
    else:
        x = float(lam) * float(displacement) * np.cos(2 * np.pi * t)
        fx, fy = -tot["q_x"].to_numpy(float), -tot["q_y"].to_numpy(float)
        names = ("prescribed displacement u = lam u_1 cos(2 pi t)", "-sum q_x", "-sum q_y",
                 "force through the contact")
    close = np.r_[np.arange(t.size), 0]
    return x[close], fx[close], fy[close], names


def loop_area(x, F) -> float:
    """``closed integral F dx`` over a closed polygon (trapezoidal) [force x length]: the work of
    the force over the loop, the dissipation per cycle when ``x`` is the work-conjugate
    displacement."""
    x = np.asarray(x, float)
    F = np.asarray(F, float)
    return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(x)))


def plot_force_loop(run, lam: float, ax=None, *, units=None, displacement=None):
    """The joint's hysteresis loop over the steady cycle.

    Without ``displacement``: total tangential reactions ``sum_i q_ix``, ``sum_i q_iy`` against
    ``lam cos(2 pi t)`` (the phase of a cosine cyclic load).  With ``displacement`` ``u_1``
    [length] (the amplitude of a prescribed cosine displacement, e.g. a lap joint's grip):
    the force through the contact ``-sum_i q_i`` (the force that the loaded body transmits, in
    the tangent frame) against the displacement ``lam u_1 cos(2 pi t)``.
    """
    x, fx, fy, (xl, lx, ly, yl) = _loop(run, lam, displacement)
    ax = _new_ax(ax)
    ax.plot(x, fx, "-o", ms=2, label=lx)
    ax.plot(x, fy, "--", label=ly)
    ax.set_xlabel(f"{xl} {_unit(units, 'length') if displacement is not None else ''}".strip())
    ax.set_ylabel(f"{yl} {_unit(units, 'force')}")
    ax.legend(fontsize="small")
    ax.set_title("force loop over the steady cycle", fontsize=10)
    return ax


def plot_loop_opening(run, lam: float, ax=None, *, units=None, displacement=None):
    """The hysteretic part of the loop: ``F_x`` minus its straight-line fit against the same
    abscissa as :func:`plot_force_loop`, so that a thin loop (a stiff joint with microslip)
    shows its opening; the title gives the loop area ``closed integral F_x dx``."""
    x, fx, _, (xl, lx, _, yl) = _loop(run, lam, displacement)
    k, c = np.polyfit(x[:-1], fx[:-1], 1)
    ax = _new_ax(ax)
    ax.plot(x, fx - (k * x + c), "-o", ms=2, color="C0")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel(f"{xl} {_unit(units, 'length') if displacement is not None else ''}".strip())
    ax.set_ylabel(f"{lx} minus the line k x + c {_unit(units, 'force')}")
    ax.text(0.02, 0.03, f"line: k = {k:.4g}, c = {c:.4g}", transform=ax.transAxes, fontsize=8)
    area = loop_area(x, fx)
    unit = f" {units['force']} {units['length']}" if units and displacement is not None else ""
    ax.set_title(f"loop opening (straight-line fit removed): area {area:.4g}{unit}", fontsize=10)
    return ax
