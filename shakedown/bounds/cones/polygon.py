"""Polyhedral lower-bound candidates in 3-D: the 2-D theory on inscribed polygons (MODEL.md 8.3).

Node ``j``'s friction cone ``|W_j q| <= p`` (``W_j = diag(1 / f_x, 1 / f_y)``) is replaced by the
inscribed regular ``k``-gon (``k`` even, ``>= 4``) whose vertices lie on the cone at the angles
``2 a pi / k`` -- so at ``0`` and ``pi``, the ``+x`` / ``-x`` directions -- and whose facets have
outward normals ``d_a = (cos, sin)((2 a + 1) pi / k)``:

    d_a . (W_j q_j(t))  <=  cos(pi / k) p_j(t)          a = 0 .. k - 1.

Each facet is a friction hyperplane of the 2-D kind (``I_j`` / ``II_j`` are the case ``d = +-1``),
so :func:`~shakedown.bounds.constraints.family_constraints` builds the ``k N`` extreme rows and the
2-D LP engine (:mod:`~shakedown.bounds.highs_path`) computes on them

* ``lam2_polygon <= lam2`` (the polygon lies inside the cone: a safe under-estimate of ``H``);
* ``lam1_cone``: every facet of every node active on ``[0, lam]`` (Ahn's criterion, facet by
  facet);
* ``lam_adj_cone``: the first ``lam`` at which two *opposite* facets ``a``, ``a + k/2`` of one
  node meet in ``H`` (the node can be at its friction limit in two opposite directions in one
  safe state: in 2-D, ``I_j`` and ``II_j``).

Whether these guarantee shakedown from every initial state is not proven: it is tested by cyclic
runs (docs/guide/bounds_3d.md, benchmarks/RESULTS_3d_bounds.md).  ``lam_adj_cone`` rises to a
limit as ``k`` grows and no run below it (55 runs, 11 random coupled systems) slipped
cyclically: it is the package's 3-D lower-bound candidate.  ``lam1_cone`` keeps falling as ``k``
grows (a flat facet stays "active" where no direction of a circle does), so it is reported, not
proposed as a bound.  When every ``y`` component is unloaded and uncoupled, the
polygon's cross-section ``q_y = 0`` is exactly the 2-D friction interval, so ``lam2_polygon``
equals the 2-D ``lam2`` and ``lam_adj_cone`` the 2-D ``lam_adj`` (only the facets next to the
``x`` vertices can meet their opposite ones, exactly when ``I_j`` and ``II_j`` do).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...model.errors import InputError
from ..constraints import Scales, family_constraints
from ..highs_path import solve_highs
from ..outcome import intervals_option
from ..result import ShakedownBounds


def facet_normals(k: int) -> np.ndarray:
    """Outward unit normals ``d_a`` (k, 2) of the inscribed regular ``k``-gon (module doc)."""
    ang = (2 * np.arange(k) + 1) * np.pi / k
    return np.column_stack([np.cos(ang), np.sin(ang)])


def polygon_constraints(system, load, k: int):
    """The ``k N`` extreme facet rows (family ``a`` = facet ``a`` of every node).

    Rows are labelled ``"j:a"`` (node from 1, facet from 0); ``pairs`` are the opposite facets
    ``(a, a + k/2)`` of every node, for ``lam_adj``.
    """
    k = _check_facets(k)
    n = system.n_nodes
    W = 1.0 / np.asarray(system.friction_xy, float)
    cosk = np.cos(np.pi / k)
    fams = [(d[None, :] * W, cosk) for d in facet_normals(k)]
    labels = tuple(f"{j + 1}:{a}" for a in range(k) for j in range(n))
    pairs = np.array([(a * n + j, (a + k // 2) * n + j) for j in range(n) for a in range(k // 2)])
    return family_constraints(system, load, fams, row_labels=labels, pairs=pairs)


def _check_facets(k):
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 4 or k % 2:
        raise InputError(f"facets must be an even integer >= 4 (facets per node of the inscribed "
                         f"polygon); got {k!r}")
    return int(k)


def polygon_bounds(system, load, res, *, facets=8, intervals="lam1", adjacency=False):
    """``res`` (a :class:`~.result.ConeBounds`) with ``lam1_cone``, ``lam_adj_cone``,
    ``lam2_polygon``, ``facets`` and ``polyhedral`` filled in (module docstring)."""
    import time

    t0 = time.perf_counter()
    cs = polygon_constraints(system, load, facets)
    sc = Scales.of(cs)
    ch = sc.nondimensional(cs)
    intervals = intervals_option(intervals)
    out = solve_highs(ch, load.has_periodic_part, intervals, adjacency, False)
    lf = sc.load_factor
    R = len(cs.c)
    poly = ShakedownBounds(
        lam1=float(out.lam1 * lf), lam2=float(out.lam2 * lf), status=out.status,
        message="; ".join(out.messages), lam_adj=float(out.lam_adj * lf),
        adjacency_node=int(out.adj_node), limiting_constraint=int(out.limiting),
        lam_low=out.lam_low * lf, lam_high=out.lam_high * lf,
        lam_high_exact=(np.zeros(R, bool) if out.hi_exact is None else out.hi_exact),
        lam_separation=np.nan, separation_nodes=(), safe_lam=np.nan, safe_state=np.zeros(0),
        safe_margin=np.nan, state_at_lam2=out.v_at_lam2 * sc.slip,
        certificate=out.certificate * (lf / sc.force),
        residuals={k: float(v) for k, v in out.residuals.items()}, n_lps=int(out.n_lps),
        simplex_iterations=int(out.iterations), solve_time=time.perf_counter() - t0,
        constraints=cs)
    return dataclasses.replace(
        res, lam1_cone=poly.lam1 if intervals else np.nan,
        lam_adj_cone=poly.lam_adj if adjacency else np.nan, lam2_polygon=poly.lam2,
        facets=int(facets), polyhedral=poly)


def adjacency_node(b) -> int:
    """Node (0-based) of the opposite facets that meet first (``-1`` if none or not computed)."""
    poly = b.polyhedral
    if poly is None or poly.adjacency_node < 0:
        return -1
    row = int(poly.constraints.adjacency_pairs()[poly.adjacency_node][0])
    return row % b.n_nodes
