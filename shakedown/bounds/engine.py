"""Constraint-hyperplane engine: shakedown load factors ``lam1``, ``lam2`` (MODEL.md s.3).

On the extreme constraints ``G v <= c + lam m`` (:mod:`.constraints`):

* ``lam2 = sup {lam >= 0 : H(lam) != {}}`` (one LP in ``(v, lam)``);
* constraint ``k`` is *active* at ``lam`` when the face ``H(lam) & {G_k v = c_k + lam m_k}`` is
  non-empty; the set of such ``lam`` is an interval ``[lo_k, hi_k]`` (two LPs);
* ``lam1 = sup {lam : every constraint is active on [0, lam]}`` = ``min_k hi_k`` when every
  ``lo_k = 0``, else 0;
* ``lam_adj = min_j inf {lam : H(lam) & {I_j tight} & {II_j tight} != {}}``: the first load
  factor at which the two extreme facets of one node meet inside ``H`` (for two nodes: the
  region's triangle with both sides of one node adjacent, Ahn et al. 2008).  Generically the
  common face has dimension ``N - 2`` right after it appears, i.e. the facets are adjacent.

The LPs are solved in nondimensional units (:class:`~.constraints.Scales`: stiffness, force and
load-factor scales of the problem itself), by the dense path (:mod:`.dense_path`) or HiGHS
(:mod:`.highs_path`); answers are scaled back here, so they do not depend on the unit system.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..model import citations
from ..model.errors import InputError
from ..model.loading import LoadCycle
from ..model.system import DiscreteSystem
from . import dense_lp
from .constraints import (
    ConstraintSet,
    SafeRegion,
    Scales,
    _check_lam,
    _polygon_2d,
    extreme_constraints,
    safe_region,
)
from .dense_path import solve_dense
from .highs_path import solve_highs
from .lp import INF, ReusableLP
from .outcome import intervals_option as _intervals_option
from .provenance import StageLog
from .quantities import parse_only
from .result import LAM_RTOL, ShakedownBounds

#: What ``only=`` may name.


def shakedown_bounds(
    system: DiscreteSystem,
    load: LoadCycle,
    *,
    lam: float | None = None,
    intervals: bool | str = "lam1",
    adjacency: bool = False,
    separation: bool = True,
    only=None,
    solver: str = "auto",
    facets: int | None = None,
    rtol: float | None = None,
    progress=None,
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
    intervals : {"lam1", True, "all", False}
        What to compute of the activity intervals ``[lam_low_k, lam_high_k]`` of the ``2N``
        constraints (``lam1`` needs them).  ``"lam1"`` (default, issue 14): every ``lam_low``
        exactly and ``lam_high`` only as far as ``lam1`` needs it -- exact for the rows marked in
        ``lam_high_exact``, elsewhere a proven lower bound that is ``>= lam1`` (the constraint is
        active at least up to that value; see :mod:`shakedown.bounds.pruning`); ``lam1``,
        ``lam2`` and the certificates are the same as with ``"all"``.  ``True`` or ``"all"``:
        every interval exactly (up to ``4N`` LPs, ``O(N^4)`` on large crack networks).
        ``False``: none (``lam1`` is ``nan``).
    adjacency : bool
        Compute ``lam_adj`` (``N`` LPs).  Off by default (issue 14): each adjacency LP walks
        from a vertex of ``H(0)`` up to ``lam_adj``, ``O(N)`` simplex pivots of ``O(N^2)`` each,
        so they cost more than all the other LPs together on large networks.  ``False``:
        ``lam_adj`` is ``nan`` and ``adjacency_node`` is ``-1`` (not computed).
    separation : bool
        Compute the no-separation limit (one LP).  ``False``: ``lam_separation`` is ``nan``.
    only : iterable of str, optional
        The quantities wanted, among ``"lam1"``, ``"lam2"``, ``"lam_adj"``,
        ``"lam_separation"`` (``lam2`` is always computed); overrides ``intervals``,
        ``adjacency`` and ``separation``.  E.g. ``only=("lam1", "lam2")`` for a sweep.
    facets : int, optional
        3-D only (``system.dim == 3``): facets ``k`` per node of the inscribed polygons of the
        polyhedral lower-bound candidates (default 8).
    rtol : float, optional
        3-D only: relative width of the certified bracket ``[lam2_lower, lam2_upper]`` at which
        the cutting planes stop (dimensionless, ``1e-12 <= rtol < 1``; default ``1e-6``).
        Below ``1e-7`` the dense interior point solves its late Newton systems in a split
        augmented form (slower, ``docs/guide/bounds_3d.md``).  2-D bounds are vertices of LPs,
        exact to round-off: no ``rtol``.
    solver : {"auto", "highs", "dense", "clarabel"}
        3-D (``system.dim == 3``): ``"dense"`` solves the SOCPs of ``lam2`` by the dense interior
        point (every answer checked, Clarabel where a check fails; recorded in
        ``ConeBounds.socp_paths``), ``"clarabel"`` (or ``"highs"``, the reference path) by
        Clarabel only, ``"auto"`` takes ``"dense"`` from 150 nodes on.  2-D: ``"auto"``: dense
        interior point + basis identification for the ``lam2`` LP, then the lock-step dense dual
        simplex of :mod:`shakedown.bounds.dense_lp` warm-started from the optimal basis for the
        activity-interval and adjacency LPs; every answer is certified by its optimality
        conditions and any LP that is not certified is re-solved by HiGHS. ``"highs"``: every LP
        by HiGHS (one model, warm starts): the reference.  A sparse system (``system.is_sparse``)
        always takes the HiGHS path on its sparse constraint matrix (``intervals="lam1"``: shared
        vertices and incumbent pruning, :mod:`shakedown.bounds.highs_pruning`); nothing is
        densified.  An uncondensed FE system
        (:class:`~shakedown.model.uncondensed.UncondensedSystem`) has dense constraint rows ``A
        -/+ F B^T`` (a Schur complement): they are formed by ``N`` sparse solves (never all of
        ``K``) and take the dense path.
    progress : callable, optional
        ``progress(iterable, total=None, desc="")`` (:class:`~shakedown.model.progress.
        ProgressDisplay`, ``tqdm.tqdm``): one step per stage (``lam2`` LP, ``lam_low``,
        ``lam_high``, adjacency, no-separation).  ``None``: nothing shown.

    A three-dimensional system (``system.dim == 3``) goes to the cone engine
    (:func:`shakedown.bounds.cones.engine.cone_bounds`, MODEL.md s.8.3): ``lam2`` on the
    circular (or elliptic) friction cones with a certified bracket, and with ``intervals`` /
    ``adjacency`` the polyhedral candidates ``lam1_cone`` / ``lam_adj_cone`` on inscribed
    ``facets``-gons; it returns a :class:`~shakedown.bounds.cones.result.ConeBounds`
    (``separation`` does not apply).  ``only=("lam2",)`` for large systems.

    Returns
    -------
    ShakedownBounds
        In the caller's units: load factors, slips ``[force / stiffness]``, the certificate
        ``[1 / force]``.

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> load = sd.LoadCycle.from_harmonics([0.0], [2.0], q_cos=[1.0])
    >>> b = sd.shakedown_bounds(s, load)
    >>> round(b.lam1, 12), round(b.lam2, 12)
    (1.0, 1.0)
    """
    if getattr(system, "dim", 2) == 3 or getattr(load, "dim", 2) == 3:
        from ..model.validation import check_same_dimension
        from .cones.engine import cone_bounds

        check_same_dimension(system, load)  # a 2-D system with a 3-D load: named by the check

        extra = {} if rtol is None else {"rtol": _bracket_rtol(rtol)}
        return cone_bounds(system, load, lam=lam, only=only, facets=facets, intervals=intervals,
                           adjacency=adjacency,
                           solver="clarabel" if solver == "highs" else solver, **extra)
    if rtol is not None:
        raise InputError(f"rtol applies to three-dimensional systems only (system.dim = 3: "
                         f"the width of the lam2 bracket); got rtol={rtol!r} for a 2-D system, "
                         "whose bounds are exact LP vertices: leave it out")
    if facets is not None:
        raise InputError(f"facets applies to three-dimensional systems only (system.dim = 3); "
                         f"got facets={facets!r} for a 2-D system: leave it out")
    citations.register("melan1936", "klarbring2007", "ahn2008")
    t0 = time.perf_counter()
    cs = extreme_constraints(system, load)
    if solver not in ("auto", "highs"):
        raise InputError(f"solver must be 'auto' or 'highs'; got {solver!r}")
    if lam is not None:
        lam = _check_lam(lam)
    if only is not None:
        intervals, adjacency, separation = parse_only(only)
    intervals = _intervals_option(intervals)
    sc = Scales.of(cs)
    ch = sc.nondimensional(cs)
    out = None
    log = StageLog(progress)
    dense = solver == "auto" and not sp.issparse(cs.G)
    if dense:
        out = solve_dense(ch, intervals, adjacency, separation, log=log)
    if out is None:
        tried = log.records()[:1] if dense else ()
        # log.handover: an optimal lam2 basis the dense path could not certify (its LPs then
        # count as fallbacks); None: no optimum (unbounded, infeasible) or no dense attempt
        out = solve_highs(ch, load.has_periodic_part, intervals, adjacency, separation,
                          log=StageLog() if dense else log, reason=log.handover)
        out.stages = tuple(tried) + tuple(out.stages)  # the dense attempt, then the HiGHS path
    lf = sc.load_factor
    lam1, lam2 = out.lam1 * lf, out.lam2 * lf
    # safe state at the chosen lam: Chebyshev centre of H(lam), a stage of its own (issue 26)
    if lam is None:
        safe_lam = 0.5 * lam1 if np.isfinite(lam1) and lam1 > 0 else 0.0
    else:
        safe_lam = lam
    log.start("safe_state")
    v_hat, r_hat = _chebyshev(ch, safe_lam / lf, solver, log)
    log.finish()
    out.stages = tuple(out.stages) + log.records()[-1:]
    lam_sep = out.lam_sep * lf
    messages = list(out.messages)
    fallbacks = sum(st.fallbacks for st in out.stages)
    if fallbacks:
        where = ", ".join(f"{st.stage}: {st.fallbacks}" for st in out.stages if st.fallbacks)
        messages.append(f"{fallbacks} LP(s) re-solved by HiGHS (not certified by the dense "
                        f"path): {where}")
    if out.sep_nodes:
        messages.append(
            f"above lam = {lam_sep:.6g} every safe state needs a tensile normal reaction "
            f"at node(s) {[j + 1 for j in out.sep_nodes]}")
    elif separation and np.isnan(out.lam_sep) and out.status != "infeasible":
        messages.append("no safe state keeps every node in compression, even at lam = 0")
    return ShakedownBounds(
        lam1=float(lam1),
        lam2=float(lam2),
        status=out.status,
        message="; ".join(messages),
        lam_adj=float(out.lam_adj * lf),
        adjacency_node=int(out.adj_node),
        limiting_constraint=int(out.limiting),
        lam_low=out.lam_low * lf,
        lam_high=out.lam_high * lf,
        lam_high_exact=(np.zeros(2 * cs.n_nodes, bool) if out.hi_exact is None
                        else np.asarray(out.hi_exact, bool)),
        lam_separation=float(lam_sep),
        separation_nodes=tuple(out.sep_nodes),
        safe_lam=float(safe_lam),
        safe_state=v_hat * sc.slip,
        safe_margin=float(r_hat * sc.slip),
        state_at_lam2=out.v_at_lam2 * sc.slip,
        certificate=out.certificate * (lf / sc.force),
        residuals={k: float(v) for k, v in out.residuals.items()},
        n_lps=int(out.n_lps),
        simplex_iterations=int(out.iterations),
        solve_time=time.perf_counter() - t0,
        constraints=cs,
        stages=tuple(out.stages),
    )


def chebyshev_centre(cs: ConstraintSet, lam: float, *, solver: str = "auto"):
    """Centre [slip] and radius [slip] of the largest ball in ``H(lam)`` (``(empty, -inf)`` if
    ``H`` is empty); the radius is exact for the centre returned and at most
    :data:`CENTRE_RTOL` (relative) below the largest.

    The radius is capped at ``1e6`` times the problem's slip scale so that unbounded regions
    return a finite point.  ``solver="auto"`` tries the dense interior point (certified vertex)
    first and falls back to HiGHS; ``"highs"`` uses HiGHS only.  Solved in nondimensional units
    (:class:`~.constraints.Scales`).
    """
    sc = Scales.of(cs)
    v_hat, r_hat = _chebyshev(sc.nondimensional(cs), lam / sc.load_factor, solver)
    return v_hat * sc.slip, float(r_hat * sc.slip)


def _chebyshev(cs: ConstraintSet, lam: float, solver: str, log=None):
    """Chebyshev centre of a nondimensional constraint set (see :func:`chebyshev_centre`);
    ``log`` (:class:`~.provenance.StageLog`) counts the LP (dense, or HiGHS with the reason
    when the dense answer was not certified)."""
    n = cs.n_nodes
    b = cs.offsets(lam)
    if sp.issparse(cs.G):
        norms = spla.norm(cs.G, axis=1)
        rows = sp.hstack([cs.G, norms[:, None]], format="csc")
        solver = "highs"
    else:
        norms = np.linalg.norm(cs.G, axis=1)
        rows = np.hstack([cs.G, norms[:, None]])
    cap = 1e6 * max(1.0, np.abs(b).max(initial=0.0) / max(norms.min(initial=1.0), 1e-300))
    if solver == "auto":
        top = np.r_[np.zeros(n), 1.0]
        # the interior point's centre first (certified by its multipliers), the crossover to a
        # vertex only when that is refused (issue 26: minutes at N = 2000, see solve_max)
        # the interior point stops as soon as its centre is proven within CENTRE_EARLY of the
        # largest (N = 2000 cracks: 21 of 26 iterations, the last ones a stall below 1e-8)
        ans, _ = dense_lp.solve_max(
            np.vstack([rows, top]), np.r_[b, cap], top, interior=True,
            accept=lambda a: _interior_centre(cs.G, norms, b, cap, a),
            stop=lambda a: _interior_centre(cs.G, norms, b, cap, a, CENTRE_EARLY) is not None,
            correctors=CENTRE_CORRECTORS)
        if ans is not None and ans.status != "optimal":
            ans = None
        if ans is not None:
            if log is not None:
                log.dense()
            if ans.x[-1] < 0:
                return np.zeros(0), -np.inf
            return ans.x[:n], float(ans.x[-1])
    t0 = time.perf_counter()
    lp = ReusableLP(
        rows,
        np.full(2 * n, -np.inf),
        b,
        np.full(n + 1, -np.inf),
        np.concatenate([np.full(n, np.inf), [cap]]),
        np.concatenate([np.zeros(n), [1.0]]),
    )
    ans = lp.solve()
    if log is not None:
        log.highs(time.perf_counter() - t0, "centre not certified by the interior point or its "
                  "crossover" if solver == "auto" else None)
    if ans.status != "optimal" or ans.x[-1] < 0:
        return np.zeros(0), -np.inf
    return ans.x[:n], float(ans.x[-1])


def _interior_centre(G, norms, b, cap, ans, rtol=None):
    """A Chebyshev centre from the interior point's iterate when the crossover fails (issue 14:
    a 2000-crack network whose largest balls form a face, not a vertex; HiGHS took 358 s).

    The centre ``v`` is the iterate's; its radius is recomputed from scratch,
    ``r = min_i (b_i - G_i v) / |G_i|`` (the ball lies in ``H``; at most the cap).  Accepted only if the
    multipliers ``y >= 0`` prove that no ball is larger by more than :data:`CENTRE_RTOL`:
    ``r* <= b.y + cap y_cap`` (weak duality, with ``G^T y = 0`` and ``|G| . y + y_cap = 1`` to
    :data:`CENTRE_STAT`; ``rtol`` in place of :data:`CENTRE_RTOL` if given).  Else ``None``
    (HiGHS)."""
    n = G.shape[1]
    v, y = ans.x[:n], np.maximum(ans.y, 0.0)
    r = min(float(np.min((b - G @ v) / norms)), cap)
    yr, ycap = y[:-1], y[-1]
    ys = max(float(np.abs(yr).max(initial=0.0)), 1e-300)
    stat = max(float(np.abs(G.T @ yr).max()) / (ys * np.abs(G).max()),
               abs(float(norms @ yr) + ycap - 1.0))
    bound = float(b @ yr) + cap * ycap
    rtol = CENTRE_RTOL if rtol is None else rtol
    if stat > CENTRE_STAT or not bound - r <= rtol * max(abs(r), 1e-300):
        return None
    return dense_lp.DenseAnswer("optimal", np.r_[v, r], ans.y, ans.basis, ans.iterations,
                                (0.0, 0.0, stat, (bound - r) / max(abs(r), 1e-300)))


#: Relative suboptimality of a Chebyshev radius accepted from the interior point.  1e-4 since
#: issue 26: on condensed FE strips (500 contact nodes, seeds 5014 and 5016) the interior point
#: stalls with its centre 2e-6 and 1.4e-5 below the largest radius (HiGHS: 2.1e-6 below on
#: 5014), was refused at 1e-7, and the crossover (a degenerate face: 2 strongly active rows,
#: a singular completed basis) and HiGHS after it took 30 s against 2 s for all the bounds.  The
#: safe state needs to be deep inside ``H``, not the exact centre; its margin is exact for the
#: point returned, and proven at most this far below the largest.
CENTRE_RTOL = 1e-4
#: Relative suboptimality at which the interior point stops early with a proven centre (an
#: interior point converges fully in a few more iterations; on 2000-crack networks they were a
#: stall of 4 iterations of ~0.8 s each below merit 1e-8, :data:`~.ipm.STALL_ITERS`).
CENTRE_EARLY = 1e-7
#: Gondzio's centrality correctors per interior-point iteration of the centre LP (its iterate
#: is accepted by its own certificate, no vertex needed): 2000-crack network 21 -> 18 iterations.
CENTRE_CORRECTORS = 2
#: Stationarity residual of the multipliers that prove it (``|G^T y|`` relative to ``|y| |G|``).
CENTRE_STAT = 1e-6

__all__ = [
    "ConstraintSet",
    "SafeRegion",
    "ShakedownBounds",
    "chebyshev_centre",
    "extreme_constraints",
    "safe_region",
    "shakedown_bounds",
    "INF",
    "LAM_RTOL",
    "_polygon_2d",
]


def _bracket_rtol(rtol) -> float:
    """``rtol`` of :func:`shakedown_bounds` checked: a real number in ``[1e-12, 1)``."""
    try:
        r = float(rtol)
    except (TypeError, ValueError):
        r = float("nan")
    if isinstance(rtol, bool) or not 1e-12 <= r < 1.0:
        raise InputError(f"rtol must be a number in [1e-12, 1) (the relative width of the lam2 "
                         f"bracket); got rtol={rtol!r}: use e.g. rtol=1e-8")
    return r
