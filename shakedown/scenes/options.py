"""Options of the analyses, as a person finds them: ``--help`` text, README tables, ``--set``.

Each analysis module holds ``OPTIONS = {key: (type, default, meaning)}``; the help of
``shakedown <analysis> --help`` and the README's option tables are generated from it here, so
the documentation cannot drift from what the program accepts (a test compares the README with
:func:`options_markdown`).  ``--set KEY=VALUE`` overrides an analysis option
(``--set lam=1.2``, ``--set cycles.max_cycles=50``) or any key of the ``[model]`` / ``[load]`` /
``[scene]`` tables (``--set model.friction=0.4``, ``--set model.material.E=2.0``); the changed
scene is validated again like a file.
"""

from __future__ import annotations

from ..model.errors import SceneError
from .files import ANALYSES, analysis_module, scene_from_dict, tomllib

#: Tables of a scene that ``--set`` may change besides the analyses.
SCENE_TABLES = ("model", "load", "scene")

_TYPE_NAMES = {float: "number", int: "integer", bool: "true/false", str: "text", list: "list"}


def type_name(typ) -> str:
    """Plain name of an option's type (``(str, list)`` -> ``"text or list"``)."""
    types = typ if isinstance(typ, tuple) else (typ,)
    return " or ".join(_TYPE_NAMES.get(t, t.__name__) for t in types)


def default_text(value) -> str:
    """An option's default as it would be written in a scene file (TOML)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(default_text(v) for v in value) + "]"
    return repr(value)


def option_rows(name: str) -> list[tuple[str, str, str, str]]:
    """``(key, type, default, meaning)`` of every option of analysis ``name``."""
    schema = analysis_module(name).OPTIONS
    return [(key, type_name(typ), default_text(default), meaning)
            for key, (typ, default, meaning) in schema.items()]


def options_help(name: str) -> str:
    """The option list shown by ``shakedown <name> --help``."""
    rows = option_rows(name)
    width = max(len(k) for k, *_ in rows)
    lines = [f"options of [analyses.{name}] (scene file, or --set KEY=VALUE):"]
    for key, typ, default, meaning in rows:
        lines.append(f"  {key:<{width}}  {typ}, default {default}")
        lines.append(f"  {'':<{width}}    {meaning}")
    return "\n".join(lines)


def options_markdown(name: str) -> str:
    """The README table of the options of analysis ``name``."""
    lines = ["| option | type | default | meaning |", "| --- | --- | --- | --- |"]
    for key, typ, default, meaning in option_rows(name):
        lines.append(f"| `{key}` | {typ} | `{default}` | {meaning.replace('|', '/')} |")
    return "\n".join(lines)


def all_options_markdown() -> str:
    """Every analysis's table, each under a heading (the README's "Options" section body)."""
    return "\n\n".join(f"#### `{name}`\n\n{options_markdown(name)}" for name in ANALYSES)


def parse_value(text: str):
    """A ``--set`` value: TOML (``0.4``, ``true``, ``[1, 2]``, ``"x"``) or else plain text."""
    try:
        return tomllib.loads(f"x = {text}")["x"]
    except tomllib.TOMLDecodeError:
        return text


def apply_overrides(scene, names, overrides):
    """The scene with ``--set [table.]key=value`` options applied, validated again.

    Parameters
    ----------
    scene : Scene
    names : list of str
        The analyses being run: a key without a table goes to the only one of them.
    overrides : list of str
        ``"KEY=VALUE"`` items; ``KEY`` is ``key`` (the analysis being run),
        ``<analysis>.key``, or ``model.key`` / ``load.key`` / ``scene.key`` (nested with
        more dots, e.g. ``model.material.E``).
    """
    import copy

    raw = copy.deepcopy(scene.raw)
    for item in overrides:
        if "=" not in item:
            raise SceneError(f"--set {item!r}: expected KEY=VALUE (e.g. --set lam=1.2 or "
                             "--set model.friction=0.4)")
        key, value = item.split("=", 1)
        key = key.strip()
        if "." in key:
            table, key = key.split(".", 1)
        elif len(names) == 1:
            table = names[0]
        else:
            raise SceneError(f"--set {item!r}: name the analysis, e.g. --set {names[0]}.{key}=...")
        if table in SCENE_TABLES:
            target = raw.setdefault(table, {})
            *parents, last = key.split(".")
            for part in parents:
                target = target.setdefault(part, {})
                if not isinstance(target, dict):
                    raise SceneError(f"--set {item!r}: [{table}] {part!r} is not a table")
        elif table in ANALYSES:
            target = raw.setdefault("analyses", {}).setdefault(table, {})
            last = key
        else:
            raise SceneError(
                f"--set {item!r}: {table!r} is neither an analysis ({', '.join(ANALYSES)}) nor "
                f"one of the tables {', '.join(SCENE_TABLES)}")
        target[last] = parse_value(value.strip())
    label = f"{scene.label} (with --set)"
    try:
        new = scene_from_dict(raw, path=scene.path)
    except SceneError as exc:
        msg = str(exc)
        msg = msg.replace(scene.label, label, 1) if scene.label in msg else f"{label}: {msg}"
        raise SceneError(msg) from None
    # options that choose where a run executes (the sweep's Dask scheduler) are trusted only
    # from the command line: keep them out of the scene's raw tables, which are what a scene
    # file said (and what the analysis checks for such keys)
    for name, table in new.raw.get("analyses", {}).items():
        for key in getattr(analysis_module(name, label), "WHERE_IT_RUNS", ()):
            table.pop(key, None)
    return new


#: Markers around the generated option tables in README.md.
README_BEGIN = "<!-- options:begin (generated by shakedown.scenes.options.update_readme) -->"
README_END = "<!-- options:end -->"


def readme_with_tables(text: str) -> str:
    """``text`` (the README) with the option tables between the markers regenerated."""
    if README_BEGIN not in text or README_END not in text:
        raise ValueError(f"README lacks the markers {README_BEGIN!r} ... {README_END!r}")
    head, rest = text.split(README_BEGIN, 1)
    _, tail = rest.split(README_END, 1)
    return f"{head}{README_BEGIN}\n{all_options_markdown()}\n{README_END}{tail}"


def update_readme(path="README.md") -> bool:
    """Regenerate the option tables of the README at ``path``; True if it changed.

    Run after changing an ``OPTIONS`` schema:
    ``python3 -c "from shakedown.scenes.options import update_readme; update_readme()"``.
    """
    from pathlib import Path

    p = Path(path)
    old = p.read_text()
    new = readme_with_tables(old)
    if new != old:
        p.write_text(new)
    return new != old
