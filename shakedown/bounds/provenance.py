"""Which path each stage of the bounds engine took, how many LPs fell back and why (issue 26).

The dense path (:mod:`.dense_path`) solves the ``lam2`` LP by the interior point, the
activity-interval LPs by the dual simplex and walks (:mod:`.pruning`); an LP that it cannot
certify is re-solved by HiGHS, that LP alone.  :class:`StageLog` keeps, per stage, the LPs
solved by each path, the fallbacks with their reasons and the seconds spent, and drives the
progress display (one step per stage).  The result carries it as
:attr:`~.result.ShakedownBounds.stages`, a tuple of :class:`StageRecord`.

Stages: ``"lam2"`` (the ``lam2`` LP), ``"lam_low"``, ``"lam_high"`` (activity intervals),
``"adjacency"``, ``"separation"``, ``"safe_state"`` (the Chebyshev centre of ``H(safe_lam)``: one
LP, dense when the interior point's centre is certified or its crossover ends certified, else
HiGHS; issue 26: on FE strips it took 30 s of a 32 s computation outside every record).
Paths: ``"dense"`` (interior point / dual simplex, certified),
``"walk"`` (rows decided by a certified vertex walk, no LP), ``"highs"`` (HiGHS re-solve of an
LP the dense path could not certify, or the HiGHS path itself).
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass

#: The stages in the order they run.
STAGES = ("lam2", "lam_low", "lam_high", "adjacency", "separation", "safe_state")


@dataclass(frozen=True)
class StageRecord:
    """What one stage of :func:`~.engine.shakedown_bounds` did.

    Attributes
    ----------
    stage : str
        One of :data:`STAGES`.
    path : str
        ``"dense"``, ``"dense+walk"``, ``"dense+highs"``, ``"highs"`` ...: the paths that
        answered at least one LP (or row) of the stage, joined by ``+``.
    dense_lps : int
        LPs solved and certified by the dense path.
    walk_rows : int
        Rows decided by a certified vertex walk without an LP (``lam_high`` lower bounds).
    highs_lps : int
        LPs solved by HiGHS.
    fallbacks : int
        Of those, LPs the dense path tried first and could not certify.
    reasons : tuple of str
        Why they fell back (``"reason (count)"``).
    seconds : float
        Wall time of the stage [s].
    fallback_seconds : float
        Of it, the time spent in the HiGHS re-solves [s].
    """

    stage: str
    path: str
    dense_lps: int
    walk_rows: int
    highs_lps: int
    fallbacks: int
    reasons: tuple
    seconds: float
    fallback_seconds: float

    def to_dict(self) -> dict:
        """JSON-serialisable form."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


class StageLog:
    """Counts per stage; ``progress`` (``progress(iterable, total=None, desc="")``) shows the
    stages as they start (``None``: nothing shown)."""

    def __init__(self, progress=None, stages=STAGES, desc="shakedown bounds"):
        self._rows = {}
        self._order = []
        #: Why the dense path handed the whole computation to HiGHS (``None``: it did not)
        self.handover = None
        self._current = None
        self._t = None
        self._ticks = iter(progress(iter(stages), total=len(stages), desc=desc)) \
            if progress is not None else None
        self._left = list(stages)  # not yet shown: a stage's tick moves past those skipped

    def _row(self, stage):
        if stage not in self._rows:
            self._rows[stage] = dict(dense=0, walk=0, highs=0, fallbacks=0, reasons=Counter(),
                                     seconds=0.0, fallback_seconds=0.0, highs_only=False)
            self._order.append(stage)
        return self._rows[stage]

    def start(self, stage: str) -> None:
        """Close the running stage (its time) and start ``stage``."""
        self.stop()
        self._row(stage)
        self._current, self._t = stage, time.perf_counter()
        if self._ticks is not None and stage in self._left:  # (a stage run again: no tick)
            while self._left and self._left.pop(0) != stage:
                next(self._ticks, None)  # a stage not run (e.g. adjacency)
            next(self._ticks, None)

    def stop(self) -> None:
        if self._current is not None:
            self._rows[self._current]["seconds"] += time.perf_counter() - self._t
            self._current = None

    def finish(self) -> None:
        """Close the last stage and the progress display."""
        self.stop()
        if self._ticks is not None:
            for _ in self._ticks:  # the stages not run: end the display cleanly
                pass
            self._ticks = None

    @property
    def stage(self) -> str:
        return self._current or "lam2"

    def dense(self, count: int = 1) -> None:
        self._row(self.stage)["dense"] += count

    def walked(self, count: int) -> None:
        self._row(self.stage)["walk"] += int(count)

    def highs(self, seconds: float, reason: str | None) -> None:
        """One HiGHS LP; ``reason``: why the dense path's answer was not used (``None``: the
        HiGHS path itself, no dense attempt)."""
        r = self._row(self.stage)
        r["highs"] += 1
        if reason is not None:
            r["fallbacks"] += 1
            r["reasons"][reason] += 1
            r["fallback_seconds"] += seconds

    def records(self) -> tuple:
        out = []
        for s in self._order:
            r = self._rows[s]
            path = "+".join(p for p in ("dense", "walk", "highs") if r[p]) or "none"
            out.append(StageRecord(
                stage=s, path=path, dense_lps=r["dense"], walk_rows=r["walk"],
                highs_lps=r["highs"], fallbacks=r["fallbacks"],
                reasons=tuple(f"{k} ({v})" for k, v in r["reasons"].most_common()),
                seconds=float(r["seconds"]), fallback_seconds=float(r["fallback_seconds"])))
        return tuple(out)


def costly_fallback(stages, total_seconds: float) -> str:
    """A sentence on the fallbacks when they cost more than everything else together, else
    ``""`` (for the verdict: :func:`~.verdict.bounds_verdict`)."""
    n = sum(s.fallbacks for s in stages)
    t = sum(s.fallback_seconds for s in stages)
    if n == 0 or not t > total_seconds - t:
        return ""
    where = ", ".join(f"{s.fallbacks} {s.stage}" for s in stages if s.fallbacks)
    why = "; ".join(r for s in stages for r in s.reasons)
    return (f"{n} LP(s) ({where}) could not be certified by the dense path ({why}) and were "
            f"re-solved by HiGHS: {t:.3g} s of the {total_seconds:.3g} s computation.")
