"""Test-session settings shared by every folder.

Hypothesis profiles (issue 15): with the ``CI`` environment variable set, the ``ci`` profile is
loaded: derandomised (the examples are a fixed function of each test, so a CI run cannot fail
for no change of code), ``print_blob=True`` (a failure prints the ``@reproduce_failure`` blob),
no deadline (the machine is shared).  Locally the ``dev`` profile explores freely with a new
random seed each run; pin one with ``pytest --hypothesis-seed=N`` to replay a failure (the seed
is printed in the header line ``hypothesis profile ...``).  ``HYPOTHESIS_PROFILE=<name>``
overrides both.

External peers (Siconos, GetFEM) run in their own job: ``pytest -m peers`` (see
benchmarks/RESULTS_peers.md); in the default run they are skipped with a visible reason.
"""

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import matplotlib
import pytest
from hypothesis import HealthCheck, settings

matplotlib.use("Agg")
os.environ.setdefault("SHAKEDOWN_NOTEBOOK_SMALL", "1")

settings.register_profile(
    "ci", derandomize=True, print_blob=True, deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

PEERS_SKIP = ("external peer cross-check (Siconos / GetFEM under /usr/bin/python3): run it with "
              "`python3 -m pytest -m peers`; last run in benchmarks/RESULTS_peers.md")


@pytest.fixture(scope="session", autouse=True)
def _kernels_compiled_in_the_background():
    """Start ``tests/warm_kernels.py`` at the start of the session (see there: on a cold numba
    cache it compiles the kernels on the second core while the first tests need none); stopped
    at the end of the session if still running.  ``SHAKEDOWN_KERNEL=numpy`` skips it."""
    import subprocess
    import sys

    from shakedown.evolution.kernel_warm import policy

    if policy() == "off":
        yield
        return
    here = Path(__file__).resolve().parent
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(here.parent), os.environ.get("PYTHONPATH", "")) if p)}
    proc = subprocess.Popen([sys.executable, str(here / "warm_kernels.py")], env=env,
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    yield
    if proc.poll() is None:
        proc.kill()
    proc.wait()


def pytest_collection_modifyitems(config, items):
    """Skip ``peers`` tests, with a visible reason, unless the run selects them (``-m peers``)."""
    import pytest

    if "peers" in (config.getoption("markexpr") or "").replace("not peers", ""):
        return
    skip = pytest.mark.skip(reason=PEERS_SKIP)
    for item in items:
        if "peers" in item.keywords:
            item.add_marker(skip)


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
    pytest.importorskip("nbclient")
    folder = tmp_path_factory.mktemp("executed_notebooks")
    done = {}

    from notebook_figures import FIGURES  # docs/execute_notebooks.py: one way to execute

    def run(path: Path, workdir: Path):
        nb = nbformat.read(path, as_version=4)
        try:
            FIGURES.execute(nb, workdir)
            error = None
            nbformat.write(nb, folder / path.name)
        except Exception as exc:  # noqa: BLE001 - reported by the notebook's own test
            error = exc
        return nb, error

    def get(path: Path):
        """The first request executes every notebook of ``path``'s folder not yet executed,
        as many at once as there are cores (each in its own kernel process: the suite's
        longest setup, about half the time on two cores)."""
        path = Path(path)
        if path.name not in done:
            todo = [p for p in sorted(path.parent.glob("*.ipynb")) if p.name not in done]
            todo = todo if path in todo else [path, *todo]
            dirs = [tmp_path_factory.mktemp(p.stem) for p in todo]
            with ThreadPoolExecutor(max(1, min(len(todo), os.cpu_count() or 1))) as pool:
                for p, out in zip(todo, pool.map(run, todo, dirs), strict=True):
                    done[p.name] = out
        return done[path.name]

    get.folder = folder
    return get


def _banded_system(n, seed=0, coupling=0.3, bands=(1, 2, 5), friction=0.3):
    """A sparse-structured SPD system (a few neighbours per node, diagonally dominant), dense."""
    import numpy as np

    import shakedown as sd

    rng = np.random.default_rng(seed)
    K = np.zeros((2 * n, 2 * n))
    for d in bands:
        v = rng.uniform(-1, 1, 2 * n - d) * 0.3
        K += np.diag(v, d) + np.diag(v, -d)
    K[:n, n:] *= coupling / 0.3
    K[n:, :n] *= coupling / 0.3
    K += np.diag(np.abs(K).sum(axis=1) + rng.uniform(0.5, 1.5, 2 * n))
    return sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=friction)


@pytest.fixture(scope="session")
def banded_system():
    """Factory ``banded_system(n, seed=0, coupling=0.3, bands=(1, 2, 5), friction=0.3)``: a dense
    SPD system whose ``K`` has a few bands (its ``to_sparse()`` twin is genuinely sparse)."""
    return _banded_system


@pytest.fixture(scope="session")  # stateless factories: usable under hypothesis too
def harmonic_load():
    """Factory ``harmonic_load(rng, system, amp=2.0, p_mean=1.0, p_amp=0.3)``: a random
    one-harmonic load (tangential amplitude ``amp`` times the friction, mean normal ``p_mean``,
    normal amplitude ``p_amp``)."""
    def make(rng, s, amp=2.0, p_mean=1.0, p_amp=0.3):
        import numpy as np

        import shakedown as sd

        n = s.n_nodes
        f = float(s.friction.max())
        return sd.LoadCycle.from_harmonics(0.1 * rng.normal(size=n), np.full(n, p_mean),
                                           q_cos=amp * f * rng.normal(size=n),
                                           p_sin=p_amp * rng.normal(size=n))
    return make
