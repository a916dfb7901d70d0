"""Every notebook runs top to bottom (at small size: SHAKEDOWN_NOTEBOOK_SMALL=1).

Each notebook is executed once per session by the ``executed_notebooks`` fixture
(``tests/conftest.py``); the docs build renders the same executed copies.
"""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, executed_notebooks):
    nb, error = executed_notebooks(path)
    if error is not None:
        raise error
    errors = [
        o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
        if o.get("output_type") == "error"
    ]
    assert not errors
    assert os.environ["SHAKEDOWN_NOTEBOOK_SMALL"] == "1"
