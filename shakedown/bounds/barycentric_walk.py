"""Facet walks in the coordinates of the ``lam2`` basis (issue 14).

At the ``lam2`` optimum ``(x*, lam2)`` of ``max lam, G v <= c + lam m`` an optimal basis has
``N + 1`` rows ``B``; ``Q = [G_B, -m_B]`` is non-singular, so the slacks ``sigma = b_B(lam) -
G_B v`` of those rows are coordinates of ``(v, lam)``: with ``Q^-1 = [E; y^T]``,

    v = x* - E sigma,    lam = lam2 - y . sigma,

(``y`` are the multipliers of the optimum, ``y >= 0``).  The rows of ``B`` become the simple
bounds ``sigma >= 0``, a load factor ``t`` the one equation ``y . sigma = lam2 - t``, and every
other row ``j``

    G_j v <= b_j(t)   <=>   K_j . sigma <= r_j(t),   K_j = -G_j E,   r_j = b_j(t) - G_j x*.

(For ``y > 0`` these are barycentric coordinates of the simplex ``{G_B v <= b_B(t)}``, which is
homothetic about ``x*``: ``lambda_a = y_a sigma_a / (lam2 - t)``; zero multipliers, as on
degenerate optima, are allowed.)  A vertex of ``H(t)`` at which ``m`` rows outside ``B`` are
tight has at most ``m + 1`` non-zero coordinates, and the primal simplex on it works with an
``(m + 1)``-square basis: a pivot costs ``O(N m)`` instead of the ``O(N^2)`` of the walk in
``v`` (:class:`~.facet_walk.FacetWalk`).  Near ``lam2`` (where the pruning's walks go: ``t`` is
the incumbent ``lam1`` candidate) ``m`` is small: on random systems 28 at N = 500, 58 at
N = 1000.  The one ``O(N^3)`` product ``G E`` is shared by every ``t``.

:class:`BarycentricWalk` has the interface the pruning uses of a ``FacetWalk`` (``walk_to``,
``covered``, ``s``, ``T``, ``pivots``, ``broken``).  Nothing is concluded in these coordinates:
each vertex that would cover new rows is mapped back to ``v`` and checked there from scratch
(:func:`~.facet_walk.certified_rows`, a batch of vertices with one product ``G X``); only the
rows tight at a checked vertex are ``covered``.  A walk that ends at an optimum with the target
slack (``False``: face empty) hands over to a ``FacetWalk`` at the same vertex
(:meth:`BarycentricWalk.facet_walk`) for the descent to the target's ``lam_high``; so does a
walk that breaks down (too many tight rows, a singular working basis, a failed check).
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
    """The ``t``-independent part: ``E``, ``y`` and the rows ``K = -G_J E`` (module docstring).

    Built once per pruning from the ``lam2`` optimum; ``None`` from :meth:`of` when the basis
    is not ``N + 1`` distinct constraint rows with a well-conditioned ``Q``.
    """

    def __init__(self, G, c, m, B, x2, lam2, E, y):
        self.G, self.c, self.m = G, c, m
        self.R, self.n = G.shape
        self.B = np.asarray(B, int)
        self.x2, self.lam2, self.E, self.y = x2, float(lam2), E, y
        self.J = np.flatnonzero(np.isin(np.arange(self.R), self.B, invert=True))
        self.loc = np.full(self.R, -1)  # row -> position in J (or -1)
        self.loc[self.J] = np.arange(len(self.J))
        self.GJx = G[self.J] @ x2
        self.K = -(G[self.J] @ E)  # (|J|, N + 1): the one O(N^3) product
        self.KF = np.asfortranarray(self.K)

    @classmethod
    def of(cls, G, c, m, basis, x2, lam2):
        """From the unit-norm rows ``G v <= c + lam m`` and an optimal ``lam2`` basis (rows of
        ``[G, -m]``; indices ``>= R`` are other rows)."""
        R, n = G.shape
        B = np.asarray(basis, int)
        if len(B) != n + 1 or np.any(B >= R) or len(np.unique(B)) != n + 1 or not lam2 > 0:
            return None
        Q = np.hstack([G[B], -m[B, None]])
        with warnings.catch_warnings():
            warnings.simplefilter("error", sla.LinAlgWarning)  # ill-conditioned: refused
            try:
                Qi = sla.inv(Q, check_finite=False)
            except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning):
                return None
        if not np.all(np.isfinite(Qi)):
            return None
        return cls(G, c, m, B, x2, lam2, Qi[:n], Qi[n])

    def r(self, t):
        """``r_j(t) = b_j(t) - G_j x*`` for the rows ``J`` outside the basis."""
        return self.c[self.J] + t * self.m[self.J] - self.GJx


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
        self.rJ = frame.r(self.t)
        self.tau = frame.lam2 - self.t
        T = np.asarray(T, int)
        inT = np.zeros(self.R, bool)
        inT[T] = True
        self.P = [int(a) for a in np.flatnonzero(~inT[frame.B])]  # basis rows left slack
        self.Tl = [int(frame.loc[j]) for j in T if frame.loc[j] >= 0]
        if (len(self.P) != len(self.Tl) + 1 or len(self.Tl) > self.limit
                or not self._factor()):
            return
        if (self.sP.min() < -1e-9 * max(1.0, float(np.abs(self.sP).max()))
                or self.sJ.min() < -1e-9 * (1.0 + float(np.abs(self.rJ).max()))):
            return
        self._buffer.append(self._vertex())
        self.ok = self._flush()

    # ------------------------------------------------------------------ state
    def _factor(self) -> bool:
        """Factor the working basis ``[K_{T,P}; y_P]`` and recompute the vertex from it."""
        P, Tl = self.P, self.Tl
        M = np.empty((len(P), len(P)))
        M[:-1] = self.f.K[np.ix_(Tl, P)]
        M[-1] = self.f.y[P]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(M, check_finite=False)
        d = np.abs(np.diag(lu[0]))
        if not d.min() > 1e-12 * d.max():
            return False
        self.lu = lu
        self.sP = sla.lu_solve(lu, np.r_[self.rJ[Tl], self.tau], check_finite=False)
        self.sJ = self.rJ - self.f.KF[:, P] @ self.sP  # slacks of the rows J
        self.sJ[Tl] = 0.0
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
        """Slacks of all ``R`` rows at the current vertex (for choosing targets)."""
        out = np.zeros(self.R)
        out[self.f.J] = self.sJ
        out[self.f.B[self.P]] = self.sP
        return out

    def _vertex(self):
        """The current vertex in ``v``: ``x* - E_P sigma_P``."""
        return self.f.x2 - self.f.E[:, self.P] @ self.sP

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
        if kl < 0:  # a row of B: tight wherever sigma_k = 0
            return None
        g = self.f.K[kl]  # max G_k v = max K_k . sigma (+ const)
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
        if res is False and self.sJ[kl] > 1e-9 * (1.0 + abs(self.b[k])):
            return False
        return None

    def _pivot(self, g, kl):
        """One primal simplex pivot for ``max g . sigma``: ``"optimal"``, ``"moved"`` or
        ``None`` (singular basis, unbounded, too many tight rows)."""
        P, Tl = self.P, self.Tl
        z = sla.lu_solve(self.lu, g[P], trans=1, check_finite=False)
        u, w = z[:-1], z[-1]
        # reduced costs per unit of slack (Dantzig pricing as in the walk in v)
        rc = g - w * self.f.y
        if Tl:
            rc -= u @ self.f.K[Tl]
        rc[P] = 0.0
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
                rhs[:-1] = self.f.K[Tl, e]
            rhs[-1] = self.f.y[e]
            dP = -sla.lu_solve(self.lu, rhs, check_finite=False)
            dS = -(self.f.KF[:, P] @ dP + self.f.KF[:, e])
        else:
            rhs[j] = -1.0
            dP = sla.lu_solve(self.lu, rhs, check_finite=False)
            dS = -(self.f.KF[:, P] @ dP)
        dS[Tl] = 0.0
        if e < 0:
            dS[Tl[j]] = 1.0
        # ratio test: the basic coordinates and the slacks of the rows not tight
        tl = PIV_TOL * max(1.0, float(np.abs(dP).max()))
        ts = PIV_TOL * max(1.0, float(np.abs(dS).max()))
        bl = dP < -tl
        bs = dS < -ts
        rl = np.where(bl, np.maximum(self.sP, 0.0) / np.where(bl, -dP, 1.0), np.inf)
        rs = np.where(bs, np.maximum(self.sJ, 0.0) / np.where(bs, -dS, 1.0), np.inf)
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
            leave = ("coord", il) if cl[il] >= cs[is_] else ("row", is_)
        # update the sets (|P| = |T| + 1 is kept by each of the four cases); on copies, kept
        # only if the new basis factors (else the walker stays at its last vertex, broken)
        P, Tl = list(P), list(Tl)
        if leave[0] == "coord":
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
