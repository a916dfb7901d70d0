"""The ``sweep`` analysis: dissipation against the load factor, from many initial states, for
every model kind (issues 4, 25; seed 002 Fig. 11).

``shakedown sweep SCENE`` (and the default job of ``shakedown run``) computes ``lam1``,
``lam2``, ``lam_adj`` of the scene's model, then the steady dissipation of every (realisation,
load factor, initial state) at load factors chosen from the bounds (inside ``(lam1, lam2)``,
between ``lam_adj`` and ``lam1``, refined where min and max differ) or listed (``lams``, or
its alias ``lam``: ``--set lam=[0.9,1.0,1.1]``), in parallel (local processes, or a Dask
cluster).  What a realisation is depends on the model, not on its kind's name: a model whose
builder says it ``draws_realisations`` (random Kachanov crack sets) is drawn anew
``n_realisations`` times and its dissipation normalised (``W*``); every other model (matrices,
files, FE, half-plane, a crack set from a file, ...) is the scene's one built system
(:class:`~shakedown.studies.spec.SystemSource`), with ``W`` in its energy unit.  Rows are
appended to ``sweep_store/`` in the output folder as they arrive: the same command run again
resumes an interrupted sweep (``fresh = true`` starts over; a store that is a symbolic link is
refused).  Realisations, initial states and load factors (``lam_index``) are numbered from 1
in the CSV/Parquet/JSON tables and on stdout (the store keeps the 0-based indices of the Python
API).

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

from ...model.numbers import sig

#: Options that choose where the sweep runs, not its result (reset in scene.resolved.toml).
WHERE_IT_RUNS = ("scheduler",)

#: ``lam`` (as in the other analyses) names the listed load factors ``lams``.
ALIASES = {"lam": "lams"}

OPTIONS = {
    "n_realisations": (int, 1, "number of random crack sets (1 for every other model)"),
    "lams": ((str, list, float), "auto",
             "'auto' (from each realisation's bounds) or load factors (alias: lam)"),
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
    "n_workers": (int, 0, "local worker processes (0: this process for a small study, else "
                          "every core)"),
    "scheduler": (str, "", "Dask scheduler address (command line or SHAKEDOWN_SCHEDULER only)"),
    "store_format": (str, "parquet", "'parquet' or 'csv' store (sweep_store/ in the output)"),
    "fresh": (bool, False, "discard a previous sweep_store instead of resuming it"),
    "plots": (bool, True, "write PNG plots"),
}

_SPEC_OPTIONS = ("n_realisations", "lams", "n_lams", "lam_span", "n_band", "n_adj", "n_refine",
                 "n_states", "state_scale", "method", "steps_per_cycle", "max_cycles", "tol")


def spec_from_scene(scene, options: dict, system=None, load=None):
    """The :class:`~shakedown.sweep.SweepSpec` of a scene and these options.

    A model whose builder ``draws_realisations`` (random crack networks) gives the crack
    study; any other gives the sweep of the scene's built ``system`` and ``load`` (needed then).
    """
    from ...model.errors import SceneError
    from ...studies.sweep import SweepSpec, SystemSource
    from ..files import builder_module

    if scene is None:
        raise SceneError("the sweep analysis needs a scene")
    kind = scene.model.get("kind")
    opts = {k: options[k] for k in _SPEC_OPTIONS}
    if isinstance(opts["lams"], float):
        opts["lams"] = [opts["lams"]]
    model = {k: v for k, v in scene.model.items() if k != "kind"}
    draws = getattr(builder_module(kind), "draws_realisations", None)
    try:
        if draws is not None and draws(model):
            if options["stress_scale"] > 0:
                opts["stress_scale"] = options["stress_scale"]
            return SweepSpec.from_scene(model, scene.load, opts)
        if system is None or load is None:
            raise SceneError(f"{scene.label}: the sweep of a {kind!r} model needs its built "
                             "system and load")
        if options["n_realisations"] != 1:
            raise SceneError(
                f"{scene.label}: [analyses.sweep] n_realisations = {options['n_realisations']}: "
                f"a {kind!r} model is one given system (only random crack networks draw "
                "several); remove the key or set it to 1")
        energy = getattr(scene, "units", {}).get("energy", "[force x length]")
        source = SystemSource.of(system, load, scene.name, energy)
        return SweepSpec(source=source, **opts)
    except SceneError:
        raise
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


def format_table(summary, name: str = "W*") -> str:
    """The per (realisation, lam) summary as a fixed-width text table (nodes and realisations
    numbered from 1; ``W`` to 4 significant digits, the tolerance of the verdict's "min and
    max differ"); ``name`` heads the dissipation columns."""
    head = (f"{'real':>4} {'lam':>8} {'lam/lam2':>8} {name + '_min':>10} {name + '_max':>10} "
            f"{'steady':>6} {'shook':>5} {'slip':>9} {'open':>9}  max from")
    lines = [head]
    for _, r in summary.iterrows():
        lines.append(
            f"{int(r.realisation) + 1:4d} {r.lam:8.4f} {r.x:8.4f} {sig(r.W_star_min):>10} "
            f"{sig(r.W_star_max):>10} {int(r.n_steady):6d} {int(r.n_shook_down):5d} "
            f"{r.frac_slip_min:4.2f}-{r.frac_slip_max:4.2f} {r.frac_open_min:4.2f}-"
            f"{r.frac_open_max:4.2f}  {r.max_from}")
    return "\n".join(lines)


def run(ctx, options: dict) -> dict:
    from ...studies.crack_study import run_sweep
    from ...studies.safe_files import refuse_link

    scene = getattr(ctx, "scene", None)
    spec = spec_from_scene(scene, options, ctx.system, ctx.load)
    scheduler = scheduler_of(scene, options)
    store = refuse_link(ctx.output.path / "sweep_store", "store")
    if options["fresh"] and store.exists():
        shutil.rmtree(store)
    n_lams = (spec.n_lams + spec.n_band + spec.n_adj + spec.n_refine if spec.lams == "auto"
              else len(spec.lams))
    ctx.log(f"sweep: {spec.describe()} x {'about ' * (spec.lams == 'auto')}{n_lams} load "
            f"factor{'s' * (n_lams != 1)} x {spec.n_states} initial states; store {store}")
    res = run_sweep(spec, store, n_workers=options["n_workers"] or None, scheduler=scheduler,
                    progress=ctx.progress.enabled if hasattr(ctx.progress, "enabled") else True,
                    format=options["store_format"],
                    meanwhile=_import_plotting if options["plots"] else None)
    runs = _from_one(res.runs)
    ctx.output.write_table("sweep_runs.csv", runs)
    try:
        ctx.output.write_table("sweep_runs.parquet", runs)
    except ImportError:  # pyarrow is optional
        pass
    ctx.output.write_table("sweep_summary.csv", _from_one(res.summary))
    ctx.output.write_table("sweep_regions.csv", _from_one(res.regions))
    ctx.output.write_table("sweep_realisations.csv",
                           _from_one(res.realisations.drop(columns="safe_state")))
    ctx.output.write_table("sweep_bands.csv", res.bands)
    digest = res.to_dict()
    for key in ("realisations", "summary", "regions"):  # numbered from 1, as the CSV tables
        digest[key] = [{**r, **{c: int(r[c]) + 1 for c in ONE_BASED if c in r}}
                       for r in digest[key]]
    ctx.output.write_json("sweep.json", digest)
    ctx.output.write_text("sweep_verdict.txt", res.verdict + "\n")
    D = spec.dissipation_name
    unit = f" {spec.source.energy_unit}" if spec.source is not None else ""
    print(f"\n{D}{unit} per realisation and load factor (min / max over initial states):")
    print(format_table(res.summary, D))
    if options["plots"]:
        _import_plotting()
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
    size = ({"n_nodes": spec.source.n_nodes} if spec.source is not None
            else {"n_cracks": spec.n_cracks})
    return {
        "verdict": res.verdict,
        "n_realisations": int(len(r)),
        **size,
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


def _import_plotting() -> None:
    """Import what the plots need (about 1.3 s; done while worker processes run the study)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot  # noqa: F401

    from ...plotting import sweep  # noqa: F401


#: Columns of the study's tables counted from 0 in the API and from 1 in its files.
ONE_BASED = ("realisation", "state", "lam_index")


def _from_one(table):
    """A copy of a sweep table with realisations, initial states and load factors numbered
    from 1 (columns :data:`ONE_BASED`), as on stdout and in everything a person reads."""
    t = table.copy()
    for col in ONE_BASED:
        if col in t:
            t[col] = t[col].astype(int) + 1
    return t
