"""The figure check of ``docs/execute_notebooks.py``, importable by the tests."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("execute_notebooks",
                                               ROOT / "docs" / "execute_notebooks.py")
FIGURES = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(FIGURES)


def executed_copies() -> list[Path]:
    """The notebooks in docs/_executed/ (left by ``python3 docs/execute_notebooks.py``)."""
    return sorted((ROOT / "docs" / "_executed").glob("*.ipynb"))
