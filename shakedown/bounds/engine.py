"""Constraint-hyperplane engine: shakedown load factors ``lam1``, ``lam2`` (MODEL.md s.3).

With every node closed, the state is the slip vector ``v``.  Node ``j`` is safe at time ``t``
when (seed 002 eq. 4, per-node friction ``F = diag(f)``)

    I_j :  ((A - F B^T) v)_j <=  f_j p_w_j(t) - q_w_j(t)
    II_j:  ((A + F B^T) v)_j >= -f_j p_w_j(t) - q_w_j(t)

With ``r_w = r_0 + lam r_1(t)`` the extreme (tightest) position over a cycle of every
constraint is affine in ``lam``; stacking the ``2N`` extreme constraints as

    G v <= c + lam m,   G = [A - F B^T; -(A + F B^T)],
                        c = [f p0 - q0; f p0 + q0],
                        m = [min_t (f p1 - q1); min_t (f p1 + q1)]

the safe shakedown region is ``H(lam) = {v : G v <= c + lam m}`` and

* ``lam2 = sup {lam >= 0 : H(lam) != {}}`` (one LP in ``(v, lam)``);
* constraint ``k`` is *active* at ``lam`` when the face ``H(lam) & {G_k v = c_k + lam m_k}`` is
  non-empty; the set of such ``lam`` is an interval ``[lo_k, hi_k]`` (two LPs);
* ``lam1 = sup {lam : every constraint is active on [0, lam]}`` = ``min_k hi_k`` when every
  ``lo_k = 0``, else 0;
* ``lam_adj = min_j inf {lam : H(lam) & {I_j tight} & {II_j tight} != {}}``: the first load
  factor at which the two extreme facets of one node meet inside ``H`` (for two nodes: the
  region's triangle with both sides of one node adjacent, Ahn et al. 2008).  Generically the
  common face has dimension ``N - 2`` right after it appears, i.e. the facets are adjacent.

All LPs use one HiGHS model (:class:`shakedown.lp.ReusableLP`) with warm starts.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..model import citations
from ..model.errors import InputError, ShapeError
from ..model.loading import LoadCycle
from ..model.system import DiscreteSystem
from . import dense_lp
from .lp import INF, LPAnswer, ReusableLP

#: Relative tolerance used to decide that two load factors coincide (LP tolerance 1e-7 of
#: HiGHS's default primal/dual feasibility, scaled).
LAM_RTOL = 1e-7


@dataclass(frozen=True)
class ConstraintSet:
    """The ``2N`` extreme constraints ``G v <= c + lam m`` (rows ``0..N-1``: I, ``N..2N-1``: II).

    Attributes
    ----------
    G : ndarray, shape (2N, N)
        Constraint normals [force / length].
    c : ndarray, shape (2N,)
        Offsets at ``lam = 0`` [force].
    m : ndarray, shape (2N,)
        Rate of change of the offsets with ``lam`` (``<= 0`` for loads with zero mean).
    t_extreme : ndarray, shape (2N,)
        Time (cycles) at which each constraint reaches its extreme position.
    sep_G, sep_c, sep_m : ndarray
        No-separation rows ``-(B^T v)_j <= p0_j + lam min_t p1_j`` (``p_w + B^T v >= 0``).
    """

    G: np.ndarray
    c: np.ndarray
    m: np.ndarray
    t_extreme: np.ndarray
    sep_G: np.ndarray
    sep_c: np.ndarray
    sep_m: np.ndarray

    @property
    def n_nodes(self) -> int:
        return self.G.shape[1]

    def labels(self) -> list[str]:
        """Names of the rows, nodes numbered from 1 as everywhere a person reads: ``I_1``..."""
        n = self.n_nodes
        return [f"I_{j + 1}" for j in range(n)] + [f"II_{j + 1}" for j in range(n)]

    def offsets(self, lam: float) -> np.ndarray:
        return self.c + lam * self.m

    def instantaneous(self, system: DiscreteSystem, load: LoadCycle, t, lam: float):
        """Offsets ``b(t)`` of the 2N constraints at time(s) ``t``: ``G v <= b(t)``."""
        q, p = load.evaluate(t, lam)
        f = system.friction
        return np.concatenate([f * p - q, f * p + q], axis=-1)


def extreme_constraints(system: DiscreteSystem, load: LoadCycle) -> ConstraintSet:
    """Assemble the extreme constraints of ``system`` under ``load`` (module docstring)."""
    _check_pair(system, load)
    A, B, f = system.A, system.B, system.friction
    FBt = f[:, None] * B.T
    G = np.vstack([A - FBt, -(A + FBt)])
    c = np.concatenate([f * load.p0 - load.q0, f * load.p0 + load.q0])
    mI, tI = load.periodic_min(-1.0, f)
    mII, tII = load.periodic_min(1.0, f)
    mp, _ = load.periodic_min(0.0, 1.0)
    return ConstraintSet(
        G=G, c=c, m=np.concatenate([mI, mII]), t_extreme=np.concatenate([tI, tII]),
        sep_G=-B.T.copy(), sep_c=load.p0.copy(), sep_m=mp,
    )


def _check_pair(system, load):
    if not isinstance(system, DiscreteSystem):
        raise InputError(
            f"system must be a shakedown.DiscreteSystem; got {type(system).__name__}"
        )
    if not isinstance(load, LoadCycle):
        raise InputError(f"load must be a shakedown.LoadCycle; got {type(load).__name__}")
    if load.n_nodes != system.n_nodes:
        raise ShapeError(
            f"load has {load.n_nodes} nodes but system has {system.n_nodes}; "
            "build the LoadCycle with one entry per contact node"
        )


# ---------------------------------------------------------------------- results
@dataclass(frozen=True)
class SafeRegion:
    """The safe shakedown region ``H(lam) = {v : normals @ v <= offsets}`` (a polyhedron).

    Attributes
    ----------
    lam : float
    normals : ndarray, shape (2N, N)
    offsets : ndarray, shape (2N,)
    labels : list of str
        ``"I_j"`` / ``"II_j"``.
    separation_normals, separation_offsets : ndarray, shape (N, N), (N,)
        Rows of ``p_w(t) + B^T v >= 0`` at every ``t`` (not part of ``H``; see MODEL.md s.3).
    """

    lam: float
    normals: np.ndarray
    offsets: np.ndarray
    labels: list
    separation_normals: np.ndarray
    separation_offsets: np.ndarray

    def contains(self, v, tol: float = 1e-9) -> bool:
        """``True`` when ``v`` satisfies every extreme constraint to ``tol * scale``."""
        v = np.asarray(v, float)
        scale = np.abs(self.normals).max() * max(1.0, np.abs(v).max()) + np.abs(self.offsets)
        return bool(np.all(self.normals @ v - self.offsets <= tol * scale))

    def slack(self, v) -> np.ndarray:
        return self.offsets - self.normals @ np.asarray(v, float)

    def vertices_2d(self):
        """Vertices (counter-clockwise) of a bounded two-node region; empty array if empty."""
        if self.normals.shape[1] != 2:
            raise InputError("vertices_2d is for two-node systems")
        return _polygon_2d(self.normals, self.offsets)

    def area(self) -> float:
        """Area of a bounded two-node region (0 when empty)."""
        P = self.vertices_2d()
        if len(P) < 3:
            return 0.0
        x, y = P[:, 0], P[:, 1]
        return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _polygon_2d(G, b, tol=1e-12):
    """Vertices of {x in R^2 : G x <= b} by pairwise intersection (bounded case)."""
    pts = []
    n = len(b)
    scale = np.abs(G).max() + np.abs(b).max()
    for i in range(n):
        for j in range(i + 1, n):
            M = G[[i, j]]
            det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
            if abs(det) <= 1e-14 * np.abs(M).max() ** 2:
                continue
            x = np.linalg.solve(M, b[[i, j]])
            if np.all(G @ x <= b + tol * scale * max(1.0, np.abs(x).max())):
                pts.append(x)
    if not pts:
        return np.zeros((0, 2))
    P = np.unique(np.round(np.array(pts), 12), axis=0)
    c = P.mean(axis=0)
    order = np.argsort(np.arctan2(P[:, 1] - c[1], P[:, 0] - c[0]))
    return P[order]


@dataclass(frozen=True)
class ShakedownBounds:
    """Shakedown load factors of a system under a periodic load, with certificates.

    Attributes
    ----------
    lam1 : float
        Below ``lam1`` every extreme constraint is active (the seed's criterion for shakedown
        from every initial state; proven for two nodes and for ``B = 0``). ``inf`` if never lost.
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
        First ``lam`` at which the extreme facets ``I_j``, ``II_j`` of one node meet in ``H``.
    adjacency_node : int
        That node (``-1`` if never).
    limiting_constraint : int
        Index ``k`` (``0..2N-1``) of the constraint that becomes inactive at ``lam1``
        (``-1`` if none); ``limiting_label`` names it (``"I_j"`` / ``"II_j"``).
    lam_low, lam_high : ndarray, shape (2N,)
        Activity interval of every extreme constraint (``nan`` if never active).
    lam_separation : float
        Largest ``lam`` for which a safe state with ``p_w(t) + B^T v >= 0`` at every node and
        time exists; above it (up to ``lam2``) every safe state needs a tensile normal reaction
        at ``separation_nodes``.  For nodes with ``f > 0`` the friction constraints already
        imply ``p >= 0`` in ``H``, so ``lam_separation = lam2`` unless a node is frictionless.
    separation_nodes : tuple of int
    safe_lam : float
        Load factor at which ``safe_state`` was computed.
    safe_state : ndarray, shape (N,)
        Chebyshev centre of ``H(safe_lam)`` (the safe slip state farthest from every extreme
        constraint) or empty if ``H`` is empty.
    safe_margin : float
        Its distance to the nearest extreme constraint [slip units].
    state_at_lam2 : ndarray, shape (N,)
        The LP optimum ``v*`` at ``lam2`` (the last safe point).
    certificate : ndarray, shape (2N,)
        Dual multipliers ``y >= 0`` of the ``lam2`` LP: ``G^T y = 0`` and
        ``lam2 = c.y / (-m.y)`` prove that ``H(lam)`` is empty for ``lam > lam2``.
    residuals : dict
        Worst primal, dual-sign, stationarity and complementarity residuals over all LPs.
    n_lps, simplex_iterations : int
    solve_time : float
        Seconds.
    constraints : ConstraintSet
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

    @property
    def n_nodes(self) -> int:
        return self.constraints.n_nodes

    @property
    def limiting_label(self) -> str:
        k = self.limiting_constraint
        return self.constraints.labels()[k] if k >= 0 else ""

    def active_at(self, lam: float) -> np.ndarray:
        """Boolean mask (2N,) of the constraints active at ``lam``."""
        tol = LAM_RTOL * max(1.0, abs(lam))
        with np.errstate(invalid="ignore"):
            return (self.lam_low <= lam + tol) & (lam - tol <= self.lam_high)

    def table(self):
        """One row per extreme constraint (pandas DataFrame)."""
        import pandas as pd

        n = self.n_nodes
        return pd.DataFrame(
            {
                "constraint": self.constraints.labels(),
                "node": np.concatenate([np.arange(1, n + 1), np.arange(1, n + 1)]),  # from 1
                "family": ["I"] * n + ["II"] * n,
                "slip_direction": ["backward"] * n + ["forward"] * n,
                "lam_low": self.lam_low,
                "lam_high": self.lam_high,
                "t_extreme": self.constraints.t_extreme,
                "offset_c": self.constraints.c,
                "offset_rate_m": self.constraints.m,
                "certificate_y": self.certificate if self.certificate.size else np.nan,
            }
        )

    def to_dict(self) -> dict:
        """JSON-serialisable summary (infinite values as the strings ``"inf"``)."""

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else str(x)

        return {
            "lam1": num(self.lam1),
            "lam2": num(self.lam2),
            "status": self.status,
            "message": self.message,
            "lam_adj": num(self.lam_adj),
            "adjacency_node": int(self.adjacency_node),
            "limiting_constraint": self.limiting_label,
            "lam_separation": num(self.lam_separation),
            "separation_nodes": [int(j) for j in self.separation_nodes],
            "safe_lam": num(self.safe_lam),
            "safe_state": [float(x) for x in self.safe_state],
            "safe_margin": num(self.safe_margin),
            "residuals": {k: float(v) for k, v in self.residuals.items()},
            "n_lps": int(self.n_lps),
            "simplex_iterations": int(self.simplex_iterations),
            "solve_time_s": float(self.solve_time),
            "n_nodes": int(self.n_nodes),
        }

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
            f"  lam_adj = {d['lam_adj']}   (node {self.adjacency_node + 1})",
            f"  no-separation holds up to lam = {d['lam_separation']}",
            f"  safe state at lam = {d['safe_lam']}: margin {d['safe_margin']}",
            f"  LPs: {self.n_lps}, simplex iterations: {self.simplex_iterations}, "
            f"time {self.solve_time:.3g} s, worst residual {max(self.residuals.values()):.2e}",
        ]
        if self.message:
            lines.append(f"  note: {self.message}")
        return "\n".join(lines)


# ---------------------------------------------------------------------- engine
def safe_region(system: DiscreteSystem, load: LoadCycle, lam: float) -> SafeRegion:
    """The safe shakedown region ``H(lam)`` as a polyhedron ``normals @ v <= offsets``."""
    citations.register("melan1936", "klarbring2007")
    lam = _check_lam(lam)
    cs = extreme_constraints(system, load)
    return SafeRegion(
        lam=lam,
        normals=cs.G,
        offsets=cs.offsets(lam),
        labels=cs.labels(),
        separation_normals=cs.sep_G,
        separation_offsets=cs.sep_c + lam * cs.sep_m,
    )


def _check_lam(lam) -> float:
    try:
        lam = float(lam)
    except (TypeError, ValueError) as exc:
        raise InputError(f"lam must be a number >= 0; got {lam!r}") from exc
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam must be finite and >= 0; got {lam}")
    return lam


class _Engine:
    """The LP model ``max/min lam`` s.t. ``G v - m lam <= c`` (+ optional separation rows)."""

    def __init__(self, cs: ConstraintSet):
        n = cs.n_nodes
        self.n = n
        rows = np.vstack(
            [np.hstack([cs.G, -cs.m[:, None]]), np.hstack([cs.sep_G, -cs.sep_m[:, None]])]
        )
        self.c = cs.c
        self.sep_c = cs.sep_c
        row_lo = np.full(3 * n, -np.inf)
        row_hi = np.concatenate([cs.c, np.full(n, np.inf)])  # separation rows off
        col_lo = np.concatenate([np.full(n, -np.inf), [0.0]])
        col_hi = np.full(n + 1, np.inf)
        cost = np.zeros(n + 1)
        cost[n] = 1.0
        self.lp = ReusableLP(rows, row_lo, row_hi, col_lo, col_hi, cost)
        self.worst = {"primal": 0.0, "dual": 0.0, "stationarity": 0.0, "complementarity": 0.0}

    def run(self, sense: str, tight=(), separation: bool = False) -> LPAnswer:
        lp = self.lp
        cost = np.zeros(self.n + 1)
        cost[self.n] = 1.0
        lp.set_objective(cost, sense)
        for k in tight:
            lp.set_row_bounds(k, self.c[k], self.c[k])
        if separation:
            for j in range(self.n):
                lp.set_row_bounds(2 * self.n + j, -np.inf, self.sep_c[j])
        ans = lp.solve()
        for k in tight:
            lp.set_row_bounds(k, -np.inf, self.c[k])
        if separation:
            for j in range(self.n):
                lp.set_row_bounds(2 * self.n + j, -np.inf, np.inf)
        if ans.status == "optimal":
            for key, val in zip(
                self.worst,
                (ans.primal_residual, ans.dual_residual, ans.stationarity_residual,
                 ans.complementarity_residual),
                strict=True,
            ):
                self.worst[key] = max(self.worst[key], val)
        return ans


def _value(ans: LPAnswer) -> float:
    if ans.status == "optimal":
        return float(ans.x[-1])
    if ans.status.startswith("unbounded"):
        return np.inf if ans.objective > 0 else -np.inf
    return np.nan


def shakedown_bounds(
    system: DiscreteSystem,
    load: LoadCycle,
    *,
    lam: float | None = None,
    intervals: bool = True,
    adjacency: bool = True,
    separation: bool = True,
    solver: str = "auto",
) -> ShakedownBounds:
    """Shakedown load factors ``lam1 <= lam2`` with certificates (MODEL.md s.3).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
        ``r_w(t) = r_0 + lam r_1(t)``.
    lam : float, optional
        Load factor at which to return a safe slip state (the Chebyshev centre of ``H(lam)``).
        Default: ``lam1 / 2`` (or 0 when ``lam1`` is 0 or not finite).
    intervals : bool
        Compute the activity interval of every constraint (``4N`` LPs; needed for ``lam1``).
    adjacency : bool
        Compute ``lam_adj`` (``N`` LPs).
    separation : bool
        Compute the no-separation limit (one LP).
    solver : {"auto", "highs"}
        ``"auto"``: dense interior point + basis identification for the ``lam2`` LP, then the
        lock-step dense dual simplex of :mod:`shakedown.dense_lp` warm-started from the optimal
        basis for the activity-interval and adjacency LPs; every answer is certified by its
        optimality conditions and any LP that is not certified is re-solved by HiGHS.
        ``"highs"``: every LP by HiGHS (one model, warm starts): the reference.

    Returns
    -------
    ShakedownBounds

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> load = sd.LoadCycle.from_harmonics([0.0], [2.0], q_cos=[1.0])
    >>> b = sd.shakedown_bounds(s, load)
    >>> round(b.lam1, 12), round(b.lam2, 12)
    (1.0, 1.0)
    """
    citations.register("melan1936", "klarbring2007", "ahn2008")
    t0 = time.perf_counter()
    cs = extreme_constraints(system, load)
    if solver not in ("auto", "highs"):
        raise InputError(f"solver must be 'auto' or 'highs'; got {solver!r}")
    if lam is not None:
        lam = _check_lam(lam)
    out = None
    if solver == "auto":
        out = _solve_dense(cs, load, intervals, adjacency, separation)
    if out is None:
        out = _solve_highs(cs, load, intervals, adjacency, separation)
    (lam1, lam2, status, messages, lam_adj, adj_node, limiting, lam_low, lam_high, lam_sep,
     sep_nodes, v_at_lam2, certificate, residuals, n_lps, iterations) = out

    # safe state at the chosen lam: Chebyshev centre of H(lam)
    if lam is None:
        safe_lam = 0.5 * lam1 if np.isfinite(lam1) and lam1 > 0 else 0.0
    else:
        safe_lam = lam
    safe_state, margin = chebyshev_centre(cs, safe_lam, solver=solver)

    return ShakedownBounds(
        lam1=float(lam1),
        lam2=float(lam2),
        status=status,
        message="; ".join(messages),
        lam_adj=float(lam_adj),
        adjacency_node=int(adj_node),
        limiting_constraint=limiting,
        lam_low=lam_low,
        lam_high=lam_high,
        lam_separation=float(lam_sep),
        separation_nodes=sep_nodes,
        safe_lam=float(safe_lam),
        safe_state=safe_state,
        safe_margin=float(margin),
        state_at_lam2=v_at_lam2,
        certificate=certificate,
        residuals=residuals,
        n_lps=int(n_lps),
        simplex_iterations=int(iterations),
        solve_time=time.perf_counter() - t0,
        constraints=cs,
    )




def _lam1(cs, lam_low, lam_high, lam2, messages):
    """``lam1`` and the limiting constraint from the activity intervals (module docstring)."""
    tol = LAM_RTOL * (1.0 if not np.isfinite(lam2) else max(1.0, lam2))
    never = np.isnan(lam_high)
    not_at_zero = never | (lam_low > tol)
    if np.any(not_at_zero):
        limiting = int(np.argmax(not_at_zero))
        messages.append(f"{cs.labels()[limiting]} is inactive already at lam = 0")
        return 0.0, limiting
    limiting = int(np.nanargmin(lam_high))
    lam1 = float(lam_high[limiting])
    if np.isfinite(lam2) and lam1 >= lam2 - tol:
        lam1 = lam2  # every constraint stays active until H vanishes (Melan case)
    if np.isinf(lam1):
        limiting = -1
    return lam1, limiting


def _separation_outcome(ans: LPAnswer, lam2: float, n: int, messages: list):
    """``(lam_separation, separation_nodes)`` from the no-separation LP; appends the message."""
    lam_sep = _value(ans)
    sep_nodes = ()
    if ans.status == "optimal" and (not np.isfinite(lam2) or lam_sep < lam2 - 1e-9 * max(1, lam2)):
        duals = ans.row_dual[2 * n :]
        sep_nodes = tuple(int(j) for j in np.flatnonzero(np.abs(duals) > 1e-12))
        messages.append(
            f"above lam = {lam_sep:.6g} every safe state needs a tensile normal reaction "
            f"at node(s) {list(sep_nodes)}"
        )
    elif np.isnan(lam_sep):
        messages.append("no safe state keeps every node in compression, even at lam = 0")
    return lam_sep, sep_nodes


def _solve_dense(cs, load, intervals, adjacency, separation):
    """Dense path (``solver="auto"``); ``None`` when the ``lam2`` LP is not a certified optimum
    (unbounded, infeasible or degenerate trouble): the caller then uses :func:`_solve_highs`.

    LP ``max e.x, A x <= b`` in ``x = (v, lam)``: rows ``[G, -m] <= c`` and ``-lam <= 0``.
    """
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, 0.0]
    e = np.r_[np.zeros(n), 1.0]
    main, tab = dense_lp.solve_max(A, b, e)
    if main is None:
        return None
    lam2 = float(main.x[-1])
    v_at_lam2 = main.x[:n].copy()
    certificate = main.y[: 2 * n].copy()
    names = ("primal", "dual", "stationarity", "complementarity")
    worst = dict(zip(names, main.residuals, strict=True))
    stats = {"lps": 1, "iters": main.iterations}
    eng = []  # the HiGHS model, built only if some LP needs it

    def record(ans):
        stats["lps"] += 1
        stats["iters"] += ans.iterations
        if ans.status == "optimal":
            for k, r in zip(names, ans.residuals, strict=True):
                worst[k] = max(worst[k], r)

    def highs(sense, tight=(), sep=False):
        if not eng:
            eng.append(_Engine(cs))
        ans = eng[0].run(sense, tight=tight, separation=sep)
        stats["lps"] += 1
        stats["iters"] += ans.iterations
        for k, key in zip(names, ("primal_residual", "dual_residual",
                                  "stationarity_residual", "complementarity_residual"),
                          strict=True):
            if ans.status == "optimal":
                worst[k] = max(worst[k], getattr(ans, key))
        return _value(ans)

    def values(answers, sense, tights):
        out = np.empty(len(answers))
        for i, (ans, tight) in enumerate(zip(answers, tights, strict=True)):
            record(ans)
            if ans.status == "optimal":
                out[i] = ans.x[-1]
            elif ans.status == "infeasible":
                out[i] = np.nan
            else:
                out[i] = highs(sense, tight)
        return out

    messages = []
    lam_low = np.full(2 * n, np.nan)
    lam_high = np.full(2 * n, np.nan)
    lam1, limiting = np.nan, -1
    lam_adj, adj_node = np.inf, -1
    if intervals or adjacency:
        # a dual-feasible basis for "min lam": the lam2 basis with the row lam >= 0 swapped in
        lamrow = 2 * n
        T1 = tab.T0.copy()
        if lamrow not in T1:
            T1[int(np.argmax(np.abs(tab.W[:, lamrow])))] = lamrow
        tab0 = dense_lp.Tableau(A, b, -e, T1)
        start = dense_lp.batch_dual_simplex(tab0, [()])[0] if not tab0.singular else None
        if start is not None:
            record(start)
        if start is not None and start.status == "optimal" and start.iterations:
            tab0 = dense_lp.Tableau(A, b, -e, start.basis)
        if start is None or start.status != "optimal" or tab0.singular:
            tab0 = None
    if intervals:
        tights = [(k,) for k in range(2 * n)]
        lam_high = values(dense_lp.batch_dual_simplex(tab, tights), "max", tights)
        lam_high[np.isfinite(lam_high)] = np.minimum(lam_high[np.isfinite(lam_high)], lam2)
        act = [k for k in range(2 * n) if np.isfinite(lam_high[k])]
        tights = [(k,) for k in act]
        if tab0 is not None:
            lo = values(dense_lp.batch_dual_simplex(tab0, tights), "min", tights)
            lo = np.where(np.isnan(lo), lo, np.maximum(lo, 0.0))  # -0.0 -> 0.0
        else:
            lo = np.array([highs("min", t) for t in tights])
        lam_low[act] = lo
        lam1, limiting = _lam1(cs, lam_low, lam_high, lam2, messages)
    if adjacency:
        tights = [(j, n + j) for j in range(n)]
        if tab0 is not None:
            adj = values(dense_lp.batch_dual_simplex(tab0, tights), "min", tights)
        else:
            adj = np.array([highs("min", t) for t in tights])
        adj = np.where(np.isnan(adj), np.inf, np.maximum(adj, 0.0))
        if np.isfinite(adj).any():
            adj_node = int(np.argmin(adj))
            lam_adj = float(adj[adj_node])
    lam_sep, sep_nodes = np.nan, ()
    if separation:
        sep = cs.sep_G @ v_at_lam2 - cs.sep_c - lam2 * cs.sep_m
        scale = np.abs(cs.sep_G).max(initial=0.0) * max(1.0, np.abs(v_at_lam2).max()) + np.abs(
            cs.sep_c
        )
        if np.all(sep <= 1e-9 * np.maximum(scale, 1e-300)):
            lam_sep = lam2  # the lam2 optimum already keeps every node in compression
        else:
            if not eng:
                eng.append(_Engine(cs))
            ans = eng[0].run("max", separation=True)
            stats["lps"] += 1
            stats["iters"] += ans.iterations
            lam_sep, sep_nodes = _separation_outcome(ans, lam2, n, messages)
    return (lam1, lam2, "bounded", messages, lam_adj, adj_node, limiting, lam_low, lam_high,
            lam_sep, sep_nodes, v_at_lam2, certificate, worst, stats["lps"], stats["iters"])


def _solve_highs(cs, load, intervals, adjacency, separation):
    """Every LP by HiGHS (the reference path)."""
    n = cs.n_nodes
    eng = _Engine(cs)
    scale_m = np.abs(cs.m).max(initial=0.0)
    messages = []

    main = eng.run("max")
    lam2 = _value(main)
    status = "bounded"
    v_at_lam2 = main.x[:n].copy() if main.status == "optimal" else np.zeros(0)
    certificate = main.row_dual[: 2 * n].copy() if main.status == "optimal" else np.zeros(0)
    if main.status.startswith("unbounded"):
        # distinguish "unbounded" from "infeasible" (HiGHS may report either way)
        feas = eng.run("min")
        if feas.status == "infeasible":
            lam2 = np.nan
        else:
            lam2 = np.inf
    if np.isnan(lam2):
        status = "infeasible"
        messages.append(
            "no safe slip state for any lam >= 0: the static load alone violates friction "
            "(gross slip) or the constraints are inconsistent"
        )
    elif np.isinf(lam2):
        if not load.has_periodic_part or scale_m == 0.0:
            status = "unbounded_no_periodic_part"
            messages.append("the load has no periodic part: a safe state exists for every lam")
        elif np.all(cs.m >= 0):
            status = "unbounded_periodic_never_excludes"
            messages.append("the periodic part never tightens a constraint (m >= 0)")
        else:
            status = "unbounded"
            messages.append("a safe state exists for every lam (the safe region moves with lam)")

    lam_low = np.full(2 * n, np.nan)
    lam_high = np.full(2 * n, np.nan)
    lam1 = np.nan
    limiting = -1
    if intervals and status != "infeasible":
        if main.status == "optimal":
            # constraints tight at the lam2 optimum are active up to lam2 (can't go higher)
            slack = cs.c + lam2 * cs.m - cs.G @ v_at_lam2
            rs = np.abs(cs.G).max(axis=1) * max(1.0, np.abs(v_at_lam2).max()) + np.abs(cs.c)
            tight_at_end = slack <= 1e-9 * rs
        else:
            tight_at_end = np.zeros(2 * n, bool)
        for k in range(2 * n):
            if tight_at_end[k]:
                lam_high[k] = lam2
            else:
                lam_high[k] = _value(eng.run("max", tight=(k,)))
        for k in range(2 * n):
            if np.isnan(lam_high[k]):
                continue  # never active
            lam_low[k] = _value(eng.run("min", tight=(k,)))
        lam1, limiting = _lam1(cs, lam_low, lam_high, lam2, messages)

    lam_adj, adj_node = np.inf, -1
    if adjacency and status != "infeasible":
        for j in range(n):
            a = _value(eng.run("min", tight=(j, n + j)))
            if np.isfinite(a) and a < lam_adj:
                lam_adj, adj_node = a, j

    lam_sep, sep_nodes = (np.nan, ())
    if separation and status != "infeasible":
        ans = eng.run("max", separation=True)
        lam_sep, sep_nodes = _separation_outcome(ans, lam2, n, messages)

    return (lam1, lam2, status, messages, lam_adj, adj_node, limiting, lam_low, lam_high,
            lam_sep, sep_nodes, v_at_lam2, certificate, dict(eng.worst), eng.lp.n_solves,
            eng.lp.total_iterations)


def chebyshev_centre(cs: ConstraintSet, lam: float, *, solver: str = "auto"):
    """Centre and radius of the largest ball in ``H(lam)`` (``(empty, -inf)`` if ``H`` empty).

    The radius is capped at ``1e6`` times the natural slip scale so that unbounded regions
    return a finite point.  ``solver="auto"`` tries the dense interior point (certified vertex)
    first and falls back to HiGHS; ``"highs"`` uses HiGHS only.
    """
    n = cs.n_nodes
    norms = np.linalg.norm(cs.G, axis=1)
    b = cs.offsets(lam)
    rows = np.hstack([cs.G, norms[:, None]])
    scale = np.abs(b).max(initial=1.0) / max(norms.min(initial=1.0), 1e-300)
    if solver == "auto":
        cap = np.r_[np.zeros(n), 1.0]
        ans, _ = dense_lp.solve_max(
            np.vstack([rows, cap]), np.r_[b, 1e6 * max(scale, 1.0)], cap
        )
        if ans is not None:
            if ans.x[-1] < 0:
                return np.zeros(0), -np.inf
            return ans.x[:n], float(ans.x[-1])
    lp = ReusableLP(
        rows,
        np.full(2 * n, -np.inf),
        b,
        np.concatenate([np.full(n, -np.inf), [-np.inf]]),
        np.concatenate([np.full(n, np.inf), [1e6 * max(scale, 1.0)]]),
        np.concatenate([np.zeros(n), [1.0]]),
    )
    ans = lp.solve()
    if ans.status != "optimal" or ans.x[-1] < 0:
        return np.zeros(0), -np.inf
    return ans.x[:n], float(ans.x[-1])


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
