"""The result of :func:`shakedown.shakedown_bounds` for a 3-D system (``system.dim == 3``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..verdict import fmt
from .certify import ConeCertificate


@dataclass(frozen=True)
class ConeBounds:
    """3-D shakedown load factors with certificates (MODEL.md s.8.3).

    Attributes
    ----------
    lam2 : float
        Melan's limit on the circular (or elliptic) friction cones: above it no state is safe
        (cyclic slip from every initial state).  Reported as the certified lower end of the
        bracket, ``lam2 = lam2_lower``.  For an uncoupled system (``B = 0``) it is the
        shakedown limit from every initial state (Klarbring, Ciavarella & Barber 2007).
    lam2_lower, lam2_upper : float
        Certified bracket ``lam2_lower <= lam2_exact <= lam2_upper``: ``safe_state_at_lam2`` is
        safe at ``lam2_lower`` over the continuous cycle (exact worst times), and
        ``certificate`` proves ``lam2_upper`` by weak duality, with the multipliers'
        residuals charged against an a-priori bound on the state (valid whatever their
        accuracy: :mod:`shakedown.bounds.cones.dual`).
    status : str
        ``"bounded"`` (bracket within ``rtol``), ``"bracket"`` (the round limit stopped it
        first: the bracket is still certified), ``"unbounded"`` (safe at every ``lam``),
        ``"unbounded_no_periodic_part"``, ``"infeasible"`` (no state strictly inside every
        cone under the static load) or ``"failed"``.
    message : str
    lam_adj_cone : float
        The 3-D lower-bound candidate (docs/guide/bounds_3d.md): ``lam_adj`` of the 2-D theory
        on the friction cones replaced by inscribed regular ``facets``-gons -- the first load
        factor at which two opposite facets of one node meet in the safe region.  It rises
        towards a limit as ``facets`` grows.  Claim: shakedown from every initial state below
        it; evidence: every one of 55 cyclic runs below it (11 random coupled systems) shook
        down, and none contradicted it; not proven.  ``nan`` when not computed
        (``adjacency=False``).
    lam1_cone : float
        ``lam1`` of the 2-D theory on the polygons (every facet active on ``[0, lam]``).  Not a
        3-D bound: it keeps falling as ``facets`` grows (on a circle no direction stays
        "active"), and at ``facets = 4`` it can exceed the 2-D ``lam1`` of an embedded 2-D
        system.  Reported for study; ``nan`` when not computed.
    lam2_polygon : float
        ``lam2`` on the inscribed polygons (``<= lam2``; ``nan`` when not computed).
    facets : int
        ``k``, facets per node of the inscribed polygons (0 when not computed).
    polyhedral : ShakedownBounds or None
        The 2-D engine's full answer on the polyhedral constraints (rows labelled
        ``"j:a"``: node ``j`` from 1, facet ``a`` from 0 with outward normal at angle
        ``(2 a + 1) pi / k`` in the node's tangent plane).
    safe_lam : float
    safe_state : ndarray, shape (2N,)
        A slip state safe at ``safe_lam`` [length] (``(v_1x, v_1y, v_2x, ...)``): the convex
        combination of the static state of largest margin and ``state_at_lam2``, checked over
        the continuous cycle; empty when ``safe_lam > lam2_lower``.
    safe_margin : float
        Its smallest distance to a cone, ``min_i min_t (p_i - |W_i q_i|)`` [force].
    state_at_lam2 : ndarray, shape (2N,)
        A slip state safe at ``lam2_lower`` [length].
    certificate : ConeCertificate
    residuals : dict
        Worst dual residuals (cone, stationarity, sign) over the SOCPs (relative).
    n_socps, n_cuts, iterations : int
        SOCP solves, cuts of the last relaxation, interior-point iterations.
    solve_time : float
        Seconds.
    history : list of tuple
        Per SOCP: ``(cuts, relaxation value, lam2_lower, lam2_upper, worst violation)``
        (nondimensional load factors and violations).
    socp_paths : tuple of str
        Which solver answered each SOCP (the static-margin SOCP first): ``"dense"`` (the dense
        interior point, its answer checked by its own conditions) or ``"clarabel"``.
    fallbacks : tuple of str
        ``"SOCP k: reason"`` for each SOCP the dense path tried and Clarabel answered.
    """

    lam2: float
    lam2_lower: float
    lam2_upper: float
    status: str
    message: str
    safe_lam: float
    safe_state: np.ndarray
    safe_margin: float
    state_at_lam2: np.ndarray
    certificate: ConeCertificate = field(repr=False)
    residuals: dict
    n_socps: int
    n_cuts: int
    iterations: int
    solve_time: float
    n_nodes: int
    lam1_cone: float = np.nan
    lam_adj_cone: float = np.nan
    lam2_polygon: float = np.nan
    facets: int = 0
    polyhedral: object = field(default=None, repr=False)
    history: list = field(default_factory=list, repr=False)
    worst_times: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    socp_paths: tuple = ()
    fallbacks: tuple = ()

    @property
    def path(self) -> str:
        """``"dense"``, ``"clarabel"`` or ``"dense+clarabel"``: the solvers that answered."""
        return "+".join(p for p in ("dense", "clarabel") if p in self.socp_paths) or "none"

    @property
    def dim(self) -> int:
        return 3

    @property
    def lam1(self) -> float:
        """``lam1_cone`` (the 3-D lower-bound candidate; see its evidence in the guide)."""
        return self.lam1_cone

    @property
    def lam_adj(self) -> float:
        """``lam_adj_cone``."""
        return self.lam_adj_cone

    def table(self):
        """One row per node (pandas DataFrame; ``node`` from 1): the exact worst time of the
        node at ``lam2_lower`` and the number of cuts the certificate holds for it."""
        import pandas as pd

        n = self.n_nodes
        cuts = np.bincount(np.asarray(self.certificate.nodes, int), minlength=n)[:n]
        return pd.DataFrame({"node": np.arange(1, n + 1), "t_worst": self.worst_times,
                             "cuts": cuts})

    def to_dict(self) -> dict:
        """JSON-serialisable summary (non-finite values as strings)."""

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else str(x)

        return {
            "dim": 3, "lam2": num(self.lam2), "lam2_lower": num(self.lam2_lower),
            "lam2_upper": num(self.lam2_upper), "status": self.status, "message": self.message,
            "lam1_cone": num(self.lam1_cone), "lam_adj_cone": num(self.lam_adj_cone),
            "lam2_polygon": num(self.lam2_polygon), "facets": int(self.facets),
            "safe_lam": num(self.safe_lam), "safe_state": [float(x) for x in self.safe_state],
            "safe_margin": num(self.safe_margin),
            "residuals": {k: float(v) for k, v in self.residuals.items()},
            "n_socps": int(self.n_socps), "n_cuts": int(self.n_cuts),
            "solve_time_s": float(self.solve_time), "n_nodes": int(self.n_nodes),
            "socp_paths": list(self.socp_paths), "fallbacks": list(self.fallbacks),
        }

    def verdict(self) -> str:
        """The answer in plain sentences (numbers to 4 significant digits)."""
        if self.status == "infeasible":
            return ("No state lies strictly inside every friction cone even at lam = 0, so lam2 "
                    "is undefined (nan): the static load alone makes the system slip.")
        if self.status.startswith("unbounded"):
            return "A safe state exists at every load factor (lam2 = inf): shakes down always."
        out = [f"No safe state above lam2 = {fmt(self.lam2)} (certified in "
               f"[{fmt(self.lam2_lower, 8)}, {fmt(self.lam2_upper, 8)}]): cyclic slip from every "
               "initial state there."]
        if self.status == "bracket":
            out.append("The bracket did not close to the requested tolerance.")
        if np.isfinite(self.lam_adj_cone):
            out.append(
                f"Below lam_adj_cone = {fmt(self.lam_adj_cone)} (inscribed {self.facets}-gons: "
                "the first load factor at which one node can reach its friction limit in two "
                "opposite directions in a safe state) every cyclic run tried shook down from "
                "every initial state; this is numerical evidence, not a proof "
                "(docs/guide/bounds_3d.md). Between it and lam2 the initial state decides, and "
                "in coupled systems most states were seen to slip cyclically.")
        elif self.n_nodes and np.isnan(self.lam_adj_cone):
            out.append("lam_adj_cone was not computed (shakedown_bounds(..., adjacency=True)): "
                       "it is the 3-D lower-bound candidate below which every run tried shook "
                       "down from every initial state.")
        return " ".join(out)

    def summary(self) -> str:
        d = self.to_dict()
        lines = [f"3-D shakedown bounds ({self.n_nodes} nodes): {self.status}",
                 f"  lam2 = {d['lam2']}   bracket [{d['lam2_lower']}, {d['lam2_upper']}]",
                 f"  SOCPs: {self.n_socps}, cuts: {self.n_cuts}, time {self.solve_time:.3g} s, "
                 f"solver: {self.path}"
                 + (f" ({len(self.fallbacks)} fallback(s))" if self.fallbacks else "")]
        if self.facets:
            lines.append(f"  inscribed {self.facets}-gons: lam1 = {d['lam1_cone']}, lam_adj = "
                         f"{d['lam_adj_cone']}, lam2 = {d['lam2_polygon']}")
        if self.message:
            lines.append(f"  note: {self.message}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        from ...model.results import short_repr

        return short_repr(self, ("status", "lam2", "lam2_lower", "lam2_upper", "lam_adj_cone",
                                 "facets", "safe_lam", "n_socps", "n_cuts", "n_nodes"))
