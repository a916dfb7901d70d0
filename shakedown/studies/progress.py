"""Progress of a study on stderr: tasks done / total, elapsed time and time left.

Kept deliberately simple (one class, ``update``/``close``) so that the command line's shared
progress display can replace it.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """Tasks done / total with elapsed time and an estimate of the time left, on stderr.

    On a terminal the line is redrawn in place (at most every ``min_interval`` s); otherwise a
    line is printed at every 10 % step.  The estimate uses this session's rate only (tasks
    resumed from the store do not count as fast work).
    """

    def __init__(self, total: int, done: int = 0, desc: str = "sweep", stream=None,
                 min_interval: float = 0.5):
        self.total, self.resumed, self.done = int(total), int(done), int(done)
        self.desc = desc
        self.stream = sys.stderr if stream is None else stream
        self.min_interval = min_interval
        self.t0 = time.perf_counter()
        self._last = -1.0
        self._last_decile = -1
        self._last_done = -1
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._draw(force=True)

    def text(self) -> str:
        el = time.perf_counter() - self.t0
        new = self.done - self.resumed
        pct = 100.0 * self.done / self.total if self.total else 100.0
        s = f"{self.desc}: {self.done}/{self.total} tasks ({pct:.0f}%)"
        if self.resumed:
            s += f", {self.resumed} from the store"
        s += f" | {el:.1f} s"
        if 0 < new and self.done < self.total:
            s += f" | ~{el / new * (self.total - self.done):.0f} s left"
        return s

    def _draw(self, force: bool = False) -> None:
        now = time.perf_counter()
        if self._tty:
            if force or now - self._last >= self.min_interval:
                self.stream.write("\r" + self.text() + "\x1b[K")
                self.stream.flush()
                self._last = now
            return
        decile = int(10 * self.done / self.total) if self.total else 10
        if (force and self.done != self._last_done) or decile > self._last_decile:
            self.stream.write(self.text() + "\n")
            self.stream.flush()
            self._last_decile, self._last_done = decile, self.done

    def update(self, n: int = 1) -> None:
        self.done += n
        self._draw(force=self.done >= self.total and not self._tty)

    def close(self) -> None:
        if self._tty:
            self._draw(force=True)
            self.stream.write("\n")
            self.stream.flush()
        else:
            self._draw(force=True)
