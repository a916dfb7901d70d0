"""Pictures of the constraint hyperplanes and the safe shakedown region (seed 002 Figs. 2-4)."""

from __future__ import annotations

import numpy as np

from ..bounds.engine import ShakedownBounds, extreme_constraints, safe_region
from ..model.errors import InputError

_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red")
_ROMAN = ("I", "II", "III", "IV")


def _ax(ax):
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5.5, 5))
    return ax


def _line_segment(g, b, xlim, ylim):
    """Points of the line g . v = b clipped to the box (for drawing)."""
    pts = []
    (x0, x1), (y0, y1) = xlim, ylim
    if abs(g[1]) > 1e-14:
        for x in (x0, x1):
            pts.append((x, (b - g[0] * x) / g[1]))
    if abs(g[0]) > 1e-14:
        for y in (y0, y1):
            pts.append(((b - g[1] * y) / g[0], y))
    pts = [p for p in pts if x0 - 1e-9 <= p[0] <= x1 + 1e-9 and y0 - 1e-9 <= p[1] <= y1 + 1e-9]
    return np.array(pts[:2]) if len(pts) >= 2 else None


def plot_constraints_2d(system, load, lam: float, *, t=None, ax=None, limits=None,
                        show_region: bool = True, show_extremes: bool = True, state=None):
    """The four constraint lines of a two-node system in ``v``-space (seed 002 Figs. 2-4).

    Constraint ``I``/``II`` belong to node 1 (slip backward / forward), ``III``/``IV`` to node 2
    (the seed's numbering; the package's labels are ``I_1, I_2, II_1, II_2``, nodes from 1).  Extreme
    positions are dashed, the safe shakedown region ``H(lam)`` is shaded, and if ``t`` is given
    the instantaneous lines at time ``t`` (cycles) are drawn solid with the excluded side hatched.

    Parameters
    ----------
    system, load : DiscreteSystem (2 nodes), LoadCycle
    lam : float
        Load factor.
    t : float, optional
        Time (cycles) of the instantaneous lines.
    limits : (xmin, xmax, ymin, ymax), optional
        Plot window in slip units; by default a box around the region.
    state : array_like (2,), optional
        A slip state to mark.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if system.n_nodes != 2:
        raise InputError(f"plot_constraints_2d needs a two-node system; got {system.n_nodes} nodes")
    ax = _ax(ax)
    region = safe_region(system, load, lam)
    G, b = region.normals, region.offsets
    verts = region.vertices_2d()
    if limits is None:
        if len(verts):
            lo, hi = verts.min(axis=0), verts.max(axis=0)
        else:
            # centre on the intersection of the I-constraints
            centre = np.linalg.lstsq(G[[0, 1]], b[[0, 1]], rcond=None)[0]
            lo = hi = centre
        span = max(float(np.max(hi - lo)), 1e-12) if len(verts) else 1.0
        if len(verts) < 3:
            span = max(span, np.abs(b).max() / np.abs(G).max())
        pad = 0.6 * span
        limits = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    xlim, ylim = limits[:2], limits[2:]
    # order rows as the seed: I (node 1 back), II (node 1 fwd), III (node 2 back), IV (node 2 fwd)
    order = (0, 2, 1, 3)
    for r, k in enumerate(order):
        seg = _line_segment(G[k], b[k], xlim, ylim) if show_extremes else None
        if seg is not None:
            n = region.normals.shape[1]
            name = f"{'I' if k < n else 'II'}_{k % n + 1}"  # nodes numbered from 1
            ax.plot(seg[:, 0], seg[:, 1], "--", color=_COLORS[r], lw=1.2,
                    label=f"{_ROMAN[r]}$^E$ ({name})")
        if t is not None:
            bt = extreme_constraints(system, load).instantaneous(system, load, t, lam)[k]
            seg_t = _line_segment(G[k], bt, xlim, ylim)
            if seg_t is not None:
                ax.plot(seg_t[:, 0], seg_t[:, 1], "-", color=_COLORS[r], lw=1.8)
                # hatch the excluded side: a short arrow along the normal
                mid = seg_t.mean(axis=0)
                nrm = G[k] / np.linalg.norm(G[k]) * 0.05 * (xlim[1] - xlim[0])
                ax.annotate("", xy=mid + nrm, xytext=mid,
                            arrowprops={"arrowstyle": "->", "color": _COLORS[r]})
    if show_region and len(verts) >= 3:
        ax.fill(verts[:, 0], verts[:, 1], color="0.85", zorder=0, label=r"safe region $\mathcal{H}$")
    elif show_region and len(verts):
        shape = "a segment" if len(verts) == 2 else "a point"
        ax.plot(verts[:, 0], verts[:, 1], "k.-", ms=8, lw=2.5,
                label=rf"safe region $\mathcal{{H}}$ (degenerate: {shape})")
    if state is not None:
        ax.plot(*np.asarray(state, float), "ko", ms=5, label="state")
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel("$v_1$, slip of node 1 [length]")
    ax.set_ylabel("$v_2$, slip of node 2 [length]")
    ax.set_title(rf"extreme constraints at $\lambda$ = {lam:.4g}")
    ax.legend(fontsize=8, loc="best")
    ax.set_aspect("equal", adjustable="box")
    return ax


def region_curve(system, load, lams):
    """Safe-region area (two nodes only, else nan) for each load factor in ``lams``."""
    lams = np.asarray(lams, float)
    area = np.full(lams.shape, np.nan)
    if system.n_nodes == 2:
        for i, lam in enumerate(lams):
            area[i] = safe_region(system, load, lam).area()
    return area


def plot_region_vs_lam(bounds: ShakedownBounds, *, system=None, load=None, lams=None, ax=None):
    """Active-constraint count (and, for two nodes, the safe-region area) against ``lam``.

    The count uses the activity intervals of ``bounds``; ``lam1`` and ``lam2`` are marked.  With
    the default ``intervals="lam1"`` some upper ends are only lower bounds, so above ``lam1`` the
    count is a lower bound (the legend says so); ``intervals=True`` gives the exact count.
    Pass ``system`` and ``load`` to add the area curve (two-node systems).

    Returns
    -------
    matplotlib.axes.Axes
        The axes of the count (the area, if drawn, is on ``ax.right_ax``).
    """
    ax = _ax(ax)
    top = bounds.lam2 if np.isfinite(bounds.lam2) else (
        bounds.lam1 if np.isfinite(bounds.lam1) and bounds.lam1 > 0 else 1.0)
    if lams is None:
        lams = np.linspace(0.0, 1.15 * top, 240)
    lams = np.asarray(lams, float)
    count = np.array([bounds.active_at(x).sum() if (not np.isfinite(bounds.lam2) or
                      x <= bounds.lam2) else 0 for x in lams])
    label = "active extreme constraints"
    if not bounds.lam_high_exact.all() and np.isfinite(bounds.lam1):
        # intervals="lam1": above lam1 some upper ends are lower bounds, so is the count
        label += r" (a lower bound above $\lambda_1$)"
    ax.step(lams, count, where="post", color="tab:blue", label=label)
    ax.set_xlabel(r"load factor $\lambda$")
    ax.set_ylabel(f"active constraints (of {2 * bounds.n_nodes})", color="tab:blue")
    ax.set_ylim(-0.2, 2 * bounds.n_nodes + 0.5)
    lam1, lam2, lam_adj = bounds.lam1, bounds.lam2, bounds.lam_adj
    # the values go in the legend, not as text on the plot: equal values cannot overlap and
    # nothing collides with the title
    same = np.isfinite(lam1) and np.isfinite(lam2) and abs(lam2 - lam1) <= 1e-7 * max(lam2, 1e-300)
    if same:
        ax.axvline(lam1, color="k", ls="--", lw=1, label=rf"$\lambda_1 = \lambda_2$ = {lam1:.4g}")
    else:
        if np.isfinite(lam2) and np.isfinite(lam1):
            ax.axvspan(lam1, lam2, color="0.9", zorder=0, label="initial state decides")
        if np.isfinite(lam1):
            ax.axvline(lam1, color="k", ls=":", lw=1.2, label=rf"$\lambda_1$ = {lam1:.4g}")
        if np.isfinite(lam2):
            ax.axvline(lam2, color="k", ls="--", lw=1, label=rf"$\lambda_2$ = {lam2:.4g}")
    if np.isfinite(lam_adj) and lam_adj <= lams[-1] and not (
            np.isfinite(lam1) and abs(lam_adj - lam1) <= 1e-7 * max(lam1, 1e-300)):
        ax.axvline(lam_adj, color="tab:red", ls="-.", lw=1,
                   label=rf"$\lambda_{{adj}}$ = {lam_adj:.4g} (node {bounds.adjacency_node + 1})")
    if system is not None and load is not None and system.n_nodes == 2:
        ax2 = ax.twinx()
        ax2.plot(lams, region_curve(system, load, lams), color="tab:orange", label="area of H")
        ax2.set_ylabel(r"area of $\mathcal{H}(\lambda)$", color="tab:orange")
        ax2.set_ylim(bottom=0)
        ax.right_ax = ax2
        lines = ax.get_legend_handles_labels()
        more = ax2.get_legend_handles_labels()
        ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="lower left")
    else:
        ax.legend(fontsize=8, loc="lower left")
    ax.set_title("extreme constraints still active against the load factor", fontsize=10)
    return ax


def plot_dissipation_vs_lam(lams, dissipation, bounds, *, ax=None, log=True):
    """Dissipation per cycle from many initial states against ``lam``, with the bounds marked.

    Parameters
    ----------
    lams : array_like, shape (L,)
        Load factors of the runs.
    dissipation : array_like, shape (L, S)
        Dissipation per cycle [force x length] of ``S`` runs (initial states) at each load
        factor (e.g. the steady ``W``, or the last cycle's); ``nan`` for a missing run.
    bounds : ShakedownBounds or ConeBounds
        2-D: ``lam1``, ``lam2`` and ``lam_adj`` are marked; 3-D (``bounds.dim == 3``): ``lam2``
        (Melan, certified), ``lam_adj_cone`` and ``lam1_cone`` (inscribed ``k``-gons) and the
        polygon's ``lam2``.
    log : bool
        Logarithmic dissipation axis (zero dissipation drawn at the bottom of the axis).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _ax(ax)
    lams = np.asarray(lams, float)
    W = np.asarray(dissipation, float)
    if W.ndim != 2 or W.shape[0] != lams.shape[0]:
        raise InputError(f"dissipation must have shape (len(lams), n_states) = ({lams.size}, S); "
                         f"got {W.shape}")
    pos = W[np.isfinite(W) & (W > 0)]
    floor = pos.min() / 10 if (log and pos.size) else 0.0
    shown = np.where(np.isfinite(W), np.maximum(W, floor), np.nan)
    for j in range(W.shape[1]):
        ax.plot(lams, shown[:, j], "o", mfc="none", ms=5, color="C0", alpha=0.6,
                label="runs (initial states)" if j == 0 else None)
    ax.plot(lams, np.nanmax(shown, axis=1), "-", color="C0", lw=1, label="max over states")
    ax.plot(lams, np.nanmin(shown, axis=1), "--", color="C3", lw=1, label="min over states")
    if log and pos.size:
        ax.set_yscale("log")
    marks = []
    if getattr(bounds, "dim", 2) == 3:
        k = bounds.facets
        marks = [(bounds.lam2, "k", "--", r"$\lambda_2$ (cones, certified)"),
                 (bounds.lam_adj_cone, "tab:red", "-.", rf"$\lambda_{{adj}}$ ({k}-gons)"),
                 (bounds.lam1_cone, "tab:purple", ":", rf"$\lambda_1$ ({k}-gons)"),
                 (bounds.lam2_polygon, "0.5", ":", rf"$\lambda_2$ ({k}-gons)")]
    else:
        marks = [(bounds.lam2, "k", "--", r"$\lambda_2$"), (bounds.lam1, "tab:purple", ":",
                                                           r"$\lambda_1$"),
                 (bounds.lam_adj, "tab:red", "-.", r"$\lambda_{adj}$")]
    for val, color, ls, name in marks:
        if np.isfinite(val):
            ax.axvline(val, color=color, ls=ls, lw=1.2, label=f"{name} = {val:.4g}")
    ax.set_xlabel(r"load factor $\lambda$")
    ax.set_ylabel("dissipation per cycle" + (" (0 drawn at the floor)" if log else ""))
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("dissipation per cycle from many initial states, with the bounds", fontsize=10)
    return ax
