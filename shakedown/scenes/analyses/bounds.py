"""The ``bounds`` analysis: shakedown load factors, activity intervals, plots.

``[analyses.bounds]`` runs :func:`shakedown.shakedown_bounds` and writes ``bounds.json`` (full
precision), ``constraints.csv`` (the activity interval of each of the ``2N`` extreme
constraints; column ``lam_high_exact`` says where ``lam_high`` is exact and where it is a proven
lower bound, see ``exact_intervals``), ``bounds_vs_lam.png`` and, for two nodes,
``safe_region_<i>.png``.  Its result
starts with a verdict in plain sentences (:func:`shakedown.bounds.verdict.bounds_verdict`).
Nodes are numbered from 1 in every file and message (constraint ``I_1`` belongs to node 1).

3-D systems (``dim = 3``): :func:`shakedown.shakedown_bounds` returns a
:class:`~shakedown.bounds.cones.result.ConeBounds` (``lam2`` certified on the friction cones,
``lam_adj_cone`` with ``adjacency``); ``bounds.json`` and ``constraints.csv`` (one row per node:
its worst time at ``lam2`` and its cuts) are written, no plots.  With ``contact = "static"``
(both dimensions) the nodes that the static load alone opens are condensed out as free
(:func:`shakedown.model.open_nodes.condense_open`): the bounds are then those of the closed
nodes, exact while the others stay open, and ``bounds.json`` records the closed nodes and the
smallest gap of the open ones in the safe state found.
"""

from __future__ import annotations

import numpy as np

from ...bounds.engine import shakedown_bounds
from ...bounds.verdict import bounds_verdict, constraint_name, fmt
from ...model.errors import SceneError

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
    "contact": (str, "all", "'all': every node in contact (the theory of the bounds); 'static': "
                            "the nodes open under the static load are condensed out as free "
                            "(exact while they stay open)"),
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


def _closed_under_static(system, load):
    """The nodes in contact after one step from the virgin state to the static load."""
    import numpy as np

    from ...evolution import solve_step
    from ...evolution.cone_step import ConeStepSolver

    n = system.n_nodes
    if system.dim == 3:
        res = ConeStepSolver(system).solve(np.zeros((n, 2)), load.q0, load.p0)
    else:
        res = solve_step(system, np.zeros(n), load.q0, load.p0)
    if not res.success:
        raise SceneError(f"[analyses.bounds] contact = 'static': the step to the static load "
                         f"failed ({res.message})")
    return np.flatnonzero(np.asarray(res.gap) <= 0.0)


def _restrict(ctx, options):
    """``(system, load, closed subsystem or None)`` as ``contact`` asks."""
    if options["contact"] not in ("all", "static"):
        raise SceneError(f"[analyses.bounds] contact = {options['contact']!r}: choose 'all' or "
                         "'static'")
    if options["contact"] == "all":
        return ctx.system, ctx.load, None
    from ...model.open_nodes import condense_open

    closed = _closed_under_static(ctx.system, ctx.load)
    if closed.size == 0:
        raise SceneError("[analyses.bounds] contact = 'static': the static load opens every "
                         "node; nothing to bound")
    cs = condense_open(ctx.system, ctx.load, closed)
    return cs.system, cs.load, cs


def _contact_note(cs, b) -> tuple[str, dict]:
    """Verdict suffix and JSON fields of a run on the closed nodes."""
    import numpy as np

    nc, n = cs.closed.size, cs.closed.size + cs.open.size
    d = {"contact": "static", "closed_nodes": [int(i) + 1 for i in cs.closed],
         "n_closed": int(nc), "n_nodes_full": int(n)}
    if cs.open.size == 0:
        return " (Every node is in contact under the static load: nothing condensed out.)", d
    note = (f" (Bounds of the {nc} of {n} nodes in contact under the static load; the other "
            f"{n - nc} are condensed out as free, exact while they stay open.")
    if np.size(b.safe_state) and np.isfinite(b.safe_lam):
        slip = np.asarray(b.safe_state, float)
        gmin = float(cs.open_gaps(slip, np.zeros(nc), b.safe_lam).min())
        d["open_gap_min_safe_state"] = gmin
        scale = max(float(np.abs(slip).max()), 1e-300)
        if gmin < -1e-9 * scale:
            note += (f" The safe state found at lam = {fmt(b.safe_lam)} would close some of "
                     f"the open nodes (smallest gap {fmt(gmin)}): above lam2 the system cannot "
                     "shake down with those nodes open; below it, shaking down may need some "
                     "of them closed.)")
        else:
            note += (f" The safe state found at lam = {fmt(b.safe_lam)} keeps every open node "
                     "open over the cycle.)")
    else:
        note += ")"
    return note, d


def run(ctx, options: dict) -> dict:
    system, load, cs = _restrict(ctx, options)
    if system.dim == 3:
        return _run_3d(ctx, options, system, load, cs)
    lam = options["lam"]
    b = shakedown_bounds(
        system, load, lam=None if lam < 0 else lam, adjacency=options["adjacency"],
        intervals=True if options["exact_intervals"] else "lam1",
        # a progress line per stage where the bounds take more than a few seconds (issue 26)
        progress=ctx.progress if system.n_nodes >= PROGRESS_NODES else None,
    )
    verdict = bounds_verdict(b, adjacency=options["adjacency"])
    d = _node_numbers(b, b.to_dict())
    if cs is not None:
        note, extra = _contact_note(cs, b)
        verdict = verdict + note
        d.update(extra)
    d["verdict"] = verdict
    ctx.output.write_json("bounds.json", d)
    ctx.output.write_table("constraints.csv", _table(b))
    if options["plots"] and cs is None:
        _plots(ctx, b, options)
    out = {"verdict": verdict}
    out.update({k: d[k] for k in ("lam1", "lam2", "lam_adj", "status", "limiting_constraint",
                                  "adjacency_node", "lam_separation", "safe_margin", "n_lps",
                                  "solve_time_s")})
    return out


def _run_3d(ctx, options, system, load, cs) -> dict:
    """The 3-D bounds: ``lam2`` on the cones, ``lam_adj_cone`` with ``adjacency``."""
    lam = options["lam"]
    # intervals=False: lam1 on the polygons is not asked for (lam_adj_cone is the candidate)
    b = shakedown_bounds(system, load, lam=None if lam < 0 else lam,
                         adjacency=options["adjacency"], intervals=False)
    verdict = b.verdict()
    d = b.to_dict()
    if cs is not None:
        note, extra = _contact_note(cs, b)
        verdict = verdict + note
        d.update(extra)
    d["node_numbering"] = "from 1"
    d["verdict"] = verdict
    ctx.output.write_json("bounds.json", d)
    ctx.output.write_table("constraints.csv", b.table())
    out = {"verdict": verdict}
    out.update({k: d[k] for k in ("lam2", "lam2_lower", "lam2_upper", "lam_adj_cone", "status",
                                  "safe_margin", "solve_time_s")})
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
