"""Pictures of the half-space contact (sphere on flat); each takes ``ax=None`` and returns the axes.

* :func:`plot_contact_map`: the cells at one instant, coloured stick / slip / open, with the
  shear tractions as arrows and the continuum circles (contact radius ``a``, stick radius ``c``).
* :func:`plot_stuck_zone`: the permanently stuck cells of a steady cycle against a predicted
  stick radius.
* :func:`plot_hysteresis`: ``Q_x`` against Mindlin's ``delta_x`` (with the
  Mindlin-Deresiewicz loop when given) and :func:`plot_load_path`: ``Q_x`` against ``Q_y``.
* :func:`plot_dissipation_amplitude`: ``W`` against the amplitude on log-log axes with the
  cubic law.

Lengths and forces are in the model's units (labels say ``[length]``, ``[force]``).
"""

from __future__ import annotations

import numpy as np

from .axes import _new_ax

#: Colours of the cell states (stick, slip, open).
STATE_COLOURS = {"stick": "#2c7fb8", "slip": "#fdae61", "open": "#f0f0f0"}


def _grid(model, values):
    return np.asarray(values).reshape(model.n, model.n).T  # rows = y, columns = x


def _circle(ax, r, **kw):
    th = np.linspace(0, 2 * np.pi, 200)
    ax.plot(r * np.cos(th), r * np.sin(th), **kw)


def plot_contact_map(model, q_full, p_full, states, *, a=None, c=None, arrows=True, title=None,
                     zoom=None, ax=None):
    """Cells at one instant: stick (blue), slip (orange), open (grey); arrows ``q / h^2``.

    Parameters
    ----------
    model : HalfSpaceModel
    q_full : ndarray, shape (n^2, 2)
    p_full : ndarray, shape (n^2,)
    states : sequence of str, length n^2
        ``"stick"``, ``"slip"`` or ``"separation"`` per cell.
    a, c : float, optional
        Continuum contact and stick radii drawn as circles [length].
    zoom : float, optional
        Half-width of the view [length] (default: the window).
    """
    from matplotlib.colors import ListedColormap

    ax = _new_ax(ax, figsize=(5, 5))
    code = np.array([{"stick": 0, "slip": 1}.get(str(s), 2) for s in states])
    code[np.asarray(p_full) <= 0] = 2
    L = model.n * model.h / 2
    cmap = ListedColormap([STATE_COLOURS["stick"], STATE_COLOURS["slip"], STATE_COLOURS["open"]])
    ax.imshow(_grid(model, code), origin="lower", extent=(-L, L, -L, L), cmap=cmap, vmin=-0.5,
              vmax=2.5, interpolation="nearest")
    if arrows:
        on = code < 2
        xy = model.xy_cells[on]
        q = np.asarray(q_full)[on] / model.h**2
        scale = np.max(np.hypot(q[:, 0], q[:, 1]), initial=0.0)
        if scale > 0:
            ax.quiver(xy[:, 0], xy[:, 1], q[:, 0], q[:, 1], color="k", angles="xy",
                      scale_units="xy", scale=scale / (1.2 * model.h), width=0.004)
    if a is not None:
        _circle(ax, a, color="k", lw=1.0, ls="--", label=f"Hertz a = {a:.3g}")
    if c is not None:
        _circle(ax, c, color="tab:red", lw=1.2, label=f"continuum c = {c:.3g}")
    from matplotlib.patches import Patch

    handles = [Patch(color=STATE_COLOURS[k], label=k) for k in ("stick", "slip", "open")]
    h2, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + h2, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16),
              ncol=3, frameon=False)
    z = L if zoom is None else zoom
    ax.set_xlim(-z, z)
    ax.set_ylim(-z, z)
    ax.set_aspect("equal")
    ax.set_xlabel("x [length]")
    ax.set_ylabel("y [length]")
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def plot_stuck_zone(model, stuck_cells, *, a=None, c_pred=None, title=None, zoom=None, ax=None):
    """Permanently stuck cells (indices into the cell grid) against a predicted stick radius."""
    ax = _new_ax(ax, figsize=(5, 5))
    code = np.zeros(model.n_cells)
    code[np.asarray(stuck_cells, int)] = 1
    L = model.n * model.h / 2
    ax.imshow(_grid(model, code), origin="lower", extent=(-L, L, -L, L), cmap="Blues", vmin=0,
              vmax=1.4, interpolation="nearest")
    if a is not None:
        _circle(ax, a, color="k", lw=1.0, ls="--", label=f"Hertz a = {a:.3g}")
    if c_pred is not None:
        _circle(ax, c_pred, color="tab:red", lw=1.4, label=f"predicted stick radius {c_pred:.3g}")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    z = L if zoom is None else zoom
    ax.set_xlim(-z, z)
    ax.set_ylim(-z, z)
    ax.set_aspect("equal")
    ax.set_xlabel("x [length]")
    ax.set_ylabel("y [length]")
    ax.set_title(title or f"permanently stuck cells ({len(stuck_cells)}, blue)", fontsize=9)
    return ax


def plot_hysteresis(Q, delta, *, reference=None, label="discrete model", ax=None):
    """``Q_x`` against ``delta_x`` over a steady cycle (closed), with an optional reference loop
    ``reference = (Q_down, d_down, Q_up, d_up)`` (:func:`...continuum.mindlin_deresiewicz_loop`)."""
    ax = _new_ax(ax, figsize=(5.5, 4))
    Q = np.asarray(Q)
    d = np.asarray(delta)
    ax.plot(np.r_[d[:, 0], d[:1, 0]], np.r_[Q[:, 0], Q[:1, 0]], "o-", ms=3, lw=1.2, label=label)
    if reference is not None:
        Qd, dd, Qu, du = reference
        ax.plot(np.r_[dd, du], np.r_[Qd, Qu], "k--", lw=1, label="Mindlin-Deresiewicz")
    ax.set_xlabel(r"tangential displacement $\delta_x$ [length]")
    ax.set_ylabel(r"tangential force $Q_x$ [force]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def plot_load_path(Q, *, friction_P=None, ax=None):
    """The tangential load path ``(Q_x(t), Q_y(t))`` with the gross-slip circle ``|Q| = f P``."""
    ax = _new_ax(ax, figsize=(4.5, 4.5))
    Q = np.asarray(Q)
    ax.plot(np.r_[Q[:, 0], Q[:1, 0]], np.r_[Q[:, 1], Q[:1, 1]], "o-", ms=3)
    if friction_P is not None:
        _circle(ax, friction_P, color="tab:red", lw=1, ls="--", label="|Q| = f P (gross slip)")
        ax.legend(fontsize=8, loc="upper right")
    ax.set_aspect("equal")
    ax.set_xlabel(r"$Q_x$ [force]")
    ax.set_ylabel(r"$Q_y$ [force]")
    ax.grid(alpha=0.3)
    return ax


def plot_dissipation_amplitude(X, W, *, W_exact=None, W_cubic=None, ax=None):
    """Dissipation per cycle against the amplitude ``Q*/(f P)`` on log-log axes (amplitudes at
    which no cell slipped, ``W = 0``, cannot be drawn there and are left out)."""
    ax = _new_ax(ax, figsize=(5.5, 4))
    X, W = np.asarray(X, float), np.asarray(W, float)
    ok = W > 0
    ax.loglog(X[ok], W[ok], "o", label="discrete model")
    xs = np.geomspace(min(X), max(X), 100)
    if W_exact is not None:
        ax.loglog(xs, W_exact(xs), "k-", lw=1, label="Mindlin-Deresiewicz")
    if W_cubic is not None:
        ax.loglog(xs, W_cubic(xs), "k:", lw=1, label=r"cubic law $W \propto Q^{*3}$")
    ax.set_xlabel(r"amplitude $Q^*/(fP)$ [-]")
    ax.set_ylabel("dissipation per cycle W [force x length]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return ax
