"""The quantities ``shakedown_bounds(..., only=...)`` can be asked for, in 2-D and 3-D."""

from __future__ import annotations

from ..model.errors import InputError

QUANTITIES = ("lam1", "lam2", "lam_adj", "lam_separation")


def parse_only(only):
    """``only`` (a name or names from :data:`QUANTITIES`) as the engines' switches
    ``(intervals, adjacency, separation)``: ``intervals`` is ``"lam1"`` or ``False``.

    Raises :class:`~shakedown.InputError` naming the unknown quantity."""
    if isinstance(only, str):
        only = (only,)
    try:
        wanted = set(only)
    except TypeError as exc:
        raise InputError(f"only must be a list of names from {QUANTITIES}; got {only!r}") from exc
    bad = sorted(str(w) for w in wanted if w not in QUANTITIES)
    if bad:
        raise InputError(
            f"only: unknown quantity {bad[0]!r}; choose from {', '.join(QUANTITIES)}")
    return ("lam1" if "lam1" in wanted else False), "lam_adj" in wanted, \
        "lam_separation" in wanted
