"""The store and the workers are safe to use in shared folders and die with their parent
(issue 10, items 4, 7, 8 and 10).

* writes create new files and rename them into place; a store, a store file or a folder that
  is a symbolic link is refused, and the file it points to stays untouched;
* ``fresh = true`` on a linked store and ``scheduler = "bogus"`` end in a clear error;
* a scene file may not name a Dask scheduler (trusted like code); the command line or the
  environment may;
* worker processes (and the multiprocessing resource tracker) exit within seconds when the
  main process is killed with SIGKILL.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from shakedown.model.errors import InputError, SceneError
from shakedown.studies.store import CsvStore, ParquetStore, Task, Workers, run_tasks, write_atomic

HERE = Path(__file__).resolve().parent


def _link(tmp_path, name="victim.txt"):
    victim = tmp_path / name
    victim.write_text("precious\n")
    return victim


def test_linked_csv_store_is_refused_and_its_target_untouched(tmp_path):
    victim = _link(tmp_path)
    (tmp_path / "runs.csv").symlink_to(victim)
    with pytest.raises(InputError, match="symbolic link"):
        CsvStore(tmp_path / "runs.csv")
    assert victim.read_text() == "precious\n"


def test_linked_parquet_store_folder_is_refused(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "store").symlink_to(tmp_path / "real", target_is_directory=True)
    with pytest.raises(InputError, match="symbolic link"):
        run_tasks([Task("a", dict, (), dict(x=1))], tmp_path / "store", progress=False)
    assert not list((tmp_path / "real").iterdir())


def test_write_atomic_replaces_nothing_through_a_link(tmp_path):
    victim = _link(tmp_path)
    (tmp_path / "out.json").symlink_to(victim)
    with pytest.raises(InputError, match="out.json"):
        write_atomic(tmp_path / "out.json", b"{}")
    assert victim.read_text() == "precious\n"
    write_atomic(tmp_path / "new.json", b"{}")
    assert (tmp_path / "new.json").read_bytes() == b"{}"
    assert not list(tmp_path.glob(".tmp-*"))  # the temporary file was renamed, not left


def test_a_lock_file_that_is_a_link_is_refused(tmp_path):
    victim = _link(tmp_path)
    st = ParquetStore(tmp_path / "s")
    (tmp_path / "s" / ".lock").symlink_to(victim)
    with pytest.raises(InputError, match="symbolic link"), st:
        pass
    assert victim.read_text() == "precious\n"


@pytest.mark.parametrize("bad", ["bogus", "http://x", "tcp://host", ""])
def test_bogus_scheduler_is_a_clear_error(bad, tmp_path):
    if bad == "":
        # the empty string is "no scheduler" in a scene; in Python it is not an address
        with pytest.raises(InputError, match="scheduler must be a Dask scheduler address"):
            Workers(1, scheduler=bad)
        return
    with pytest.raises(InputError, match=f"scheduler must be .*got {bad!r}"):
        run_tasks([Task("a", dict)], tmp_path / "s", scheduler=bad, progress=False)


def test_unreachable_scheduler_is_a_clear_error():
    pytest.importorskip("distributed")
    with pytest.raises(InputError, match="no Dask scheduler answered"):
        Workers(1, scheduler="tcp://127.0.0.1:9", connect_timeout=1.0)


def _sweep_scene(extra=""):
    from shakedown.scenes.files import scene_from_string

    return scene_from_string(textwrap.dedent(f"""
        [model]
        kind = "crack_network"
        n_cracks = 4
        density = 0.05
        seed = 4
        [load]
        static = [-1.0, 0.0, -1.0]
        cyclic = [0.0, 1.0, 0.0]
        [analyses.sweep]
        n_lams = 2
        n_states = 1
        n_workers = 1
        {extra}
    """))


def _ctx(scene, out):
    from shakedown.scenes.files import AnalysisContext
    from shakedown.scenes.output import OutputFolder, Progress

    return AnalysisContext(None, None, None, OutputFolder(out), Progress(enabled=False), None,
                           scene)


def test_scene_file_may_not_name_a_scheduler_but_the_environment_may(tmp_path, monkeypatch):
    from shakedown.scenes.analyses import sweep as analysis

    scene = _sweep_scene('scheduler = "tcp://10.0.0.1:8786"')
    with pytest.raises(SceneError, match="may not name a Dask scheduler.*SHAKEDOWN_SCHEDULER"):
        analysis.run(_ctx(scene, tmp_path / "out"), scene.analyses["sweep"])
    plain = _sweep_scene()
    assert analysis.scheduler_of(plain, plain.analyses["sweep"]) is None
    monkeypatch.setenv("SHAKEDOWN_SCHEDULER", "tcp://127.0.0.1:8786")
    assert analysis.scheduler_of(plain, plain.analyses["sweep"]) == "tcp://127.0.0.1:8786"
    opts = dict(plain.analyses["sweep"], scheduler="tcp://127.0.0.1:1")  # as --set gives it
    assert analysis.scheduler_of(plain, opts) == "tcp://127.0.0.1:1"


def test_fresh_on_a_linked_store_is_refused(tmp_path):
    from shakedown.scenes.analyses import sweep as analysis

    scene = _sweep_scene("fresh = true")
    out = tmp_path / "out"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "keep.txt").write_text("keep")
    (out / "sweep_store").symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(InputError, match="symbolic link"):
        analysis.run(_ctx(scene, out), scene.analyses["sweep"])
    assert (elsewhere / "keep.txt").read_text() == "keep"


# ------------------------------------------------------------------ orphaned workers
def pid_then_sleep(i: int, folder: str) -> dict:
    Path(folder, f"{i}.pid").write_text(str(os.getpid()))
    time.sleep(120)
    return dict(i=i)


def _children(pid: int) -> set[int]:
    out = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        with open(task / "children") as fh:
            out |= {int(x) for x in fh.read().split()}
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    return "\nState:\tZ" not in state  # a zombie has exited; only its parent's wait is left


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("mp_context", ["auto", "spawn"])
def test_workers_exit_when_the_main_process_is_killed(tmp_path, mp_context):
    script = textwrap.dedent(f"""
        import sys
        sys.path[:0] = [{str(HERE)!r}, {str(HERE.parents[1])!r}]
        from test_store_safety import pid_then_sleep
        from shakedown.studies.store import Task, run_tasks
        tasks = [Task(f"k{{i}}", pid_then_sleep, (i, {str(tmp_path)!r})) for i in range(4)]
        if __name__ == "__main__":
            run_tasks(tasks, {str(tmp_path / 'store')!r}, n_workers=2, progress=False,
                      mp_context={mp_context!r})
    """)
    (tmp_path / "main.py").write_text(script)
    proc = subprocess.Popen([sys.executable, str(tmp_path / "main.py")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60
        while len(list(tmp_path.glob("*.pid"))) < 2:
            assert time.time() < deadline, "the workers did not start in 60 s"
            assert proc.poll() is None, "the main process ended early"
            time.sleep(0.1)
        children = _children(proc.pid)  # the 2 workers (and, when spawned, a resource tracker)
        workers = {int(p.read_text()) for p in tmp_path.glob("*.pid")}
        assert workers <= children and len(workers) == 2
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    deadline = time.time() + 10
    while any(_alive(p) for p in children) and time.time() < deadline:
        time.sleep(0.1)
    left = [p for p in children if _alive(p)]
    for p in left:  # do not leave them behind if the test fails
        os.kill(p, signal.SIGKILL)
    assert not left, f"processes {left} outlived their parent by 10 s"


def test_cli_takes_the_scheduler_from_set_but_not_from_the_scene_file(tmp_path, capsys):
    from shakedown.scenes.cli import main

    text = textwrap.dedent("""
        [model]
        kind = "crack_network"
        n_cracks = 4
        density = 0.05
        seed = 4
        [load]
        static = [-1.0, 0.0, -1.0]
        cyclic = [0.0, 1.0, 0.0]
        [analyses.sweep]
        n_lams = 2
        n_states = 1
    """)
    plain = tmp_path / "plain.toml"
    plain.write_text(text)
    shared = tmp_path / "shared.toml"
    shared.write_text(text + 'scheduler = "tcp://10.0.0.1:8786"\n')
    assert main(["sweep", str(shared), "-q", "-o", str(tmp_path / "a")]) == 2
    assert "may not name a Dask scheduler" in capsys.readouterr().err
    # the command line may: the address reaches the workers (and this one is refused there)
    assert main(["sweep", str(plain), "-q", "-o", str(tmp_path / "b"),
                 "--set", "sweep.scheduler=\"bogus\""]) == 2
    err = capsys.readouterr().err
    assert "scheduler must be a Dask scheduler address" in err and "may not name" not in err


def test_the_auto_start_method_forks_only_a_single_threaded_process():
    import multiprocessing
    import threading

    from shakedown.studies.workers import start_method

    assert start_method("spawn") == "spawn" and start_method("forkserver") == "forkserver"
    can_fork = "fork" in multiprocessing.get_all_start_methods()
    if threading.active_count() == 1:
        assert start_method() == ("fork" if can_fork else "spawn")
    stop = threading.Event()
    other = threading.Thread(target=stop.wait, daemon=True)
    other.start()
    try:
        assert start_method() == "spawn"  # a forked child would inherit that thread's locks
    finally:
        stop.set()
        other.join()
