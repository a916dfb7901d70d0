"""Scene files (TOML): a model, its loading, and the analyses wanted.

A scene has four tables::

    [scene]                 # optional: name, description
    name = "two-node coupled"   # a plain name (no '/', '\\', ':', '..'): the output folder

    [model]                 # how to build the DiscreteSystem; `kind` picks the builder
    kind = "matrices"       # "matrices" | "crack_network" | "fe" | "half_plane" | "half_space"
    A = [[...]]             # builder-specific keys (see shakedown/scenes/builders/<kind>.py)

    [load]                  # the periodic welded reactions; keys depend on the model kind

    [analyses.bounds]       # one table per analysis; keys validated against its OPTIONS
    [analyses.cycles]

Builders live in ``shakedown/scenes/builders/<kind>.py`` (``build(model, load, scene_dir)``) and
analyses in ``shakedown/scenes/analyses/<name>.py`` (``OPTIONS``, ``run(ctx, options)``); both are
imported only when a scene names them, so a crack-network scene never imports the FE code.
Every error names the file, the table and key, the value and what is allowed.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.resources
from dataclasses import dataclass, field
from pathlib import Path

from ..model.errors import InputError, SceneError
from .output import check_plain_name
from .reading import parse_toml, read_text, tomllib  # noqa: F401 (tomllib: re-exported)

#: Model kinds and the module that builds each.
MODEL_KINDS = {
    "matrices": "shakedown.scenes.builders.matrices",
    "crack_network": "shakedown.scenes.builders.crack_network",
    "fe": "shakedown.scenes.builders.fe",
    "half_plane": "shakedown.scenes.builders.half_plane",
    "half_space": "shakedown.scenes.builders.half_space",
}

#: Analyses and the module that runs each.
ANALYSES = {
    "bounds": "shakedown.scenes.analyses.bounds",
    "cycles": "shakedown.scenes.analyses.cycles",
    "sweep": "shakedown.scenes.analyses.sweep",
    "stability": "shakedown.scenes.analyses.stability",
    "fretting": "shakedown.scenes.analyses.fretting",
}

TOP_LEVEL_TABLES = ("scene", "model", "load", "analyses")

#: Keys of the ``[scene]`` table and their meaning (all optional text).
SCENE_KEYS = {
    "name": "name of the scene and of its output folder",
    "description": "one line shown with the results",
    "force_unit": "unit of forces, e.g. 'N' or 'N/mm' (used in messages; default [force])",
    "length_unit": "unit of lengths (slips, gaps), e.g. 'mm' (default [length])",
}

#: The scene `shakedown run` uses when none is given.
DEFAULT_SCENE = "default"


@dataclass(frozen=True)
class Scene:
    """A parsed, validated scene.

    Attributes
    ----------
    name : str
    description : str
    model : dict
        The ``[model]`` table (``kind`` plus builder keys).
    load : dict
        The ``[load]`` table.
    analyses : dict
        ``{analysis name: options}`` with every option filled from the analysis defaults.
    path : Path or None
        The scene file (``None`` for a scene built from a string).
    """

    name: str
    description: str
    model: dict
    load: dict
    analyses: dict
    path: Path | None = None
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def units(self) -> dict:
        """``{"force": ..., "length": ..., "energy": ...}``: declared units or placeholders."""
        meta = self.raw.get("scene", {})
        force = meta.get("force_unit") or "[force]"
        length = meta.get("length_unit") or "[length]"
        if "force_unit" in meta and "length_unit" in meta:
            energy = f"{force} {length}"
        else:
            energy = "[force x length]"
        return {"force": force, "length": length, "energy": energy}

    @property
    def directory(self) -> Path:
        return self.path.parent if self.path is not None else Path.cwd()

    @property
    def label(self) -> str:
        return str(self.path) if self.path is not None else f"<scene {self.name}>"


def builtin_scenes() -> dict[str, Path]:
    """Names and paths of the scenes shipped with the package."""
    root = importlib.resources.files("shakedown.scenes") / "builtin"
    return {
        p.name[: -len(".toml")]: Path(str(p))
        for p in root.iterdir()
        if p.name.endswith(".toml")
    }


def resolve_scene_path(scene: str | Path | None) -> Path:
    """A path for ``scene``: a file, or the name of a built-in scene (default if None)."""
    if scene is None:
        scene = DEFAULT_SCENE
    p = Path(scene)
    if p.is_file():
        return p
    builtin = builtin_scenes()
    name = str(scene)[:-5] if str(scene).endswith(".toml") else str(scene)
    if name in builtin:
        return builtin[name]
    raise SceneError(
        f"scene {str(scene)!r} is neither a file nor a built-in scene; "
        f"built-in scenes: {', '.join(sorted(builtin))}"
    )


def load_scene(scene: str | Path | None = None) -> Scene:
    """Read and validate a scene file (or a built-in scene by name, or a run's manifest.json).

    The file is checked before it is parsed (size at most
    :data:`~shakedown.model.limits.MAX_SCENE_BYTES`, UTF-8 text) and after (nesting at most
    :data:`~shakedown.model.limits.MAX_NESTING` levels); a manifest goes through the same
    refusals as a scene file (no Dask scheduler or other "where it runs" option from a file).
    """
    path = resolve_scene_path(scene)
    if path.suffix == ".json":  # a run's manifest.json: its resolved scene (scenes/manifest.py)
        from .manifest import scene_from_manifest

        raw = scene_from_manifest(path)
    else:
        raw = parse_toml(read_text(path, "scene file"), str(path))
    refuse_where_it_runs(raw, str(path))
    return scene_from_dict(raw, path=path)


def refuse_where_it_runs(raw: dict, label: str) -> None:
    """:class:`SceneError` if a file's ``[analyses.*]`` tables set an option that chooses where
    the work runs (``WHERE_IT_RUNS``, e.g. the sweep's Dask ``scheduler``): connecting to a
    host is trusted like running its code, so it comes from the command line only."""
    analyses = raw.get("analyses") if isinstance(raw, dict) else None
    if not isinstance(analyses, dict):
        return
    for name, table in analyses.items():
        if name not in ANALYSES or not isinstance(table, dict):
            continue
        module = analysis_module(name, label)
        for key in getattr(module, "WHERE_IT_RUNS", ()):
            if table.get(key) not in (None, module.OPTIONS[key][1]):
                raise SceneError(
                    f"{label}: [analyses.{name}] {key} = {table[key]!r}: a scene or manifest "
                    f"file may not name a Dask scheduler or any other host ({key!r} chooses "
                    "where the work runs, trusted like running its code); remove it and pass "
                    f"--set {key}=... on the command line (or set SHAKEDOWN_SCHEDULER)")


def scene_from_string(text: str, directory: Path | None = None) -> Scene:
    """Parse a scene from TOML text (files it names are looked up in ``directory``)."""
    raw = parse_toml(text, "<string>")
    path = (Path(directory) / "<string>.toml") if directory is not None else None
    return scene_from_dict(raw, path=path)


def scene_from_dict(raw: dict, path: Path | None = None) -> Scene:
    label = str(path) if path is not None else "<scene>"
    for key in raw:
        if key not in TOP_LEVEL_TABLES:
            raise SceneError(
                f"{label}: unknown top-level table [{key}]; allowed: "
                f"{', '.join('[' + t + ']' for t in TOP_LEVEL_TABLES)}"
            )
    meta = raw.get("scene", {})
    _require_table(label, "scene", meta)
    for key in meta:
        if key not in SCENE_KEYS:
            raise SceneError(
                f"{label}: [scene] key {key!r} is not allowed; allowed: "
                f"{', '.join(repr(k) for k in SCENE_KEYS)}"
            )
    for key in SCENE_KEYS:
        if key in meta:
            check_type(label, "scene", key, meta[key], str, SCENE_KEYS[key])
    model = raw.get("model")
    if model is None:
        raise SceneError(f"{label}: missing table [model] (with kind = one of {sorted(MODEL_KINDS)})")
    _require_table(label, "model", model)
    kind = model.get("kind")
    if not isinstance(kind, str) or kind not in MODEL_KINDS:
        raise SceneError(
            f"{label}: [model] key 'kind' = {kind!r} is not allowed; "
            f"allowed: {', '.join(repr(k) for k in MODEL_KINDS)}"
        )
    load = raw.get("load", {})
    _require_table(label, "load", load)
    analyses_raw = raw.get("analyses", {})
    _require_table(label, "analyses", analyses_raw)
    analyses = {}
    for name, opts in analyses_raw.items():
        analyses[name] = validate_options(label, name, opts)
    default_name = path.stem if path is not None else "scene"
    name = meta.get("name", default_name)
    if not isinstance(name, str):
        raise SceneError(f"{label}: [scene] key 'name' = {name!r} must be a string")
    try:
        name = check_plain_name(name, "[scene] key 'name'")
    except InputError as exc:
        raise SceneError(f"{label}: {exc}") from None
    return Scene(
        name=name,
        description=str(meta.get("description", "")),
        model=dict(model),
        load=dict(load),
        analyses=analyses,
        path=path,
        raw=raw,
    )


def _require_table(label, name, value):
    if not isinstance(value, dict):
        raise SceneError(f"{label}: [{name}] must be a table; got {type(value).__name__} {value!r}")


def analysis_module(name: str, label: str = "<scene>"):
    if name not in ANALYSES:
        raise SceneError(
            f"{label}: [analyses.{name}] is not a known analysis; allowed: "
            f"{', '.join(sorted(ANALYSES))}"
        )
    return importlib.import_module(ANALYSES[name])


def builder_module(kind: str):
    return importlib.import_module(MODEL_KINDS[kind])


def validate_options(label: str, name: str, opts) -> dict:
    """Fill and type-check the options of analysis ``name`` from its ``OPTIONS`` schema."""
    if not isinstance(opts, dict):
        raise SceneError(f"{label}: [analyses.{name}] must be a table; got {opts!r}")
    module = analysis_module(name, label)
    schema = module.OPTIONS
    aliases = getattr(module, "ALIASES", {})  # old option names still accepted
    out = {}
    for key, value in opts.items():
        if key in aliases:
            if aliases[key] in opts:
                raise SceneError(f"{label}: [analyses.{name}] give {aliases[key]!r} or its old "
                                 f"name {key!r}, not both")
            key = aliases[key]
        if key not in schema:
            raise SceneError(
                f"{label}: [analyses.{name}] key {key!r} is not allowed; allowed: "
                f"{', '.join(sorted(schema))}"
            )
        typ, _, help_ = schema[key]
        out[key] = check_type(label, f"analyses.{name}", key, value, typ, help_)
    for key, (_, default, _) in schema.items():
        out.setdefault(key, default)
    return out


def resolved_analyses(scene: Scene, names: list[str]) -> dict:
    """``{name: options}`` of the analyses ``names`` as they run (every option filled).

    Options an analysis lists in ``WHERE_IT_RUNS`` (e.g. the sweep's Dask ``scheduler``) choose
    where the work runs, not its result; they are reset to their defaults here, so that the
    resolved scene reruns anywhere (the command line in the manifest still records them).
    """
    out = {}
    for name in names:
        opts = dict(scene.analyses.get(name) or validate_options(scene.label, name, {}))
        module = analysis_module(name, scene.label)
        for key in getattr(module, "WHERE_IT_RUNS", ()):
            opts[key] = module.OPTIONS[key][1]
        out[name] = opts
    return out


def check_type(label, table, key, value, typ, help_=""):
    """Check one scene value against a type spec (a type or a tuple of types)."""
    types = typ if isinstance(typ, tuple) else (typ,)
    ok = False
    for t in types:
        if t is float and isinstance(value, (int, float)) and not isinstance(value, bool):
            value, ok = float(value), True
            break
        if t is int and isinstance(value, int) and not isinstance(value, bool):
            ok = True
            break
        if t not in (float, int) and isinstance(value, t):
            ok = True
            break
    if not ok:
        names = " or ".join(t.__name__ for t in types)
        raise SceneError(
            f"{label}: [{table}] key {key!r} = {value!r} must be {names}"
            + (f" ({help_})" if help_ else "")
        )
    return value


@dataclass
class AnalysisContext:
    """What an analysis sees: the built model, an output folder, progress and log."""

    system: object
    load: object
    model: object
    output: object
    progress: object
    scene_path: Path | None
    scene: Scene | None = None

    def log(self, message: str) -> None:
        self.progress.log(message)


def build(scene: Scene, output=None, progress=None):
    """Build ``(system, load, extra)`` for a scene with its model kind's builder.

    ``output`` (an :class:`~shakedown.output.OutputFolder`) is where builders that cache
    expensive products (FE condensation) may keep them; nothing is written elsewhere.
    """
    import inspect

    builder = builder_module(scene.model["kind"])
    model = {k: v for k, v in scene.model.items() if k != "kind"}
    kwargs = {}
    if output is not None and "cache_root" in inspect.signature(builder.build).parameters:
        kwargs["cache_root"] = output.path
    phase = progress.phase if progress is not None else _no_phase
    try:
        with phase(f"building the {scene.model['kind']} model of {scene.label}"):
            return builder.build(model, scene.load, scene.directory, **kwargs)
    except SceneError as exc:
        msg = str(exc)
        if scene.label not in msg:
            msg = f"{scene.label}: {msg}"
        raise SceneError(msg) from exc
    except InputError as exc:
        raise SceneError(f"{scene.label}: the model or load is invalid: {exc}") from exc


@contextlib.contextmanager
def _no_phase(desc):
    yield


def run_scene(scene: Scene, output, progress, only: list[str] | None = None) -> dict:
    """Run the scene's analyses (or ``only`` those) and return ``{name: summary}``."""
    names = list(only) if only else list(scene.analyses) or ["bounds"]
    for name in names:
        analysis_module(name, scene.label)
    system, load, extra = build(scene, output, progress)
    ctx = AnalysisContext(system, load, extra, output, progress, scene.path, scene)
    summaries = {}
    for name in names:
        opts = scene.analyses.get(name) or validate_options(scene.label, name, {})
        summaries[name] = analysis_module(name).run(ctx, opts)
    return summaries
