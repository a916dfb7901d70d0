"""The ``sweep`` analysis: the Monte Carlo crack-network study (issue 4; seed 002 Fig. 11).

``shakedown sweep SCENE`` (and the default job of ``shakedown run``) draws
``n_realisations`` crack sets with the scene's ``[model]`` keys (``kind = "crack_network"``),
computes ``lam1``, ``lam2``, ``lam_adj`` of each, then the steady dissipation ``W*`` of every
(realisation, load factor, initial state) at load factors chosen from each realisation's bounds
(inside ``(lam1, lam2)``, between ``lam_adj`` and ``lam1``, refined where min and max differ),
in parallel (local processes, or a Dask cluster).  Rows are appended to ``sweep_store/`` in the
output folder as they arrive: the same command run again resumes an interrupted sweep
(``fresh = true`` starts over; a store that is a symbolic link is refused).

Writes ``sweep_runs.csv`` (and ``.parquet``), ``sweep_summary.csv`` (min / max ``W*`` per
realisation and ``lam``), ``sweep_regions.csv`` (runs in cyclic slip per band of load factors),
``sweep_realisations.csv``, ``sweep_bands.csv``, ``sweep_verdict.txt``, ``sweep.json``,
``dissipation_vs_lam.png`` and ``fractions_vs_lam.png``; prints the verdict and summary table.

Dask: a ``scheduler`` address makes this process unpickle what that host sends, so it is
trusted like code.  It is taken only from the command line (``--set scheduler=tcp://...``) or
the environment variable ``SHAKEDOWN_SCHEDULER``; a scene *file* that names one is refused,
so that running a shared scene never connects anywhere by itself.

The scene's realisations are drawn from child seeds of ``[model] seed``
(``SeedSequence(seed).spawn``), so realisation 0 is not the crack set that the other analyses
of the scene see (that one is drawn from ``seed`` itself).
"""

from __future__ import annotations

import shutil

#: Options that choose where the sweep runs, not its result (reset in scene.resolved.toml).
WHERE_IT_RUNS = ("scheduler",)

OPTIONS = {
    "n_realisations": (int, 1, "number of random crack sets"),
    "lams": ((str, list), "auto", "'auto' (from each realisation's bounds) or load factors"),
    "n_lams": (int, 12, "evenly spaced points in lam / lam2 with lams = 'auto'"),
    "lam_span": (list, [0.5, 2.5], "range of lam / lam2 of the evenly spaced points"),
    "n_band": (int, 5, "extra points inside (lam1, lam2)"),
    "n_adj": (int, 2, "extra points inside (lam_adj, lam1) when lam_adj < lam1"),
    "n_refine": (int, 2, "points added where min and max W* differ most and at lam_u"),
    "n_states": (int, 8, "initial states: zero, safe, 2 friction-limit corners, random"),
    "state_scale": (float, 2.0, "box of the random initial slips, in natural slip scales"),
    "method": (str, "implicit", "cyclic solver: 'implicit' or 'events'"),
    "steps_per_cycle": (int, 64, "implicit steps per load cycle"),
    "max_cycles": (int, 200, "cycles before a run is declared not steady"),
    "tol": (float, 1e-10, "steady-state tolerance of the cyclic solver"),
    "stress_scale": (float, 0.0, "p0 of W* (0: max |static stress|)"),
    "n_workers": (int, 0, "local worker processes (0: every core)"),
    "scheduler": (str, "", "Dask scheduler address (command line or SHAKEDOWN_SCHEDULER only)"),
    "store_format": (str, "parquet", "'parquet' or 'csv' store (sweep_store/ in the output)"),
    "fresh": (bool, False, "discard a previous sweep_store instead of resuming it"),
    "plots": (bool, True, "write PNG plots"),
}

_SPEC_OPTIONS = ("n_realisations", "lams", "n_lams", "lam_span", "n_band", "n_adj", "n_refine",
                 "n_states", "state_scale", "method", "steps_per_cycle", "max_cycles", "tol")


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


def scheduler_of(scene, options: dict) -> str | None:
    """The Dask scheduler address: ``--set scheduler=...`` or ``SHAKEDOWN_SCHEDULER``; a scene
    file that names one is refused (trusted like code, see the module docstring).

    The scene *file* is read again from disk to tell its own keys from ``--set`` values (which
    are merged into the parsed scene); a scene given as a string has no file and its own
    ``scheduler`` key is refused the same way.
    """
    import os

    from ...model.errors import SceneError
    from ..files import tomllib

    path = getattr(scene, "path", None)
    if path is not None and os.path.isfile(path):
        try:
            raw = tomllib.loads(open(path, encoding="utf-8").read())
        except (OSError, ValueError):  # it was parsed once already; nothing to refuse
            raw = {}
    elif path is None:
        raw = getattr(scene, "raw", None) or {}
    else:
        raw = {}
    own = raw.get("analyses", {}).get("sweep", {}) if isinstance(raw, dict) else {}
    if isinstance(own, dict) and own.get("scheduler"):
        raise SceneError(
            f"{scene.label}: [analyses.sweep] scheduler = {own['scheduler']!r}: a scene file may "
            "not name a Dask scheduler (connecting to one is trusted like running its code); "
            "remove the key and pass --set scheduler=ADDRESS or set SHAKEDOWN_SCHEDULER")
    return options.get("scheduler") or os.environ.get("SHAKEDOWN_SCHEDULER") or None


def format_table(summary) -> str:
    """The per (realisation, lam) summary as a fixed-width text table (nodes and realisations
    numbered from 1)."""
    head = (f"{'real':>4} {'lam':>8} {'lam/lam2':>8} {'W*_min':>10} {'W*_max':>10} "
            f"{'steady':>6} {'shook':>5} {'slip':>9} {'open':>9}  max from")
    lines = [head]
    for _, r in summary.iterrows():
        lines.append(
            f"{int(r.realisation) + 1:4d} {r.lam:8.4f} {r.x:8.4f} {r.W_star_min:10.4g} "
            f"{r.W_star_max:10.4g} {int(r.n_steady):6d} {int(r.n_shook_down):5d} "
            f"{r.frac_slip_min:4.2f}-{r.frac_slip_max:4.2f} {r.frac_open_min:4.2f}-"
            f"{r.frac_open_max:4.2f}  {r.max_from}")
    return "\n".join(lines)


def run(ctx, options: dict) -> dict:
    from ...studies.crack_study import run_sweep
    from ...studies.safe_files import refuse_link

    scene = getattr(ctx, "scene", None)
    spec = spec_from_scene(scene, options)
    scheduler = scheduler_of(scene, options)
    store = refuse_link(ctx.output.path / "sweep_store", "store")
    if options["fresh"] and store.exists():
        shutil.rmtree(store)
    n_lams = (spec.n_lams + spec.n_band + spec.n_adj + spec.n_refine if spec.lams == "auto"
              else len(spec.lams))
    ctx.log(f"sweep: {spec.n_realisations} realisation(s) of {spec.n_cracks} cracks x "
            f"about {n_lams} load factors x {spec.n_states} initial states; store {store}")
    res = run_sweep(spec, store, n_workers=options["n_workers"] or None, scheduler=scheduler,
                    progress=ctx.progress.enabled if hasattr(ctx.progress, "enabled") else True,
                    format=options["store_format"])
    ctx.output.write_table("sweep_runs.csv", res.runs)
    try:
        ctx.output.write_table("sweep_runs.parquet", res.runs)
    except ImportError:  # pyarrow is optional
        pass
    ctx.output.write_table("sweep_summary.csv", res.summary)
    ctx.output.write_table("sweep_regions.csv", res.regions)
    ctx.output.write_table("sweep_realisations.csv", res.realisations.drop(columns="safe_state"))
    ctx.output.write_table("sweep_bands.csv", res.bands)
    ctx.output.write_json("sweep.json", res.to_dict())
    ctx.output.write_text("sweep_verdict.txt", res.verdict + "\n")
    print("\nW* per realisation and load factor (min / max over initial states):")
    print(format_table(res.summary))
    if options["plots"]:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        from ...plotting.sweep import plot_fractions, plot_sweep

        axis = "x" if spec.n_realisations > 1 else "lam"
        fig, ax = plt.subplots(figsize=(7, 4.5))
        plot_sweep(res, ax=ax, axis=axis)
        ctx.output.save_figure("dissipation_vs_lam.png", fig)
        fig, ax = plt.subplots(figsize=(7, 4))
        plot_fractions(res, ax=ax, axis=axis)
        ctx.output.save_figure("fractions_vs_lam.png", fig)
    r = res.realisations
    runs = res.runs
    return {
        "verdict": res.verdict,
        "n_realisations": int(len(r)),
        "n_cracks": spec.n_cracks,
        "lam1": float(r["lam1"].mean()),
        "lam2": float(r["lam2"].mean()),
        "lam_adj": float(r["lam_adj"].mean()),
        "lam_u": float(r["lam_u"].mean()),
        "lam_min": float(res.lams.min()),
        "lam_max": float(res.lams.max()),
        "n_runs": int(len(runs)),
        "n_not_steady": int(runs["W_star"].isna().sum()),
        "n_cyclic_slip_below_lam1": int(res.summary.loc[
            res.summary["lam"] < res.summary["lam1"], "n_cyclic_slip"].sum()),
        "W_star_max": float(runs["W_star"].max()),
        "n_resumed": res.n_resumed,
        "wall_s": res.wall_seconds,
    }
