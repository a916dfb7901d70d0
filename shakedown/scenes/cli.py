"""The ``shakedown`` command.

    shakedown run [SCENE]        run every analysis of a scene (default: the built-in scene)
    shakedown bounds SCENE       shakedown load factors lam1, lam2
    shakedown cycles SCENE       cyclic evolution, steady state, dissipation
    shakedown sweep SCENE        Monte Carlo / parameter sweep
    shakedown stability SCENE    complementarity eigenvalue check
    shakedown scenes             list the built-in scenes

Results (JSON, CSV, PNG) go to ``--out`` (default ``shakedown-out/<scene name>``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..model.errors import InputError, SceneError, ShakedownError

ANALYSIS_COMMANDS = ("bounds", "cycles", "sweep", "stability")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="shakedown",
        description="Shakedown, cyclic dissipation and stability of frictional elastic systems.",
    )
    p.add_argument("--version", action="version", version=f"shakedown {_version()}")
    sub = p.add_subparsers(dest="command", required=True)

    def common(sp, scene_optional):
        sp.add_argument(
            "scene",
            nargs="?" if scene_optional else None,
            default=None,
            help="scene file (TOML) or built-in scene name"
            + (" (default: the built-in default scene)" if scene_optional else ""),
        )
        sp.add_argument("-o", "--out", default=None, help="output folder")
        sp.add_argument("-q", "--quiet", action="store_true", help="no progress display")
        sp.add_argument(
            "--set",
            action="append",
            default=[],
            metavar="KEY=VALUE",
            help="override an analysis option (TOML value), e.g. --set lam=1.2 or "
            "--set cycles.max_cycles=50",
        )

    common(sub.add_parser("run", help="run every analysis of a scene"), True)
    for name in ANALYSIS_COMMANDS:
        common(sub.add_parser(name, help=f"run the {name} analysis of a scene"), True)
    sub.add_parser("scenes", help="list the built-in scenes")
    return p


def _version() -> str:
    from ..model.version import __version__

    return __version__


def _parse_value(text: str):
    from .files import tomllib

    try:
        return tomllib.loads(f"x = {text}")["x"]
    except tomllib.TOMLDecodeError:
        return text


def _apply_overrides(scene, names, overrides):
    """Apply ``--set [analysis.]key=value`` options on top of the scene's analysis tables."""
    from dataclasses import replace

    from .files import validate_options

    raw = {name: dict(opts) for name, opts in scene.raw.get("analyses", {}).items()}
    touched = []
    for item in overrides:
        if "=" not in item:
            raise SceneError(f"--set {item!r}: expected KEY=VALUE (e.g. --set lam=1.2)")
        key, value = item.split("=", 1)
        if "." in key:
            name, key = key.split(".", 1)
        elif len(names) == 1:
            name = names[0]
        else:
            raise SceneError(f"--set {item!r}: name the analysis, e.g. --set {names[0]}.{key}=...")
        raw.setdefault(name, {})[key] = _parse_value(value)
        touched.append(name)
    analyses = dict(scene.analyses)
    for name in dict.fromkeys(touched):
        analyses[name] = validate_options(f"{scene.label} (with --set)", name, raw[name])
    return replace(scene, analyses=analyses)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        return _main(args, sys.argv[1:] if argv is None else argv)
    except (SceneError, InputError, ShakedownError) as exc:
        print(f"shakedown: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("shakedown: interrupted", file=sys.stderr)
        return 130


def _main(args, argv=()) -> int:
    from .files import builder_module, builtin_scenes, load_scene, resolved_analyses, run_scene
    from .manifest import RunRecord
    from .output import OutputFolder, Progress

    if args.command == "scenes":
        for name, path in sorted(builtin_scenes().items()):
            sc = load_scene(path)
            print(f"{name:24s} {sc.model['kind']:14s} {sc.description}")
        return 0
    scene = load_scene(args.scene)
    names = None if args.command == "run" else [args.command]
    if names is None:
        run_names = list(scene.analyses) or ["bounds"]
    else:
        run_names = names
    if args.set:
        scene = _apply_overrides(scene, run_names, args.set)
    out = OutputFolder(args.out or Path("shakedown-out") / scene.name)
    progress = Progress(enabled=not args.quiet)
    print(f"scene: {scene.label} ({scene.model['kind']}): {scene.description}".rstrip(": "))
    record = RunRecord.start(scene, out, resolved_analyses(scene, run_names),  # provenance
                             builder_module(scene.model["kind"]), argv)
    t0 = time.perf_counter()
    summaries = run_scene(scene, out, progress, only=run_names)
    elapsed = time.perf_counter() - t0
    for name, summary in summaries.items():
        print(f"\n[{name}]")
        for key, value in summary.items():
            if isinstance(value, float):
                value = f"{value:.6g}"
            print(f"  {key}: {value}")
    meta = {"scene": scene.label, "analyses": summaries, "elapsed_s": elapsed, "cite": record.cite()}
    out.write_json("summary.json", meta)
    record.finish()
    print(f"\n{record.cite()} (BibTeX: CITATIONS.bib)")
    print(f"\nresults written to {out.path}/ ({len(set(out.written))} files, {elapsed:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

