"""Pictures of the half-plane contact (each takes ``ax=None`` and returns the axes).

Units are whatever the model was built in; labels say "force/length" (force per unit
thickness) and "length".
"""

from __future__ import annotations

import numpy as np

from ..models.half_plane.continuum import ellipse_construction


def _ax(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.5, 4))
    return ax


def plot_loading_ellipse(P0, P1, Q1, phase, friction, lam: float = 1.0, ax=None, path=None):
    """The load cycle in ``(P, Q)`` space with the friction cone, the tangents of slope ``+-f``
    at their tangent points, and the point ``T`` of the seed's construction (Fig. 13).

    ``path``: an optional initial loading path ``OA`` as ``(P, Q)`` arrays (drawn from ``O``).
    """
    ax = _ax(ax)
    f = float(friction)
    t = np.linspace(0, 1, 400)
    P = P0 + lam * P1 * np.cos(2 * np.pi * t + phase)
    Q = lam * Q1 * np.cos(2 * np.pi * t)
    con = ellipse_construction(P0, P1, Q1, phase, f, lam)
    Pmax = 1.15 * P.max()
    ax.plot(P, Q, "k-", lw=1.8, label="load cycle")
    pp = np.array([0.0, Pmax])
    ax.fill_between(pp, -f * pp, f * pp, color="0.93", zorder=0, label=r"$|Q| < fP$")
    for key, slope, col, name in (("t_plus", f, "tab:red", "+f"), ("t_minus", -f, "tab:blue", "-f")):
        tk = con[key]
        Pk = P0 + lam * P1 * np.cos(2 * np.pi * tk + phase)
        Qk = lam * Q1 * np.cos(2 * np.pi * tk)
        xs = np.array([min(con["P_T"], Pk) - 0.05 * Pmax, max(con["P_T"], Pk) + 0.05 * Pmax])
        ax.plot(xs, Qk + slope * (xs - Pk), "--", color=col, lw=1.2,
                label=f"tangent of slope {name}")
        ax.plot([Pk], [Qk], "o", color=col, ms=5)
    ax.plot([con["P_T"]], [con["Q_T"]], "ks", ms=6)
    ax.annotate("T", (con["P_T"], con["Q_T"]), textcoords="offset points", xytext=(-12, 4))
    ax.axvline(con["P_T"], color="0.5", lw=0.8, ls=":")
    if path is not None:
        ax.plot(np.r_[0, path[0]], np.r_[0, path[1]], "-", color="tab:green", lw=1,
                label="initial path OA")
    ax.set_xlim(0, Pmax)
    ax.set_xlabel("normal load P [force/length]")
    ax.set_ylabel("tangential load Q [force/length]")
    ax.legend(fontsize=7, loc="lower left")
    return ax


def plot_tractions(model, run, times, P_of_t, Q_of_t, ax=None):
    """Tractions ``q/h`` (solid) and ``+-f p/h`` (dotted) at ``times`` of a run's steady cycle.

    Markers: slipping nodes (filled), separated nodes (crosses), stuck nodes (none).
    """
    ax = _ax(ax)
    tab = run.steady_table
    ts = np.array(sorted(tab["t"].unique()))
    f = model.friction
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown"]
    for i, t in enumerate(times):
        tt = ts[np.argmin(np.abs((ts - ts[0]) % 1.0 - t % 1.0))]
        s = tab[tab["t"] == tt].sort_values("node")
        qm, pm = model.reference_reactions(s["q"].to_numpy(), s["p"].to_numpy(),
                                           Q_of_t(tt), P_of_t(tt))
        q = model.full(s["q"].to_numpy(), qm) / model.h
        p = model.full(s["p"].to_numpy(), pm) / model.h
        st = np.insert(s["state"].to_numpy().astype(object), model.reference, "stick")
        c = colors[i % len(colors)]
        x = model.x_cells
        ax.plot(x, q, "-", color=c, lw=1.3, label=f"q, t = {t:.2f}")
        ax.plot(x, f * p, ":", color=c, lw=0.9)
        ax.plot(x, -f * p, ":", color=c, lw=0.9)
        slip = np.isin(st, ["forward", "backward"])
        sep = st == "separation"
        ax.plot(x[slip], q[slip], "o", color=c, ms=3)
        ax.plot(x[sep], q[sep], "x", color=c, ms=3)
    ax.set_xlabel("x [length]")
    ax.set_ylabel("shear traction q, bounds ±f p [force/length²]")
    ax.legend(fontsize=7, title="dots: slip, x: open", title_fontsize=7)
    return ax


def plot_stuck_zone(model, run, a_T, ax=None):
    """Slip range over the steady cycle per node, the permanently stuck nodes and ``A_T``."""
    ax = _ax(ax)
    tab = run.steady_table
    rng = tab.groupby("node")["slip"].agg(lambda s: s.max() - s.min()).to_numpy()
    closed = tab.groupby("node")["state"].agg(lambda s: (s != "separation").all()).to_numpy()
    x = model.x
    ax.axvspan(-a_T, a_T, color="0.88", label=r"$\mathcal{A}_T$ (continuum)")
    stuck = run.stuck_nodes
    floor = max(rng.max(), 1e-300) * 1e-6
    shown = np.where(rng > floor, rng, np.nan)
    ax.semilogy(x, shown, "k.-", lw=0.8, label="slip range over the cycle")
    ax.plot([model.x_cells[model.reference]], [floor], "D", color="0.3", ms=4,
            label="reference cell (stuck by construction)")
    ax.plot(x[stuck], np.full(stuck.size, floor), "s", color="tab:red", ms=4,
            label="permanently stuck nodes")
    ax.plot(x[~closed], np.full((~closed).sum(), floor), "x", color="tab:blue", ms=4,
            label="opens during the cycle")
    ax.set_ylim(floor / 3, rng.max() * 3 if rng.max() > 0 else 1)
    ax.set_xlabel("x [length]")
    ax.set_ylabel("slip range [length]")
    ax.legend(fontsize=7)
    return ax


def plot_beta_study(table, ax=None):
    """Spread of ``W`` over initial paths, cycles to steady state, and the bounds, against ``beta``."""
    ax = _ax(ax)
    b = table["beta"].to_numpy()
    ax.plot(b, 100 * table["W_spread"], "o-", color="tab:red", label="W spread over OA paths [%]")
    ax.set_xlabel("Dundurs beta [-]")
    ax.set_ylabel("W spread [%]", color="tab:red")
    ax2 = ax.twinx()
    ax2.plot(b, table["lam1"], "s--", color="tab:blue", label="lam1")
    ax2.plot(b, table["lam2"], "^--", color="tab:green", label="lam2")
    ax2.plot(b, table["lam_adj"], "v:", color="tab:purple", label="lam_adj")
    ax2.set_ylabel("load factor (Q amplitude / Q1) [-]")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    return ax
