"""Execute every notebook at small size into ``docs/_executed/`` (for a docs build by hand).

    python docs/execute_notebooks.py

The test suite does the same in its notebook test (``tests/test_notebooks.py``, through
:func:`execute`) and hands the executed copies to the docs build, so the docs never execute a
notebook themselves.  The kernel draws with matplotlib's inline backend, so every figure a cell
makes is kept in the notebook as an ``image/png`` output (a non-interactive backend such as
``Agg`` would keep none).  A notebook that ran with fewer figures than its drawing cells
(:func:`missing_figures`) stops this script with an error.
"""

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Environment of the kernel: small size, and the inline backend (figures become outputs).
KERNEL_ENV = {"SHAKEDOWN_NOTEBOOK_SMALL": "1",
              "MPLBACKEND": "module://matplotlib_inline.backend_inline"}

#: A code cell that draws: makes a figure, shows one, or calls a plotting function.
DRAWS = re.compile(r"plt\.(subplots|figure|show)\(|\bplot_\w+\(|\.plot\(|\.loglog\(|\.imshow\(")


def execute(nb, workdir: Path, timeout: int = 600):
    """Execute the notebook ``nb`` (an ``nbformat`` node, changed in place) in ``workdir``.

    The kernel gets :data:`KERNEL_ENV` on top of this process's environment and imports the
    package of this checkout (its root first on ``PYTHONPATH``); errors raise
    (``nbclient.exceptions.CellExecutionError``) with the outputs up to the failing cell kept.
    """
    import nbclient

    os.environ["SHAKEDOWN_NOTEBOOK_SMALL"] = "1"
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(workdir)}})
    # the kernel imports this checkout's package (not another installed copy)
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    client.execute(env={**os.environ, **KERNEL_ENV, "PYTHONPATH": path})
    return nb


def n_figures(cell) -> int:
    """Number of ``image/png`` outputs of a cell."""
    return sum("image/png" in o.get("data", {}) for o in cell.get("outputs", []))


def missing_figures(source, executed) -> list[str]:
    """What an executed notebook lacks against its source (empty: nothing).

    Every code cell of ``source`` that draws (:data:`DRAWS`) must have at least one figure in
    ``executed``, and no cell fewer figures than the stored ``source`` cell has.
    """
    out = []
    code = [(i, c) for i, c in enumerate(source.cells) if c.cell_type == "code"]
    done = [c for c in executed.cells if c.cell_type == "code"]
    if len(code) != len(done):
        return [f"{len(done)} code cells executed, the source has {len(code)}"]
    for (i, src), ex in zip(code, done, strict=True):
        need = max(n_figures(src), 1 if DRAWS.search(src.source) else 0)
        if n_figures(ex) < need:
            out.append(f"cell {i + 1}: {n_figures(ex)} figure(s), its source draws {need}")
    return out


def main() -> int:
    import tempfile

    import nbformat

    out = ROOT / "docs" / "_executed"
    out.mkdir(parents=True, exist_ok=True)
    bad = 0
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        with tempfile.TemporaryDirectory() as tmp:
            execute(nb, Path(tmp))
        nbformat.write(nb, out / path.name)
        missing = missing_figures(nbformat.read(path, as_version=4), nb)
        figures = sum(n_figures(c) for c in nb.cells)
        print(f"executed {path.name}: {figures} figure(s)", file=sys.stderr)
        for m in missing:
            print(f"  missing figure: {m}", file=sys.stderr)
        bad += bool(missing)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
