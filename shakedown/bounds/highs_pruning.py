"""``lam1`` by HiGHS with shared vertices: the activity intervals of a sparse ``G`` (issue 14).

The dense path prunes the ``lam_high`` LPs with a facet walk on a dense ``G``
(:mod:`.pruning`).  On a sparse constraint set (a truncated crack interaction, a user's sparse
``K``) every LP is solved by HiGHS on the sparse matrix, and three facts cut the work:

* **Family points** (``lam_low``).  The point where every ``I`` row (or every ``II`` row) is
  tight is one sparse solve; when it lies in ``H(lam)`` it proves a non-empty face for all
  ``N`` rows of the family.  At ``lam = 0`` under a compressive static load both family points
  are in ``H(0)`` (the all-``I`` point is safe exactly when every normal reaction there stays
  compressive), so every ``lam_low = 0`` costs two sparse solves.  Rows left get covering LPs
  (``lam`` fixed, the sum of their normals maximised) and then one LP each.
* **Shared vertices.**  Every certified optimum ``(v*, lam*)`` is a point of ``H(lam*)``; each
  row tight there has a non-empty face at ``lam*``.
* **Incumbent pruning** (as :mod:`.pruning`): once every ``lam_low = 0``, ``lam1 = min_k
  lam_high_k``.  With the incumbent ``t`` (the smallest exact ``lam_high`` so far, first
  ``lam2``), row ``k`` only needs the capped LP ``max lam`` with row ``k`` tight and
  ``lam <= t`` (a few dual simplex pivots from the previous basis): a value below ``t`` is row
  ``k``'s exact ``lam_high`` and the new incumbent; a binding cap proves ``lam_high_j >= t``
  for every row ``j`` tight at the optimum.  Rows are visited in order of decreasing slack at
  the ``lam2`` optimum (the facets farthest from the last safe state leave first).

Each LP answer is certified by :class:`~.lp.ReusableLP` (primal and dual feasibility,
stationarity, complementarity); a family point by its slack in every row.  A row counts as
tight when its slack is below :data:`TIGHT_RTOL` of its force scale.  Result: per row the
exact ``lam_high`` (``hi_exact``) or a proven lower bound ``>=`` the final ``lam1``; every
``lam_low`` exact.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .outcome import value

#: Relative slack below which a row counts as tight at a certified vertex.
TIGHT_RTOL = 1e-9


def row_max(G) -> np.ndarray:
    """``max_j |G_kj|`` per row (dense or sparse ``G``)."""
    return abs(G).max(axis=1).toarray().ravel() if sp.issparse(G) else np.abs(G).max(axis=1)


def _slack(cs, x, lam, gmax):
    """Slack of every row of ``G v <= c + lam m`` at ``v = x``, and each row's force scale
    ``max|G_k| max(|v|, 1) + |c_k + lam m_k|``."""
    b = cs.c + lam * cs.m
    scale = gmax * max(np.abs(x).max(initial=0.0), 1.0) + np.abs(b)
    return b - cs.G @ x, np.maximum(scale, 1e-300)


def tight_rows(cs, x, lam, gmax=None):
    """Rows of ``G v <= c + lam m`` tight at ``v = x`` (slack below :data:`TIGHT_RTOL` of the
    row's scale ``max|G_k| max|v| + |c_k + lam m_k|``; ``gmax``: :func:`row_max` of ``G``)."""
    slack, scale = _slack(cs, x, lam, row_max(cs.G) if gmax is None else gmax)
    return np.flatnonzero(np.abs(slack) <= TIGHT_RTOL * scale)


def family_vertices(cs, lam, undecided, gmax=None):
    """Cheap covering: the point where every row of one family (all ``I``, then all ``II``) is
    tight, by one sparse solve each; when it lies in ``H(lam)`` (checked row by row, the same
    test as an LP vertex's) all ``N`` rows of the family are marked decided.  At ``lam = 0``
    under a compressive static load the all-``I`` point is in ``H(0)`` exactly when every
    normal reaction there stays compressive, so this usually settles every ``lam_low``."""
    n = cs.n_nodes
    gmax = row_max(cs.G) if gmax is None else gmax
    b = cs.c + lam * cs.m
    for rows in (np.arange(n), np.arange(n, 2 * n)):
        if not undecided[rows].any():
            continue
        try:
            x = spla.splu(sp.csc_matrix(cs.G[rows])).solve(b[rows])
        except (RuntimeError, ValueError):  # singular family matrix
            continue
        if not np.all(np.isfinite(x)):
            continue
        slack, scale = _slack(cs, x, lam, gmax)
        if np.all(slack >= -TIGHT_RTOL * scale):
            undecided[np.abs(slack) <= TIGHT_RTOL * scale] = False


def cover(eng, cs, lam, undecided, max_lps=64, gmax=None):
    """Rows whose face is non-empty at ``lam``, found by covering LPs: ``lam`` fixed,
    maximise the sum of the normals of the undecided rows of one family (all ``I`` or all
    ``II``; the two families of one node point opposite ways) so that the optimal vertex makes
    as many of them tight as it can.  Marks them in ``undecided`` (set to ``False``); stops when
    an LP adds nothing new.  Returns the number of LPs."""
    n = cs.n_nodes
    gmax = row_max(cs.G) if gmax is None else gmax
    eng.lp.set_col_bounds(n, lam, lam)
    lps = 0
    try:
        while lps < max_lps and undecided.any():
            half = [np.flatnonzero(undecided[:n]), n + np.flatnonzero(undecided[n:])]
            rows = max(half, key=len)
            cost = np.append(np.asarray(cs.G[rows].sum(axis=0)).ravel(), 0.0)
            ans = eng.run("max", cost=cost)
            lps += 1
            if ans.status != "optimal":
                break
            tight = tight_rows(cs, ans.x[:n], lam, gmax)
            new = tight[undecided[tight]]
            if not new.size:
                break
            undecided[new] = False
    finally:
        eng.lp.set_col_bounds(n, 0.0, np.inf)
    return lps


def intervals_pruned(eng, cs, lam2, v_at_lam2):
    """``(lam_low, lam_high, hi_exact)`` with every ``lam_low`` exact and ``lam_high`` exact only
    where ``lam1`` needs it (module docstring); ``None`` when some ``lam_low`` is not 0 or a row
    is never active (then ``lam1 = 0`` and the caller computes every interval exactly).

    ``eng``: the :class:`~.highs_path.HighsModel` of the nondimensional ``cs``.
    """
    n = cs.n_nodes
    R = 2 * n
    if not np.isfinite(lam2):
        return None
    tol = 1e-9 * max(1.0, lam2)
    gmax = row_max(cs.G)
    # lam_low: the two family points, covering LPs at lam = 0, then one LP per row left
    undecided = np.ones(R, bool)
    family_vertices(cs, 0.0, undecided, gmax)
    cover(eng, cs, 0.0, undecided, gmax=gmax)
    lo = np.where(undecided, np.nan, 0.0)
    for k in np.flatnonzero(undecided):
        if not np.isnan(lo[k]):
            continue
        ans = eng.run("min", tight=(int(k),))
        if ans.status != "optimal" or value(ans) > tol:
            return None  # never active, or inactive at 0: lam1 = 0, the exact path says why
        lo[k] = 0.0
        lo[tight_rows(cs, ans.x[:n], ans.x[-1], gmax)] = 0.0
    # lam_high: capped LPs, rows in order of decreasing slack at the lam2 optimum; each
    # optimum also decides the rows tight at it (covering LPs at lam = t cost more than they
    # save here: measured 67 s against 20 s at N = 1000)
    hi = np.full(R, -np.inf)
    exact = np.zeros(R, bool)
    t = lam2
    at_end = tight_rows(cs, v_at_lam2, lam2, gmax)
    hi[at_end], exact[at_end] = lam2, True  # a face at the lam2 optimum: active up to lam2
    slack = cs.c + lam2 * cs.m - cs.G @ v_at_lam2
    for k in np.argsort(-slack, kind="stable"):
        if hi[k] >= t - tol:
            continue
        eng.lp.set_col_bounds(n, 0.0, t)
        try:
            ans = eng.run("max", tight=(int(k),))
        finally:
            eng.lp.set_col_bounds(n, 0.0, np.inf)
        if ans.status != "optimal":
            return None
        lam = float(ans.x[-1])
        if lam < t - tol:  # the cap is slack: this is row k's exact lam_high
            hi[k], exact[k] = lam, True
            t = lam
        tight = tight_rows(cs, ans.x[:n], lam, gmax)
        hi[tight] = np.maximum(hi[tight], lam)
        hi[k] = max(hi[k], lam)
    return lo, hi, exact
