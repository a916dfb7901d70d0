"""The ``bounds`` analysis: shakedown load factors, activity intervals, plots."""

from __future__ import annotations

import numpy as np

from ...bounds.engine import shakedown_bounds

OPTIONS = {
    "lam": (float, -1.0, "load factor of the reported safe state (< 0: lam1 / 2)"),
    "plot_lams": (list, [], "load factors of extra safe-region pictures (two-node systems)"),
    "adjacency": (bool, True, "compute lam_adj (N LPs)"),
    "plots": (bool, True, "write PNG plots"),
}


def run(ctx, options: dict) -> dict:
    lam = options["lam"]
    b = shakedown_bounds(
        ctx.system, ctx.load, lam=None if lam < 0 else lam, adjacency=options["adjacency"]
    )
    ctx.log(b.summary())
    ctx.output.write_json("bounds.json", b.to_dict())
    ctx.output.write_table("constraints.csv", b.table())
    if options["plots"]:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        from ...plotting.bounds import plot_constraints_2d, plot_region_vs_lam

        fig, ax = plt.subplots(figsize=(7, 4))
        plot_region_vs_lam(b, system=ctx.system, load=ctx.load, ax=ax)
        ctx.output.save_figure("bounds_vs_lam.png", fig)
        if ctx.system.n_nodes == 2:
            lams = [float(x) for x in options["plot_lams"]] or [
                x for x in (0.0, b.safe_lam, 0.5 * (b.lam1 + b.lam2) if np.isfinite(b.lam2)
                            else None) if x is not None
            ]
            for i, x in enumerate(lams):
                fig, ax = plt.subplots(figsize=(5.5, 5))
                plot_constraints_2d(ctx.system, ctx.load, x, ax=ax)
                ctx.output.save_figure(f"safe_region_{i}.png", fig)
    d = b.to_dict()
    return {k: d[k] for k in ("lam1", "lam2", "lam_adj", "status", "limiting_constraint",
                              "lam_separation", "safe_margin", "n_lps", "solve_time_s")}
