"""The result object of :func:`shakedown.shakedown_bounds` (fields, table, JSON, summary)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .constraints import ConstraintSet

#: Relative tolerance used to decide that two load factors coincide (LP tolerance 1e-7 of
#: HiGHS's default primal/dual feasibility, in nondimensional units).
LAM_RTOL = 1e-7


@dataclass(frozen=True)
class ShakedownBounds:
    """Shakedown load factors of a system under a periodic load, with certificates.

    Attributes
    ----------
    lam1 : float
        Below ``lam1`` every extreme constraint is active (the seed's criterion for shakedown
        from every initial state; proven for two nodes and for ``B = 0``). ``inf`` if never lost;
        ``nan`` when not computed (``intervals=False``) or when no safe state exists.
    lam2 : float
        Above ``lam2`` no safe state exists: cyclic slip from every initial state.
    status : str
        ``"bounded"``; ``"unbounded_no_periodic_part"`` (no periodic load: ``lam2 = inf``);
        ``"unbounded_periodic_never_excludes"`` (the periodic part never tightens a constraint,
        ``m >= 0``); ``"unbounded"`` (a safe state exists for every ``lam`` for another
        reason); ``"infeasible"`` (no safe state for any ``lam >= 0``: gross slip under the
        static load, ``lam1 = lam2 = nan``).
    message : str
    lam_adj : float
        First ``lam`` at which the extreme facets ``I_j``, ``II_j`` of one node meet in ``H``;
        ``inf`` if they never meet, ``nan`` when not computed (``adjacency=False``).
    adjacency_node : int
        That node (0-based; ``-1`` if never or not computed).
    limiting_constraint : int
        Index ``k`` (``0..2N-1``) of the constraint that becomes inactive at ``lam1``
        (``-1`` if none); ``limiting_label`` names it (``"I_j"`` / ``"II_j"``).
    lam_low, lam_high : ndarray, shape (2N,)
        Activity interval of every extreme constraint (``nan`` if never active or not
        computed).  ``lam_low`` is exact.  ``lam_high[k]`` is exact where ``lam_high_exact[k]``;
        elsewhere (default ``intervals="lam1"``) it is a proven lower bound, ``>= lam1``: the
        constraint is active at least on ``[lam_low[k], lam_high[k]]``, possibly beyond.
    lam_high_exact : ndarray of bool, shape (2N,)
        Which ``lam_high`` entries are exact (all ``True`` with ``intervals=True`` /
        ``"all"`` or ``solver="highs"``; all ``False`` when intervals were not computed).
    lam_separation : float
        Largest ``lam`` for which a safe state with ``p_w(t) + B^T v >= 0`` at every node and
        time exists; above it (up to ``lam2``) every safe state needs a tensile normal reaction
        at ``separation_nodes``.  For nodes with ``f > 0`` the friction constraints already
        imply ``p >= 0`` in ``H``, so ``lam_separation = lam2`` unless a node is frictionless.
        ``nan`` when not computed (``separation=False``) or when no such state exists.
    separation_nodes : tuple of int
        0-based node indices.
    safe_lam : float
        Load factor at which ``safe_state`` was computed.
    safe_state : ndarray, shape (N,)
        Chebyshev centre of ``H(safe_lam)`` (the safe slip state farthest from every extreme
        constraint) or empty if ``H`` is empty.
    safe_margin : float
        Its distance to the nearest extreme constraint [slip units], exact for ``safe_state``
        and proven at most ``engine.CENTRE_RTOL`` (1e-4, relative) below the largest possible.
    state_at_lam2 : ndarray, shape (N,)
        The LP optimum ``v*`` at ``lam2`` (the last safe point).
    certificate : ndarray, shape (2N,)
        Dual multipliers ``y >= 0`` of the ``lam2`` LP [1 / force]: ``G^T y = 0`` and
        ``lam2 = c.y / (-m.y)`` prove that ``H(lam)`` is empty for ``lam > lam2``.
    residuals : dict
        Worst primal, dual-sign, stationarity and complementarity residuals over all LPs
        (relative to the problem's scales: unit-free).
    n_lps, simplex_iterations : int
    solve_time : float
        Seconds.
    constraints : ConstraintSet
    stages : tuple of StageRecord
        Which path each stage took (dense, walk, HiGHS re-solve), how many LPs fell back to
        HiGHS and why, and the seconds of each (:mod:`shakedown.bounds.provenance`).
    """

    lam1: float
    lam2: float
    status: str
    message: str
    lam_adj: float
    adjacency_node: int
    limiting_constraint: int
    lam_low: np.ndarray
    lam_high: np.ndarray
    lam_high_exact: np.ndarray
    lam_separation: float
    separation_nodes: tuple
    safe_lam: float
    safe_state: np.ndarray
    safe_margin: float
    state_at_lam2: np.ndarray
    certificate: np.ndarray
    residuals: dict
    n_lps: int
    simplex_iterations: int
    solve_time: float
    constraints: ConstraintSet = field(repr=False)
    stages: tuple = field(default=(), repr=False)

    @property
    def n_nodes(self) -> int:
        return self.constraints.n_nodes

    @property
    def intervals_computed(self) -> str:
        """``"exact"`` (every activity interval exact), ``"lam1"`` (``lam_high`` exact only where
        ``lam1`` needs it, proven lower bounds elsewhere) or ``"none"`` (not computed)."""
        if self.lam_high_exact.size and self.lam_high_exact.all():
            return "exact"
        if np.isnan(self.lam_high).all() and not self.lam_high_exact.any():
            return "none"
        return "lam1"

    @property
    def limiting_label(self) -> str:
        k = self.limiting_constraint
        return self.constraints.labels()[k] if k >= 0 else ""

    def active_at(self, lam: float) -> np.ndarray:
        """Boolean mask (2N,) of the constraints active at ``lam``.

        Exact where ``lam_high_exact``; elsewhere ``lam_high`` is a lower bound (default
        ``intervals="lam1"``), so above ``lam1`` the mask may miss constraints that are still
        active (it never includes an inactive one).  Use ``intervals=True`` for exact counts.
        """
        tol = LAM_RTOL * max(1.0, abs(lam))
        with np.errstate(invalid="ignore"):
            return (self.lam_low <= lam + tol) & (lam - tol <= self.lam_high)

    def table(self):
        """One row per extreme constraint (pandas DataFrame; ``node`` numbered from 1)."""
        import pandas as pd

        n = self.n_nodes
        return pd.DataFrame(
            {
                "constraint": self.constraints.labels(),
                "node": np.concatenate([np.arange(1, n + 1), np.arange(1, n + 1)]),
                "family": ["I"] * n + ["II"] * n,
                "slip_direction": ["backward"] * n + ["forward"] * n,
                "lam_low": self.lam_low,
                "lam_high": self.lam_high,
                "lam_high_exact": self.lam_high_exact,
                "t_extreme": self.constraints.t_extreme,
                "offset_c": self.constraints.c,
                "offset_rate_m": self.constraints.m,
                "certificate_y": self.certificate if self.certificate.size else np.nan,
            }
        )

    def to_dict(self) -> dict:
        """JSON-serialisable summary (non-finite values as the strings ``"inf"``, ``"nan"``;
        nodes numbered from 1; ``"nan"`` = not computed, see the attributes)."""

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else str(x)

        return {
            "lam1": num(self.lam1),
            "lam2": num(self.lam2),
            "status": self.status,
            "message": self.message,
            "lam_adj": num(self.lam_adj),
            "adjacency_node": int(self.adjacency_node) + 1 if self.adjacency_node >= 0 else None,
            "limiting_constraint": self.limiting_label,
            "lam_separation": num(self.lam_separation),
            "intervals": self.intervals_computed,
            "separation_nodes": [int(j) + 1 for j in self.separation_nodes],
            "safe_lam": num(self.safe_lam),
            "safe_state": [float(x) for x in self.safe_state],
            "safe_margin": num(self.safe_margin),
            "residuals": {k: float(v) for k, v in self.residuals.items()},
            "n_lps": int(self.n_lps),
            "simplex_iterations": int(self.simplex_iterations),
            "solve_time_s": float(self.solve_time),
            "n_nodes": int(self.n_nodes),
            "stages": [s.to_dict() for s in self.stages],
        }

    def __repr__(self) -> str:
        from ..model.results import short_repr

        return short_repr(self, ("status", "lam1", "lam2", "lam_adj", "lam_separation",
                                 "safe_lam", "n_lps"),
                          {"n_nodes": self.n_nodes, "limiting": self.limiting_label or "-"})

    def verdict(self) -> str:
        """The answer in plain sentences, numbers rounded for reading (:mod:`.verdict`)."""
        from .verdict import bounds_verdict

        return bounds_verdict(self)

    def summary(self) -> str:
        """A readable multi-line summary."""
        d = self.to_dict()
        lines = [
            f"shakedown bounds ({self.n_nodes} nodes): {self.status}",
            f"  lam1 = {d['lam1']}   (limiting constraint: {d['limiting_constraint'] or '-'})",
            f"  lam2 = {d['lam2']}",
            f"  lam_adj = {d['lam_adj']}"
            + (f"   (node {self.adjacency_node + 1})" if self.adjacency_node >= 0 else ""),
            f"  no-separation holds up to lam = {d['lam_separation']}",
            f"  safe state at lam = {d['safe_lam']}: margin {d['safe_margin']}",
            f"  LPs: {self.n_lps}, simplex iterations: {self.simplex_iterations}, "
            f"time {self.solve_time:.3g} s, worst residual {max(self.residuals.values()):.2e}",
        ]
        if self.message:
            lines.append(f"  note: {self.message}")
        return "\n".join(lines)


