"""Sweeps on a local Dask cluster give the same rows, bit for bit, as the local run.

A `distributed.LocalCluster` with two worker processes stands in for a remote cluster; the
engine is given its scheduler *address* (as `shakedown sweep --scheduler tcp://...` would be).
The stand-in task functions of tests/test_sweep.py are shipped to the workers by value
(cloudpickle), as a user's own task functions would be.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
import pytest

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")

sys.path.insert(0, str(Path(__file__).resolve().parent))
import test_sweep as helpers  # noqa: E402

from shakedown.studies.store import KEY, run_tasks  # noqa: E402

cloudpickle.register_pickle_by_value(helpers)


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as lc:
        yield lc


def test_dask_run_equals_local_run(tmp_path, cluster):
    tasks = helpers.tasks_for(12)
    local = run_tasks(tasks, tmp_path / "local", progress=False).rows
    res = run_tasks(tasks, tmp_path / "dask", scheduler=cluster.scheduler_address,
                    progress=False)
    assert res.n_run == 12
    pd.testing.assert_frame_equal(res.rows, local, check_exact=True)


def test_dask_resumes_a_local_store(tmp_path, cluster):
    """Half the sweep run locally, the rest on the cluster: every row once, same answer."""
    tasks = helpers.tasks_for(10)
    run_tasks(tasks[:5], tmp_path / "s", progress=False)
    with distributed.Client(cluster.scheduler_address) as client:
        res = run_tasks(tasks, tmp_path / "s", scheduler=client, progress=False)
    assert (res.n_resumed, res.n_run) == (5, 5)
    assert res.rows[KEY].is_unique
    ref = run_tasks(tasks, tmp_path / "ref", progress=False).rows
    pd.testing.assert_frame_equal(res.rows, ref, check_exact=True)


def test_crack_study_on_dask_equals_local(tmp_path, cluster):
    pytest.importorskip("crack_networks")
    pytest.importorskip("shakedown.evolution")
    from shakedown.studies.sweep import SweepSpec, run_sweep

    spec = SweepSpec(n_cracks=8, n_realisations=1, n_lams=3, n_states=2, steps_per_cycle=16,
                     max_cycles=40, seed=9)
    local = run_sweep(spec, tmp_path / "local", n_workers=1, progress=False)
    dask = run_sweep(spec, tmp_path / "dask", scheduler=cluster.scheduler_address,
                     progress=False)
    pd.testing.assert_frame_equal(dask.runs, local.runs, check_exact=True)
    pd.testing.assert_frame_equal(dask.summary, local.summary, check_exact=True)
