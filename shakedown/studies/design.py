"""What a study runs: load factors from each realisation's own bounds, and initial states that
find the extremes of the steady dissipation.

Load factors (:func:`lam_points`)
---------------------------------
Seed 002 (s.4.1, Fig. 11) makes three claims that only points in the right places can test:
``lam < lam1``: every initial state shakes down (max ``W*`` = 0); ``lam1 < lam < lam2``: some
state shakes down (min ``W*`` = 0) but not necessarily every one; above ``lam2`` min and max
differ until every crack slips in every steady cycle (``lam_u``).  An evenly spaced grid from
``0.5 lam1`` to ``2 lam2`` misses the band ``(lam1, lam2)`` (3 % wide for the default network),
so each realisation gets, on the axis ``x = lam / lam2`` (dimensionless, common to all
realisations so that they can be averaged):

* ``grid``: ``n_lams`` points evenly spaced in ``x`` over ``lam_span`` (the same ``x`` for
  every realisation: the points that are averaged);
* ``band``: ``n_band`` points inside ``(lam1, lam2)``, from 2 % to 98 % of the band (near
  both ends);
* ``adj``: ``n_adj`` points inside ``(lam_adj, lam1)`` when ``lam_adj < lam1``;
* ``refine``: after the first runs, midpoints where min and max ``W*`` differ most and of the
  bracket of ``lam_u`` (:func:`refine_points`).

Initial states (:func:`initial_states`)
---------------------------------------
The same states at every load factor, in a fixed order (so that the first ``k`` states of a
larger study are the states of a smaller one, and the convergence of min / max with ``k`` can
be measured, ``benchmarks/RESULTS_study.md``):

0. ``zero``: the virgin state;
1. ``safe``: a slip state inside the safe region ``H(lam2)`` (the bounds' ``state_at_lam2``);
   ``H(lam)`` only grows as ``lam`` decreases, so this state shakes down at once for every
   ``lam <= lam2``: it finds min ``W*`` = 0 wherever the theory says it is 0;
2. ``corner+`` / 3. ``corner-``: every node at its static friction limit, ``q = +-f p`` under
   the static load (a vertex of the safe region at ``lam = 0``: the largest locked-in slip a
   body at rest can hold);
4. ... alternately ``corner~`` (a vertex with random signs per node) and ``box`` (uniform in the
   box of :func:`shakedown.sample_initial_slips`), each drawn from its own child seed.

Every state is shrunk, if needed, so that each node keeps at least half its static normal
reaction (every state starts closed), as :func:`shakedown.sample_initial_slips` does.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["STATE_KINDS", "state_kind", "initial_states", "lam_points", "refine_points"]

STATE_KINDS = ("zero", "safe", "corner+", "corner-", "corner~", "box")


def state_kind(j: int) -> str:
    """Kind of initial state ``j`` (see the module docstring)."""
    if j < 4:
        return STATE_KINDS[j]
    return "corner~" if j % 2 == 0 else "box"


def _keep_closed(system, p0, v):
    """``v`` shrunk so that every node keeps half its static normal reaction."""
    dp = v @ system.B
    need = dp < 0
    if np.any(need):
        room = 0.5 * np.maximum(p0[need], 0.0) / -dp[need]
        v = v * min(1.0, float(room.min()))
    return v


def _corner(system, load, signs):
    """Slip with ``q = s f p`` at every node under the static load: solves
    ``(A - diag(s f) B^T) v = s f p0 - q0`` (MODEL.md s.2: ``q = q0 + A v``, ``p = p0 + B^T v``
    at ``w = 0``); the uncoupled answer ``(s f p0 - q0) / A_kk`` if that matrix is singular or
    the solve does not reproduce the right-hand side to 1e-8 (an ill-conditioned system, e.g.
    friction near its critical value, where the corner runs off to a huge slip)."""
    f = np.asarray(system.friction, float)
    sf = signs * f
    rhs = sf * load.p0 - load.q0
    if sp.issparse(system.A):
        M = (system.A - sp.diags(sf) @ system.B.T).tocsc()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a singular M is handled below
                v = spla.spsolve(M, rhs)
        except RuntimeError:
            v = None
    else:
        M = system.A - sf[:, None] * system.B.T
        try:
            v = np.linalg.solve(M, rhs)
        except np.linalg.LinAlgError:
            v = None
    scale = np.abs(rhs).max(initial=0.0)
    if v is None or not np.all(np.isfinite(v)) or \
            np.abs(M @ v - rhs).max(initial=0.0) > 1e-8 * scale:
        v = rhs / system.A.diagonal()
    return v


def initial_states(system, load, n_states: int, seed, *, safe_state=None, scale: float = 2.0):
    """The study's initial slips, shape (n_states, N) (order and kinds: module docstring).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    n_states : int
    seed : tuple of int
        ``(entropy, *spawn_key)``: state ``j >= 4`` is drawn from
        ``SeedSequence(entropy, spawn_key=(*spawn_key, j))``.
    safe_state : array_like, shape (N,), optional
        A state in ``H(lam2)``; the zero state is used in its place when not given.
    scale : float
        Size of the ``box`` states in natural slip scales.
    """
    from ..evolution.steady import sample_initial_slips

    n = system.n_nodes
    p0 = np.asarray(load.p0, float)
    entropy, key = int(seed[0]), tuple(int(k) for k in seed[1:])
    out = np.zeros((int(n_states), n))
    for j in range(int(n_states)):
        kind = state_kind(j)
        if kind == "zero":
            continue
        if kind == "safe":
            v = np.zeros(n) if safe_state is None else np.asarray(safe_state, float)
            out[j] = v
            continue
        if kind in ("corner+", "corner-"):
            v = _corner(system, load, np.full(n, 1.0 if kind == "corner+" else -1.0))
        else:
            rng = np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=(*key, j)))
            if kind == "corner~":
                v = _corner(system, load, rng.choice([-1.0, 1.0], n))
            else:
                v = sample_initial_slips(system, load, 2, rng=rng, scale=scale)[1]
        out[j] = _keep_closed(system, p0, v)
    return out


def lam_points(lam1: float, lam2: float, lam_adj: float, *, n_lams: int, lam_span,
               n_band: int, n_adj: int) -> list[tuple[str, float]]:
    """The first load factors of one realisation: ``[(point, lam), ...]`` sorted by ``lam``.

    ``point`` names the point the same way in every realisation (``g3``: grid point 3,
    ``b1``: band point 1, ``a0``: point 0 between ``lam_adj`` and ``lam1``), so that
    realisations can be averaged point by point.
    """
    pts = []
    if np.isfinite(lam2) and lam2 > 0:
        for i, x in enumerate(np.linspace(lam_span[0], lam_span[1], n_lams)):
            pts.append((f"g{i}", float(x * lam2)))
        if np.isfinite(lam1) and lam1 < lam2 and n_band:
            for i, u in enumerate(np.linspace(0.02, 0.98, n_band) if n_band > 1 else [0.5]):
                lam = float(lam1 + u * (lam2 - lam1))
                if lam1 < lam < lam2:  # a band narrower than rounding has no inside
                    pts.append((f"b{i}", lam))
        if np.isfinite(lam_adj) and np.isfinite(lam1) and lam_adj < lam1 and n_adj:
            for i in range(n_adj):
                lam = float(lam_adj + (i + 1) / (n_adj + 1) * (lam1 - lam_adj))
                if lam_adj < lam < lam1:
                    pts.append((f"a{i}", lam))
    return sorted(pts, key=lambda p: (p[1], p[0]))


def refine_points(points, n_refine: int) -> list[tuple[str, float]]:
    """Refinement after the first runs of one realisation.

    Parameters
    ----------
    points : pandas.DataFrame
        One row per load factor: ``lam``, ``W_star_min``, ``W_star_max``, ``all_slip`` (every
        state's steady cycle has every crack slipping).
    n_refine : int

    Returns
    -------
    list of (point, lam)
        ``u0``: the midpoint of the bracket of ``lam_u`` (largest ``lam`` not all slipping,
        smallest all slipping), when there is one; then ``f0, f1, ...``: midpoints of the
        intervals whose end points have the largest spread ``max - min`` of ``W*``.
    """
    p = points.sort_values("lam", kind="stable").reset_index(drop=True)
    lam = p["lam"].to_numpy(float)
    out = []
    if n_refine <= 0 or len(p) < 2:
        return out
    allslip = p["all_slip"].to_numpy(bool)
    if allslip.any() and not allslip.all():
        hi = int(np.argmax(allslip))
        if hi > 0:
            out.append(("u0", 0.5 * (lam[hi - 1] + lam[hi])))
    spread = np.nan_to_num((p["W_star_max"] - p["W_star_min"]).to_numpy(float))
    score = np.maximum(spread[:-1], spread[1:])
    for k, i in enumerate(np.argsort(-score, kind="stable")):
        if len(out) >= n_refine or score[i] <= 0:
            break
        out.append((f"f{k}", 0.5 * (lam[i] + lam[i + 1])))
    return out[:n_refine]
