"""Short ``repr`` and callable verdicts for every result type (issue 25).

``print(run)`` of a result should show what it is in a few lines, not its arrays:
:func:`short_repr` writes ``ClassName(key=value, ...)`` for the scalar attributes a class names,
numbers to 4 significant digits (:func:`~shakedown.model.numbers.sig`), arrays and tables as
their shapes, wrapped at 100 characters.  Every result type also has ``verdict()``: its answer
in plain sentences.  :class:`VerdictText` lets a result whose verdict is a stored string
(``SweepResult.verdict``) be called like the others.
"""

from __future__ import annotations

import textwrap

import numpy as np

from .numbers import sig

__all__ = ["short_repr", "VerdictText", "every_state_claim", "bounds_claim"]

WIDTH = 100


def _value(v) -> str:
    if isinstance(v, bool | np.bool_):
        return str(bool(v))
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return sig(v)
    if isinstance(v, str):
        return repr(v if len(v) <= 60 else v[:57] + "...")
    if isinstance(v, np.ndarray):
        return f"<array {'x'.join(map(str, v.shape)) or 'scalar'}>"
    if hasattr(v, "shape") and hasattr(v, "columns"):
        return f"<table {v.shape[0]} rows x {v.shape[1]} columns>"
    if isinstance(v, tuple | list):
        return f"<{len(v)} items>"
    if v is None:
        return "None"
    return f"<{type(v).__name__}>"


def short_repr(obj, keys, extra: dict | None = None) -> str:
    """``ClassName(key=value, ...)`` of ``obj``'s attributes ``keys`` (then ``extra``), wrapped.

    Parameters
    ----------
    obj : object
    keys : sequence of str
        Attribute names, in order; scalars are printed, arrays and tables as their shapes.
    extra : dict, optional
        More ``name: value`` pairs (derived quantities).

    Returns
    -------
    str
        At most a few lines of ``WIDTH`` characters.
    """
    items = [f"{k}={_value(getattr(obj, k))}" for k in keys]
    items += [f"{k}={_value(v)}" for k, v in (extra or {}).items()]
    name = type(obj).__name__
    body = ", ".join(items)
    lines = textwrap.wrap(body, WIDTH - len(name) - 2, break_long_words=False,
                          break_on_hyphens=False)
    pad = " " * (len(name) + 1)
    return name + "(" + ("\n" + pad).join(lines) + ")"


def every_state_claim(n_nodes: int, coupled: bool) -> tuple[bool, str]:
    """Whether "shakes down from every initial state for lam < lam1" is proved for a system of
    ``n_nodes`` nodes (``coupled``: ``B != 0``), and the words for the status of that claim.

    Proved for one or two nodes and for ``B = 0`` (the seed's theorem); for three or more
    coupled nodes it is numerical evidence (README 'Findings'): it failed between ``lam_adj``
    and ``lam1``, and no run contradicted it below ``lam_adj``.
    """
    if n_nodes <= 2:
        return True, "proved for one or two nodes"
    if not coupled:
        return True, "proved for B = 0"
    return False, ("numerical evidence for three or more coupled nodes, not a proof: README "
                   "'Findings'")


def bounds_claim(b) -> tuple[bool, str]:
    """:func:`every_state_claim` of a :class:`~shakedown.ShakedownBounds` (``B = 0`` read from
    its no-separation rows ``-B^T``)."""
    sep = b.constraints.sep_G
    coupled = bool(sep.nnz if hasattr(sep, "nnz") else np.count_nonzero(sep))
    return every_state_claim(int(b.n_nodes), coupled)


class VerdictText(str):
    """A verdict stored as a string that can also be called: ``res.verdict`` and
    ``res.verdict()`` give the same text, as ``verdict()`` does for every other result."""

    def __call__(self) -> str:
        return str(self)
