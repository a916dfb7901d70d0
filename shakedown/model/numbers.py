"""Numbers for reading: one formatter for every verdict (issue 25).

Verdicts promise numbers "rounded to 4 significant digits"; ``f"{x:.4g}"`` drops trailing zeros
(``2.650`` prints as ``2.65``, ``1.000`` as ``1``), so a reader cannot tell 2.65 from 2.650 or
an exact 1 from 0.99996.  :func:`sig` keeps them.
"""

from __future__ import annotations

import math

__all__ = ["sig", "position"]


def sig(x, digits: int = 4) -> str:
    """``x`` to ``digits`` significant digits, trailing zeros kept; ``inf``/``nan`` spelled out.

    Parameters
    ----------
    x : float
        Any real number (dimensionless or in the caller's units).
    digits : int
        Significant digits (>= 1).

    Returns
    -------
    str
        ``"2.650"`` for 2.6498, ``"1.000"`` for 1, ``"0.0004751"`` for 4.751e-4,
        ``"1.235e+06"`` for 1234567, ``"0"`` for 0 (an exact zero has no significant digits).

    Examples
    --------
    >>> sig(2.6498), sig(1.0), sig(1000.0), sig(-0.047509), sig(0.0), sig(float("inf"))
    ('2.650', '1.000', '1000', '-0.04751', '0', 'inf')
    """
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x == 0:
        return "0"
    text = f"{x:#.{int(digits)}g}"
    return text[:-1] if text.endswith(".") else text


def position(index) -> str:
    """An array position in the words of everything a person reads: numbered from 1.

    ``(0, 1)`` -> ``"row 1, column 2"``; ``(4,)`` or ``4`` -> ``"entry 5"``; more axes ->
    ``"position (1, 2, 3) (numbered from 1)"``.  Python indices stay 0-based (README).
    """
    idx = tuple(int(i) for i in (index if isinstance(index, tuple | list) else (index,)))
    if len(idx) == 1:
        return f"entry {idx[0] + 1}"
    if len(idx) == 2:
        return f"row {idx[0] + 1}, column {idx[1] + 1}"
    return f"position {tuple(i + 1 for i in idx)} (numbered from 1)"
