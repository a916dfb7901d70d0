"""The ``stability`` analysis: MCEIP-mu (critical friction) and MCEIP-lam (growth rates).

MCEIP is the *mixed complementarity eigenvalue problem* of a frictional equilibrium (seed 000,
seed 001; :mod:`shakedown.stability`): with some nodes slipping, find the smallest friction
``mu*`` at which a non-zero perturbation of the slips can grow while the slipping nodes stay
in the friction cone (MCEIP-mu, quasi-static divergence), and, with a mass, the growth rates
``s >= 0`` of perturbations ``~ e^(s t)`` at a given friction (MCEIP-lam).  Below ``mu*`` the
equilibrium is stable against divergence.

``[analyses.stability]`` classifies the contact nodes (every node in impending slip with the
given directions, hand-given states, or the welded state of the load at a time), solves
MCEIP-mu for the critical friction ``mu*`` and its mode, and, when ``growth_rate_max > 0`` and
the model has a mass (an FE scene condensed with ``mass = true``), the branches ``s(mu)`` with
their returning points and the growth rates at ``mu``.  Writes ``stability.json``,
``partition.csv``, ``mode.csv``, ``curves.csv`` and the plots ``mode.png``, ``growth_rates.png``.
``mode.csv`` has per slip node (numbered from 1) its direction ``chi``, ``slip_mode`` (the mode
``x = chi v'``, the node's slip along its slip direction, scaled to ``max |x| = 1``) and
``cone_unloading`` (``y = chi q' + mu* p'``, how fast the node leaves its friction cone; 0 where
it slips in the mode).
Its result starts with a verdict ("stable: friction 0.5 is below mu* = 1.955").  The growth
rate is called ``lam`` in the Python API (:func:`shakedown.stability.growth_rates`) and ``s``
(``growth_rate``) in everything this analysis prints or writes; ``lam`` stays the load factor.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ...model.errors import SceneError
from ...model.numbers import sig

OPTIONS = {
    "partition": (str, "all-slip", "'all-slip', 'states' (see states) or 'welded'"),
    "chi": (list, [], "slip direction(s) +1/-1 (one value or one per node; default +1)"),
    "states": (list, [], "per-node 'free'/'stick'/'slip'/'frictionless' (partition='states')"),
    "time": (float, 0.0, "time (cycles) of the welded state (partition='welded')"),
    "load_factor": (float, 1.0, "load factor lam of the welded state (partition='welded')"),
    "method": (str, "auto", "MCEIP method: auto, enumeration, linear, power, active-set, ..."),
    "mu": (float, 0.0, "> 0: growth rates s at this friction (needs growth_rate_max > 0)"),
    "growth_rate_max": (float, 0.0, "> 0: scan growth rates s in [0, growth_rate_max] "
                                    "[1/time] for the branches s(mu); needs a mass"),
    "n_growth_rates": (int, 41, "points of the growth-rate scan"),
    "plots": (bool, True, "write PNG plots"),
}

#: Old option names (0.1) still accepted in scene files and --set.
ALIASES = {"lam_max": "growth_rate_max", "n_lam": "n_growth_rates"}


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
        from ...model.validation import check_load_factor  # (issue 24: lam < 0 refused)

        try:
            lam = check_load_factor(options["load_factor"], ctx.load)
        except ValueError as exc:
            raise SceneError(f"[analyses.stability] key 'load_factor': {exc}") from None
        q, p = ctx.load.evaluate(np.array(options["time"]), lam)
        return classify_nodes(np.zeros(n), q, p, ctx.system.friction)
    raise SceneError(
        f"[analyses.stability] key 'partition' must be 'all-slip', 'states' or 'welded'; "
        f"got {kind!r}"
    )


def _fmt(x) -> str:
    return sig(x)


def stability_verdict(res, friction: float, part, growth=None) -> str:
    """Plain sentences: stable / unstable against divergence, with ``mu*`` and growth rates.

    Parameters
    ----------
    res : MCEIPResult
        MCEIP-mu of ``part``.
    friction : float
        The system's friction at the slip nodes (largest value if it varies).
    part : NodePartition
    growth : GrowthRates, optional
    """
    n_slip = int(part.slip.size)
    who = f"{n_slip} slipping node{'s' * (n_slip != 1)}"
    if not res.found:
        text = (f"Stable: no critical friction exists for this partition ({who}; mu* = inf), "
                f"so no friction makes it diverge ({res.message}).")
    elif friction < res.mu:
        text = (f"Stable: friction {_fmt(friction)} is below the critical friction mu* = "
                f"{_fmt(res.mu)} ({who}); a divergence mode appears only at mu >= mu*.")
    else:
        text = (f"Unstable: friction {_fmt(friction)} is at or above the critical friction "
                f"mu* = {_fmt(res.mu)} ({who}): a divergence mode exists, in which "
                f"{int(res.support.size)} of them slip.")
        if growth is None:
            text += (" Its growth rate needs a mass: an FE scene with mass = true and "
                     "growth_rate_max > 0, mu > 0.")
    if growth is not None:
        rates = np.asarray(growth.lam, float)
        if rates.size:
            text += (f" At friction {_fmt(growth.mu)} the largest growth rate is s = "
                     f"{_fmt(rates.max())} [1/time] (perturbations grow like e^(s t)"
                     + (f"; {rates.size} rates in all" if rates.size > 1 else "") + ").")
        else:
            top = float(growth.curves.lam[-1])
            text += (f" At friction {_fmt(growth.mu)} no growth rate s <= {_fmt(top)} "
                     "[1/time] exists (no divergence in the scanned range).")
    return text


def _curves_table(curves):
    return curves.table().rename(columns={"lam": "growth_rate"})


def run(ctx, options: dict) -> dict:
    from ...stability import METHODS, growth_rates, lam_mu_curves, mceip_mu

    options = dict(options)
    for old, new in ALIASES.items():  # options given by their 0.1 names
        if old in options:
            options[new] = options.pop(old)
    if options["method"] not in METHODS:
        raise SceneError(
            f"[analyses.stability] key 'method' must be one of {METHODS}; got {options['method']!r}"
        )
    part = _partition(ctx, options)
    table = part.table()
    if "node" in table:
        table["node"] = table["node"].astype(int) + 1
    ctx.output.write_table("partition.csv", table)
    if part.slip.size == 0:
        verdict = ("Stable: no node slips in this partition, so friction cannot make it "
                   "diverge (mu* = inf).")
        summary = {"verdict": verdict, "status": "no slip node", "mu_star": float("inf"),
                   **part.counts()}
        ctx.output.write_json("stability.json", summary)
        return summary
    with ctx.progress.phase(f"MCEIP-mu on {part.slip.size} slip nodes ({options['method']})") \
            if hasattr(ctx.progress, "phase") else _nothing():
        res = mceip_mu(ctx.system.K, part, method=options["method"])
    friction = float(np.max(ctx.system.friction[part.slip]))
    summary = {
        "status": res.status, "mu_star": res.mu, "actual_friction": friction,
        "method": res.method, "verified": res.verified, "certified_minimal": res.minimal,
        "support_size": int(res.support.size), "n_slip": int(part.slip.size),
        "unloading_nodes": [int(j) + 1 for j in res.unloading_nodes] if res.found else [],
        "residual": res.residual, "sign_violation": res.sign_violation,
        "complementarity": res.complementarity, "message": res.message,
        **{f"n_{k}": v for k, v in part.counts().items()},
        "borderline_nodes": [int(j) + 1 for j in part.borderline],
        "node_numbering": "from 1",
    }
    if res.found:
        ctx.output.write_table("mode.csv", pd.DataFrame(
            {"node": np.asarray(res.nodes) + 1, "chi": res.chi, "slip_mode": res.mode,
             "cone_unloading": res.y}))
    figs = {}
    growth = None
    if options["growth_rate_max"] > 0:
        model = ctx.model
        if model is None or getattr(model, "M", None) is None or not hasattr(
                model, "dynamic_stiffness"):
            raise SceneError(
                "[analyses.stability] key 'growth_rate_max' > 0 needs a mass: an FE model "
                "condensed with mass (model key mass = true)"
            )
        if options["n_growth_rates"] < 2:
            raise SceneError("[analyses.stability] key 'n_growth_rates' must be >= 2; got "
                             f"{options['n_growth_rates']}")
        rates = np.linspace(0.0, options["growth_rate_max"], options["n_growth_rates"])
        curves = lam_mu_curves(model, part, rates, progress=_scan(ctx))
        ctx.output.write_table("curves.csv", _curves_table(curves))
        summary["returning_points"] = [
            {"growth_rate": r.lam, "mu": r.mu, "kind": r.kind} for r in curves.returning_points]
        if options["mu"] > 0:
            growth = growth_rates(model, part, options["mu"], curves=curves)
            summary["growth_rates"] = growth.lam.tolist()
            summary["growth_status"] = growth.status
        if options["plots"]:
            from ...plotting.stability import plot_lam_mu

            figs["growth_rates.png"] = plot_lam_mu(
                curves, mu=options["mu"] or None, growth=growth, mu_star=res.mu if res.found
                else None, friction=friction).figure
    if options["plots"] and res.found:
        from ...plotting.stability import plot_mode

        coords = getattr(ctx.model, "node_coordinates", None)
        figs["mode.png"] = plot_mode(res, coords).figure
    for name, fig in figs.items():
        ctx.output.save_figure(name, fig)
    verdict = stability_verdict(res, friction, part, growth)
    summary = {"verdict": verdict, **summary}
    ctx.output.write_json("stability.json", summary)
    return summary


def _scan(ctx):
    """The progress wrapper of the growth-rate scan, with a description a person can read."""
    from ...model.progress import described

    return described(ctx.progress, "growth-rate scan s (all MCEIP solutions at each s)", "s")


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
