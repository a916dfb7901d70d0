"""The progress display (issue 9): tqdm on stderr, with what is done and the time left; a few
lines per phase when stderr is not a terminal (CI logs); nothing with --quiet."""

import io

from shakedown.model.progress import QUARTERS, ProgressDisplay


def test_log_style_prints_a_few_lines_with_the_description_and_time_left():
    buf = io.StringIO()
    out = list(ProgressDisplay(stream=buf, tty=False)(range(1000), desc="lam scan"))
    assert out == list(range(1000))  # items pass through unchanged
    lines = buf.getvalue().splitlines()
    # start, every quarter, end: QUARTERS + 1 lines at most, whatever the length of the phase
    assert 2 <= len(lines) <= QUARTERS + 1, lines
    assert all(ln.startswith("lam scan:") for ln in lines)
    assert "1000/1000" in lines[-1] and "<" in lines[-1]  # count, elapsed<left
    assert "\r" not in buf.getvalue()


def test_terminal_style_redraws_in_place():
    buf = io.StringIO()
    list(ProgressDisplay(stream=buf, tty=True)(range(50), desc="runs"))
    assert "\r" in buf.getvalue() and "50/50" in buf.getvalue()


def test_bar_resumed_work_and_phase():
    buf = io.StringIO()
    p = ProgressDisplay(stream=buf, tty=False)
    bar = p.bar(total=10, desc="runs", initial=4, unit="task")
    for _ in range(6):
        bar.update(1)
    bar.close()
    assert "10/10" in buf.getvalue().splitlines()[-1]
    with p.phase("building the fe model"):
        pass
    assert "building the fe model ..." in buf.getvalue()


def test_disabled_prints_nothing():
    buf = io.StringIO()
    p = ProgressDisplay(enabled=False, stream=buf)
    assert list(p(range(5), desc="x")) == list(range(5))
    bar = p.bar(total=3)
    bar.update(3)
    bar.close()
    p.log("hello")
    with p.phase("x"):
        pass
    assert buf.getvalue() == ""
