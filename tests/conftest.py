import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("SHAKEDOWN_NOTEBOOK_SMALL", "1")


@pytest.fixture(scope="session")
def executed_notebooks(tmp_path_factory):
    """Execute each notebook at most once per test session (small size).

    ``executed_notebooks(path)`` returns ``(notebook, error)``: the executed notebook and the
    exception its execution raised (``None`` when it ran).  A notebook that ran is also saved
    in ``executed_notebooks.folder``: ``tests/test_notebooks.py`` checks the run, and the docs
    build (``tests/docs/test_docs.py``) renders these copies with their figures instead of
    executing the notebooks again.
    """
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    folder = tmp_path_factory.mktemp("executed_notebooks")
    done = {}

    def get(path: Path):
        path = Path(path)
        if path.name not in done:
            os.environ["SHAKEDOWN_NOTEBOOK_SMALL"] = "1"
            os.environ["MPLBACKEND"] = "Agg"
            nb = nbformat.read(path, as_version=4)
            work = tmp_path_factory.mktemp(path.stem)
            client = nbclient.NotebookClient(
                nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(work)}}
            )
            try:
                client.execute()
                error = None
                nbformat.write(nb, folder / path.name)
            except Exception as exc:  # noqa: BLE001 - reported by the notebook's own test
                error = exc
            done[path.name] = (nb, error)
        return done[path.name]

    get.folder = folder
    return get
