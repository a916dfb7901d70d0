"""Progress of a study on stderr: the shared display (:mod:`shakedown.model.progress`), tasks
done / total with the time left."""

from __future__ import annotations

from ..model.progress import ProgressDisplay

__all__ = ["Progress"]


def Progress(total: int, done: int = 0, desc: str = "sweep", stream=None):  # noqa: N802 (0.1 name)
    """A progress bar of ``total`` tasks, ``done`` of them already in the store."""
    return ProgressDisplay(stream=stream).bar(total=total, desc=desc, initial=done, unit="task")
