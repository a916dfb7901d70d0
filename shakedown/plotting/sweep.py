"""Plots of the Monte Carlo study (:func:`shakedown.sweep.run_sweep`; seed 002 Fig. 11)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_sweep", "plot_fractions"]


_XLABEL = {"lam": r"load factor $\lambda$ [-]", "x": r"$\lambda / \lambda_2$ [-]"}


def _axes(ax, size=(7, 4.5)):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=size)
    return ax


def _col(axis):
    if axis not in ("lam", "x"):
        from ..model.errors import InputError

        raise InputError(f"axis must be 'lam' or 'x' (lam / lam2); got {axis!r}")
    return axis


def _mark_bounds(ax, result, axis):
    """``lam1`` (dotted) and ``lam2`` (dashed) marked with their values, the band between them
    shaded; ``lam_adj`` (dash-dot) and ``lam_u`` (dash-dot-dot) marked with their values.

    Values are the mean over the realisations (said when there are several); on the axis
    ``lam / lam2`` the marks are at each bound over that realisation's ``lam2``.
    """
    r = result.realisations
    l2 = r["lam2"].to_numpy(float)
    scale = l2 if axis == "x" else np.ones_like(l2)
    n = len(r)

    def where_and_value(col):
        raw = r[col].to_numpy(float) if col in r else np.full(n, np.nan)
        x, ok = raw / scale, np.isfinite(raw / scale)
        return (x[ok].mean(), raw[ok].mean()) if ok.any() else (np.nan, np.nan)

    mean = " (mean)" if n > 1 else ""

    def at(x):  # where the mark is, on the axis lam / lam2
        return rf", at $\lambda/\lambda_2$ = {x:.3g}" if axis == "x" else ""

    x1, v1 = where_and_value("lam1")
    x2, v2 = where_and_value("lam2")
    if np.isfinite(x1) and np.isfinite(x2) and abs(v2 - v1) <= 1e-7 * abs(v2):
        ax.axvline(x2, color="k", ls="--", lw=1,
                   label=rf"$\lambda_1 = \lambda_2$ = {v2:.4g}{mean}{at(x2)}")
    else:
        if np.isfinite(x1) and np.isfinite(x2):
            ax.axvspan(x1, x2, color="0.6", alpha=0.35, lw=0,
                       label=r"$\lambda_1 < \lambda < \lambda_2$: the initial state decides")
        if np.isfinite(x1):
            ax.axvline(x1, color="k", ls=":", lw=1.2, label=rf"$\lambda_1$ = {v1:.4g}{mean}{at(x1)}")
        if np.isfinite(x2):
            ax.axvline(x2, color="k", ls="--", lw=1, label=rf"$\lambda_2$ = {v2:.4g}{mean}{at(x2)}")
    xa, va = where_and_value("lam_adj")
    if np.isfinite(xa) and np.isfinite(x1) and xa < x1:
        ax.axvline(xa, color="tab:purple", ls="-.", lw=1,
                   label=rf"$\lambda_{{adj}}$ = {va:.4g}{mean}{at(xa)}")
    xu, vu = where_and_value("lam_u")
    if np.isfinite(xu):
        ax.axvline(xu, color="tab:brown", ls=(0, (5, 2, 1, 2, 1, 2)), lw=1.2,
                   label=rf"$\lambda_u$ = {vu:.4g}{mean}{at(xu)}: every {_word(result)} slips")


def _word(result) -> str:
    """"crack" for the crack study, "node" for a given system (``spec.node_word``)."""
    return getattr(getattr(result, "spec", None), "node_word", "crack")


def _zoom_range(result, col):
    """``(lo, hi)`` around ``lam_adj .. lam2`` on the plotted axis, or None."""
    r = result.realisations
    l1, l2, la = (r[c].to_numpy(float) for c in ("lam1", "lam2", "lam_adj"))
    scale = l2 if col == "x" else np.ones_like(l2)
    lo = np.fmin(la, l1) / scale
    hi = l2 / scale
    ok = np.isfinite(lo) & np.isfinite(hi)
    if not ok.any():
        return None
    lo, hi = lo[ok].min(), hi[ok].max()
    return lo - 0.1 * (hi - lo), hi + 0.35 * (hi - lo)


def _draw_realisations(ax, s, col, alpha, label):
    for k, (_, g) in enumerate(s.groupby("realisation")):
        g = g.sort_values("lam")
        lab = k == 0 and label
        ax.plot(g[col], g["W_star_max"], "-o", mfc="none", ms=7, color="C0", alpha=alpha,
                lw=1, label="max over initial states" if lab else None)
        ax.plot(g[col], g["W_star_min"], "--^", color="C3", alpha=alpha, ms=4, lw=1,
                label="min over initial states" if lab else None)


def _inset(ax, result, col, alpha):
    """A zoom on ``lam_adj .. lam2`` (the band is a few per cent of the load-factor range)."""
    rng = _zoom_range(result, col)
    if rng is None:
        return
    s = result.summary
    sub = s[(s[col] >= rng[0]) & (s[col] <= rng[1])]
    if len(sub) < 2:
        return
    ins = ax.inset_axes([0.09, 0.52, 0.34, 0.36])  # upper left: W* ~ 0 there
    _draw_realisations(ins, sub, col, alpha, False)
    _mark_bounds(ins, result, col)
    ins.set_xlim(*rng)
    top = float(np.nanmax(sub["W_star_max"].to_numpy(float)))
    ins.set_ylim(-0.05 * top if top > 0 else -1, 1.1 * top if top > 0 else 1)
    ins.tick_params(labelsize=6)
    ins.text(0.03, 0.95, r"zoom: $\lambda_{adj}$ .. $\lambda_2$", transform=ins.transAxes,
             fontsize=7, va="top", bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})


def plot_sweep(result, ax=None, *, axis: str = "lam", bands: bool = True,
               realisations: bool = True, zoom: bool = True):
    """``W*`` against ``lam`` (or ``x = lam / lam2``): min and max over initial states.

    One realisation: the maximum (open circles, solid line) and the minimum (filled triangles,
    dashed line) over the initial states at each load factor, the band ``lam1 .. lam2`` shaded,
    ``lam1``, ``lam2``, ``lam_adj`` and ``lam_u`` marked with their values in the legend.
    Several: each realisation's points faintly, and the mean over realisations of min and max
    at the points common to all (same ``lam / lam2``) with their confidence bands
    (``result.bands``).

    Parameters
    ----------
    result : SweepResult
    ax : matplotlib Axes, optional
    axis : {"lam", "x"}
        Load factor, or load factor over each realisation's ``lam2`` (dimensionless).
    zoom : bool
        An inset on ``lam_adj .. lam2``, where the band is.

    Returns
    -------
    matplotlib Axes
    """
    ax = _axes(ax)
    col = _col(axis)
    s = result.summary
    n_real = int(s["realisation"].nunique()) if len(s) else 0
    alpha = 1.0 if n_real <= 1 else 0.25
    if n_real <= 1 or realisations:
        _draw_realisations(ax, s, col, alpha, n_real <= 1)
    if n_real > 1:
        b = result.bands
        b = b[b["point"].astype(str).str.startswith("g")]
        level = getattr(result, "confidence", 0.95)
        for c, color, name in (("W_star_max", "C0", "max"), ("W_star_min", "C3", "min")):
            ax.plot(b[col], b[f"{c}_mean"], "-" if name == "max" else "--", color=color, lw=2,
                    label=f"{name} over initial states, mean of {n_real} realisations")
            if bands:
                ax.fill_between(b[col], b[f"{c}_lo"], b[f"{c}_hi"], color=color, alpha=0.2,
                                lw=0, label=f"{level:.0%} confidence of the mean ({name})")
    _mark_bounds(ax, result, col)
    ax.set_xlabel(_XLABEL[col])
    spec = getattr(result, "spec", None)
    source = getattr(spec, "source", None)  # a given system (any model): W, not W*
    ax.set_ylabel(f"$W$ per cycle {source.energy_unit}" if source is not None
                  else r"$W^* = W\mu / (4(1-\nu)p_0^2\bar a^2)$ per cycle [-]")
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    if source is not None:
        ax.set_title(f"Steady dissipation: {spec.describe()}, {spec.n_states} initial states",
                     fontsize=9)
    elif spec is not None:
        reals = (f"{spec.n_realisations} realisations x " if spec.n_realisations != 1 else "")
        ax.set_title(f"Steady dissipation: {spec.n_cracks} cracks, density {spec.density}, "
                     f"f = {spec.friction}, {reals}{spec.n_states} initial states", fontsize=9)
    # beside the axes: the curves, the marks and the zoom stay uncovered
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    if zoom:
        _inset(ax, result, col, alpha if n_real > 1 else 1.0)
    return ax


def plot_fractions(result, ax=None, *, axis: str = "lam"):
    """Fractions of cracks that slip / open in the steady cycle: min and max over initial states.

    Solid: maximum over the initial states, dashed: minimum (per realisation; faint when there
    are several).  The seed links the return of a unique ``W*`` to every crack slipping.

    Returns
    -------
    matplotlib Axes
    """
    ax = _axes(ax, (7, 4))
    col = _col(axis)
    s = result.summary
    n_real = int(s["realisation"].nunique()) if len(s) else 0
    alpha = 1.0 if n_real <= 1 else 0.3
    for k, (_, g) in enumerate(s.groupby("realisation")):
        g = g.sort_values("lam")
        for c, color, what in (("frac_slip", "C2", "slip"), ("frac_open", "C1", "open")):
            for ext, ls, mk in (("max", "-", "o"), ("min", "--", "v")):
                ax.plot(g[col], g[f"{c}_{ext}"], ls, marker=mk, ms=3.5, color=color,
                        alpha=alpha, lw=1,
                        label=f"{ext} over initial states: fraction that {what}s"
                        if k == 0 else None)
    _mark_bounds(ax, result, col)
    ax.set_xlabel(_XLABEL[col])
    ax.set_ylabel(f"fraction of {_word(result)}s (steady cycle) [-]")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title(f"{_word(result).capitalize()}s that slip / open in the steady cycle"
                 + (f" ({n_real} realisations)" if n_real > 1 else ""), fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    return ax
