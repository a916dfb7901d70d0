"""The ``cycles`` analysis: cyclic evolution, steady cycle, dissipation; uniqueness studies.

``[analyses.cycles]`` runs :func:`shakedown.solve_cycles` from one initial state (or the direct
:func:`shakedown.steady_cycle` solver with ``steady_solver = true``) and writes

* ``cycles.json`` -- the summary (steady ``W``, period, shook down, stuck nodes, counts, status),
* ``dissipation.csv`` -- ``W`` and the change of state of every cycle,
* ``steady_cycle.csv`` -- the steady cycle's time series (t, node, slip, gap, q, p, state),
* ``dissipation.png``, ``steady_cycle.png``, ``node_states.png`` and, for two nodes,
  ``trajectory.png`` (v space) and ``trajectory_tau.png`` (tau = A v space); for a 3-D model
  with node positions (3-D FE bodies), ``node_states.png`` and the contact patch maps
  ``contact_patch.png`` (states and traction arrows at four instants), ``stuck_zone.png`` and
  ``force_loop.png`` (the force through the contact against the prescribed displacement when
  the cyclic load is one displacement along ``x``, as a lap joint's grip, beside the loop with
  its straight-line fit removed; :mod:`shakedown.plotting.contact_patch`) instead of
  ``steady_cycle.png``;
  for any ``dim = 3`` system also ``cone_paths.png`` (per node, ``q / p`` over the steady cycle inside
  the friction cone) and ``slip_trajectories.png`` (``(v_x, v_y)``).

With ``n_initial_states > 1`` (or several ``initial_slips``) it also runs a uniqueness study
(:func:`shakedown.uniqueness_study`) and writes ``uniqueness.csv`` and ``uniqueness.png``; the
single-run outputs are then those of the first initial state.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ...evolution.verdicts import cycles_verdict
from ...model.errors import SceneError, SolverError

__all__ = ["OPTIONS", "run", "cycles_verdict"]

OPTIONS = {
    "lam": (float, 1.0, "load factor lam >= 0"),
    "method": (str, "implicit", "time integration: 'implicit' or 'events'"),
    "steps_per_cycle": (int, 200, "implicit steps per load cycle (>= 2)"),
    "max_cycles": (int, 200, "largest number of cycles simulated per run"),
    "tol": (float, 1e-10, "relative change of the cycle-start state that counts as steady"),
    "initial_slip": (list, [], "initial slip of every node (empty: zeros)"),
    "initial_slips": (list, [], "several initial states (list of lists): a uniqueness study"),
    "n_initial_states": (int, 1, "> 1: a uniqueness study from this many sampled states"),
    "seed": (int, 0, "seed of the sampled initial states"),
    "sampling_scale": (float, 2.0, "box of the sampled states, in natural slips f p0 / A_jj"),
    "n_jobs": (int, 1, "worker processes of the uniqueness study (0: all cores)"),
    "steady_solver": (bool, False, "find the steady cycle as a fixed point (steady_cycle)"),
    "log_scale": (bool, False, "logarithmic W axis in dissipation.png"),
    "plots": (bool, True, "write PNG plots"),
}


def _vector(name, value, n, dim=2):
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise SceneError(f"[analyses.cycles] key {name!r} must be numbers; got {value!r}") from exc
    if v.shape != ((n, 2) if dim == 3 else (n,)):
        each = " (a pair [v_x, v_y] each: dim = 3)" if dim == 3 else ""
        raise SceneError(
            f"[analyses.cycles] key {name!r} must list one slip per node ({n}){each}; got "
            f"{value!r}"
        )
    return v


def _check(options, n, dim=2):
    if options["lam"] < 0:
        raise SceneError(f"[analyses.cycles] key 'lam' must be >= 0; got {options['lam']}")
    if options["method"] not in ("implicit", "events"):
        raise SceneError(
            f"[analyses.cycles] key 'method' must be 'implicit' or 'events'; got "
            f"{options['method']!r}"
        )
    for key, low in (("steps_per_cycle", 2), ("max_cycles", 1), ("n_initial_states", 1),
                     ("n_jobs", 0)):
        if options[key] < low:
            raise SceneError(f"[analyses.cycles] key {key!r} must be >= {low}; got {options[key]}")
    if dim == 3 and options["method"] != "implicit":
        raise SceneError("[analyses.cycles] key 'method' must be 'implicit' for dim = 3 (the "
                         "event path is 2-D only)")
    v0 = (_vector("initial_slip", options["initial_slip"], n, dim) if options["initial_slip"]
          else None)
    states = None
    if options["initial_slips"]:
        states = np.array([_vector("initial_slips", s, n, dim) for s in options["initial_slips"]])
    return v0, states


def run(ctx, options: dict) -> dict:
    from ...evolution import steady_cycle, uniqueness_study
    from ...evolution.cycles import solve_cycles
    from ...model.progress import described

    system, load = ctx.system, ctx.load
    n = system.n_nodes
    dim = getattr(system, "dim", 2)
    v0, states = _check(options, n, dim)
    lam = float(options["lam"])
    solver = dict(method=options["method"], steps_per_cycle=options["steps_per_cycle"],
                  tol=options["tol"])
    study = None
    if states is not None or options["n_initial_states"] > 1:
        if states is None:
            count = options["n_initial_states"]
            states = count  # sampled inside uniqueness_study
        study = uniqueness_study(
            system, load, lam, states, rng=options["seed"], n_jobs=options["n_jobs"] or None,
            max_cycles=options["max_cycles"], scale=options["sampling_scale"],
            solver="steady" if options["steady_solver"] else "cycles",
            progress=described(ctx.progress, f"uniqueness study at lam = {lam:.4g}: one run per "
                               "initial state", "run"), **solver,
        )
        ctx.output.write_table("uniqueness.csv", _from_one(study.table))
        cols = ([f"initial_slip_{j}_{c}" for j in range(n) for c in "xy"] if dim == 3
                else [f"initial_slip_{j}" for j in range(n)])
        v0 = study.table[cols].to_numpy(float)[0].reshape((n, 2) if dim == 3 else (n,))
    sc = None
    if options["steady_solver"]:
        ctx.log("direct steady-cycle solver (fixed point of the period map)")
        sc = steady_cycle(system, load, lam, v0, max_evaluations=options["max_cycles"], **solver)
        ctx.log(f"steady_cycle: {sc.status}: {sc.message}; {sc.n_evaluations} periods simulated")
        run_ = sc.run
    else:
        desc = f"cycles at lam = {lam:.4g} (stops at a steady state)"
        with _CycleProgress(ctx, options["max_cycles"], desc, _units(ctx)["energy"]) as cb:
            run_ = solve_cycles(system, load, lam, initial_slip=v0,
                                max_cycles=options["max_cycles"], progress=cb,
                                record_history=n == 2 and dim == 2 and options["plots"],
                                **solver)
    if run_ is not None and run_.status == "non_finite":  # overflow is a failure (issue 10)
        raise SolverError(f"[analyses.cycles] lam = {lam:g}: {run_.message}", partial=run_)
    summary = _summary(run_, lam, options, sc, study)
    exact = None
    if getattr(run_, "within_sampling_error", False):  # the bounds of the exact load decide
        from ...bounds.engine import shakedown_bounds

        exact = shakedown_bounds(system, load, separation=False)
    verdict = cycles_verdict(run_, lam, _units(ctx)["energy"], study, bounds=exact)
    summary = {"verdict": verdict, **summary}
    ctx.output.write_json("cycles.json", summary)
    ctx.output.write_table("dissipation.csv", _dissipation_table(run_))
    steady = run_.steady_table if run_.steady_table is not None else pd.DataFrame()
    ctx.output.write_table("steady_cycle.csv", _from_one(steady))
    if options["plots"]:
        _plots(ctx, run_, study, lam, options)
    keys = ("verdict", "steady_dissipation", "period", "shook_down", "stuck_nodes", "n_cycles",
            "status")
    out = {k: summary[k] for k in keys}
    if getattr(run_, "within_sampling_error", False):
        out["sampling_warning"] = run_.message  # the verdict lies within the sampling error
    if study is not None:
        out.update(unique_dissipation=study.unique_dissipation,
                   dissipation_spread=study.dissipation_spread,
                   fraction_shook_down=study.fraction_shook_down)
    return out


class _CycleProgress:
    """Drives one progress bar from ``solve_cycles``'s ``progress(cycle, max_cycles, W)`` callback."""

    def __init__(self, ctx, total, desc, energy):
        bar = getattr(ctx.progress, "bar", None)
        self._bar = bar(total=total, desc=desc, unit="cycle") if bar else None
        self._energy = energy

    def __call__(self, cycle, max_cycles, W):
        if self._bar is not None:
            self._bar.set_postfix_str(f"W = {W:.4g} {self._energy}", refresh=False)
            self._bar.update(1)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.close()
        return False


def _from_one(table):
    """A copy of a result table with nodes and initial states numbered from 1 (columns
    ``node``, ``state`` (the uniqueness study's initial state), ``stuck``,
    ``initial_slip_<j>``, ``steady_slip_<j>``), as in everything a person reads."""
    import re

    t = table.copy()
    for col in ("node", "state"):
        if col in t and pd.api.types.is_integer_dtype(t[col]):
            t[col] = t[col].astype(int) + 1
    if "stuck" in t:
        t["stuck"] = [",".join(str(int(j) + 1) for j in str(x).split(",") if j.strip() != "")
                      for x in t["stuck"]]
    pattern = re.compile(r"^(initial_slip|steady_slip|slip|gap)_(\d+)(_[xy])?$")
    return t.rename(columns=lambda c: pattern.sub(
        lambda m: f"{m[1]}_{int(m[2]) + 1}{m[3] or ''}", c))


def _dissipation_table(run):
    W = np.asarray(run.dissipation, float)
    change = np.asarray(getattr(run, "state_change", np.full(W.size, np.nan)), float)
    if change.size != W.size:
        change = np.resize(change, W.size) if change.size else np.full(W.size, np.nan)
    return pd.DataFrame({"cycle": np.arange(1, W.size + 1), "W": W, "state_change": change})


def _summary(run, lam, options, sc, study):
    d = {
        "lam": lam,
        "method": options["method"],
        "steps_per_cycle": options["steps_per_cycle"],
        "steady_dissipation": float(run.steady_dissipation),
        "period": int(run.period),
        "shook_down": bool(run.shook_down),
        "stuck_nodes": [int(j) + 1 for j in np.atleast_1d(run.stuck_nodes)],
        "node_numbering": "from 1",
        "n_cycles": int(run.n_cycles),
        "cycles_to_steady": getattr(run, "cycles_to_steady", None),
        "status": str(run.status),
        "message": str(getattr(run, "message", "")),
        "max_residual": getattr(run, "max_residual", None),
        "energy_identity": getattr(run, "energy_identity", None),
        "final_slip": np.asarray(run.final_slip, float),
    }
    if sc is not None:
        d["steady_solver"] = {
            "status": sc.status, "message": sc.message, "n_evaluations": sc.n_evaluations,
            "n_iterations": sc.n_iterations, "residual": sc.residual, "method": sc.method,
        }
        d["status"] = sc.status
    if study is not None:
        d["uniqueness"] = {
            "n_states": study.n_states,
            "unique_dissipation": study.unique_dissipation,
            "dissipation_spread": study.dissipation_spread,
            "time_varying_spread": study.time_varying_spread,
            "slip_spread": study.slip_spread,
            "reaction_spread": study.reaction_spread,
            "fraction_shook_down": study.fraction_shook_down,
            "fraction_steady": study.fraction_steady,
            "summary": study.summary(),
        }
    for k, v in list(d.items()):
        if hasattr(v, "item") and np.ndim(v) == 0:
            d[k] = v.item()
        elif not isinstance(v, (dict, list, str, int, float, bool, np.ndarray, type(None))):
            d[k] = str(v)
    return d


def _units(ctx) -> dict:
    scene = getattr(ctx, "scene", None)
    if scene is not None:
        return scene.units
    return {"force": "[force]", "length": "[length]", "energy": "[force x length]"}


def _plots(ctx, run, study, lam, options):
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ...plotting.cycles import (
        plot_dissipation,
        plot_node_states,
        plot_steady_cycle,
        plot_trajectory,
        plot_uniqueness,
    )

    units = _units(ctx)
    fig, ax = plt.subplots(figsize=(6, 4))
    plot_dissipation(run, ax, log=options["log_scale"], units=units)
    ax.set_title(f"dissipation per cycle at lam = {lam:.4g}", fontsize=10)
    ctx.output.save_figure("dissipation.png", fig)
    has_steady = run.steady_table is not None and len(run.steady_table) > 0
    maps = has_steady and getattr(ctx.system, "dim", 2) == 3 and _has_positions(ctx.model)
    if maps:  # a 3-D body with node positions: maps of the contact patch
        _patch_plots(ctx, run, lam, units)
    elif has_steady:
        fig, axs = plt.subplots(2, 1, sharex=True, figsize=(6.4, 5.6))
        src = run
        if getattr(ctx.system, "dim", 2) == 3:  # magnitudes |v|, |q| of the 3-D columns
            t = run.steady_table
            src = t.assign(slip=np.hypot(t["slip_x"], t["slip_y"]), q=np.hypot(t["q_x"], t["q_y"]))
        plot_steady_cycle(src, axs, units=units)
        if src is not run:
            axs[0].set_ylabel(f"|v| {units['length']}")
            axs[1].set_ylabel(f"|q| (solid), p (dashed) {units['force']}")
        axs[0].set_title(f"steady cycle at lam = {lam:.4g}"
                         + axs[0].get_title()[len("steady cycle"):], fontsize=10)
        ctx.output.save_figure("steady_cycle.png", fig)
        fig, ax = plt.subplots(figsize=(6.4, 3.5))
        plot_node_states(src, ax)
        ctx.output.save_figure("node_states.png", fig)
    else:
        ctx.log("no steady cycle reached: steady_cycle.png and node_states.png not written")
    if getattr(ctx.system, "dim", 2) == 3 and has_steady and not maps:  # per-node cones (3-D)
        from ...plotting.cones import plot_cone_paths, plot_slip_trajectories

        axs = plot_cone_paths(run, ctx.system)
        axs[0].figure.suptitle(f"tangential reaction q / p in the friction cone, lam = {lam:.4g}",
                               fontsize=10, y=1.02)
        ctx.output.save_figure("cone_paths.png", axs[0].figure)
        fig, ax = plt.subplots(figsize=(5.5, 5))
        plot_slip_trajectories(run, ax=ax, units=units)
        ctx.output.save_figure("slip_trajectories.png", fig)
    if ctx.system.n_nodes == 2 and getattr(ctx.system, "dim", 2) == 2:
        for space, name in (("v", "trajectory.png"), ("tau", "trajectory_tau.png")):
            fig, ax = plt.subplots(figsize=(5.5, 5))
            plot_trajectory(ctx.system, ctx.load, lam, run, ax, space=space, units=units)
            ax.set_title(f"trajectory at lam = {lam:.4g}", fontsize=10)
            ctx.output.save_figure(name, fig)
    if study is not None:
        fig, ax = plt.subplots(figsize=(6, 4))
        plot_uniqueness(study, ax, units=units)
        ctx.output.save_figure("uniqueness.png", fig)


def _has_positions(model) -> bool:
    """The model gives node positions for contact patch maps (3-D FE bodies)."""
    from ...plotting.contact_patch import patch_coordinates

    try:
        patch_coordinates(model)
    except Exception:  # noqa: BLE001 - a 3-D system without node positions: no maps
        return False
    return True


def _grip_amplitude(ctx):
    """The amplitude [length] of the scene's cyclic load when it is one prescribed cosine
    displacement along ``x`` (``[load.cyclic] displacement = {"<body>:<surface>" = [u, 0, 0]}``,
    e.g. a lap joint's grip): the abscissa of the force loop.  ``None`` otherwise."""
    load = getattr(getattr(ctx, "scene", None), "load", None) or {}
    cyc = load.get("cyclic") if isinstance(load, dict) else None
    if not isinstance(cyc, dict) or set(cyc) != {"displacement"} or "cyclic_sin" in load:
        return None
    disp = cyc["displacement"]
    if not isinstance(disp, dict) or len(disp) != 1:
        return None
    u = np.asarray(next(iter(disp.values())), float).ravel()
    if u.size < 2 or u[0] == 0 or np.any(u[1:] != 0):
        return None
    return float(u[0])


def _patch_plots(ctx, run, lam, units):
    """The 3-D steady cycle as maps of the contact patch (and the node-state image)."""
    import matplotlib.pyplot as plt

    from ...plotting.contact_patch import (
        plot_force_loop,
        plot_loop_opening,
        plot_patch_states,
        plot_stuck_zone,
    )
    from ...plotting.cycles import plot_node_states

    fig, ax = plt.subplots(figsize=(6.4, 3.5))
    plot_node_states(run, ax)
    ctx.output.save_figure("node_states.png", fig)
    u1 = _grip_amplitude(ctx)
    fig, axs = plt.subplots(1, 2, figsize=(12, 4.5))
    plot_force_loop(run, lam, axs[0], units=units, displacement=u1)
    plot_loop_opening(run, lam, axs[1], units=units, displacement=u1)
    fig.tight_layout()
    ctx.output.save_figure("force_loop.png", fig)
    tab = run.steady_table
    qmax = float(np.hypot(tab["q_x"], tab["q_y"]).max()) or 1.0
    fig, axs = plt.subplots(2, 2, figsize=(9, 8.4), sharex=True, sharey=True)
    for ax, t in zip(axs.ravel(), (0.0, 0.25, 0.5, 0.75), strict=True):
        plot_patch_states(ctx.model, run, t, ax, units=units, legend=False)
        if u1 is not None:  # the grip's displacement at that instant
            u = lam * u1 * np.cos(2 * np.pi * t)
            ax.set_title(f"{ax.get_title()}: u = {0.0 if abs(u) < 1e-12 * abs(u1) else u:.3g} "
                         f"{units['length']}", fontsize=10)
    fig.legend(*axs[0, 0].get_legend_handles_labels(), loc="lower center", ncol=3,
               fontsize="small")
    fig.suptitle(f"contact patch over the steady cycle at lam = {lam:.4g}: node states, arrows "
                 f"q (longest {qmax:.3g} {units['force']})", fontsize=10)
    ctx.output.save_figure("contact_patch.png", fig)
    fig, ax = plt.subplots(figsize=(7.5, 5))
    plot_stuck_zone(ctx.model, run, ax, units=units)
    ctx.output.save_figure("stuck_zone.png", fig)
