"""Provenance of a run: ``manifest.json``, ``scene.resolved.toml`` and ``CITATIONS.bib``.

Every output folder of the ``shakedown`` command holds

``scene.resolved.toml``
    The scene as it ran: the analyses that ran with every option filled from its ``OPTIONS``
    defaults (``--set`` overrides included), the ``[model]`` and ``[load]`` tables with the
    builder's defaults filled in (its ``resolved(model, load)``) and every file path made
    absolute.  ``shakedown run scene.resolved.toml`` runs it again.
``manifest.json``
    Package and dependency versions, the resolved scene (the same tables), the seeds found in
    it, the command line, start and end time (UTC), the machine, the SHA-256 of every input
    file and of every file the run wrote.  ``shakedown run manifest.json`` runs the resolved
    scene again (refusing if an input file has changed since), and gives the same result files
    bit for bit on the same machine and versions.
``CITATIONS.bib``
    The references of exactly the methods that ran (:mod:`shakedown.model.citations`).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import platform
import re
import sys
from pathlib import Path

from ..model import citations
from ..model.errors import SceneError

#: Distributions whose versions a manifest records (those absent are recorded as ``None``).
DEPENDENCIES = ("numpy", "scipy", "highspy", "cvxpy", "matplotlib", "pandas", "scikit-fem",
                "meshio", "pyarrow", "dask", "distributed")

#: Keys of ``[model]`` / ``[load]`` (and nested tables) that name files beside the scene.
_FILE_KEY = re.compile(r"^(file|.*_file)$")
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


# ------------------------------------------------------------------ TOML writing
def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # shortest round-trip text: read back as the same double
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(str(k))} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return _toml_value(value.tolist())
    raise SceneError(f"cannot write a {type(value).__name__} value ({value!r}) to a scene file")


def to_toml(tables: dict) -> str:
    """TOML text of ``{table: {key: value}}`` (``analyses`` holds one sub-table per analysis).

    Values round-trip exactly through :mod:`tomllib` (floats by their shortest ``repr``);
    nested tables inside a table are written inline.
    """
    out = []
    for name, table in tables.items():
        if name == "analyses":
            for sub, opts in table.items():
                out.append(f"[analyses.{_toml_key(sub)}]")
                out += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in opts.items()]
                out.append("")
            continue
        out.append(f"[{name}]")
        out += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items()]
        out.append("")
    return "\n".join(out)


# ------------------------------------------------------------------ resolving a scene
def _absolute_files(table: dict, directory: Path) -> dict:
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            value = _absolute_files(value, directory)
        elif isinstance(value, str) and _FILE_KEY.fullmatch(key):
            value = str((directory / value).resolve())
        out[key] = value
    return out


def _files(table: dict) -> list[str]:
    found = []
    for key, value in table.items():
        if isinstance(value, dict):
            found += _files(value)
        elif isinstance(value, str) and _FILE_KEY.fullmatch(key):
            found.append(value)
    return found


def resolved_scene(scene, analyses: dict, builder=None) -> dict:
    """The scene's tables as they run: defaults filled, file paths absolute.

    Parameters
    ----------
    scene : shakedown.scenes.Scene
    analyses : dict
        ``{name: options}`` of the analyses that run, every option filled
        (:func:`shakedown.scenes.files.resolved_analyses`).
    builder : module, optional
        The model kind's builder; its ``resolved(model, load)``, if any, fills the defaults.

    Returns
    -------
    dict
        ``{"scene": ..., "model": ..., "load": ..., "analyses": {name: options}}``.
    """
    model = {k: v for k, v in scene.model.items() if k != "kind"}
    load = dict(scene.load)
    if hasattr(builder, "resolved"):
        model, load = builder.resolved(model, load)
    model = {"kind": scene.model["kind"], **_absolute_files(model, scene.directory)}
    load = _absolute_files(load, scene.directory)
    meta = {"name": scene.name, "description": scene.description}
    raw_meta = (scene.raw or {}).get("scene", {})
    meta.update({k: raw_meta[k] for k in ("force_unit", "length_unit") if k in raw_meta})
    return {"scene": meta, "model": model, "load": load,
            "analyses": {k: dict(v) for k, v in analyses.items()}}


def _seeds(tables: dict, prefix: str = "") -> dict:
    found = {}
    for key, value in tables.items():
        if isinstance(value, dict):
            found.update(_seeds(value, f"{prefix}{key}."))
        elif key == "seed" or key.endswith("_seed"):
            found[prefix + key] = value
    return found


def sha256(path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ------------------------------------------------------------------ the environment
def dependency_versions() -> dict:
    """Installed versions of :data:`DEPENDENCIES` (``None`` when not installed)."""
    from importlib import metadata

    out = {}
    for name in DEPENDENCIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def machine() -> dict:
    """The machine and interpreter: platform, processor, cores, thread settings."""
    threads = {k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                          "MKL_NUM_THREADS") if k in os.environ}
    return {"platform": platform.platform(), "machine": platform.machine(),
            "processor": platform.processor(), "node": platform.node(),
            "cpu_count": os.cpu_count(), "python": sys.version.split()[0],
            "python_implementation": platform.python_implementation(),
            "thread_settings": threads}


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


# ------------------------------------------------------------------ a run's record
class RunRecord:
    """The provenance of one run into an output folder.

    :meth:`start` (before the analyses) resets the citation registry and writes
    ``scene.resolved.toml``; :meth:`finish` (after them) writes ``CITATIONS.bib`` and
    ``manifest.json``.
    """

    def __init__(self, scene, output, analyses: dict, builder=None, argv=None):
        from ..model.version import __version__

        self.output = output
        self.tables = resolved_scene(scene, analyses, builder)
        self.started = _now()
        source = scene.path if scene.path is not None and scene.path.is_file() else None
        self.data = {
            "shakedown_version": __version__,
            "command": ["shakedown", *(sys.argv[1:] if argv is None else list(argv))],
            "working_directory": str(Path.cwd()),
            "scene_file": str(source.resolve()) if source else None,
            "scene_sha256": sha256(source) if source else None,
            "reproduces": str(source.resolve()) if source and source.suffix == ".json" else None,
            "resolved_scene_file": "scene.resolved.toml",
            "resolved_scene": self.tables,
            "seeds": _seeds({k: self.tables[k] for k in ("model", "load", "analyses")}),
            "input_notes": (builder.provenance(self.tables["model"], self.tables["load"])
                            if hasattr(builder, "provenance") else {}),
            "input_files": {},
            "dependencies": dependency_versions(),
            "machine": machine(),
            "start_utc": self.started,
        }

    @classmethod
    def start(cls, scene, output, analyses: dict, builder=None, argv=None) -> RunRecord:
        """Begin a run: reset the citations.  Nothing is written until :meth:`finish`.

        ``analyses`` and ``builder`` as in :func:`resolved_scene`; ``argv`` the command's
        arguments (default ``sys.argv[1:]``).
        """
        citations.reset()
        return cls(scene, output, analyses, builder, argv)

    def cite(self) -> str:
        """What to cite for the methods used so far."""
        return citations.summary()

    def finish(self) -> dict:
        """Write ``scene.resolved.toml``, ``CITATIONS.bib`` and ``manifest.json`` (once the run
        has succeeded: a failed run leaves no provenance); returns the manifest.

        The input files are hashed here, after the builder has read (and size-checked) them.
        """
        inputs = {}
        for name in _files(self.tables["model"]) + _files(self.tables["load"]):
            if Path(name).is_file():
                inputs[name] = sha256(name)
        self.output.write_text(
            "scene.resolved.toml",
            f"# resolved by shakedown {self.data['shakedown_version']}: "
            "every default filled in; `shakedown run` this file to run it again\n"
            + to_toml(self.tables))
        self.output.write_text("CITATIONS.bib", citations.bibtex())
        written = sorted({p for p in self.output.written if p.name != "manifest.json"})
        final = getattr(self.output, "final", lambda name: self.output.path / name)
        self.data.update(
            input_files=inputs,
            end_utc=_now(),
            citations=list(citations.used()),
            output_files={p.name: sha256(final(p.name)) for p in written
                          if final(p.name).is_file()},
        )
        self.output.write_json("manifest.json", self.data)
        return self.data


# ------------------------------------------------------------------ reading it back
def scene_from_manifest(path) -> dict:
    """The resolved scene tables of a ``manifest.json`` (input files checked unchanged).

    Raises
    ------
    SceneError
        If the file is not a manifest, or an input file is missing or changed since the run.
    """
    from ..model.errors import InputError
    from ..model.limits import MAX_NESTING, check_file_size, check_nesting
    from .reading import read_text

    path = Path(path)
    try:
        data = json.loads(read_text(path, "manifest"))
        check_nesting(path, data)
    except json.JSONDecodeError as exc:
        raise SceneError(f"{path}: not a readable manifest (JSON): {exc}") from None
    except (RecursionError, MemoryError):
        raise SceneError(f"{path}: the manifest nests tables or lists too deeply (more than "
                         f"{MAX_NESTING} levels) or is too large to parse") from None
    except InputError as exc:
        raise SceneError(str(exc)) from None
    if not isinstance(data, dict) or not isinstance(data.get("resolved_scene"), dict):
        raise SceneError(f"{path}: not a shakedown manifest (no 'resolved_scene' table); give the "
                         "manifest.json of an output folder or a scene file (.toml)")
    inputs = data.get("input_files") or {}
    if not isinstance(inputs, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in inputs.items()):
        raise SceneError(f"{path}: 'input_files' must map file names to SHA-256 texts")
    for name, digest in inputs.items():
        if not Path(name).is_file():
            raise SceneError(f"{path}: input file {name} of the recorded run is missing")
        try:
            check_file_size(name, "input file")  # before hashing it
        except InputError as exc:
            raise SceneError(f"{path}: {exc}") from None
        if sha256(name) != digest:
            raise SceneError(f"{path}: input file {name} has changed since the recorded run "
                             "(SHA-256 differs), so the run cannot be reproduced; run "
                             "scene.resolved.toml to accept the new file")
    return data["resolved_scene"]
