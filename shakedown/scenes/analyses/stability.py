"""The ``stability`` analysis: MCEIP-mu (critical friction) and MCEIP-lam (growth rates).

``[analyses.stability]`` classifies the contact nodes (every node in impending slip with the
given directions, hand-given states, or the welded state of the load at a time), solves
MCEIP-mu for the critical friction ``mu*`` and its mode, and, when ``lam_max > 0`` and the
model has a mass (an FE scene condensed with ``mass = true``), the branches ``lam(mu)`` with
their returning points and the growth rates at ``mu``.  Writes ``stability.json``,
``partition.csv``, ``mode.csv``, ``curves.csv`` and the plots ``mode.png``, ``lam_mu.png``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ...model.errors import SceneError

OPTIONS = {
    "partition": (str, "all-slip", "'all-slip', 'states' (see states) or 'welded'"),
    "chi": (list, [], "slip direction(s) +1/-1 (one value or one per node; default +1)"),
    "states": (list, [], "per-node 'free'/'stick'/'slip'/'frictionless' (partition='states')"),
    "time": (float, 0.0, "time (cycles) of the welded state (partition='welded')"),
    "load_factor": (float, 1.0, "load factor of the welded state (partition='welded')"),
    "method": (str, "auto", "MCEIP method: auto, enumeration, linear, power, active-set, ..."),
    "mu": (float, 0.0, "> 0: growth rates at this friction (needs lam_max > 0)"),
    "lam_max": (float, 0.0, "> 0: scan lam in [0, lam_max] for the lam(mu) branches"),
    "n_lam": (int, 41, "points of the lam scan"),
    "plots": (bool, True, "write PNG plots"),
}


def _partition(ctx, options):
    from ...stability import NodePartition, classify_nodes

    n = ctx.system.n_nodes
    chi = options["chi"] or [1.0]
    try:
        chi = np.broadcast_to(np.asarray(chi, float), (n,))
    except ValueError:
        raise SceneError(
            f"[analyses.stability] key 'chi' must have 1 or {n} values; got {options['chi']!r}"
        ) from None
    if np.any(np.abs(chi) != 1):
        raise SceneError(f"[analyses.stability] key 'chi' must be +1 or -1; got {chi.tolist()}")
    kind = options["partition"]
    if kind == "all-slip":
        return NodePartition.all_slip(n, chi)
    if kind == "states":
        if len(options["states"]) != n:
            raise SceneError(
                f"[analyses.stability] key 'states' must list {n} states; got {options['states']!r}"
            )
        try:
            return NodePartition.from_states(options["states"], chi)
        except ValueError as exc:
            raise SceneError(f"[analyses.stability] key 'states': {exc}") from None
    if kind == "welded":
        q, p = ctx.load.evaluate(np.array(options["time"]), options["load_factor"])
        return classify_nodes(np.zeros(n), q, p, ctx.system.friction)
    raise SceneError(
        f"[analyses.stability] key 'partition' must be 'all-slip', 'states' or 'welded'; "
        f"got {kind!r}"
    )


def run(ctx, options: dict) -> dict:
    from ...stability import METHODS, growth_rates, lam_mu_curves, mceip_mu

    if options["method"] not in METHODS:
        raise SceneError(
            f"[analyses.stability] key 'method' must be one of {METHODS}; got {options['method']!r}"
        )
    part = _partition(ctx, options)
    ctx.output.write_table("partition.csv", part.table())
    if part.slip.size == 0:
        summary = {"status": "no slip node", "mu_star": float("inf"), **part.counts()}
        ctx.output.write_json("stability.json", summary)
        return summary
    res = mceip_mu(ctx.system.K, part, method=options["method"])
    ctx.log(str(res))
    summary = {
        "status": res.status, "mu_star": res.mu, "method": res.method,
        "verified": res.verified, "certified_minimal": res.minimal,
        "support_size": int(res.support.size), "n_slip": int(part.slip.size),
        "unloading_nodes": res.unloading_nodes.tolist() if res.found else [],
        "residual": res.residual, "sign_violation": res.sign_violation,
        "complementarity": res.complementarity, "message": res.message,
        "actual_friction": float(np.max(ctx.system.friction)),
        **{f"n_{k}": v for k, v in part.counts().items()},
        "borderline_nodes": part.borderline.tolist(),
    }
    if res.found:
        ctx.output.write_table("mode.csv", pd.DataFrame(
            {"node": res.nodes, "chi": res.chi, "x": res.mode, "y": res.y}))
    fig_mode = fig_curves = None
    if options["lam_max"] > 0:
        model = ctx.model
        if model is None or getattr(model, "M", None) is None or not hasattr(
                model, "dynamic_stiffness"):
            raise SceneError(
                "[analyses.stability] key 'lam_max' > 0 needs a mass: an FE model condensed "
                "with mass (model key mass = true)"
            )
        if options["n_lam"] < 2:
            raise SceneError(f"[analyses.stability] key 'n_lam' must be >= 2; got {options['n_lam']}")
        lams = np.linspace(0.0, options["lam_max"], options["n_lam"])
        curves = lam_mu_curves(model, part, lams, progress=ctx.progress)
        ctx.output.write_table("curves.csv", curves.table())
        summary["returning_points"] = [
            {"lam": r.lam, "mu": r.mu, "kind": r.kind} for r in curves.returning_points]
        growth = None
        if options["mu"] > 0:
            growth = growth_rates(model, part, options["mu"], curves=curves)
            summary["growth_rates"] = growth.lam.tolist()
            summary["growth_status"] = growth.status
        if options["plots"]:
            from ...plotting.stability import plot_lam_mu

            ax = plot_lam_mu(curves, mu=options["mu"] or None, growth=growth)
            fig_curves = ax.figure
    if options["plots"] and res.found:
        from ...plotting.stability import plot_mode

        coords = getattr(ctx.model, "node_coordinates", None)
        fig_mode = plot_mode(res, coords).figure
    for name, fig in (("mode.png", fig_mode), ("lam_mu.png", fig_curves)):
        if fig is not None:
            ctx.output.save_figure(name, fig)
            import matplotlib.pyplot as plt

            plt.close(fig)
    ctx.output.write_json("stability.json", summary)
    return summary
