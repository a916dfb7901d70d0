"""The fast LP path (``solver="auto"``): dense interior point + lock-step dual simplex.

LP ``max e.x, A x <= b`` in ``x = (v, lam)``: rows ``[G, -m] <= c`` and ``-lam <= 0``, on a
nondimensional constraint set.  The ``lam2`` LP is solved by :func:`~.dense_lp.solve_max`; the
activity-interval LPs (``max`` / ``min lam`` with row ``k`` tight) and the adjacency LPs
(``min lam`` with ``I_j`` and ``II_j`` tight) by the batched dual simplex, warm-started from the
``lam2`` basis (``max``) or from a vertex of ``H(0)`` (``min``).

Answers are shared between LPs when one optimal basis solves several of them (all exact, with
the same certificate): a basis optimal for "row ``k`` tight" with multipliers ``y >= 0`` on every
basic row except ``k`` is optimal for "row ``j`` tight" for every basic row ``j`` when also
``y_k >= 0``; and a vertex with ``lam = 0`` proves ``lam_low = 0`` for every basic row (``lam >= 0``
is a constraint).  Any answer that is not certified is re-solved by HiGHS.
"""

from __future__ import annotations

import numpy as np

from . import dense_lp
from .barycentric_walk import SimplexFrame
from .certificates import CERT_TOL
from .constraints import ConstraintSet
from .highs_path import RESIDUAL_NAMES, HighsModel
from .lp import LPAnswer
from .no_separation import separation_lp
from .outcome import PathOutcome, lam1_from_intervals, separation_outcome, value
from .provenance import StageLog
from .pruning import lam_high_pruned
from .result import LAM_RTOL

#: Why the ``min lam`` LPs go to HiGHS when they do.
NO_MIN_START = "no dual-feasible start for min lam"


class _Book:
    """Counts LPs and iterations, keeps the worst residuals, builds HiGHS only if needed, and
    records per stage which path answered (:class:`~.provenance.StageLog`)."""

    def __init__(self, cs, log=None):
        self.cs = cs
        self.worst = dict.fromkeys(RESIDUAL_NAMES, 0.0)
        self.lps = 0
        self.iters = 0
        self._highs = None
        self.log = log if log is not None else StageLog()

    def record(self, ans):
        self.lps += 1
        self.iters += ans.iterations
        if ans.status == "optimal":
            for k, r in zip(RESIDUAL_NAMES, ans.residuals, strict=True):
                self.worst[k] = max(self.worst[k], r)
        if ans.status in ("optimal", "infeasible"):
            self.log.dense()

    def model(self):
        """The HiGHS model (built on first use)."""
        if self._highs is None:
            self._highs = HighsModel(self.cs)
            self._highs.log = self.log
        return self._highs

    def highs(self, sense, tight=(), separation=False, reason="dense answer not certified"):
        """One LP by HiGHS in place of the dense path (a fallback, counted with ``reason``)."""
        model = self.model()
        ans = model.run(sense, tight=tight, separation=separation, reason=reason)
        self.lps += 1
        self.iters += ans.iterations
        for k in RESIDUAL_NAMES:
            self.worst[k] = max(self.worst[k], model.worst[k])
        return ans


def _family(tab, groups, sense, book, lam_row):
    """Values of ``max`` (``sense="max"``) or ``min lam`` with the rows of each group tight.

    ``tab`` is a dual-feasible start for the objective (``+lam`` or ``-lam``).  Groups are
    started in order; an optimal basis that also solves groups not yet started (module
    docstring) answers them without a solve.  ``nan`` = infeasible (never active).
    """
    out = np.full(len(groups), np.nan)
    done = np.zeros(len(groups), bool)
    by_row = _by_row(groups, tab.R)
    failed = []

    def on_answer(g, ans):
        book.record(ans)
        done[g] = True
        if ans.status == "optimal":
            out[g] = ans.x[-1]
            _share(ans, g, groups, by_row, out, done, sense, lam_row)
        elif ans.status == "infeasible":
            out[g] = np.nan
        else:
            failed.append(g)

    dense_lp.batch_dual_simplex(tab, groups, on_answer=on_answer, skip=lambda g: done[g])
    for g in failed:  # not certified: the reference solver decides
        out[g] = value(book.highs(sense, groups[g]))
    return out


def _by_row(groups, R):
    """``{row: [groups holding it]}`` for :func:`_share`; when every group is one distinct row
    (the interval LPs), also ``"single"``: an array ``row -> group`` (``-1``: none) of length
    ``R``, with which :func:`_share` applies its rule without a Python loop over the basis
    (N = 2000: 2036 answers x 2001 basic rows took 40 % of the ``lam_low`` stage)."""
    by_row = {}
    for g, rows in enumerate(groups):
        for r in rows:
            by_row.setdefault(int(r), []).append(g)
    if groups and all(len(rows) == 1 for rows in groups) and len(by_row) == len(groups):
        single = np.full(R, -1)
        for r, (g,) in by_row.items():
            single[r] = g
        by_row["single"] = single
    return by_row


def _share(ans, g, groups, by_row, out, done, sense, lam_row):
    """Give the answer of group ``g`` to every not yet solved group it provably solves."""
    T = ans.basis
    yT = ans.y[T]
    tol = CERT_TOL * max(float(np.abs(yT).max(initial=0.0)), np.finfo(float).tiny)
    at_zero = sense == "min" and lam_row in T  # the vertex has lam = 0 exactly
    single = by_row.get("single")
    if single is not None:  # every group one row (the interval LPs): the same rule, vectorised
        neg = T[yT < -tol]
        if not at_zero and len(neg) > 1:
            return
        h = single[T]
        h = h[h >= 0]
        h = h[~done[h]]
        if not at_zero and len(neg) == 1:  # only the group of the one negative multiplier
            h = h[single[neg[0]] == h]
        out[h] = 0.0 if at_zero else ans.x[-1]
        done[h] = True
        return
    neg = set(T[yT < -tol].tolist())
    basic = set(T.tolist())
    for r in T:
        for h in by_row.get(int(r), ()):
            if done[h]:
                continue
            rows = set(groups[h])
            if rows <= basic and (at_zero or neg <= rows):
                out[h] = 0.0 if at_zero else ans.x[-1]
                done[h] = True


def solve_dense(cs: ConstraintSet, intervals: bool, adjacency: bool,
                separation: bool, log: StageLog | None = None) -> PathOutcome | None:
    """Dense path; ``None`` when the ``lam2`` LP has no optimum (unbounded or infeasible) or
    its optimal basis cannot be certified in the dense coordinates: the caller then uses
    :func:`~.highs_path.solve_highs`.

    An LP that the dense path cannot certify is re-solved by HiGHS, that LP alone (issue 26):
    for the ``lam2`` LP from the best basis at hand, and its optimal basis comes back here, so
    the intervals, walks and pruning go on in the coordinates of the ``lam2`` basis.  ``log``
    (:class:`~.provenance.StageLog`) records the path of each stage."""
    n = cs.n_nodes
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, 0.0]
    e = np.r_[np.zeros(n), 1.0]
    book = _Book(cs, log)
    book.log.start("lam2")
    why = {}
    main, tab = dense_lp.solve_max(A, b, e, why=why)
    if main is None:
        main, tab = _lam2_by_highs(A, b, e, book, why)
        if main is None:
            return None
    else:
        book.record(main)
    lam2 = float(main.x[-1])
    out = PathOutcome(lam1=np.nan, lam2=lam2, status="bounded", messages=[],
                      lam_low=np.full(2 * n, np.nan), lam_high=np.full(2 * n, np.nan),
                      v_at_lam2=main.x[:n].copy(), certificate=main.y[: 2 * n].copy())
    lamrow = 2 * n
    if intervals or adjacency:
        book.log.start("lam_low")
    tab0 = _min_start(A, b, e, tab, lamrow, book) if (intervals or adjacency) else None
    frame = _Frame(cs, main)
    if intervals:
        _intervals(cs, A, b, e, tab, tab0, main, book, out, exact_all=intervals == "all",
                   frame=frame)
    if adjacency:
        book.log.start("adjacency")
        pairs = [(j, n + j) for j in range(n)]
        if tab0 is not None:
            adj = _family(tab0, pairs, "min", book, lamrow)
        else:
            adj = np.array([value(book.highs("min", t, reason=NO_MIN_START)) for t in pairs])
        adj = np.where(np.isnan(adj), np.inf, np.maximum(adj, 0.0))
        out.lam_adj = np.inf
        if np.isfinite(adj).any():
            out.adj_node = int(np.argmin(adj))
            out.lam_adj = float(adj[out.adj_node])
    if separation:
        book.log.start("separation")
        v2 = out.v_at_lam2
        sep = cs.sep_G @ v2 - cs.sep_c - lam2 * cs.sep_m
        scale = np.abs(cs.sep_G).max(initial=0.0) * np.abs(v2).max(initial=0.0) + np.abs(cs.sep_c)
        if np.all(sep <= 1e-9 * np.maximum(scale, 1e-300)):
            out.lam_sep = lam2  # the lam2 optimum already keeps every node in compression
        else:
            out.lam_sep, out.sep_nodes = separation_outcome(
                _separation(cs, frame, book), lam2, n)
    book.log.stop()
    out.stages = book.log.records()
    out.residuals, out.n_lps, out.iterations = book.worst, book.lps, book.iters
    return out


def _lam2_by_highs(A, b, e, book, why):
    """The ``lam2`` LP by HiGHS when the dense solve was not certified (``why``: its reason
    and best basis, see :func:`~.dense_lp.solve_max`), started from that basis; HiGHS's optimal
    basis is then certified here as a dense tableau, so everything after it runs on the dense
    path as usual.  ``(None, None)``: no optimum (unbounded or infeasible: the HiGHS path
    reports which) or a basis the dense coordinates cannot certify."""
    model = book.model()
    if why.get("basis") is not None:
        model.start_from(why["basis"])
    ans = book.highs("max", reason=why.get("reason", "not certified"))
    if ans.status != "optimal":
        value(ans)  # SolverError unless unbounded or infeasible (the HiGHS path says which)
        return None, None
    book.log.handover = "HiGHS's optimal lam2 basis not certified in the dense coordinates"
    T = model.tight_basis()
    tab = dense_lp.Tableau(A, b, e, T) if T is not None else None
    if tab is None or tab.singular:
        return None, None
    if not tab.dual_feasible:  # (multipliers of HiGHS's tolerance, not ours)
        main, tab = dense_lp.finish_from(A, b, e, tab)
    else:
        main = dense_lp.batch_dual_simplex(tab, [()])[0]  # certify (no pivot at an optimum)
        if main.iterations:
            tab = dense_lp.Tableau(A, b, e, main.basis, like=tab)
    if main is None or main.status != "optimal" or tab.singular:
        return None, None
    book.log.handover = None
    return main, tab


class _Frame:
    """The coordinates of the ``lam2`` basis (:class:`.SimplexFrame`), built on first use and
    shared by the pruning and the no-separation LP; ``get()`` is ``None`` where they do not
    apply."""

    def __init__(self, cs, main):
        self.cs, self.main, self.frame = cs, main, False

    def get(self):
        if self.frame is False:
            self.frame = SimplexFrame.from_lp(self.cs, self.main)
        return self.frame


def _separation(cs, frame, book):
    """The no-separation LP: by the dual simplex in the coordinates of the ``lam2`` basis
    (:func:`.separation_lp`) when its answer is certified, else by HiGHS."""
    fr = frame.get()
    if fr is not None:
        ans, _ = separation_lp(fr, cs)
        if ans is not None and ans.status == "optimal" and max(ans.residuals) <= CERT_TOL:
            book.record(ans)
            R = len(cs.c)
            return LPAnswer("optimal", float(ans.x[-1]), ans.x, ans.y[: R + cs.n_nodes],
                            np.zeros(len(ans.x)), *ans.residuals, ans.iterations)
    return book.highs("max", separation=True,
                      reason="no-separation LP not certified in the lam2 basis coordinates")


def _intervals(cs, A, b, e, tab, tab0, main, book, out, exact_all, frame):
    """Activity intervals and ``lam1``.  ``exact_all``: every ``lam_high`` exactly (one LP per
    row not shared); else ``lam_low`` first and, when every ``lam_low`` is 0, only what ``lam1``
    needs (:mod:`.pruning`: exact ``lam_high`` for some rows, proven lower bounds elsewhere)."""
    n = cs.n_nodes
    lamrow = 2 * n
    lam2 = out.lam2
    hi = out.lam_high
    if not exact_all:
        rows = list(range(2 * n))
        lo = _lows(tab0, rows, book, lamrow)
        out.lam_low[:] = lo
        tol = LAM_RTOL * max(1.0, lam2)  # as lam1_from_intervals reads "active at 0"
        if np.all(lo <= tol):  # (False for nan: never active)
            book.log.start("lam_high")
            hi[:], out.hi_exact = lam_high_pruned(cs, A, b, tab, main, book, frame.get())
            out.lam1, out.limiting = lam1_from_intervals(
                cs.labels(), out.lam_low, np.where(out.hi_exact, hi, np.inf), lam2,
                out.messages)
            return
        # some constraint is not active at lam = 0 (lam1 = 0): every interval exactly
    book.log.start("lam_high")
    hi[main.basis[main.basis < lamrow]] = lam2  # tight at the lam2 optimum
    rest = [k for k in range(2 * n) if np.isnan(hi[k])]
    hi[rest] = _family(tab, [(k,) for k in rest], "max", book, lamrow)
    fin = np.isfinite(hi)
    hi[fin] = np.minimum(hi[fin], lam2)
    act = [k for k in range(2 * n) if np.isfinite(hi[k])]
    lo = np.full(2 * n, np.nan)
    book.log.start("lam_low")
    lo[act] = _lows(tab0, act, book, lamrow)
    out.lam_low[:] = lo
    out.hi_exact = np.ones(2 * n, bool)
    out.lam1, out.limiting = lam1_from_intervals(cs.labels(), out.lam_low, out.lam_high,
                                                 lam2, out.messages)


def _lows(tab0, rows, book, lamrow):
    """``lam_low`` of ``rows`` (``nan``: never active), ``-0.0`` read as 0."""
    if tab0 is not None:
        lo = _family(tab0, [(k,) for k in rows], "min", book, lamrow)
    else:
        lo = np.array([value(book.highs("min", (k,), reason=NO_MIN_START)) for k in rows])
    return np.where(np.isnan(lo), lo, np.maximum(lo, 0.0))


def _min_start(A, b, e, tab, lamrow, book):
    """A dual-feasible basis for ``min lam``: the ``lam2`` basis with the row ``lam >= 0``
    swapped in, cleaned up by one dual simplex solve; ``None`` if that fails."""
    T1 = tab.T0.copy()
    if lamrow not in T1:
        T1[int(np.argmax(np.abs(tab.columns([lamrow])[:, 0])))] = lamrow
    tab0 = dense_lp.Tableau(A, b, -e, T1, like=tab)
    if tab0.singular:
        return None
    start = dense_lp.batch_dual_simplex(tab0, [()])[0]
    book.record(start)
    if start.status != "optimal":
        return None
    if start.iterations:
        tab0 = tab0.rebased(start.basis)
    return None if tab0.singular else tab0
