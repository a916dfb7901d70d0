"""The constraint-hyperplane engine: shakedown load factors ``lam1``, ``lam2``, ``lam_adj``.

Modules, in the order of the pipeline:

* :mod:`.constraints` -- the extreme constraints ``G v <= c + lam m``, the safe region, and the
  problem's own scales (every LP is solved nondimensionally: answers do not depend on units);
* :mod:`.engine` -- :func:`shakedown_bounds` (drives the LPs, scales the answers back) and the
  Chebyshev safe state;
* :mod:`.dense_path` / :mod:`.highs_path` -- the two LP paths (``solver="auto"`` / ``"highs"``);
* :mod:`.dense_lp` -- dense LP solvers: :mod:`.ipm` (interior point + basis identification) and
  :mod:`.dual_simplex` (batched dual simplex with a Woodbury basis update);
* :mod:`.certificates` -- optimality certificates of every dense answer; :mod:`.lp` -- HiGHS;
* :mod:`.outcome`, :mod:`.result` -- what the paths return and the public result object.

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
