"""The constraint-hyperplane engine: shakedown load factors ``lam1``, ``lam2``, ``lam_adj``.

Holds the extreme constraints (MODEL.md s.3), the LP solvers (dense interior point and batched
dual simplex in :mod:`.dense_lp`, HiGHS in :mod:`.lp`) and their certificates.
May import :mod:`shakedown.model` only.
"""

from .engine import (
    INF,
    ConstraintSet,
    SafeRegion,
    ShakedownBounds,
    chebyshev_centre,
    extreme_constraints,
    safe_region,
    shakedown_bounds,
)

__all__ = [
    "ConstraintSet",
    "SafeRegion",
    "ShakedownBounds",
    "chebyshev_centre",
    "extreme_constraints",
    "safe_region",
    "shakedown_bounds",
    "INF",
]
