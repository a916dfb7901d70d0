"""The ``sweep`` analysis: the Monte Carlo crack-network study (issue 4; seed 002 Fig. 11).

``shakedown sweep SCENE`` (and the default job of ``shakedown run``) draws
``n_realisations`` crack sets with the scene's ``[model]`` keys (``kind = "crack_network"``),
computes ``lam1``, ``lam2`` of each, then the steady dissipation ``W*`` of every (realisation,
load factor, initial state), in parallel (local processes, or a Dask cluster with
``scheduler``).  Rows are appended to ``sweep_store/`` in the output folder as they arrive: the
same command run again resumes an interrupted sweep (``fresh = true`` starts over).

Writes ``sweep_runs.csv`` (and ``.parquet``), ``sweep_summary.csv`` (min / max ``W*`` per
realisation and ``lam``), ``sweep_realisations.csv``, ``sweep.json``,
``dissipation_vs_lam.png`` and ``fractions_vs_lam.png``; prints the summary table.

The scene's realisations are drawn from child seeds of ``[model] seed``
(``SeedSequence(seed).spawn``), so realisation 0 is not the crack set that the other analyses
of the scene see (that one is drawn from ``seed`` itself).
"""

from __future__ import annotations

import shutil

OPTIONS = {
    "n_realisations": (int, 1, "number of random crack sets"),
    "lams": ((str, list), "auto", "'auto' or a list of load factors"),
    "n_lams": (int, 12, "number of load factors with lams = 'auto'"),
    "lam_span": (list, [0.5, 2.0], "'auto' spans lam_span[0] * lam1 .. lam_span[1] * lam2"),
    "n_states": (int, 4, "initial states per (realisation, lam): zero + random slips"),
    "state_scale": (float, 2.0, "box of the random initial slips, in natural slip scales"),
    "method": (str, "implicit", "cyclic solver: 'implicit' or 'events'"),
    "steps_per_cycle": (int, 64, "implicit steps per load cycle"),
    "max_cycles": (int, 200, "cycles before a run is declared not steady"),
    "tol": (float, 1e-10, "steady-state tolerance of the cyclic solver"),
    "stress_scale": (float, 0.0, "p0 of W* (0: max |static stress|)"),
    "n_workers": (int, 0, "local worker processes (0: every core)"),
    "scheduler": (str, "", "Dask scheduler address, e.g. tcp://host:8786 ('' = local)"),
    "store_format": (str, "parquet", "'parquet' or 'csv' store (sweep_store/ in the output)"),
    "fresh": (bool, False, "discard a previous sweep_store instead of resuming it"),
    "plots": (bool, True, "write PNG plots"),
}

_SPEC_OPTIONS = ("n_realisations", "lams", "n_lams", "lam_span", "n_states", "state_scale",
                 "method", "steps_per_cycle", "max_cycles", "tol")


def spec_from_scene(scene, options: dict):
    """The :class:`~shakedown.sweep.SweepSpec` of a scene and these options."""
    from ...model.errors import SceneError
    from ...studies.sweep import SweepSpec

    if scene is None or scene.model.get("kind") != "crack_network":
        kind = None if scene is None else scene.model.get("kind")
        raise SceneError(
            f"the sweep analysis needs [model] kind = 'crack_network'; got {kind!r} "
            "(for other systems use shakedown.sweep.system_sweep from Python)")
    opts = {k: options[k] for k in _SPEC_OPTIONS}
    if options["stress_scale"] > 0:
        opts["stress_scale"] = options["stress_scale"]
    model = {k: v for k, v in scene.model.items() if k != "kind"}
    try:
        return SweepSpec.from_scene(model, scene.load, opts)
    except (TypeError, ValueError) as exc:
        raise SceneError(f"{scene.label}: [analyses.sweep] / [model]: {exc}") from exc


def format_table(summary) -> str:
    """The per (realisation, lam) summary as a fixed-width text table."""
    cols = ["realisation", "lam", "W_star_min", "W_star_max", "n_steady", "n_shook_down",
            "frac_slip_max", "frac_open_max"]
    head = f"{'real':>4} {'lam':>8} {'W*_min':>10} {'W*_max':>10} {'steady':>6} {'shook':>5} " \
           f"{'slip':>5} {'open':>5}"
    lines = [head]
    for _, r in summary[cols].iterrows():
        lines.append(
            f"{int(r.realisation):4d} {r.lam:8.4f} {r.W_star_min:10.4g} {r.W_star_max:10.4g} "
            f"{int(r.n_steady):6d} {int(r.n_shook_down):5d} {r.frac_slip_max:5.2f} "
            f"{r.frac_open_max:5.2f}")
    return "\n".join(lines)


def run(ctx, options: dict) -> dict:
    from ...studies.sweep import run_sweep

    spec = spec_from_scene(getattr(ctx, "scene", None), options)
    store = ctx.output.path / "sweep_store"
    if options["fresh"] and store.exists():
        shutil.rmtree(store)
    ctx.log(f"sweep: {spec.n_realisations} realisation(s) of {spec.n_cracks} cracks x "
            f"{spec.n_lams if spec.lams == 'auto' else len(spec.lams)} load factors x "
            f"{spec.n_states} initial states; store {store}")
    res = run_sweep(spec, store, n_workers=options["n_workers"] or None,
                    scheduler=options["scheduler"] or None, progress=ctx.progress.enabled
                    if hasattr(ctx.progress, "enabled") else True,
                    format=options["store_format"])
    ctx.output.write_table("sweep_runs.csv", res.runs)
    try:
        ctx.output.write_table("sweep_runs.parquet", res.runs)
    except ImportError:  # pyarrow is optional
        pass
    ctx.output.write_table("sweep_summary.csv", res.summary)
    ctx.output.write_table("sweep_realisations.csv", res.realisations)
    if spec.n_realisations > 1:
        ctx.output.write_table("sweep_bands.csv", res.bands)
    ctx.output.write_json("sweep.json", res.to_dict())
    print("\nW* per realisation and load factor (min / max over initial states):")
    print(format_table(res.summary))
    if options["plots"]:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        from ...plotting.sweep import plot_fractions, plot_sweep

        fig, ax = plt.subplots(figsize=(7, 4.5))
        plot_sweep(res, ax=ax)
        ctx.output.save_figure("dissipation_vs_lam.png", fig)
        fig, ax = plt.subplots(figsize=(7, 4))
        plot_fractions(res, ax=ax)
        ctx.output.save_figure("fractions_vs_lam.png", fig)
    r = res.realisations
    runs = res.runs
    return {
        "n_realisations": int(len(r)),
        "n_cracks": spec.n_cracks,
        "lam1": float(r["lam1"].mean()),
        "lam2": float(r["lam2"].mean()),
        "lam_min": float(res.lams.min()),
        "lam_max": float(res.lams.max()),
        "n_runs": int(len(runs)),
        "n_not_steady": int(runs["W_star"].isna().sum()),
        "W_star_max": float(runs["W_star"].max()),
        "n_resumed": res.n_resumed,
        "wall_s": res.wall_seconds,
    }
