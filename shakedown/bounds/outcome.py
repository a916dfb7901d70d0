"""What an LP path (dense or HiGHS) hands back to :func:`~.engine.shakedown_bounds`.

Both paths work on a nondimensional :class:`~.constraints.ConstraintSet` (see
:class:`~.constraints.Scales`) and return a :class:`PathOutcome` in those units; the engine scales
it back.  The helpers here turn LP values into ``lam1`` and the no-separation limit the same way
for both paths.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.errors import InputError, SolverError
from .lp import LPAnswer
from .result import LAM_RTOL


@dataclass
class PathOutcome:
    """Answers of one LP path, nondimensional (see the fields of :class:`ShakedownBounds`)."""

    lam1: float
    lam2: float
    status: str
    messages: list
    lam_low: np.ndarray
    lam_high: np.ndarray
    v_at_lam2: np.ndarray
    certificate: np.ndarray
    hi_exact: np.ndarray | None = None
    lam_adj: float = np.nan
    adj_node: int = -1
    limiting: int = -1
    lam_sep: float = np.nan
    sep_nodes: tuple = ()
    residuals: dict = field(default_factory=dict)
    n_lps: int = 0
    iterations: int = 0
    stages: tuple = ()  # provenance.StageRecord per stage


def value(ans: LPAnswer) -> float:
    """The ``lam`` column of a HiGHS answer (``+-inf`` unbounded, ``nan`` infeasible).

    Raises
    ------
    SolverError
        Any other status (time limit, numerical trouble): formerly read as "infeasible", which
        turned a 2000-crack ``lam2`` LP that hit HiGHS's time limit into ``status =
        "infeasible"`` (issue 26)."""
    if ans.status == "optimal":
        return float(ans.x[-1])
    if ans.status.startswith("unbounded"):
        return np.inf if ans.objective > 0 else -np.inf
    if ans.status == "infeasible":
        return np.nan
    raise SolverError(f"HiGHS stopped with status {ans.status!r} after {ans.iterations} "
                      "iterations: no answer to report (raise ReusableLP's time_limit, or "
                      "check the model's scales)")


def lam1_from_intervals(labels, lam_low, lam_high, lam2, messages):
    """``lam1`` and the limiting constraint from the activity intervals (engine docstring)."""
    tol = LAM_RTOL * (1.0 if not np.isfinite(lam2) else max(1.0, lam2))
    never = np.isnan(lam_high)
    not_at_zero = never | (lam_low > tol)
    if np.any(not_at_zero):
        limiting = int(np.argmax(not_at_zero))
        messages.append(f"{labels[limiting]} is inactive already at lam = 0")
        return 0.0, limiting
    limiting = int(np.nanargmin(lam_high))
    lam1 = float(lam_high[limiting])
    if np.isfinite(lam2) and lam1 >= lam2 - tol:
        lam1 = lam2  # every constraint stays active until H vanishes (Melan case)
    if np.isinf(lam1):
        limiting = -1
    return lam1, limiting


def separation_outcome(ans: LPAnswer, lam2: float, n: int, rows: int | None = None):
    """``(lam_separation, separation_nodes)`` from the no-separation LP (nondimensional); the
    first ``rows`` rows (default ``2 n``: I and II) are the friction rows, the ``n``
    separation rows follow."""
    lam_sep = value(ans)
    sep_nodes = ()
    if ans.status == "optimal" and (not np.isfinite(lam2) or lam_sep < lam2 - 1e-9 * max(1, lam2)):
        duals = ans.row_dual[(2 * n if rows is None else rows):]
        dmax = float(np.abs(duals).max(initial=0.0))
        sep_nodes = tuple(int(j) for j in np.flatnonzero(np.abs(duals) > 1e-9 * dmax))
    return lam_sep, sep_nodes


def intervals_option(intervals):
    """``"lam1"``, ``"all"`` or ``False`` from the ``intervals=`` argument."""
    if intervals is True or intervals == "all":
        return "all"
    if intervals is False or intervals is None:
        return False
    if intervals == "lam1":
        return "lam1"
    raise InputError(f"intervals must be 'lam1', True ('all') or False; got {intervals!r}")
