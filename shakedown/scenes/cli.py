"""The ``shakedown`` command.

    shakedown run [SCENE]        run every analysis of a scene (default: the built-in scene)
    shakedown bounds SCENE       shakedown load factors lam1, lam2
    shakedown cycles SCENE       cyclic evolution, steady state, dissipation
    shakedown sweep SCENE        Monte Carlo / parameter sweep
    shakedown stability SCENE    critical friction mu* (MCEIP) and growth rates
    shakedown scenes             list the built-in scenes

What it prints, the same for every command:

* **stdout**: first one verdict per analysis (plain sentences, the answer first), then the
  details (numbers rounded to 4 significant digits; the JSON files keep full precision), then
  where the results were written;
* **stderr**: the progress display (:mod:`shakedown.model.progress`) and log lines; nothing
  with ``--quiet``; errors as one line ``shakedown: error: ...`` (exit status 2).

Results (JSON, CSV, PNG) go to ``--out`` (default ``shakedown-out/<scene name>``).  Nodes are
numbered from 1 in everything printed or written.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import time
from pathlib import Path

from ..model.errors import InputError, OutputError, SceneError, ShakedownError

ANALYSIS_COMMANDS = ("bounds", "cycles", "sweep", "stability", "fretting")

_SET_HELP = ("override an option (TOML value): an analysis option (--set lam=1.2, "
             "--set cycles.max_cycles=50) or a scene key (--set model.friction=0.4, "
             "--set model.material.E=2.0, --set load.q0=[0.1,0.2]); repeatable")

_DESCRIPTIONS = {
    "bounds": "Shakedown load factors lam1 <= lam2 (and lam_adj) by linear programming.",
    "cycles": "Cyclic evolution from an initial state: shakedown or cyclic slip, W per cycle.",
    "sweep": "Monte Carlo study of a crack network: W* over realisations x lam x initial states.",
    "stability": "Critical friction mu* (MCEIP-mu) and growth rates s of the divergence "
                 "(MCEIP-lam). MCEIP: mixed complementarity eigenvalue problem.",
    "fretting": "Steady fretting cycle of a half-space scene (sphere on flat): W per cycle, "
                "contact maps, hysteresis loop, stuck zone.",
}


_SHORT = {
    "bounds": "shakedown load factors lam1, lam2, lam_adj",
    "cycles": "cyclic evolution: shakedown or cyclic slip, W per cycle",
    "sweep": "Monte Carlo study of a crack network",
    "stability": "critical friction mu* and growth rates s (MCEIP)",
    "fretting": "steady fretting cycle of a sphere on a flat (half_space scenes)",
}


def _parser() -> argparse.ArgumentParser:
    from .options import options_help

    p = argparse.ArgumentParser(
        prog="shakedown",
        description="Shakedown, cyclic dissipation and stability of frictional elastic systems.",
        epilog="Verdicts and details go to stdout, progress to stderr. "
               "See 'shakedown <command> --help' for the options of each analysis.",
    )
    p.add_argument("--version", action="version", version=f"shakedown {_version()}")
    sub = p.add_subparsers(dest="command", required=True)

    def common(sp):
        sp.add_argument("scene", nargs="?", default=None,
                        help="scene file (TOML) or built-in scene name "
                             "(default: the built-in default scene)")
        sp.add_argument("-o", "--out", default=None,
                        help="output folder (default: shakedown-out/<scene name>)")
        sp.add_argument("-q", "--quiet", action="store_true",
                        help="no progress display or log on stderr")
        sp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help=_SET_HELP)

    fmt = argparse.RawDescriptionHelpFormatter
    common(sub.add_parser(
        "run", help="run every analysis of a scene", formatter_class=fmt,
        description="Run every analysis of the scene's [analyses] tables (bounds if none).",
        epilog="The options of each analysis: shakedown bounds|cycles|sweep|stability|fretting "
               "--help"))
    for name in ANALYSIS_COMMANDS:
        common(sub.add_parser(name, help=_SHORT[name],
                              description=_DESCRIPTIONS[name], epilog=options_help(name),
                              formatter_class=fmt))
    sub.add_parser("scenes", help="list the built-in scenes")
    return p


def _version() -> str:
    from ..model.version import __version__

    return __version__


def _apply_overrides(scene, names, overrides):
    """``--set`` options applied (kept for callers of the 0.1 name; see :mod:`.options`)."""
    from .options import apply_overrides

    return apply_overrides(scene, names, overrides)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    # a cold numba cache (first run after installing): steps in Python now, the kernel
    # compiled in the background for the next runs (evolution/kernel_warm.py); the variable
    # reaches this command's worker processes and is restored afterwards
    from ..evolution import kernel_warm

    policy = os.environ.get(kernel_warm.POLICY_VAR)
    if policy is None:
        os.environ[kernel_warm.POLICY_VAR] = "background"
    try:
        return _run_main(args, argv)
    finally:
        if policy is None:
            os.environ.pop(kernel_warm.POLICY_VAR, None)
        note = kernel_warm.background_note()
        if note and not getattr(args, "quiet", False):
            print(f"shakedown: {note}", file=sys.stderr)


def _run_main(args, argv) -> int:
    try:
        return _main(args, sys.argv[1:] if argv is None else argv)
    except OutputError as exc:  # the disk refused a result file: nothing half-written
        print(f"shakedown: error: {exc}", file=sys.stderr)
        return 74  # EX_IOERR
    except (SceneError, InputError, ShakedownError) as exc:
        print(f"shakedown: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("shakedown: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `shakedown run | head`: the reader stopped early, after every
        # result file was written (they are written before anything is printed): success
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, AttributeError, ValueError):  # (a stdout without a file descriptor)
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 -- silence the exit-time flush
        return 0


def format_value(value) -> str:
    """A detail value for reading: floats to 4 significant digits, lists shortened."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, (list, tuple)):
        items = [format_value(v) for v in value[:10]]
        return "[" + ", ".join(items) + (", ..." if len(value) > 10 else "") + "]"
    return str(value)


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
    run_names = (list(scene.analyses) or ["bounds"]) if args.command == "run" else [args.command]
    if args.set:
        scene = _apply_overrides(scene, run_names, args.set)
    # results are staged inside the folder and moved into place only once the run has
    # succeeded (with its provenance): a failed or refused run leaves the folder as it was
    out = OutputFolder(args.out or Path("shakedown-out") / scene.name, staged=True)
    progress = Progress(enabled=not args.quiet)
    t0 = time.perf_counter()
    # whatever an analysis prints while it runs is a detail: shown after all verdicts
    printed = io.StringIO()
    try:
        record = RunRecord.start(scene, out, resolved_analyses(scene, run_names),  # provenance
                                 builder_module(scene.model["kind"]), argv)
        with contextlib.redirect_stdout(printed):
            summaries = run_scene(scene, out, progress, only=run_names)
        elapsed = time.perf_counter() - t0
        meta = {"scene": scene.label, "analyses": summaries, "elapsed_s": elapsed,
                "node_numbering": "from 1", "cite": record.cite()}
        out.write_json("summary.json", meta)
        record.finish()
        out.commit()
    except BaseException:
        out.discard()
        with contextlib.suppress(OSError, ValueError):
            sys.stdout.write(printed.getvalue())
        raise
    # every file is in place before anything is printed: a closed stdout costs no file
    for name, summary in summaries.items():
        print(f"{name}: {summary.get('verdict', '(no verdict)')}")
    print(f"\nscene: {scene.label} ({scene.model['kind']}): {scene.description}".rstrip(": "))
    for name, summary in summaries.items():
        print(f"\n[{name}]")
        for key, value in summary.items():
            if key != "verdict":
                print(f"  {key}: {format_value(value)}")
    if printed.getvalue().strip():
        print("\n" + printed.getvalue().rstrip())
    print(f"\n{record.cite()} (BibTeX: CITATIONS.bib)")
    print(f"\nresults written to {out.path}/ ({len(set(out.written))} files, {elapsed:.1f} s)")
    sys.stdout.flush()
    return 0

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
