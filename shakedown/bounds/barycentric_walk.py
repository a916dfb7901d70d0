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
the vertices that cover every row ever tight (the one before each pivot that loosens a tight
row not yet covered, and the one where a walk ends: :meth:`BarycentricWalk._hold`) are mapped
back to ``v`` and checked there from scratch (:func:`~.facet_walk.certified_rows`, a batch of
vertices with one product ``G X``); only the rows tight at a checked vertex are ``covered``.
On problems of :data:`.basis_lp.KERNEL_MIN_N` nodes or more the pivots run compiled
(:mod:`.walk_kernel`, the same rules).  A walk that ends at an optimum with the target
slack (``False``: face empty) hands over to a ``FacetWalk`` at the same vertex
(:meth:`BarycentricWalk.facet_walk`) for the descent to the target's ``lam_high``; so does a
walk that breaks down (too many tight rows, a singular working basis, a failed check).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from . import basis_lp
from . import inverse_updates as iu
from . import walk_kernel as wk
from .facet_walk import FacetWalk, batch_check

#: Most rows outside the ``lam2`` basis that may be tight at a vertex of a walk (beyond it the
#: walk stops, ``broken``, and the pruning goes on in ``v`` from the same vertex).  No limit by
#: default: a pivot costs ``O(N m + m^2)``, at most that of the walk in ``v``.
MAX_TIGHT = 1 << 30
#: Vertices checked together (one product ``G X``).
CHECK_BATCH = 16
#: What :meth:`BarycentricWalk.walk_to` returns when the target is tight at a vertex that is
#: not checked yet (it is checked with the next batch, :meth:`BarycentricWalk.flush`).
UNCHECKED = "unchecked"
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
        self.ET = np.ascontiguousarray(E.T)  # rows: the columns of E (gathered by P)
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

    @classmethod
    def from_lp(cls, cs, main):
        """From a (nondimensional) constraint set and the certified ``lam2`` answer of the LP
        in ``(v, lam)`` (rows ``[G, -m]``, then ``-lam <= 0``); rows scaled to unit ``|G_i|``."""
        gn = np.linalg.norm(cs.G, axis=1)
        gn[gn == 0] = 1.0
        n = cs.n_nodes
        return cls.of(cs.G / gn[:, None], cs.c / gn, cs.m / gn, main.basis, main.x[:n],
                      float(main.x[-1]))

    def r(self, t):
        """``r_j(t) = b_j(t) - G_j x*`` for the rows ``J`` outside the basis."""
        return self.c[self.J] + t * self.m[self.J] - self.GJx


class BarycentricWalk:
    """Primal simplex walker on ``H(t)`` in the coordinates of the ``lam2`` basis (module
    docstring).

    The working basis ``M`` (rows: ``y_P`` and ``K_{T,P}``; columns: the basic coordinates
    ``P``) is kept as an explicit inverse, updated in ``O(m^2)`` per pivot (a column or a row
    replaced, or both added, or both removed) and recomputed from scratch when
    :func:`.inverse_updates.refactor_due` says; the columns ``K_{J,P}`` and rows ``K_{T,J}``
    the pivots multiply with are kept contiguous.

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
        self.unchecked = np.zeros(self.R, bool)  # tight at a vertex not yet checked
        self.limit = min(MAX_TIGHT, self.n)
        self.pivots = 0
        self.broken = False
        self.ok = False
        self._buffer = []
        self._held = False  # the current vertex is in the batch or checked
        if not (0.0 <= self.t < frame.lam2):
            return
        self.rJ = frame.r(self.t)
        self.tau = frame.lam2 - self.t
        T = np.asarray(T, int)
        inT = np.zeros(self.R, bool)
        inT[T] = True
        self.P = [int(a) for a in np.flatnonzero(~inT[frame.B])]  # basis rows left slack
        self.Tl = [int(frame.loc[j]) for j in T if frame.loc[j] >= 0]
        if len(self.P) != len(self.Tl) + 1 or len(self.Tl) > self.limit:
            return
        nJ, cap = len(frame.J), self.limit + 2
        self.KP = np.empty((nJ, cap), order="F")  # K[:, P] in its first |P| columns
        self.KT = np.empty((cap, frame.K.shape[1]))  # K[Tl, :] in its first |Tl| rows
        if not self._refactor():
            return
        if (self.sP.min() < -1e-9 * max(1.0, float(np.abs(self.sP).max()))
                or self.sJ.min() < -1e-9 * (1.0 + float(np.abs(self.rJ).max()))):
            return
        self._buffer.append(self._vertex())
        self.ok = self._held = self._flush()

    # ------------------------------------------------------------------ state
    def _refactor(self) -> bool:
        """The working basis from scratch: its inverse, the kept columns and rows, the vertex."""
        P, Tl, K = self.P, self.Tl, self.f.K
        m = len(P)
        M = np.empty((m, m))
        M[0] = self.f.y[P]
        self.KT[: m - 1] = K[Tl]
        self.kt32_rows = -1  # (the kernel's single-precision copy of K_T is stale)
        M[1:] = self.KT[: m - 1][:, P]  # (a gather from K[Tl] rows, not K[ix_]: ~7x cheaper)
        W = iu.inverse(M)
        if W is None:
            return False
        self.W = W
        self.KP[:, :m] = self.f.KF[:, P]
        self.since = 0
        self._vertex_from_basis()
        return True

    def _vertex_from_basis(self):
        m = len(self.P)
        self.sP = self.W @ np.r_[self.tau, self.rJ[self.Tl]]
        self.sJ = self.rJ - self.KP[:, :m] @ self.sP  # slacks of the rows J
        self.sJ[self.Tl] = 0.0

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
        """The coordinates ``sigma`` of the current vertex (length ``N + 1``, zero outside
        ``P``); :meth:`_flush` maps a batch of them to ``v``."""
        sigma = np.zeros(self.n + 1)
        sigma[self.P] = self.sP
        return sigma

    def _flush(self) -> bool:
        """Check the buffered vertices in ``v`` (one product with ``E^T`` maps them, ``v = x* -
        E sigma``, one product ``G X`` checks them); their tight rows join ``covered``.
        If the last one fails, the working basis is recomputed from scratch (the updates
        drift: issue 26, m ~ 800, a vertex off by more than the check's tolerance after ~110
        updates) and the current vertex checked once more; ``False`` if that fails too (the
        walk then stops as broken; an earlier vertex that fails only adds nothing)."""
        S, self._buffer = self._buffer, []
        self.unchecked[:] = False
        if not S:
            return True
        S = np.vstack(S)
        nz = np.flatnonzero(S.any(axis=0))  # the coordinates basic at some vertex of the batch
        V = self.f.x2 - S[:, nz] @ self.f.ET[nz]  # (batch, N): one GEMM over those rows of E^T
        _, tights = batch_check(self.G, self.b, list(V))
        for tight in tights:
            if tight is not None:
                self.covered |= tight
        if tights[-1] is not None:
            return True
        if self.since == 0 or not self._refactor():
            return False
        _, (tight,) = batch_check(self.G, self.b, [self.f.x2 - self._vertex() @ self.f.ET])
        if tight is None:
            return False
        self.covered |= tight
        return True

    # ------------------------------------------------------------------ walking
    def walk_to(self, k: int, cap: int):
        """Walk towards row ``k`` (``max G_k v``): ``True`` (``k`` tight at a checked vertex),
        :data:`UNCHECKED` (tight at the current vertex, checked with the next batch: the caller
        reads :attr:`covered` after :meth:`flush`), ``False`` (optimum with ``k`` slack: face
        empty), ``None`` (undecided: ``cap`` pivots, a failed check, or too many tight rows)."""
        if self.broken:
            return None
        if self.covered[k]:
            return True
        kl = int(self.f.loc[k])
        if kl < 0:  # a row of B: tight wherever sigma_k = 0
            return None
        g = self.f.K[kl]  # max G_k v = max K_k . sigma (+ const)
        res = None
        if self.n >= basis_lp.KERNEL_MIN_N and wk.HAVE_KERNEL:  # the same pivots, compiled
            end = wk.walk(self, g, kl, cap, CHECK_BATCH, PIV_TOL)
            self.broken = end is None
            res = False if end == "optimal" else None
        else:
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
        if not self.broken and not self._hold():  # the walk ends here: its vertex joins the batch
            self.broken = True
        if res is None and not self.broken and kl in self.Tl and 0 < len(self._buffer) < CHECK_BATCH:
            return UNCHECKED  # k tight at the current vertex: checked with the next batch
        if not self.flush():
            return None
        if self.covered[k]:
            return True
        if res is False and self.sJ[kl] > 1e-9 * (1.0 + abs(self.b[k])):
            return False
        return None

    def flush(self) -> bool:
        """Check the vertices not yet checked (:attr:`unchecked`: their tight rows); ``False``
        (and the walk ``broken``) if the current one fails."""
        if self._flush():
            return True
        self.broken = True
        return False

    def _pivot(self, g, kl):
        """One primal simplex pivot for ``max g . sigma``: ``"optimal"``, ``"moved"`` or
        ``None`` (unbounded, a vanishing pivot element, too many tight rows)."""
        P, Tl, W = self.P, self.Tl, self.W
        m = len(P)
        z = W.T @ g[P]
        w, u = z[0], z[1:]
        # reduced costs per unit of slack (Dantzig pricing as in the walk in v)
        rc = g - w * self.f.y
        if Tl:
            rc -= u @ self.KT[: m - 1]
        rc[P] = 0.0
        scale = max(float(np.abs(rc).max()), float(np.abs(u).max(initial=0.0)), 1e-300)
        e = int(np.argmax(rc))
        best = rc[e]
        j = int(np.argmin(u)) if len(u) else -1
        if j >= 0 and -u[j] > best:  # loosen tight row Tl[j]
            best, e = -u[j], -1
        if not best > PIV_TOL * scale:
            return "optimal"
        if e >= 0:
            col = np.r_[self.f.y[e], self.KT[: m - 1, e]]
            dP = -(W @ col)
            dS = -(self.KP[:, :m] @ dP + self.f.KF[:, e])
        else:
            dP = -W[:, 1 + j]
            dS = -(self.KP[:, :m] @ dP)
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
            kind, q = "row", kl
        else:
            cl = np.where(rl <= near, -dP, -np.inf)
            cs = np.where(rs <= near, -dS, -np.inf)
            il, is_ = int(np.argmax(cl)), int(np.argmax(cs))
            kind, q = ("coord", il) if cl[il] >= cs[is_] else ("row", is_)
        if kind == "row" and len(Tl) + (e >= 0) > self.limit:
            return None
        if e < 0 and not self._held:  # row Tl[j] is about to loosen: hold the vertex
            if not self._hold([self.f.J[Tl[j]]]):
                return None
            if self._held and not self._buffer:  # checked now (the state may be recomputed)
                return self._pivot(g, kl)
        self._update(kind, q, e, j, dP, dS, float(tmin))
        self._held = False
        self.pivots += 1
        self.since += 1
        if iu.refactor_due(self.since, len(self.P)) and not self._refactor():
            return None
        return "moved"

    def _hold(self, rows=None) -> bool:
        """The current vertex joins the batch to check (checked when full; ``False`` if that
        fails) unless it is there or each of ``rows`` (default: its tight rows) is covered or in
        the batch.  A row leaves the tight rows only by a pivot whose entering variable is its
        slack: holding the vertex before such pivots and where a walk ends checks every row
        ever tight (issue 26, a dense system of 2000 nodes: 23119 -> ~1300 vertices)."""
        if self._held:
            return True
        rows = self.f.J[self.Tl] if rows is None else rows
        if (self.covered[rows] | self.unchecked[rows]).all():
            return True
        self._buffer.append(self._vertex())
        self.unchecked[self.f.J[self.Tl]] = True
        self._held = True
        return len(self._buffer) < CHECK_BATCH or self._flush()

    def _update(self, kind, q, e, j, dP, dS, step):
        """Move to the adjacent vertex: coordinate ``e`` (or the slack of tight row ``Tl[j]``,
        ``e < 0``) enters; coordinate ``P[q]`` (``kind="coord"``) or the slack of row ``q`` of
        ``J`` (``kind="row"``) leaves.  ``O(m^2)`` on the inverse ``W`` of the working basis;
        ``-dP`` is ``W`` times the entering column, ``dS`` its effect on the slacks, ``step``
        the entering variable's new value (the vertex is updated, not recomputed)."""
        P, Tl, W, K = self.P, self.Tl, self.W, self.f.K
        m = len(P)
        self.kt32_rows = -1  # (K_T may change: the kernel's copy is refreshed)
        self.sP = self.sP + step * dP
        self.sJ += step * dS
        if kind == "row":
            self.sJ[q] = 0.0
        else:
            self.sP[q] = 0.0
        if kind == "coord" and e >= 0:  # column q of M replaced by column e
            self.W = iu.replace_column(W, q, -dP)
            P[q] = e
            self.sP[q] = step
            self.KP[:, q] = self.f.KF[:, e]
        elif kind == "coord":  # column q and row 1 + j of M removed (the last ones move in)
            self.W = iu.remove(W, q, 1 + j)
            P[q], Tl[j] = P[m - 1], Tl[m - 2]
            self.sP[q] = self.sP[m - 1]
            self.sP = self.sP[:-1]
            self.KP[:, q] = self.KP[:, m - 1]
            self.KT[j] = self.KT[m - 2]
            P.pop()
            Tl.pop()
        elif e >= 0:  # column e and row q added; schur = K[q, e] - K[q, P] W col_e = -dS[q]
            self.W = iu.border(W, -dP, K[q, P] @ W, -dS[q])
            P.append(e)
            Tl.append(q)
            self.KP[:, m] = self.f.KF[:, e]
            self.KT[m - 1] = K[q]
            self.sP = np.r_[self.sP, step]
        else:  # row 1 + j of M replaced by row q of K; 1 + delta . W e_r = dS[q]
            self.W = iu.replace_row(W, 1 + j, (K[q, P] - self.KT[j, P]) @ W, dS[q])
            Tl[j] = q
            self.KT[j] = K[q]

    def facet_walk(self):
        """A :class:`~.facet_walk.FacetWalk` at the current vertex (``None`` if not usable)."""
        fw = FacetWalk(self.G, self.b, self.T)
        return fw if fw.ok else None
