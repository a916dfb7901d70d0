"""Certified facet walks: which extreme constraints touch ``H(t)`` at one fixed load factor ``t``.

Issue 14 (pruning the activity-interval LPs).  Constraint ``k`` is active at ``t`` when the face
``H(t) & {G_k v = b_k(t)}`` is non-empty.  Its activity interval is convex, so once ``lam_low_k
= 0`` is known, *one point* of that face proves ``lam_high_k >= t`` -- and a vertex of ``H(t)``
is such a point for every row tight at it.  :class:`FacetWalk` is a dense primal simplex on
``H(t) = {v : G v <= b}`` (rows of unit norm) that steers from vertex to vertex towards a chosen
row ``k`` (objective ``max G_k v``, Dantzig pricing, Harris-style ratio test): it stops as soon
as ``k`` is tight at a visited vertex (face non-empty), or at an optimum where ``k`` is slack
(face empty: ``lam_high_k < t``), or after ``cap`` pivots (undecided).  Consecutive walks start
where the last one ended, so one walk's vertices certify the rows of later targets.

Every certificate is checked on its own point: :func:`certified_rows` recomputes ``b - G v``
from scratch at each visited vertex and accepts its tight rows only when the vertex satisfies
every row to :data:`WALK_TOL` (relative to the row's scale ``|v| + |b_i|``).  The basis inverse
is kept by Sherman-Morrison updates and recomputed when a check fails; if it still fails the walk
reports the point unusable (``None``) and the caller falls back to exact LPs.
"""

from __future__ import annotations

import numpy as np

from .inverse_updates import inverse, rank1

#: Feasibility / tightness tolerance of a certificate point (relative to the row scale).
WALK_TOL = 1e-9
#: Smallest ``G_i d`` that limits a primal step (rows have unit norm).
STEP_TOL = 1e-9
#: Vertices of a walk checked together (one product ``G X``; the slacks in between are
#: updated, not recomputed).
CHECK_BATCH = 16


def certified_rows(G, b, x, tol=WALK_TOL, Gx=None):
    """Rows of ``G v <= b`` (unit-norm rows) that the point ``x`` proves touchable: ``None`` if
    ``x`` violates a row by more than ``tol`` times its scale ``|x|_inf + |b_i|``, else the
    boolean mask of the rows tight at ``x`` to that tolerance (``x`` is then a point of the face
    of each of them).  ``Gx`` may pass ``G @ x`` when already computed."""
    x = np.asarray(x, float)
    s = b - (G @ x if Gx is None else Gx)
    scale = np.maximum(max(float(np.abs(x).max(initial=0.0)), 1.0) + np.abs(b),
                       np.finfo(float).tiny)
    if np.any(s < -tol * scale):
        return None
    return np.abs(s) <= tol * scale


def batch_check(G, b, X):
    """``(G X, masks)`` for the points of the list ``X``: one product with ``G``, then each
    point's :func:`certified_rows` (``None`` where it fails)."""
    GX = G @ np.column_stack(X)
    return GX, [certified_rows(G, b, x, Gx=GX[:, i]) for i, x in enumerate(X)]


class FacetWalk:
    """Primal simplex walker on ``{v : G v <= b}`` from the vertex with tight rows ``T``.

    Parameters
    ----------
    G : ndarray, shape (R, N)
        Rows of unit norm.
    b : ndarray, shape (R,)
    T : array of int, shape (N,)
        Rows defining a vertex (``G_T`` non-singular, the vertex feasible).

    Attributes
    ----------
    ok : bool
        The start vertex was non-singular and certified; if ``False`` nothing may be used.
    covered : ndarray of bool, shape (R,)
        Rows tight at some certified vertex visited so far.
    pivots : int
    """

    def __init__(self, G, b, T):
        self.G, self.b = G, b
        self.R, self.n = G.shape
        self.T = np.asarray(T, int).copy()
        self.covered = np.zeros(self.R, bool)
        self.pivots = 0
        self.reinversions = -1
        self.broken = False
        self.ok = len(self.T) == self.n and self._reinvert() and self._certify()

    def _reinvert(self) -> bool:
        Binv = inverse(self.G[self.T])
        if Binv is None:
            return False
        self.Binv = Binv
        self.reinversions += 1
        self.x = self.Binv @ self.b[self.T]
        self.inb = np.zeros(self.R, bool)
        self.inb[self.T] = True
        return True

    def _certify(self, Gx=None) -> bool:
        """Check the current vertex from scratch (``Gx = G @ x`` if given); on success add its
        tight rows to ``covered`` and keep the slacks ``s``.  On failure the basis is
        re-inverted and checked once more."""
        for attempt in range(2):
            tight = certified_rows(self.G, self.b, self.x, Gx=Gx)
            if tight is not None and tight[self.T].all():
                self.covered |= tight
                self.s = self.b - (self.G @ self.x if Gx is None else Gx)
                return True
            Gx = None
            if attempt == 0 and not self._reinvert():
                break
        self.broken = True
        return False

    def walk_to(self, k: int, cap: int):
        """Walk towards row ``k``: ``True`` (a certified vertex has ``k`` tight), ``False``
        (optimum of ``max G_k v`` with ``k`` slack: the face is empty), or ``None`` (``cap``
        pivots without a decision, or a vertex failed its check)."""
        return self._walk(self.G[k], k, cap)

    def maximise(self, g, cap: int) -> bool:
        """Primal simplex for ``max g.v`` from the current vertex: ``True`` at a certified
        optimal vertex (basis ``T``), ``False`` otherwise (cap, unbounded, failed check)."""
        return self._walk(np.asarray(g, float), -1, cap) is False and not self.broken

    def _walk(self, g, k, cap):
        y = None  # multipliers B^-T g, updated with the basis (recomputed after a reinversion)
        self._buffer = []
        for it in range(cap + 1):
            if self.broken:
                return None
            if k >= 0 and self.covered[k]:
                return True
            if y is None or it % 32 == 0:
                y = self.Binv.T @ g
            r = int(np.argmin(y))
            optimal = y[r] >= -1e-11 * max(float(np.abs(y).max()), 1e-300)
            if optimal and it % 32:  # decide on fresh multipliers, not updated ones
                y = self.Binv.T @ g
                r = int(np.argmin(y))
                optimal = y[r] >= -1e-11 * max(float(np.abs(y).max()), 1e-300)
            if optimal or it == cap:
                if not self._flush():
                    return None
                return True if k >= 0 and self.covered[k] else (False if optimal else None)
            d = -self.Binv[:, r]  # G_T d = -e_r: row T_r loosens, the others stay tight
            Gd = self.G @ d
            ok = (Gd > STEP_TOL) & ~self.inb
            if not ok.any():
                self._flush()
                return None  # unbounded direction: cannot happen with k among the rows
            ratio = np.where(ok, np.maximum(self.s, 0.0) / np.where(ok, Gd, 1.0), np.inf)
            tmin = ratio.min()
            near = ok & (ratio <= tmin + 1e-12 * (1.0 + tmin))
            p = int(np.argmax(np.where(near, Gd, -np.inf)))
            step = float(ratio[p])
            w = self.G[p] @ self.Binv
            w[r] -= 1.0
            # Binv -= (d / Gd_p) w^T, in place (BLAS rank-1 update on the transposed view);
            # then y = Binv^T g changes by -(g.d / Gd_p) w = (y_r / Gd_p) w
            self.Binv = rank1(self.Binv, -1.0 / Gd[p], d, w)
            y = y + (y[r] / Gd[p]) * w
            self.x = self.x + step * d
            self.s -= step * Gd  # updated slacks (the ratio test); exact ones come in batches
            self.s[p] = 0.0
            self.inb[self.T[r]] = False
            self.inb[p] = True
            self.T[r] = p
            self.pivots += 1
            self._buffer.append(self.x)
            near_k = k >= 0 and self.s[k] <= 10 * WALK_TOL * (
                max(float(np.abs(self.x).max()), 1.0) + abs(self.b[k]))
            if near_k or len(self._buffer) >= CHECK_BATCH:
                before = self.reinversions
                if not self._flush():
                    return None
                if self.reinversions != before:  # the check re-inverted: price again
                    y = None
        self._flush()
        return None

    def _flush(self) -> bool:
        """Check the vertices visited since the last check, all with one product ``G X``; their
        tight rows join ``covered`` (a vertex that fails its check adds nothing).  The current
        vertex must pass (else the basis is re-inverted and checked, :meth:`_certify`); its
        exact slacks replace the updated ones.  ``False``: the walk is broken."""
        X = self._buffer
        self._buffer = []
        if not X or X[-1] is not self.x:
            return self._certify()
        GX, tights = batch_check(self.G, self.b, X)
        for tight in tights[:-1]:
            if tight is not None:
                self.covered |= tight
        return self._certify(GX[:, -1])


    def descend(self, k: int, c, m, lam: float, max_steps: int):
        """Exact ``lam_high_k`` below ``lam`` by a parametric dual simplex (rows ``G v <= c +
        lam m``; the walker's offsets are ``c + lam m``), from an optimum of ``max G_k v`` at
        which row ``k`` is slack (face ``k`` empty at ``lam``, as :meth:`walk_to` returns
        ``False``).  ``lam`` decreases; at each breakpoint a row that would be violated enters
        (dual ratio test keeps the multipliers ``y >= 0``), until row ``k`` is tight.

        Returns the new ``lam`` (the walker is then at a certified vertex of ``H(lam)`` with
        ``k`` tight) or ``None``.  Certificate, both checked here: the point (face ``k``
        non-empty at ``lam``) and the multipliers ``y >= 0``, ``G_T^T y = G_k``, whose bound
        ``G_k v <= y.(c_T + l m_T)`` on ``H(l)`` for every ``l`` stays below ``c_k + l m_k``
        for ``l > lam`` (face ``k`` empty above ``lam``)."""
        G, g = self.G, self.G[k]
        for _ in range(max_steps):
            y = self.Binv.T @ g
            ys = max(float(np.abs(y).max()), 1e-300)
            if y.min() < -1e-9 * ys:
                return None
            x = self.Binv @ (c[self.T] + lam * m[self.T])
            dx = self.Binv @ m[self.T]
            sl = c + lam * m - G @ x
            ds = m - G @ dx  # s(lam - tau) = sl - tau ds
            cand = ~self.inb & (ds > STEP_TOL)
            cand[k] = False
            tau = np.where(cand, np.maximum(sl, 0.0) / np.where(cand, ds, 1.0), np.inf)
            p = int(np.argmin(tau))
            tau_k = max(float(sl[k]), 0.0) / ds[k] if ds[k] > STEP_TOL else np.inf
            if tau_k <= tau[p]:
                return self._land(k, c, m, lam - tau_k, x - tau_k * dx, y)
            if not np.isfinite(tau[p]) or tau[p] > lam:
                return None
            lam -= float(tau[p])
            alpha = G[p] @ self.Binv
            ok = alpha > STEP_TOL
            if not ok.any():
                return None
            ratio = np.where(ok, np.maximum(y, 0.0) / np.where(ok, alpha, 1.0), np.inf)
            tmin = ratio.min()
            near = ok & (ratio <= tmin + 1e-12 * (1.0 + tmin))
            r = int(np.argmax(np.where(near, alpha, -np.inf)))
            w = alpha.copy()
            w[r] -= 1.0
            self.Binv = rank1(self.Binv, -1.0 / alpha[r], self.Binv[:, r].copy(), w)
            self.inb[self.T[r]] = False
            self.inb[p] = True
            self.T[r] = p
            self.pivots += 1
        return None

    def _land(self, k, c, m, lam, x, y):
        """Check the descent's end point and dual bound; move the walker to ``H(lam)``."""
        if lam < 0:
            return None
        T = self.T
        stat = np.abs(self.G[T].T @ y - self.G[k]).max() / max(float(np.abs(y).max()), 1.0)
        slope = float(y @ m[T] - m[k])
        gap = float(y @ (c[T] + lam * m[T]) - (c[k] + lam * m[k]))  # U(lam) >= 0
        if stat > 1e-9 or not slope < 0 or -gap / slope > 1e-10 * max(1.0, lam):
            return None
        self.b = c + lam * m
        self.x = x
        self.covered = np.zeros(self.R, bool)
        if not self._certify() or not self.covered[k]:
            return None
        return lam

def vertex_rows(G, m, basis, keep):
    """``N`` rows of an ``(N+1)``-row optimal basis of a ``(v, lam)`` LP (rows ``[G, -m]``) that
    define a vertex of ``H`` at the optimum's ``lam``: drop the row with the largest component of
    the null vector of ``G_basis^T`` (never ``keep``).  ``None`` if no such row exists."""
    basis = np.asarray(basis, int)
    M = np.hstack([G[basis], -m[basis, None]])
    try:
        z = np.linalg.solve(M.T, np.r_[np.zeros(G.shape[1]), 1.0])
    except np.linalg.LinAlgError:
        return None
    z = np.abs(z)
    z[basis == keep] = -1.0
    r = int(np.argmax(z))
    if not z[r] > 1e-12 * max(float(z.max()), 1e-300):
        return None
    return np.delete(basis, r)
