"""Every notebook runs top to bottom (at small size: SHAKEDOWN_NOTEBOOK_SMALL=1) and keeps its
figures.

Each notebook is executed once per session by the ``executed_notebooks`` fixture
(``tests/conftest.py``, through ``docs/execute_notebooks.py``); the docs build renders the same
executed copies.
"""

import os
from pathlib import Path

import nbformat
import pytest
from notebook_figures import FIGURES, executed_copies

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


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_executed_notebook_keeps_every_figure(path, executed_notebooks):
    """Each cell that draws has its figure as an image/png output (issue 25: none had)."""
    nb, error = executed_notebooks(path)
    if error is not None:
        pytest.skip("the notebook failed: reported by test_notebook_runs")
    missing = FIGURES.missing_figures(nbformat.read(path, as_version=4), nb)
    assert not missing, f"{path.name}: {missing}"


@pytest.mark.parametrize("path", executed_copies(), ids=lambda p: p.name)
def test_docs_executed_copies_keep_every_figure(path):
    """The copies ``docs/execute_notebooks.py`` left in docs/_executed/ (when there are any)."""
    source = ROOT / "notebooks" / path.name
    if not source.is_file():
        pytest.skip(f"{path.name} is no longer in notebooks/")
    missing = FIGURES.missing_figures(nbformat.read(source, as_version=4),
                                      nbformat.read(path, as_version=4))
    assert not missing, (f"{path}: {missing}; rerun python3 docs/execute_notebooks.py")


def test_figure_check_catches_a_notebook_without_figures():
    """The check itself: a drawing cell with no image/png output is reported."""
    src = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_code_cell("import matplotlib.pyplot as plt"),
        nbformat.v4.new_code_cell("fig, ax = plt.subplots()\nax.plot([0, 1])")])
    executed = nbformat.from_dict(src)
    assert FIGURES.missing_figures(src, executed) == ["cell 2: 0 figure(s), its source draws 1"]
    executed.cells[1].outputs = [nbformat.v4.new_output(
        "display_data", data={"image/png": "iVBOR", "text/plain": "<Figure>"})]
    assert FIGURES.missing_figures(src, executed) == []


def _text_outputs(nb) -> str:
    return "\n".join(
        o.get("text", "") + o.get("data", {}).get("text/plain", "")
        for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_outputs_hold_no_solver_banner(path, executed_notebooks):
    """HiGHS printed its banner into notebook 03 (issue 25); no output shows a solver's log."""
    nb, error = executed_notebooks(path)
    if error is not None:
        pytest.skip("the notebook failed: reported by test_notebook_runs")
    assert "Running HiGHS" not in _text_outputs(nb)


def test_notebook_04_says_which_study_its_outputs_come_from(executed_notebooks):
    """The stored outputs are the full-size study's, the executed (rendered) ones the small one's:
    the introduction names both, with the sizes their SweepSpec outputs print."""
    import re

    path = ROOT / "notebooks" / "04_monte_carlo.ipynb"
    stored = nbformat.read(path, as_version=4)
    intro = " ".join(stored.cells[0].source.split())
    for nb, label in ((stored, "stored"), (executed_notebooks(path)[0], "executed")):
        spec = re.search(r"SweepSpec\(n_cracks=(\d+),.*?n_realisations=(\d+)", _text_outputs(nb))
        assert spec, f"{label}: no SweepSpec output"
        n_cracks, n_real = map(int, spec.groups())
        said = (f"{n_real} x " if label == "stored" else f"{n_real} realisations of {n_cracks} cracks")
        assert said in intro, (label, said, intro[-700:])
    assert "full-size" in intro and "small size" in intro
