"""The ``bounds`` analysis: shakedown load factors, activity intervals, plots.

``[analyses.bounds]`` runs :func:`shakedown.shakedown_bounds` and writes ``bounds.json`` (full
precision), ``constraints.csv`` (the activity interval of each of the ``2N`` extreme
constraints; column ``lam_high_exact`` says where ``lam_high`` is exact and where it is a proven
lower bound, see ``exact_intervals``), ``bounds_vs_lam.png`` and, for two nodes,
``safe_region_<i>.png``.  Its result
starts with a verdict in plain sentences (:func:`shakedown.bounds.verdict.bounds_verdict`).
Nodes are numbered from 1 in every file and message (constraint ``I_1`` belongs to node 1).
"""

from __future__ import annotations

import numpy as np

from ...bounds.engine import shakedown_bounds
from ...bounds.verdict import bounds_verdict, constraint_name

#: ``{key: (type, default, meaning)}``; ``shakedown bounds --help`` and the README table are
#: generated from it.
OPTIONS = {
    "lam": (float, -1.0, "load factor of the reported safe state (< 0: lam1 / 2)"),
    "plot_lams": (list, [], "load factors of the safe-region pictures (two-node systems; "
                            "empty: 0, the safe state's lam and (lam1 + lam2) / 2)"),
    "adjacency": (bool, True, "compute lam_adj (N more LPs)"),
    "exact_intervals": (bool, False, "every activity interval exactly (default: lam_high exact "
                                     "only where lam1 needs it, a proven lower bound elsewhere; "
                                     "column lam_high_exact of constraints.csv)"),
    "plots": (bool, True, "write PNG plots"),
}


def _node_numbers(b, d: dict) -> dict:
    """``to_dict()`` with every node numbered from 1 (computed from the 0-based API fields)."""
    n = b.n_nodes
    k = int(b.limiting_constraint)
    d = dict(d)
    d["limiting_constraint"] = constraint_name(k, n) if k >= 0 else ""
    d["adjacency_node"] = int(b.adjacency_node) + 1 if b.adjacency_node >= 0 else None
    d["separation_nodes"] = [int(j) + 1 for j in b.separation_nodes]
    d["node_numbering"] = "from 1"
    return d


def _table(b):
    t = b.table()
    n = b.n_nodes
    t["constraint"] = [constraint_name(k, n) for k in range(2 * n)]
    t["node"] = np.concatenate([np.arange(1, n + 1), np.arange(1, n + 1)])
    return t


#: Nodes from which the bounds show their stages on the progress display (about 2 s for a
#: 300-crack network, one core).
PROGRESS_NODES = 300


def run(ctx, options: dict) -> dict:
    lam = options["lam"]
    b = shakedown_bounds(
        ctx.system, ctx.load, lam=None if lam < 0 else lam, adjacency=options["adjacency"],
        intervals=True if options["exact_intervals"] else "lam1",
        # a progress line per stage where the bounds take more than a few seconds (issue 26)
        progress=ctx.progress if ctx.system.n_nodes >= PROGRESS_NODES else None,
    )
    verdict = bounds_verdict(b, adjacency=options["adjacency"])
    d = _node_numbers(b, b.to_dict())
    d["verdict"] = verdict
    ctx.output.write_json("bounds.json", d)
    ctx.output.write_table("constraints.csv", _table(b))
    if options["plots"]:
        _plots(ctx, b, options)
    out = {"verdict": verdict}
    out.update({k: d[k] for k in ("lam1", "lam2", "lam_adj", "status", "limiting_constraint",
                                  "adjacency_node", "lam_separation", "safe_margin", "n_lps",
                                  "solve_time_s")})
    return out


def _plots(ctx, b, options):
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ...plotting.bounds import plot_constraints_2d, plot_region_vs_lam

    units = ctx.scene.units if getattr(ctx, "scene", None) is not None else None
    fig, ax = plt.subplots(figsize=(7, 4))
    plot_region_vs_lam(b, system=ctx.system, load=ctx.load, ax=ax, units=units)
    ctx.output.save_figure("bounds_vs_lam.png", fig)
    if ctx.system.n_nodes != 2:
        return
    lams = [float(x) for x in options["plot_lams"]] or [
        x for x in (0.0, b.safe_lam, 0.5 * (b.lam1 + b.lam2) if np.isfinite(b.lam2) else None)
        if x is not None and np.isfinite(x)
    ]
    for i, x in enumerate(dict.fromkeys(lams)):
        fig, ax = plt.subplots(figsize=(5.5, 5))
        # mark the reported safe state (none when no state is safe)
        at_safe = np.size(b.safe_state) == 2 and np.isfinite(b.safe_state).all() and x == b.safe_lam
        plot_constraints_2d(ctx.system, ctx.load, x, ax=ax, units=units,
                            state=b.safe_state if at_safe else None, state_label="safe state")
        ctx.output.save_figure(f"safe_region_{i}.png", fig)
