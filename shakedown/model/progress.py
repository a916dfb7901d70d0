"""One progress display for every long phase (realisations, runs, load-factor scans, FE builds).

Built on :mod:`tqdm`.  Progress goes to **stderr** (results and verdicts go to stdout), with a
description of what is being done, the count, the elapsed time and the time left:

* on a terminal, one line redrawn in place (at most 5 times a second);
* otherwise (a CI log, a pipe, a file) a few plain lines per phase: at the start, at each
  quarter of the work and at the end, so a log stays short however long the run.

Every stage of the package takes a ``progress`` argument with one calling convention,
``progress(iterable, total=None, desc="")`` returning an iterable (``tqdm`` itself fits), so a
caller may pass a :class:`ProgressDisplay`, ``tqdm.tqdm`` or nothing.
"""

from __future__ import annotations

import contextlib
import re
import sys
import time

#: Redraw interval on a terminal [s].
TTY_INTERVAL = 0.2
#: Lines per phase when stderr is not a terminal: start, each 1/QUARTERS of the work, end.
QUARTERS = 4
#: A phase that took at least this long [s] also reports its end.
PHASE_REPORT = 1.0


_COUNT = re.compile(r"^.*?\d+/(\d+|\?)")


class _Lines:
    """A text stream for tqdm that turns each in-place redraw into one plain line."""

    def __init__(self, stream):
        self.stream = stream
        self._last = None

    def write(self, text: str) -> None:
        text = text.replace("\x1b[A", "").strip("\r\n").split("\r")[-1].rstrip()
        if not text.strip():
            return
        count = _COUNT.search(text)
        key = count.group(0) if count else text
        if key != self._last:  # tqdm's close() repeats the last count: one line is enough
            self.stream.write(text + "\n")
            self._last = key

    def flush(self) -> None:
        self.stream.flush()


class ProgressDisplay:
    """The progress display of a command: tqdm bars on stderr, or nothing.

    Parameters
    ----------
    enabled : bool
        ``False`` shows nothing (``shakedown ... --quiet``).
    stream : text stream, optional
        Default ``sys.stderr``.
    tty : bool, optional
        Force terminal (``True``) or log (``False``) style; default: ``stream.isatty()``.

    Examples
    --------
    >>> progress = ProgressDisplay(enabled=False)
    >>> [x for x in progress(range(3), desc="cycles")]
    [0, 1, 2]
    """

    def __init__(self, enabled: bool = True, stream=None, tty: bool | None = None):
        self.enabled = bool(enabled)
        self.stream = sys.stderr if stream is None else stream
        if tty is None:
            tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.tty = tty

    def bar(self, total: int | None = None, desc: str = "", initial: int = 0, unit: str = "it"):
        """A tqdm bar to drive by hand (``update(n)``, ``set_postfix_str``, ``close()``).

        Parameters
        ----------
        total : int, optional
            Number of items (``None``: unknown, no time left shown).
        desc : str
            What is being done, e.g. ``"cycles at lam = 1.2"``.
        initial : int
            Items already done (e.g. resumed from a store); the rate counts new items only.
        unit : str
            Name of one item, e.g. ``"cycle"``.
        """
        from tqdm import tqdm

        kw = dict(total=total, desc=desc, initial=initial, unit=unit, disable=not self.enabled,
                  dynamic_ncols=True, leave=True)
        if self.tty:
            kw.update(file=self.stream, mininterval=TTY_INTERVAL)
        else:
            # a line at the start, at every quarter, at the end; tqdm prints when both
            # `miniters` items and `mininterval` seconds have passed since the last line
            step = max(1, -(-int(total) // QUARTERS)) if total else 1
            kw.update(file=_Lines(self.stream), mininterval=0.0 if total else 30.0,
                      miniters=step, ncols=100, ascii=True)
        return tqdm(**kw)

    def __call__(self, iterable, total: int | None = None, desc: str = "", unit: str = "it"):
        """Wrap ``iterable``: yields its items and advances the display by one per item."""
        if total is None:
            try:
                total = len(iterable)
            except TypeError:
                total = None
        if not self.enabled:
            yield from iterable
            return
        bar = self.bar(total=total, desc=desc, unit=unit)
        try:
            for item in iterable:
                yield item
                bar.update(1)
        finally:
            bar.close()

    def log(self, message: str) -> None:
        """A line of information on stderr (kept clear of a bar being drawn)."""
        if not self.enabled:
            return
        from tqdm import tqdm

        tqdm.write(message, file=self.stream)

    @contextlib.contextmanager
    def phase(self, desc: str):
        """A phase without a count (e.g. an FE condensation): says what it does and how long it took.

        Examples
        --------
        >>> with ProgressDisplay(enabled=False).phase("building the FE model"):
        ...     pass
        """
        t0 = time.perf_counter()
        self.log(f"{desc} ...")
        yield self
        elapsed = time.perf_counter() - t0
        if elapsed >= PHASE_REPORT:
            self.log(f"{desc}: done in {elapsed:.1f} s")


def progress_bar(total: int | None = None, desc: str = "", initial: int = 0, unit: str = "it",
                 enabled: bool = True):
    """A :meth:`ProgressDisplay.bar` on stderr (terminal or log style chosen automatically)."""
    return ProgressDisplay(enabled=enabled).bar(total=total, desc=desc, initial=initial,
                                                unit=unit)


def described(progress, desc: str, unit: str = "it"):
    """``progress`` with its description replaced by ``desc`` (what a person reads).

    Stages name their phases tersely (``"lam scan"``); a command wraps their ``progress``
    argument with a sentence saying what is being done, e.g. ``"growth-rate scan s"``.
    """
    if progress is None:
        return None

    def call(iterable, total=None, desc=None, **kw):
        if isinstance(progress, ProgressDisplay):
            return progress(iterable, total=total, desc=text, unit=unit)
        return progress(iterable, total=total, desc=text)

    text = desc
    return call
