"""``lam1`` without every ``lam_high``: incumbent pruning of the "max lam" LPs (issue 14).

``lam1 = min_k lam_high_k`` once every ``lam_low_k = 0`` (:func:`~.outcome.lam1_from_intervals`);
only the minimum is needed, not every ``lam_high_k``.  With an incumbent ``t >= lam1`` (the
smallest exact ``lam_high`` found so far), a constraint whose face is non-empty at ``t`` has
``lam_high_k >= t >= lam1`` (its interval is convex and contains 0) and needs no LP.  The
driver :func:`lam_high_pruned`:

1. solves exactly (dual simplex from the ``lam2`` basis) the rows tight at the ``lam2``
   optimum (``lam_high = lam2``, free) and :data:`INIT_LPS` candidate rows; the smallest value
   is the first incumbent ``t``.  Candidates (:data:`SCREEN_MIN_N` nodes or more; below, the
   :data:`UNSCREENED_LPS` rows of largest slack at the ``lam2`` optimum): the best of a screen
   (:meth:`_Pruner.screen`) among the rows whose offset ``c_k + lam m_k`` falls
   slowest as ``lam`` grows (largest ``m_k`` of the unit-norm rows; ties: largest slack at the
   ``lam2`` optimum).  As ``lam`` grows the region shrinks by its rows moving in at the rates
   ``-m``; a row that moves in slowly is overtaken by the others and loses contact first.  On
   Kachanov networks this finds an incumbent near ``lam1`` (issue 14: at N = 2000 the rows of
   largest slack gave ``t`` within 3 % of ``lam2`` and walks of hundreds of pivots each);
2. walks over the vertices of ``H(t)`` (:class:`~.facet_walk.FacetWalk`, from the vertex of
   the incumbent's optimum), first towards the next :data:`PRIORITY` screened rows, then each
   time towards the not yet decided row of least slack; every
   certified vertex proves ``lam_high >= t`` for all its tight rows;
3. a row the walk cannot reach (face empty at ``t``, or undecided after :data:`WALK_CAP`
   pivots), or that the walks would decide for more pivots than the LPs
   (:class:`~.walk_budget.WalkBudget`), gets an exact LP, ``max lam`` with the row tight (with
   ``lam <= t`` in ``v``: dual simplex from the walk's vertex), in batches of :data:`BATCH`: a
   value below ``t`` is that row's exact ``lam_high`` and lowers the incumbent (the walk
   restarts from that optimum's vertex, the rows still running are decided again there); a
   binding cap proves ``lam_high >= t``.  In the coordinates below the batch's LPs run side by
   side, a row proven below ``t`` by its dual bound first (:meth:`~.basis_lp.BasisLP.race`).
   An LP that fails while ``t`` stands is solved from the ``lam2`` basis, then by HiGHS.

Every optimum of step 1 and 3 also proves ``lam_high_j >= value`` for each row ``j`` tight at
it (checked by :func:`~.facet_walk.certified_rows`).  Result: per row either the exact
``lam_high`` or a proven lower bound that is ``>=`` the final ``lam1``; ``lam1`` = the smallest
exact value.  Anything that cannot be certified falls back to exact LPs for the rows left.

Where the ``lam2`` basis gives coordinates (:class:`~.barycentric_walk.SimplexFrame`: the
slacks of its ``N + 1`` rows; almost always), the walks and the LPs work in them: the walk is a
:class:`~.barycentric_walk.BarycentricWalk` and the LPs of steps 1 and 3 and of the screen are
solved exactly, uncapped, by :class:`~.basis_lp.BasisLP` (a dual simplex from the ``lam2``
vertex with an ``m x m`` working basis, ``m`` the rows tight outside the ``lam2`` basis: a pivot
costs ``O(N m)`` instead of ``O(N^2)``).  Everything they find is checked in ``v`` as above; the
walk in ``v`` and the LPs in ``v`` described above are the fallback (issue 14, N = 2000: the
random system of ``test_n2000_finishes`` 549 s -> 43 s, a 2000-crack network 720 s -> 80 s).
"""

from __future__ import annotations

import numpy as np

from . import dense_lp
from .barycentric_walk import UNCHECKED, BarycentricWalk, SimplexFrame
from .basis_lp import BasisLP
from .facet_walk import FacetWalk, certified_rows, vertex_rows
from .outcome import value
from .single_simplex import single_dual_simplex
from .walk_budget import WalkBudget

#: Exact "max lam" LPs solved first, and further screened candidates the walk visits first.
INIT_LPS, PRIORITY = 1, 8
#: Rows (of largest ``m``) whose "max lam" LPs are screened by a few dual simplex pivots
#: (problems of at least :data:`SCREEN_MIN_N` nodes; smaller ones solve the
#: :data:`UNSCREENED_LPS` rows of largest slack at the ``lam2`` optimum exactly, as before).
SCREEN_ROWS = 400
SCREEN_MIN_N = 300
UNSCREENED_LPS = 16
#: Screening rounds (successive halving): ``(rows, pivots)``: the best ``rows`` of the
#: previous round (the first: :data:`SCREEN_ROWS`) get ``pivots`` dual simplex pivots each.
SCREEN_ROUNDS = ((None, 10), (48, 40), (12, 160))
#: At most this many LPs of at least :data:`SINGLE_MIN_N` unknowns are solved one by one with
#: an explicit basis inverse instead of the batched dual simplex (N = 2000, seed 2: 8 capped
#: LPs of ~4000 pivots 327 s one by one, 122 s pooled; a lone long LP 14 s against 18 s).
SINGLE_MAX = 1
SINGLE_MIN_N = 200
#: Smallest problem whose screen runs its partial LPs in the coordinates of the lam2 basis
#: (:mod:`.basis_lp`); below, the batch in ``v`` is cheaper (N = 500: 0.63 s against 0.2 s).
SCREEN_BASIS_MIN_N = 800
#: Pivots a walk may spend on one target before it goes to an exact LP, and go on with (where
#: :class:`~.walk_budget.WalkBudget` says it is worth it) when these did not decide.
WALK_CAP, LONG_WALK_CAP = 60, 400
#: Undecided rows solved together by capped LPs.
BATCH = 8
#: Breakpoints a parametric descent may pass before its row goes to an exact LP.
DESCENT_CAP = 400


class _Pruner:
    def __init__(self, cs, A, b, tab, main, book, frame=False):
        n = cs.n_nodes
        self.n, self.R = n, 2 * n
        self.A, self.b, self.tab, self.book = A, b, tab, book
        gn = np.linalg.norm(cs.G, axis=1)
        gn[gn == 0] = 1.0
        self.G, self.c, self.m = cs.G / gn[:, None], cs.c / gn, cs.m / gn
        self.lam2 = float(main.x[-1])
        self.hi = np.full(self.R, np.nan)
        self.exact = np.zeros(self.R, bool)
        self.lower = np.full(self.R, -np.inf)
        self.best = None  # (value, row, answer) of the smallest exact lam_high with a basis
        self.take(None, main, lam2_answer=True)
        self.main, self.cs = main, cs
        self.frame = frame  # the coordinates of the lam2 basis (False: built on first use)
        self.lp = None  # its exact LPs (BasisLP)
        self.budget = WalkBudget()  # walk or LP (issue 26)

    # ---------------------------------------------------------------- answers
    def take(self, k, ans, lam2_answer=False, cap=None):
        """Record the answer of "max lam with row ``k`` tight" (``cap``: with ``lam <= cap``)."""
        if not lam2_answer:
            self.book.record(ans)
        if ans.status != "optimal":
            return False
        lam = float(ans.x[-1])
        T = np.asarray(ans.basis, int)
        tight = certified_rows(self.tab.A, self.tab.b, ans.x[: self.n + 1])
        if tight is None or (k is not None and not tight[k]):
            return False
        if cap is not None and (self.R + 1) in T:  # binding cap: a point of face k at lam = cap
            cover = tight[: self.R]
            self.lower[cover] = np.maximum(self.lower[cover], cap)
            return True
        val = min(lam, self.lam2)
        if lam2_answer:
            rows = T[T < self.R]
            self.hi[rows], self.exact[rows] = self.lam2, True
        else:
            self.hi[k], self.exact[k] = val, True
        cover = tight[: self.R]
        self.lower[cover] = np.maximum(self.lower[cover], val)
        if (self.R not in T and len(T[T < self.R]) == self.n + 1
                and (self.best is None or val < self.best[0])):
            self.best = (val, k if k is not None else int(T[0]), ans)
        return True

    def basis_lps(self, rows, below=None):
        """Exact "max lam" LPs in the coordinates of the lam2 basis (:mod:`.basis_lp`); returns
        the rows it could not decide (no frame, or an answer not certified) or did not finish.
        ``below``: the LPs run side by side (:meth:`.BasisLP.race`) and stop at the first answer
        below ``below`` (the rows left are decided again at that incumbent)."""
        if not self.simplex():
            return [int(k) for k in rows]
        self.lp = self.lp or BasisLP(self.frame, self.tab)
        rows = [int(k) for k in rows if not self.exact[k]]
        answers = ((k, self.lp.solve(k)) for k in rows) if below is None else self.lp.race(rows, below)
        left, done = [], set()
        for k, ans in answers:
            done.add(k)
            if ans is None or not self.take(k, ans):
                left.append(k)
            if below is not None and self.best[0] < below:
                break
        return left + [k for k in rows if k not in done]

    def exact_lps(self, rows):
        """Exact "max lam" LPs: in the coordinates of the lam2 basis, else from the lam2 basis
        in ``v`` (HiGHS if not certified)."""
        rows = self.basis_lps(rows)
        failed = []

        def on_answer(g, ans):
            if not self.take(rows[g], ans):
                failed.append(rows[g])

        _solve(self.tab, rows, on_answer, skip=lambda g: self.exact[rows[g]])
        for k in failed:
            self.hi[k], self.exact[k] = min(value(self.book.highs("max", (k,))), self.lam2), True

    def screen(self, order):
        """The candidates of ``order`` re-ranked by upper bounds of their ``lam_high``.

        A dual simplex "max lam with row ``k`` tight" stopped after a few pivots sits at a
        dual-feasible basis: its ``lam`` bounds ``lam_high_k`` from above and falls towards it
        with every pivot.  The first ``max(SCREEN_ROWS, R / 10)`` rows of ``order`` get a few
        pivots each, the best of them more and so on (:data:`SCREEN_ROUNDS`); the order of
        the last bounds ranks the candidates (only a heuristic: nothing is concluded from a
        bound).  An LP that finishes within its pivots is an exact answer and is recorded as
        such.  On the Kachanov networks this puts the row of ``lam1`` first (N = 2000: rank 10
        of 400 after 10 pivots, 2 of 48 after 40 more, 0 of 12 after 160 more; N = 1000:
        rank 3 after 10 pivots), where the order of ``m`` alone has it at rank 176 / 131.
        """
        rows = [int(k) for k in order[:max(SCREEN_ROWS, self.R // 10, INIT_LPS)]]
        if not SCREEN_ROWS or len(rows) <= INIT_LPS:
            return order
        for keep, piv in SCREEN_ROUNDS:
            rows = rows if keep is None else rows[:max(keep, INIT_LPS + PRIORITY)]
            ub = np.full(len(rows), np.inf)

            def on_answer(g, ans, rows=rows, ub=ub):
                k = rows[g]
                if ans.status == "optimal":
                    self.take(k, ans)
                elif ans.status == "failed" and ans.x is not None:
                    self.book.iters += ans.iterations  # pivots counted, not a solved LP
                    ub[g] = float(ans.x[-1])  # a dual-feasible basis: an upper bound
                if self.exact[k]:
                    ub[g] = np.inf  # known exactly (and an incumbent if smallest): done

            def skip(g, rows=rows):
                return self.exact[rows[g]]

            if self.n >= SCREEN_BASIS_MIN_N and self.simplex():
                self.lp = self.lp or BasisLP(self.frame, self.tab)
                for g, k in enumerate(rows):
                    if not skip(g):
                        on_answer(g, self.lp.solve(k, max_pivots=piv))
            else:
                dense_lp.batch_dual_simplex(self.tab, [(k,) for k in rows], max_pivots=piv,
                                            on_answer=on_answer, skip=skip)
            rows = [rows[g] for g in np.argsort(ub, kind="stable")]
        rows = rows[:INIT_LPS + PRIORITY]
        rest = set(rows)
        return rows + [k for k in order if k not in rest]

    def slack0(self):
        """Slacks of the (unit-norm) rows at the ``lam2`` optimum."""
        return self.tab.b[: self.R] - self.tab.A[: self.R] @ self.best[2].x

    # ---------------------------------------------------------------- walk
    def open(self, todo):
        val, k, ans = self.best
        if ans is None:
            return None
        T = vertex_rows(self.G, self.m, ans.basis[ans.basis < self.R], keep=k)
        if T is None:
            return None
        walk = self.fast_walk(val, T) or FacetWalk(self.G, self.c + val * self.m, T)
        return walk if walk.ok else None

    def simplex(self):
        """The coordinates of the lam2 basis (:class:`.SimplexFrame`, built on first use), or
        ``None`` where they do not apply."""
        if self.frame is False:
            self.frame = SimplexFrame.from_lp(self.cs, self.main)
        return self.frame

    def fast_walk(self, t, T):
        """A walk in the coordinates of the lam2 basis from the vertex ``T`` of ``H(t)``
        (:mod:`.barycentric_walk`), or ``None`` where they do not apply."""
        if not self.simplex() or not 0.0 <= t < self.lam2:
            return None
        walk = BarycentricWalk(self.frame, t, T)
        return walk if walk.ok else None

    def walk_to(self, walk, k, cap, kind, t):
        """``walk.walk_to(k, cap)``, counted in the budget (``kind``: "short" or "long")."""
        before, pivots = self.decided(walk, t), walk.pivots
        res = walk.walk_to(k, cap)
        self.budget.walked(kind, walk.pivots - pivots, self.decided(walk, t) - before)
        return res

    def decided(self, walk, t):
        """Rows decided at ``t``: exact, proven ``lam_high >= t``, or reached by ``walk``."""
        done = self.exact | (self.lower >= t) | walk.covered
        unchecked = getattr(walk, "unchecked", None)
        return int(np.count_nonzero(done if unchecked is None else done | unchecked))

    def lp_pivots(self):
        """LP pivots so far (those of LPs a race dropped unfinished too)."""
        return self.book.iters + (self.lp.dropped if self.lp else 0)

    def settle(self, walk, t):
        """Check the vertices of ``walk`` not yet checked (a :class:`.BarycentricWalk`'s
        batch) and credit the rows tight at its checked vertices (``lam_high >= t``)."""
        if walk is None:
            return
        if getattr(walk, "unchecked", None) is not None and walk.unchecked.any():
            walk.flush()
        self.lower[walk.covered] = np.maximum(self.lower[walk.covered], t)

    def to_v(self, walk, t):
        """The walk in ``v`` at the vertex of ``walk`` (:meth:`.BarycentricWalk.facet_walk`),
        after crediting what ``walk`` found."""
        self.settle(walk, t)
        return walk.facet_walk()

    def capped_lps(self, walk, t, rows):
        """``max lam`` with row ``k`` tight: exactly in the coordinates of the lam2 basis where
        it applies, else with ``lam <= t`` from the walk's vertex.  A value below ``t`` ends
        the batch: the rows left are decided again at the new, lower incumbent (most by walks
        there), not by long LPs at ``t``."""
        rows = self.basis_lps(rows, below=t)
        if self.best[0] < t:
            return rows
        if not rows:
            return []
        A = np.vstack([self.A, np.r_[np.zeros(self.n), 1.0][None, :]])
        b = np.r_[self.b, t]
        e = np.r_[np.zeros(self.n), 1.0]
        tab = dense_lp.Tableau(A, b, e, np.r_[walk.T, self.R + 1])
        if tab.singular or not tab.dual_feasible:
            return list(rows)
        failed = []

        def on_answer(g, ans):
            if not self.take(rows[g], ans, cap=t):
                failed.append(rows[g])

        # a value below t ends the batch: the rows still running are decided again at the
        # new, lower incumbent (most of them by the walk there), not by long LPs at t
        _solve(tab, rows, on_answer, skip=lambda g: self.lower[rows[g]] >= t,
               max_pivots=2 * self.n + 50, stop=lambda: self.best[0] < t)
        return failed

    def run(self):
        if SCREEN_ROWS and self.n >= SCREEN_MIN_N:
            order = [k for k in np.lexsort((-self.slack0(), -self.m)) if not self.exact[k]]
            order = self.screen(order)
            self.exact_lps(order[:INIT_LPS])
            priority = order[INIT_LPS:INIT_LPS + PRIORITY]
        else:  # small problems: short LPs, the screen costs more than it saves
            order = [k for k in np.argsort(-self.slack0(), kind="stable") if not self.exact[k]]
            self.exact_lps(order[:UNSCREENED_LPS])
            priority = []
        walk, t = None, np.inf
        while True:
            if walk is None or self.best[0] < t:
                t = self.best[0]
                todo = ~self.exact & (self.lower < t)
                if not todo.any():
                    return
                if t <= 0.0:
                    self.lower[todo] = np.maximum(self.lower[todo], 0.0)
                    return
                walk = self.open(todo)
                if walk is None:
                    self.exact_lps(np.flatnonzero(todo))
                    return
            pending = []
            while True:
                self.lower[walk.covered] = np.maximum(self.lower[walk.covered], t)
                todo = ~self.exact & (self.lower < t)
                todo[pending] = False
                unchecked = getattr(walk, "unchecked", None)  # (a BarycentricWalk's)
                if unchecked is not None:
                    todo &= ~unchecked  # reached, checked with the next batch
                left = np.flatnonzero(todo)
                if not left.size and unchecked is not None and unchecked.any():
                    walk.flush()  # the rows of a vertex that fails come back to todo
                    continue
                if left.size and len(pending) < BATCH:
                    first = [j for j in priority if todo[j]]
                    k = first[0] if first else int(left[np.argmin(walk.s[left])])
                    if not self.budget.worth("short"):  # the LPs decide rows for less
                        pending.append(k)
                        continue
                    res = self.walk_to(walk, k, WALK_CAP, "short", t)
                    if res is None and walk.broken and isinstance(walk, BarycentricWalk):
                        walk = self.to_v(walk, t)  # too many tight rows: go on in v
                        if walk is None:
                            pending.append(k)
                            break
                        res = self.walk_to(walk, k, WALK_CAP, "short", t)
                    if res is None and not walk.broken and self.budget.worth("long"):
                        res = self.walk_to(walk, k, LONG_WALK_CAP, "long", t)  # on to a decision
                    if res is UNCHECKED:
                        continue
                    if res is False and isinstance(walk, BarycentricWalk):
                        walk = self.to_v(walk, t)  # the descent walks in v
                        if walk is None:
                            pending.append(k)
                            break
                    if res is False:  # face k empty at t: follow lam down to lam_high_k
                        lam = walk.descend(k, self.c, self.m, t, DESCENT_CAP)
                        if lam is not None:
                            walk = self.fast_walk(lam, walk.T) or walk
                            self.hi[k], self.exact[k] = min(lam, self.lam2), True
                            self.best = (lam, k, None)
                            t = lam  # the walk is at a vertex of H(lam) with k tight
                            pending = []
                            continue
                        walk = None  # the walker's state is no longer usable
                        pending.append(k)
                        break
                    if res is not True:
                        pending.append(k)
                    continue
                break
            self.settle(walk, t)
            if not pending:
                if walk is not None:
                    return
                continue
            if walk is None:  # reopen at the incumbent's optimum, then decide the rest
                self.exact_lps(pending)
                continue
            before, pivots = self.decided(walk, t), self.lp_pivots()
            failed = self.capped_lps(walk, t, pending)
            if self.best[0] >= t:
                self.exact_lps(failed)
            self.budget.solved(self.lp_pivots() - pivots, self.decided(walk, t) - before)
            if self.best[0] < t:  # lower incumbent: the failed rows are decided at it
                walk = None


def _solve(tab, rows, on_answer, skip, max_pivots=None, stop=None):
    """"max lam" with row ``k`` tight for each ``k`` of ``rows`` from ``tab``'s basis: a few
    LPs on a large problem (long paths, issue 14) one by one with an explicit basis inverse
    (:func:`~.single_simplex.single_dual_simplex`), else the batched dual simplex."""
    if len(rows) <= SINGLE_MAX and tab.n >= SINGLE_MIN_N:
        for g, k in enumerate(rows):
            if not skip(g):
                on_answer(g, single_dual_simplex(tab, (k,), max_pivots=max_pivots))
        return
    dense_lp.batch_dual_simplex(tab, [(k,) for k in rows], max_pivots=max_pivots,
                                on_answer=on_answer, skip=skip, stop=stop)


def lam_high_pruned(cs, A, b, tab, main, book, frame=False):
    """Per row: the exact ``lam_high`` or a proven lower bound ``>= lam1`` (module docstring).

    Returns ``(lam_high, exact)`` (nondimensional; ``exact[k]`` says which).  Requires every
    ``lam_low`` to be 0 (the caller checks first).  ``frame``: the coordinates of the lam2 basis
    (:meth:`.SimplexFrame.from_lp`) if already built, ``None`` if they do not apply.
    """
    p = _Pruner(cs, A, b, tab, main, book, frame)
    p.run()
    book.log.walked(int(np.count_nonzero(~p.exact)))  # decided by walks and shared vertices
    hi = np.where(p.exact, p.hi, p.lower)
    return np.minimum(hi, p.lam2), p.exact.copy()
