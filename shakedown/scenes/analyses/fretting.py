"""The ``fretting`` analysis of a ``half_space`` scene: the steady cycle of a sphere on a flat.

``[analyses.fretting]`` takes the scene's load (constant ``P0``; ``P1`` must be 0), reaches the
steady cycle with :func:`shakedown.studies.half_space.fretting_run` (dense) or
:func:`~shakedown.studies.half_space.fretting_run_fft` (matrix-free: ``engine = "fft"``, and
``"auto"`` above :data:`~shakedown.models.half_space.DENSE_MAX_CELLS` cells) from Mindlin's first
loading (``P0``, then ``Q_x`` up to its amplitude) and writes

* ``fretting.json`` -- ``W`` per cycle, the steady ``W``, periods to steady, the continuum
  references (Hertz ``a``, Mindlin-Deresiewicz ``W`` and stick radius where they apply: an
  oscillating load on similar materials), the reference cell check, a verdict;
* ``steady_cycle.csv`` -- per instant and cell: ``t``, ``cell``, ``x``, ``y``, ``q_x``, ``q_y``,
  ``p``, ``state``;
* ``contact_maps.png`` (stick / slip / open with traction arrows at ``t = 0, 1/4, 1/2, 3/4``),
  ``stuck_zone.png`` (against Mindlin's stick radius), ``hysteresis.png`` (``Q_x``-``delta_x``
  with the Mindlin-Deresiewicz loop where it applies, and ``Q_x``-``Q_y``);
* with ``amplitudes`` (multiples of the scene's ``Qx``, ``Qy``): the steady ``W`` at each
  (``dissipation_amplitude.csv``) and ``dissipation_amplitude.png`` (log-log, with
  Mindlin-Deresiewicz and the cubic law where they apply).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ...model.errors import SceneError

OPTIONS = {
    "steps_per_cycle": (int, 40, "implicit steps per load cycle (>= 4)"),
    "max_cycles": (int, 10, "largest number of cycles simulated"),
    "tol": (float, 1e-9, "relative change of the cycle-start state that counts as steady"),
    "plots": (bool, True, "write PNG plots"),
    "amplitudes": (list, [], "multiples of the tangential amplitude (Qx, Qy) at which to run the "
                             "steady cycle too: W against amplitude on log-log axes"),
    "engine": (str, "auto", "'dense' (cone engine on the condensed stiffness), 'fft' (matrix-free "
               "FFT steps) or 'auto' (fft above DENSE_MAX_CELLS cells)"),
}


def _load_amplitudes(ctx):
    tab = ctx.scene.load if ctx.scene is not None else {}
    if float(tab.get("P1", 0.0)) != 0.0:
        raise SceneError("[analyses.fretting] needs a constant normal force: [load] P1 = 0")
    return float(tab["P0"]), float(tab.get("Qx", 0.0)), float(tab.get("Qy", 0.0))


def run(ctx, options: dict) -> dict:
    from ...models.half_space import continuum as cont
    from ...studies import half_space as hs

    model = ctx.model
    if not hasattr(model, "xy_cells"):
        raise SceneError("[analyses.fretting] needs a scene of [model] kind = 'half_space'")
    if options["steps_per_cycle"] < 4 or options["max_cycles"] < 1:
        raise SceneError("[analyses.fretting] steps_per_cycle must be >= 4 and max_cycles >= 1")
    P0, Qx, Qy = _load_amplitudes(ctx)
    from ...models.half_space import DENSE_MAX_CELLS

    engine = options["engine"]
    if engine not in ("auto", "dense", "fft"):
        raise SceneError(f"[analyses.fretting] engine must be 'auto', 'dense' or 'fft', got {engine!r}")
    if engine == "auto":
        engine = "fft" if model.n_cells > DENSE_MAX_CELLS else "dense"
    kw = dict(steps_per_cycle=options["steps_per_cycle"], max_cycles=options["max_cycles"],
              tol=options["tol"])
    fretting_run = hs.fretting_run_fft if engine == "fft" else hs.fretting_run
    run_, loop = fretting_run(model, P0, Qx, Qy, **kw)
    if engine == "fft":
        stuck_cells = np.asarray(run_.stuck_cells, int)
    else:
        stuck_cells = np.r_[model.keep[np.asarray(run_.stuck_nodes, int)], model.reference]
    qm = loop["q_full"][:, model.reference]
    pm = loop["p_full"][:, model.reference]
    ref_margin = float(np.max((np.linalg.norm(qm, axis=-1) - model.friction * pm) / P0))
    f = model.friction
    summary = {
        "steady_dissipation": float(run_.steady_dissipation),
        "dissipation_per_cycle": [float(w) for w in run_.dissipation],
        "cycles_to_steady": int(run_.cycles_to_steady), "period": int(run_.period),
        "status": str(run_.status), "n_stuck_cells": int(len(stuck_cells)), "engine": engine,
        "reference_cell_margin": ref_margin, "reference_cell_ok": bool(ref_margin <= 1e-9),
        "W_loop": float(loop["W_loop"]),
    }
    a = c = None
    if model.profile == "sphere" and model.beta == 0:
        a = float(cont.hertz_radius(P0, model.radius, model.e_star))
        summary["hertz_radius"] = a
        if Qy == 0 and abs(Qx) < f * P0:
            mats = getattr(model, "materials", None)
            c = float(cont.cattaneo_mindlin_radius(Qx, P0, f, a))
            summary["mindlin_stick_radius"] = c
            if mats is not None:
                ct = cont.tangential_compliance_constant(mats)
                summary["mindlin_deresiewicz_W"] = float(
                    cont.mindlin_deresiewicz_dissipation(Qx, P0, f, a, ct))
    verdict = _verdict(run_, summary, model.n_cells)
    summary = {"verdict": verdict, **summary}
    ctx.output.write_json("fretting.json", summary)
    T, Nc = loop["p_full"].shape
    ctx.output.write_table("steady_cycle.csv", pd.DataFrame({
        "t": np.repeat(loop["t"], Nc), "cell": np.tile(np.arange(1, Nc + 1), T),
        "x": np.tile(model.xy_cells[:, 0], T), "y": np.tile(model.xy_cells[:, 1], T),
        "q_x": loop["q_full"][..., 0].ravel(), "q_y": loop["q_full"][..., 1].ravel(),
        "p": loop["p_full"].ravel(), "state": np.asarray(loop["states"]).ravel()}))
    amps = _amplitudes(options)
    if amps.size:
        Ws = np.array([fretting_run(model, P0, x * Qx, x * Qy, **kw)[0].dissipation[-1]
                       for x in amps])
        ctx.output.write_table("dissipation_amplitude.csv", pd.DataFrame(
            {"amplitude": amps, "Q_amplitude": amps * np.hypot(Qx, Qy), "W": Ws}))
    if options["plots"]:
        _plots(ctx, model, stuck_cells, loop, a, c, f * P0)
        if amps.size:
            _amplitude_plot(ctx, model, amps, Ws, P0, Qx, Qy, a)
    return {k: summary[k] for k in ("verdict", "steady_dissipation", "cycles_to_steady", "status")}


def _amplitudes(options):
    try:
        amps = np.asarray(options["amplitudes"], float).ravel()
    except (TypeError, ValueError):
        raise SceneError("[analyses.fretting] amplitudes must be a list of positive numbers; "
                         f"got {options['amplitudes']!r}") from None
    if np.any(~np.isfinite(amps)) or np.any(amps <= 0):
        raise SceneError("[analyses.fretting] amplitudes must be positive multiples of the "
                         f"tangential amplitude; got {options['amplitudes']!r}")
    return np.sort(amps)


def _verdict(run_, summary, n_cells) -> str:
    """Plain sentences, the answer first."""
    W = run_.steady_dissipation
    k = run_.cycles_to_steady
    if run_.status != "periodic":
        when = f"not yet steady after {len(run_.dissipation)} cycles (last W = {run_.dissipation[-1]:.4g})"
    else:
        when = "steady from the first cycle" if k == 0 else f"steady after {k} cycle(s)"
    out = (f"Partial slip: the contact keeps slipping at its rim every cycle and dissipates "
           f"W = {W:.4g} per cycle ({when}); {summary['n_stuck_cells']} of {n_cells} cells stay "
           "stuck throughout")
    if "mindlin_deresiewicz_W" in summary:
        out += (f". Mindlin-Deresiewicz: W = {summary['mindlin_deresiewicz_W']:.4g} "
                f"({W / summary['mindlin_deresiewicz_W'] - 1:+.1%}), stick radius "
                f"{summary['mindlin_stick_radius']:.4g}")
    out += "."
    if not summary["reference_cell_ok"]:
        out += " WARNING: the reference cell slips or opens (the model is not exact)."
    return out


def _clean(x, scale):
    """``x`` with round-off (below 1e-9 of ``scale``) shown as 0."""
    return 0.0 if abs(x) <= 1e-9 * scale else float(x)


def _amplitude_plot(ctx, model, amps, Ws, P0, Qx, Qy, a):
    import matplotlib.pyplot as plt

    from ...models.half_space import continuum as cont
    from ...plotting import half_space as ph

    f = model.friction
    X = amps * np.hypot(Qx, Qy) / (f * P0)
    exact = cubic = None
    mats = getattr(model, "materials", None)
    if a is not None and Qy == 0 and mats is not None:
        ct = cont.tangential_compliance_constant(mats)

        def exact(x):
            return cont.mindlin_deresiewicz_dissipation(x * f * P0, P0, f, a, ct)

        def cubic(x):
            return cont.mindlin_cubic_dissipation(x * f * P0, P0, f, a, ct)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    ph.plot_dissipation_amplitude(X, Ws, W_exact=exact, W_cubic=cubic, ax=ax)
    ax.set_title("dissipation per cycle against the tangential amplitude", fontsize=9)
    ctx.output.save_figure("dissipation_amplitude.png", fig)


def _plots(ctx, model, cells, loop, a, c, fP):
    import matplotlib.pyplot as plt

    from ...models.half_space import continuum as cont
    from ...plotting import half_space as ph

    zoom = 1.15 * a if a is not None else None
    tt = np.mod(np.asarray(loop["t"], float), 1.0)
    Qs = float(np.abs(loop["Q"]).max()) or 1.0
    fig, axs = plt.subplots(1, 4, figsize=(18, 4.8))
    # the orbit's first row repeats its last instant (t = 0 and 1) as the state before the
    # first step: the instants are taken from the steps' results (rows 1..T-1)
    first = 1 if len(tt) > 1 and abs((tt[-1] - tt[0] + 0.5) % 1.0 - 0.5) < 1e-9 else 0
    for ax, target in zip(axs, (0.0, 0.25, 0.5, 0.75), strict=True):
        k = first + int(np.argmin(np.abs((tt[first:] - target + 0.5) % 1.0 - 0.5)))
        Qk = [_clean(x, Qs) for x in loop["Q"][k]]
        ph.plot_contact_map(model, loop["q_full"][k], loop["p_full"][k], loop["states"][k], a=a,
                            c=c, zoom=zoom, ax=ax,
                            title=f"t = {tt[k]:.3g} T: Q = ({Qk[0]:.3g}, {Qk[1]:.3g})")
    fig.tight_layout()
    ctx.output.save_figure("contact_maps.png", fig)
    fig, ax = plt.subplots(figsize=(5, 5))
    ph.plot_stuck_zone(model, cells, a=a, c_pred=c, zoom=zoom, ax=ax)
    ctx.output.save_figure("stuck_zone.png", fig)
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.2))
    ref = None
    mats = getattr(model, "materials", None)
    if c is not None and mats is not None and np.all(np.asarray(loop["Q"])[:, 1] == 0):
        ref = cont.mindlin_deresiewicz_loop(float(np.abs(loop["Q"][:, 0]).max()), fP / model.friction,
                                            model.friction, a,
                                            cont.tangential_compliance_constant(mats))
    ph.plot_hysteresis(loop["Q"], loop["delta"], reference=ref, ax=axs[0])
    ph.plot_load_path(loop["Q"], friction_P=fP, ax=axs[1])
    fig.tight_layout()
    ctx.output.save_figure("hysteresis.png", fig)
