"""Dask is the one optional extra (issue 9): without it a scheduler gives one line naming the
extra to install, never a traceback."""

import sys

import pytest

import shakedown as sd
from shakedown.scenes.cli import main


def test_workers_without_dask_name_the_extra(monkeypatch):
    from shakedown.studies.store import Workers

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    with pytest.raises(sd.MissingDependencyError, match=r'pip install "shakedown\[parallel\]"'):
        Workers(1, scheduler="tcp://127.0.0.1:8786")


def test_cli_without_dask_prints_one_line(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)
    rc = main(["sweep", "-q", "-o", str(tmp_path), "--set", "model.n_cracks=4",
               "--set", "sweep.scheduler=\"tcp://127.0.0.1:8786\""])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert 'pip install "shakedown[parallel]"' in err and "Traceback" not in err
