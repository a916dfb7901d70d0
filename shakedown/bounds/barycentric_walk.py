"""Facet walks in barycentric coordinates of the ``lam2`` simplex (issue 14).

At the ``lam2`` optimum ``(x*, lam2)`` of ``max lam, G v <= c + lam m`` an optimal basis has
``N + 1`` rows ``B`` with multipliers ``y > 0``, ``G_B^T y = 0``: their normals span space
positively, so for ``t < lam2`` the rows ``B`` alone bound a simplex ``S(t) = x* + (lam2 - t)
S(0)`` -- homothetic about ``x*``.  Its vertices are ``V_a(t) = x* + (lam2 - t) d_a`` with
``[G_B, m_B] [d_a; 1] = sigma_a e_a`` (``sigma_a = -1 / y_a < 0``: row ``a`` is the one vertex
``a`` leaves slack).  Every point of ``S(t)`` is ``v = sum_a lambda_a V_a(t)`` with ``lambda``
in the unit simplex, and for every other row ``j``

    G_j v - b_j(t) = sum_a lambda_a h_ja(t),    h_ja(t) = G_j V_a(t) - b_j(t),

while row ``a`` of ``B`` reads ``lambda_a >= 0``.  So ``H(t) = {lambda >= 0, sum lambda = 1,
h_j . lambda <= 0}``: the ``N + 1`` rows of ``B`` have become simple bounds.  A vertex of
``H(t)`` at which ``m`` rows outside ``B`` are tight has ``m + 1`` positive coordinates, and
the primal simplex on it works with an ``(m + 1)``-square basis: a pivot costs ``O(N m)``
instead of the ``O(N^2)`` of the walk in ``v`` (:class:`~.facet_walk.FacetWalk`).  Near
``lam2`` (where the pruning's walks go: ``t`` is the incumbent ``lam1`` candidate) ``m`` is
small: on random systems 28 at N = 500, 58 at N = 1000.

:class:`BarycentricWalk` has the interface the pruning uses of a ``FacetWalk`` (``walk_to``,
``covered``, ``s``, ``T``, ``pivots``, ``broken``).  Nothing is concluded in barycentric
coordinates: each vertex that would cover new rows is mapped back to ``v`` and checked there
from scratch (:func:`~.facet_walk.certified_rows`, a batch of vertices with one product
``G X``); only the rows tight at a checked vertex are ``covered``.  A walk that ends at an
optimum with the target slack (``False``: face empty) hands over to a ``FacetWalk`` at the same
vertex (:meth:`BarycentricWalk.facet_walk`) for the descent to the target's ``lam_high``.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from .facet_walk import FacetWalk, certified_rows

#: Most rows outside the simplex basis that may be tight at a vertex (and at most
#: ``max(N / 3, 32)``):
#: the basis of the walk is refactorised at each pivot, ``O(m^3)``; beyond it the walk stops
#: (``broken``) and the pruning goes on in ``v`` from the same vertex.
MAX_TIGHT = 400
#: Vertices checked together (one product ``G X``).
CHECK_BATCH = 16
#: Relative tolerance of the reduced costs and of the ratio test's pivot elements.
PIV_TOL = 1e-11


class SimplexFrame:
    """The ``t``-independent part: vertex directions ``d_a`` and the products ``G d_a``.

    Built once per pruning from the ``lam2`` optimum; ``None`` from :meth:`of` when the optimal
    basis does not bound a simplex (a multiplier ``y_a <= 0``: degenerate optimum, or a basic
    row that is not a constraint row).
    """

    def __init__(self, G, c, m, B, x2, lam2, D, sigma):
        self.G, self.c, self.m = G, c, m
        self.R, self.n = G.shape
        self.B = np.asarray(B, int)
        self.x2, self.lam2, self.D, self.sigma = x2, float(lam2), D, sigma
        self.pos = np.full(self.R, -1)  # row -> position in B (or -1)
        self.pos[self.B] = np.arange(len(self.B))
        self.J = np.flatnonzero(self.pos < 0)
        self.loc = np.full(self.R, -1)  # row -> position in J (or -1)
        self.loc[self.J] = np.arange(len(self.J))
        self.GJx = G[self.J] @ x2
        self.GJD = G[self.J] @ D  # (|J|, N + 1): the one O(N^3) product

    @classmethod
    def of(cls, G, c, m, basis, x2, lam2):
        """From the unit-norm rows ``G v <= c + lam m`` and an optimal ``lam2`` basis (rows of
        ``[G, -m]``; indices ``>= R`` are other rows)."""
        R, n = G.shape
        B = np.asarray(basis, int)
        if len(B) != n + 1 or np.any(B >= R) or len(np.unique(B)) != n + 1 or not lam2 > 0:
            return None
        Q = np.hstack([G[B], m[B, None]])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            try:
                Qi = sla.inv(Q, check_finite=False)
            except (np.linalg.LinAlgError, ValueError):
                return None
        y = -Qi[n]  # multipliers of the lam2 optimum: y^T [G_B, -m_B] = [0, 1]
        if not np.all(np.isfinite(Qi)) or not y.min() > 1e-9 * np.abs(y).max():
            return None
        D = Qi[:n] / Qi[n][None, :]  # d_a = sigma_a Qi[:n, a], sigma_a = 1 / Qi[n, a]
        return cls(G, c, m, B, x2, lam2, D, 1.0 / Qi[n])

    def h(self, t):
        """``h_ja(t)`` for the rows ``J`` outside the basis, shape ``(|J|, N + 1)``."""
        bJ = self.c[self.J] + t * self.m[self.J]
        return (self.GJx - bJ)[:, None] + (self.lam2 - t) * self.GJD


class BarycentricWalk:
    """Primal simplex walker on ``H(t)`` in barycentric coordinates (module docstring).

    Parameters
    ----------
    frame : SimplexFrame
    t : float
        Load factor, ``0 <= t < lam2``.
    T : array of int, shape (N,)
        Rows defining a vertex of ``H(t)`` (as for a ``FacetWalk``).
    """

    def __init__(self, frame: SimplexFrame, t: float, T):
        self.f, self.t = frame, float(t)
        self.G, self.b = frame.G, frame.c + self.t * frame.m
        self.R, self.n = frame.G.shape
        self.covered = np.zeros(self.R, bool)
        self.limit = min(MAX_TIGHT, max(self.n // 3, 32))
        self.pivots = 0
        self.broken = False
        self.ok = False
        self._buffer = []
        if not (0.0 <= self.t < frame.lam2):
            return
        self.H = frame.h(self.t)
        self.HF = np.asfortranarray(self.H)
        self.scale = frame.lam2 - self.t
        self.gap = -self.scale * frame.sigma  # slack of row a of B per unit of lambda_a
        T = np.asarray(T, int)
        inT = np.zeros(self.R, bool)
        inT[T] = True
        self.P = [int(a) for a in np.flatnonzero(~inT[frame.B])]  # basis rows left slack
        self.Tl = [int(frame.loc[j]) for j in T if frame.loc[j] >= 0]
        if (len(self.P) != len(self.Tl) + 1 or len(self.Tl) > self.limit
                or not self._factor()):
            return
        tol = 1e-9 * max(1.0, float(np.abs(self.lamP).max()))
        if self.lamP.min() < -tol or self.sigma.min() < -1e-9 * (1.0 + np.abs(self.H).max()):
            return
        self._buffer.append(self._vertex())
        self.ok = self._flush()

    # ------------------------------------------------------------------ state
    def _factor(self) -> bool:
        """Factor the working basis ``[H_{T,P}; 1]`` and recompute the vertex from it."""
        P, Tl = self.P, self.Tl
        M = np.ones((len(P), len(P)))
        if Tl:
            M[:-1] = self.H[np.ix_(Tl, P)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(M, check_finite=False)
        d = np.abs(np.diag(lu[0]))
        if not d.min() > 1e-12 * d.max():
            return False
        self.lu = lu
        e = np.zeros(len(P))
        e[-1] = 1.0
        self.lamP = sla.lu_solve(lu, e, check_finite=False)
        self.sigma = -(self.HF[:, P] @ self.lamP)  # slacks of the rows J
        self.sigma[Tl] = 0.0
        return True

    @property
    def T(self):
        """The vertex in ``v``: the ``N`` rows that define it (``B`` minus ``P``, plus the tight
        rows outside ``B``)."""
        keep = np.ones(len(self.f.B), bool)
        keep[self.P] = False
        return np.r_[self.f.B[keep], self.f.J[self.Tl]].astype(int)

    @property
    def s(self):
        """Slacks of all ``R`` rows at the current vertex (``v`` units; for choosing targets):
        row ``a`` of ``B`` has ``-(lam2 - t) sigma_a lambda_a``."""
        out = np.empty(self.R)
        out[self.f.J] = self.sigma
        lam = np.zeros(len(self.f.B))
        lam[self.P] = self.lamP
        out[self.f.B] = self.gap * lam
        return out

    def _vertex(self):
        """The current vertex in ``v``: ``x* + (lam2 - t) D_P lambda_P``."""
        return self.f.x2 + self.scale * (self.f.D[:, self.P] @ self.lamP)

    def _flush(self) -> bool:
        """Check the buffered vertices in ``v`` (one product ``G X``); their tight rows join
        ``covered``.  ``False`` if the last one (the current vertex) fails."""
        X, self._buffer = self._buffer, []
        if not X:
            return True
        GX = self.G @ np.column_stack(X)
        good = True
        for i, x in enumerate(X):
            tight = certified_rows(self.G, self.b, x, Gx=GX[:, i])
            if tight is None:
                good = i < len(X) - 1 and good
                continue
            self.covered |= tight
        return good

    # ------------------------------------------------------------------ walking
    def walk_to(self, k: int, cap: int):
        """Walk towards row ``k`` (``max G_k v``): ``True`` (``k`` tight at a checked vertex),
        ``False`` (optimum with ``k`` slack: face empty), ``None`` (undecided: ``cap`` pivots,
        a failed check, or too many tight rows)."""
        if self.broken:
            return None
        if self.covered[k]:
            return True
        kl = int(self.f.loc[k])
        if kl < 0:  # a row of B: tight wherever lambda_k = 0
            return None
        g = self.H[kl]
        res = None
        for _ in range(cap + 1):
            step = self._pivot(g, kl)
            if step is None:  # broken
                self.broken = True
                break
            if step == "optimal":
                res = False
                break
            if kl in self.Tl:
                break
        if not self._flush():
            self.broken = True
            return None
        if self.covered[k]:
            return True
        if res is False and self.sigma[kl] > 1e-9 * (1.0 + abs(self.b[k])):
            return False
        return None

    def _pivot(self, g, kl):
        """One primal simplex pivot for ``max g . lambda``: ``"optimal"``, ``"moved"`` or
        ``None`` (singular basis, unbounded, too many tight rows)."""
        P, Tl = self.P, self.Tl
        z = sla.lu_solve(self.lu, g[P], trans=1, check_finite=False)
        u, w = z[:-1], z[-1]
        rc = g - w
        if Tl:
            rc -= u @ self.H[Tl]
        rc[P] = 0.0
        # Dantzig pricing on the multipliers of the rows as in v (the walk of FacetWalk):
        # a unit of lambda_a is a slack gap_a of row a of B
        rc /= self.gap
        scale = max(float(np.abs(rc).max()), float(np.abs(u).max(initial=0.0)), 1e-300)
        e = int(np.argmax(rc))
        best = rc[e]
        j = int(np.argmin(u)) if len(u) else -1
        if j >= 0 and -u[j] > best:  # loosen tight row Tl[j]
            best, e = -u[j], -1
        if not best > PIV_TOL * scale:
            return "optimal"
        rhs = np.zeros(len(P))
        if e >= 0:
            if Tl:
                rhs[:-1] = self.H[Tl, e]
            rhs[-1] = 1.0
            dP = -sla.lu_solve(self.lu, rhs, check_finite=False)
            dS = -(self.HF[:, P] @ dP + self.HF[:, e])
        else:
            rhs[j] = -1.0
            dP = sla.lu_solve(self.lu, rhs, check_finite=False)
            dS = -(self.HF[:, P] @ dP)
        dS[Tl] = 0.0
        if e < 0:
            dS[Tl[j]] = 1.0
        # ratio test: basic lambdas and the slacks of the rows not tight
        tl = PIV_TOL * max(1.0, float(np.abs(dP).max()))
        ts = PIV_TOL * max(1.0, float(np.abs(dS).max()))
        bl = dP < -tl
        bs = dS < -ts
        rl = np.where(bl, np.maximum(self.lamP, 0.0) / np.where(bl, -dP, 1.0), np.inf)
        rs = np.where(bs, np.maximum(self.sigma, 0.0) / np.where(bs, -dS, 1.0), np.inf)
        tmin = min(rl.min(initial=np.inf), rs.min(initial=np.inf))
        if not np.isfinite(tmin):
            return None
        near = tmin + 1e-12 * (1.0 + tmin)
        # prefer the target's row among ties, then the largest pivot element
        if bs[kl] and rs[kl] <= near:
            leave = ("row", kl)
        else:
            cl = np.where(rl <= near, -dP, -np.inf)
            cs = np.where(rs <= near, -dS, -np.inf)
            il, is_ = int(np.argmax(cl)), int(np.argmax(cs))
            leave = ("lam", il) if cl[il] >= cs[is_] else ("row", is_)
        # update the sets (|P| = |T| + 1 is kept by each of the four cases); on copies, kept
        # only if the new basis factors (else the walker stays at its last vertex, broken)
        P, Tl = list(P), list(Tl)
        if leave[0] == "lam":
            P.remove(P[leave[1]])
            if e >= 0:
                P.append(e)
            else:
                Tl.pop(j)
        else:
            if e >= 0:
                P.append(e)
                Tl.append(leave[1])
            else:
                Tl[j] = leave[1]
        if len(Tl) > self.limit:
            return None
        old = self.P, self.Tl
        self.P, self.Tl = P, Tl
        if not self._factor():
            self.P, self.Tl = old
            self._factor()
            return None
        self.pivots += 1
        if e >= 0 or leave[0] == "row":
            newly = [r for r in Tl if not self.covered[self.f.J[r]]]
            if newly:
                self._buffer.append(self._vertex())
                if len(self._buffer) >= CHECK_BATCH and not self._flush():
                    return None
        return "moved"

    def facet_walk(self):
        """A :class:`~.facet_walk.FacetWalk` at the current vertex (``None`` if not usable)."""
        fw = FacetWalk(self.G, self.b, self.T)
        return fw if fw.ok else None
