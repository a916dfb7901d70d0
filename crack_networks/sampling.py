"""Random crack sets: :func:`sample_crack_set` (random sequential adsorption, MODEL.md s.6).

The half-lengths and angles are drawn first; the square window then has the area
``sum a^2 / density`` so that the density ``rho = sum a^2 / area`` is met exactly.  Centres are
uniform in the window and a candidate is rejected when its segment comes closer than
``min_spacing * (a_i + a_j) / 2`` to an accepted crack (or meets it).  Cracks are tried in
rounds of up to 1024: each still unplaced (length, angle) draw gets a fresh uniform centre, the
candidates are checked against the accepted cracks (k-d tree on the centres, then exact
vectorised segment distances) and against each other (greedy, in order); the rejected draws
wait for the next round.  The result depends only on the seed.  The returned set is in
acceptance order.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from shakedown.model.errors import InputError

from .cracks import CrackSet, segment_distance

__all__ = ["sample_crack_set"]

_BATCH = 1024  # cracks tried per round (fixed: the result depends on the seed only)


def _draw(name, spec, rng, n, default_range):
    if spec is None:
        return rng.uniform(*default_range, size=n)
    if callable(spec):
        out = np.asarray(spec(rng, n), dtype=float)
        if out.shape != (n,):
            raise InputError(
                f"{name} callable must return an array of shape ({n},); got {out.shape}"
            )
        return out
    try:
        arr = np.asarray(spec, dtype=float)
    except (TypeError, ValueError):
        arr = np.zeros((0, 0))
    if arr.ndim == 0:
        return np.full(n, float(arr))
    if arr.shape == (2,):
        lo, hi = float(arr[0]), float(arr[1])
        if not lo <= hi:
            raise InputError(f"{name} range (lo, hi) needs lo <= hi; got {tuple(arr)}")
        return rng.uniform(lo, hi, size=n)
    raise InputError(
        f"{name} must be a number, a (lo, hi) pair or a callable(rng, n); got {spec!r}"
    )


def sample_crack_set(
    n: int,
    density: float = 0.1,
    half_length=1.0,
    orientation=None,
    min_spacing: float = 0.1,
    rng=None,
    *,
    max_attempts: int | None = None,
) -> CrackSet:
    """Sample ``n`` non-intersecting straight cracks at a given density.

    Parameters
    ----------
    n : int
        Number of cracks (``>= 1``).
    density : float
        ``rho = sum a^2 / area`` of the square window (``> 0``).
    half_length : float, (lo, hi) or callable(rng, n)
        Half-lengths: constant, uniform in ``[lo, hi]``, or drawn by the callable.
    orientation : None, float, (lo, hi) or callable(rng, n)
        Angles [rad]: ``None`` = uniform in ``[0, pi)``; a number = all equal; ``(lo, hi)``
        uniform; or drawn by the callable.
    min_spacing : float
        Minimum segment-segment distance between two cracks in units of their mean
        half-length ``(a_i + a_j) / 2`` (``>= 0``; intersecting cracks are always rejected).
    rng : int, numpy.random.Generator or None
        Seed or generator; the same seed gives the same set.
    max_attempts : int, optional
        Give up after this many candidate centres (default ``200 n + 10 000``).

    Returns
    -------
    CrackSet
        Cracks in the order they were accepted.

    Raises
    ------
    InputError
        Bad parameters, or the window is too crowded to place ``n`` cracks with the requested
        spacing (the message gives the number placed and what to relax).

    Examples
    --------
    >>> import crack_networks as cn
    >>> cs = cn.sample_crack_set(50, density=0.1, rng=7)
    >>> cs.n_cracks
    50
    """
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise InputError(f"n must be a positive integer; got {n!r}")
    n = int(n)
    if not (np.isfinite(density) and density > 0):
        raise InputError(f"density must be a finite number > 0; got {density!r}")
    if not (np.isfinite(min_spacing) and min_spacing >= 0):
        raise InputError(f"min_spacing must be a finite number >= 0; got {min_spacing!r}")
    rng = np.random.default_rng(rng)
    a = _draw("half_length", half_length, rng, n, (1.0, 1.0))
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise InputError(f"half_length must give values > 0; got min {np.min(a)!r}")
    ang = np.mod(_draw("orientation", orientation, rng, n, (0.0, np.pi)), np.pi)
    side = float(np.sqrt(np.sum(a**2) / density))
    max_attempts = int(200 * n + 10_000) if max_attempts is None else int(max_attempts)
    amax = float(a.max())

    t_all = np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    reach = 2.0 * amax + min_spacing * amax
    cen = np.empty((n, 2))
    p0 = np.empty((n, 2))
    p1 = np.empty((n, 2))
    shape = np.empty(n, dtype=int)  # which (length, angle) draw each accepted crack carries
    pending = np.arange(n)  # shapes still to place, in order
    count = 0
    attempts = 0
    while pending.size:
        if attempts >= max_attempts:
            raise InputError(
                f"could place only {count} of {n} cracks after {attempts} candidate positions "
                f"(density {density}, min_spacing {min_spacing}); lower the density or "
                "the min_spacing, or raise max_attempts"
            )
        # each pending draw gets `reps` candidate centres (many when few are left)
        s0 = pending[:_BATCH]
        reps = max(1, _BATCH // s0.size)
        s = np.repeat(s0, reps)
        m = s.size
        xy = rng.uniform(0.0, side, size=(m, 2))
        attempts += m
        q0 = xy - a[s, None] * t_all[s]
        q1 = xy + a[s, None] * t_all[s]
        ok = np.ones(m, dtype=bool)
        if count:  # against the accepted cracks
            tree = cKDTree(cen[:count])
            rows, cols = _pairs_within(tree, xy, reach)
            if rows.size:
                d = segment_distance(q0[rows], q1[rows], p0[cols], p1[cols])
                bad = (d <= min_spacing * 0.5 * (a[s[rows]] + a[shape[cols]])) | (d == 0.0)
                ok[rows[bad]] = False
        # first admissible candidate of every draw
        okr = ok.reshape(s0.size, reps)
        has = okr.any(axis=1)
        pick = np.arange(s0.size) * reps + np.argmax(okr, axis=1)
        s, xy, q0, q1 = s0, xy[pick], q0[pick], q1[pick]
        ok = has
        m = s.size
        # within the batch: greedy in order over the conflicting pairs
        btree = cKDTree(xy)
        pr = btree.query_pairs(reach, output_type="ndarray")
        if pr.size:
            i, j = pr[:, 0], pr[:, 1]
            d = segment_distance(q0[i], q1[i], q0[j], q1[j])
            clash = (d <= min_spacing * 0.5 * (a[s[i]] + a[s[j]])) | (d == 0.0)
            pr = np.sort(pr[clash], axis=1)
            pr = pr[np.lexsort((pr[:, 1], pr[:, 0]))]
            for i, j in pr:
                if ok[i]:
                    ok[j] = False
        k = np.flatnonzero(ok)
        sl = slice(count, count + k.size)
        cen[sl], p0[sl], p1[sl], shape[sl] = xy[k], q0[k], q1[k], s[k]
        count += k.size
        pending = np.concatenate([s[~ok], pending[s0.size:]])
    return CrackSet(cen, a[shape], ang[shape])


def _pairs_within(tree, points, r):
    """(row, col) index pairs with ``|points[row] - tree.data[col]| <= r``."""
    lists = tree.query_ball_point(points, r)
    lens = np.fromiter((len(x) for x in lists), dtype=int, count=len(lists))
    rows = np.repeat(np.arange(len(lists)), lens)
    cols = np.fromiter((c for x in lists for c in x), dtype=int, count=int(lens.sum()))
    return rows, cols
