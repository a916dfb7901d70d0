"""Plots of the Monte Carlo study (:func:`shakedown.sweep.run_sweep`; seed 002 Fig. 11)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_sweep", "plot_fractions"]


def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 4.5))
    return ax


def _mark_bounds(ax, realisations):
    """lam1, lam2: dashed / dotted lines at their means, shaded over their range."""
    for col, style, label in (("lam1", "--", r"$\lambda_1$"), ("lam2", ":", r"$\lambda_2$")):
        x = realisations[col].to_numpy(float)
        x = x[np.isfinite(x)]
        if not x.size:
            continue
        n = len(realisations)
        ax.axvline(x.mean(), color="k", ls=style, lw=1.2,
                   label=label + (f" (mean of {n})" if n > 1 else f" = {x.mean():.3g}"))
        if x.size > 1 and x.max() > x.min():
            ax.axvspan(x.min(), x.max(), color="k", alpha=0.07, lw=0)


def plot_sweep(result, ax=None, *, bands: bool = True, realisations: bool = True):
    """``W*`` against ``lam``: minimum and maximum over initial states, ``lam1``, ``lam2``.

    With one realisation, the seed's Fig. 11: the maximum (circles) and minimum (triangles)
    over the initial states at each ``lam``.  With several, each realisation's points are drawn
    faintly (``realisations=True``) and the mean over realisations of the minimum and of the
    maximum with their confidence bands (``result.bands``, Student t) on top.

    Parameters
    ----------
    result : SweepResult
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    ax = _axes(ax)
    s = result.summary
    n_real = int(s["realisation"].nunique()) if len(s) else 0
    if n_real <= 1 or realisations:
        alpha = 1.0 if n_real <= 1 else 0.25
        for r, g in s.groupby("realisation"):
            first = r == s["realisation"].iloc[0]
            ax.plot(g["lam"], g["W_star_max"], "o", mfc="none", color="C0", alpha=alpha,
                    label="max over initial states" if first and n_real <= 1 else None)
            ax.plot(g["lam"], g["W_star_min"], "^", color="C3", alpha=alpha, ms=5,
                    label="min over initial states" if first and n_real <= 1 else None)
            if n_real <= 1:
                ax.fill_between(g["lam"], g["W_star_min"], g["W_star_max"], color="C0",
                                alpha=0.12, lw=0)
    if n_real > 1:
        b = result.bands
        level = getattr(result, "confidence", 0.95)
        for col, color, name in (("W_star_max", "C0", "max"), ("W_star_min", "C3", "min")):
            ax.plot(b["lam"], b[f"{col}_mean"], "-", color=color, lw=1.8,
                    label=f"{name} over initial states (mean of {n_real})")
            if bands:
                ax.fill_between(b["lam"], b[f"{col}_lo"], b[f"{col}_hi"], color=color,
                                alpha=0.2, lw=0, label=f"{level:.0%} confidence")
    _mark_bounds(ax, result.realisations)
    ax.set_xlabel(r"load factor $\lambda$")
    ax.set_ylabel(r"$W^* = W\mu / (4(1-\nu)p_0^2\bar a^2)$")
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    spec = getattr(result, "spec", None)
    if spec is not None:
        ax.set_title(f"{spec.n_cracks} cracks, density {spec.density}, f = {spec.friction}, "
                     f"{spec.n_realisations} realisation(s) x {spec.n_states} initial states",
                     fontsize=9)
    ax.legend(fontsize=8, loc="upper left")
    return ax


def plot_fractions(result, ax=None):
    """Fractions of cracks that slip / open during the steady cycle, against ``lam``.

    Lines: mean over realisations and initial states; shading: the range over them.  The seed
    links the return of a unique ``W*`` at large ``lam`` to every crack slipping each cycle.

    Returns
    -------
    matplotlib Axes
    """
    ax = _axes(ax)
    runs = result.runs
    g = runs.groupby("lam_index")
    lam = g["lam"].first().to_numpy(float)
    for col, color, label in (("frac_slip", "C2", "slip"), ("frac_open", "C1", "open")):
        ax.plot(lam, g[col].mean().to_numpy(float), "-o", color=color, ms=4,
                label=f"fraction that {label}s")
        ax.fill_between(lam, g[col].min().to_numpy(float), g[col].max().to_numpy(float),
                        color=color, alpha=0.15, lw=0)
    _mark_bounds(ax, result.realisations)
    ax.set_xlabel(r"load factor $\lambda$")
    ax.set_ylabel("fraction of cracks (steady cycle)")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(fontsize=8, loc="center right")
    return ax
