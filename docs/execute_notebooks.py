"""Execute every notebook at small size into ``docs/_executed/`` (for a docs build by hand).

    python docs/execute_notebooks.py

The test suite does the same in its notebook test (``tests/test_notebooks.py``) and hands the
executed copies to the docs build, so the docs never execute a notebook themselves.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def execute(path: Path, workdir: Path):
    """The notebook at ``path`` executed at small size in ``workdir``."""
    import nbclient
    import nbformat

    os.environ["SHAKEDOWN_NOTEBOOK_SMALL"] = "1"
    os.environ["MPLBACKEND"] = "Agg"
    nb = nbformat.read(path, as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(workdir)}}).execute()
    return nb


def main() -> int:
    import tempfile

    import nbformat

    out = ROOT / "docs" / "_executed"
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        with tempfile.TemporaryDirectory() as tmp:
            nbformat.write(execute(path, Path(tmp)), out / path.name)
        print(f"executed {path.name}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
