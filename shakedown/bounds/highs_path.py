"""The reference LP path: every LP of the bounds engine by HiGHS (one model, warm starts).

All LPs are ``max/min lam`` subject to ``G v - m lam <= c`` (optionally some rows tight, and the
no-separation rows), on a nondimensional constraint set (:class:`~.constraints.Scales`), so
HiGHS's absolute tolerances (1e-7) are relative to the problem's own scales.
"""

from __future__ import annotations

import time

import highspy
import numpy as np
import scipy.sparse as sp

from .constraints import ConstraintSet
from .highs_pruning import intervals_pruned, tight_rows
from .lp import LPAnswer, ReusableLP
from .outcome import PathOutcome, lam1_from_intervals, separation_outcome, value

RESIDUAL_NAMES = ("primal", "dual", "stationarity", "complementarity")
#: HiGHS statuses that answer an LP (besides "unbounded..."); any other is solved again cold.
DECIDED = ("optimal", "infeasible")

#: On a sparse model, an optimal simplex answer whose certificate residual exceeds this is
#: solved again by interior point + crossover.  HiGHS's tolerance is 1e-7 in its own scaling;
#: measured on the unscaled rows at N = 2000, four capped LPs of 939 came back at 3.5e-6 to
#: 5.5e-6 and a re-solve did not lower them (2.8e-6 to 4.5e-6) but cost 20-40 s: answers up
#: to 1e-5 are kept (reported in ``residuals``), larger ones re-solved.
RESOLVE_RESIDUAL = 1e-5


class HighsModel:
    """The LP model ``max/min lam`` s.t. ``G v - m lam <= c`` (+ optional separation rows)."""

    def __init__(self, cs: ConstraintSet):
        n = cs.n_nodes
        self.n = n
        self.R = len(cs.c)  # 2N in 2-D (rows I, II); any number of families in 3-D
        if sp.issparse(cs.G):  # a sparse system: the model is built without densifying
            rows = sp.bmat([[cs.G, -cs.m[:, None]], [cs.sep_G, -cs.sep_m[:, None]]],
                           format="csc")
        else:
            rows = np.vstack(
                [np.hstack([cs.G, -cs.m[:, None]]), np.hstack([cs.sep_G, -cs.sep_m[:, None]])]
            )
        self.c = cs.c
        self.sep_c = cs.sep_c
        row_lo = np.full(self.R + len(cs.sep_c), -np.inf)
        row_hi = np.concatenate([cs.c, np.full(len(cs.sep_c), np.inf)])  # separation rows off
        col_lo = np.concatenate([np.full(n, -np.inf), [0.0]])
        col_hi = np.full(n + 1, np.inf)
        cost = np.zeros(n + 1)
        cost[n] = 1.0
        self.lp = ReusableLP(rows, row_lo, row_hi, col_lo, col_hi, cost)
        self.worst = dict.fromkeys(RESIDUAL_NAMES, 0.0)
        # sparse: no dense answer stands behind these LPs, so a simplex answer whose own
        # certificate is loose is solved again by interior point + crossover
        self.resolve_above = RESOLVE_RESIDUAL if sp.issparse(rows) else np.inf
        self.resolved = 0
        self.log = None  # a provenance.StageLog: each run is counted in it
        self.reason = None  # why these LPs are not solved by the dense path (None: by choice)

    def tight_basis(self):
        """The last optimal basis as rows of the dense path's LP (:mod:`.dense_path`: rows
        ``0..2N-1`` the constraints, ``2N`` the row ``-lam <= 0``): the rows HiGHS holds at a
        bound, sorted; ``None`` when that is not ``N + 1`` rows (a free column non-basic)."""
        n = self.n
        bas = self.lp._h.getBasis()
        if not bas.valid:
            return None
        basic = highspy.HighsBasisStatus.kBasic
        T = [i for i, st in enumerate(bas.row_status[: 2 * n]) if st != basic]
        if bas.col_status[n] != basic:
            T.append(2 * n)
        if len(T) != n + 1 or any(st != basic for st in bas.col_status[:n]):
            return None
        return np.asarray(T, int)

    def start_from(self, T) -> bool:
        """Give HiGHS the start basis ``T`` (rows of the dense path's LP, see
        :meth:`tight_basis`, ``N + 1`` of them): those rows at their bound, every other row and
        every ``v`` column basic.  ``False`` if HiGHS refuses it (the solve then starts as
        before)."""
        n = self.n
        T = np.asarray(T, int)
        if len(T) != n + 1:
            return False
        st = highspy.HighsBasisStatus
        rows = [st.kBasic] * self.lp.n_rows
        for i in T[T < 2 * n]:
            rows[int(i)] = st.kUpper
        basis = highspy.HighsBasis()
        basis.col_status = [st.kBasic] * n + [st.kLower if 2 * n in T else st.kBasic]
        basis.row_status = rows
        basis.valid = True
        basis.alien = False
        return self.lp._h.setBasis(basis) == highspy.HighsStatus.kOk

    def run(self, sense: str, tight=(), separation: bool = False, cost=None,
            method: str = "simplex", reason: str | None = None) -> LPAnswer:
        """Optimise ``lam`` (or ``cost . (v, lam)``) with rows ``tight`` held tight.

        ``method="ipm"``: HiGHS's interior point with crossover (a basis for the next warm
        starts), for a cold start on a large sparse model.  ``reason``: why the dense path
        handed this LP over (recorded in ``log``; ``None``: no dense attempt)."""
        t0 = time.perf_counter()
        ans = self._run(sense, tight, separation, cost, method)
        if self.log is not None:
            self.log.highs(time.perf_counter() - t0, reason or self.reason)
        return ans

    def _run(self, sense, tight, separation, cost, method):
        lp = self.lp
        if method != "simplex":
            lp._h.setOptionValue("solver", method)
        if cost is None:
            cost = np.zeros(self.n + 1)
            cost[self.n] = 1.0
        lp.set_objective(cost, sense)
        for k in tight:
            lp.set_row_bounds(k, self.c[k], self.c[k])
        if separation:
            for j in range(len(self.sep_c)):
                lp.set_row_bounds(self.R + j, -np.inf, self.sep_c[j])
        ans = lp.solve()
        if ans.status not in DECIDED and not ans.status.startswith("unbounded") \
                and "limit" not in ans.status.lower():
            # HiGHS stopped undecided ("Unknown" after a warm start: test_auto_agrees_with_highs,
            # formerly read as infeasible): once more from scratch; still undecided, or a time
            # limit, and outcome.value raises SolverError
            lp._h.clearSolver()
            ans = lp.solve()
        if method == "simplex" and ans.status == "optimal" \
                and ans.max_residual > self.resolve_above:
            lp._h.setOptionValue("solver", "ipm")
            again = lp.solve()
            self.resolved += 1
            if again.status == "optimal" and again.max_residual < ans.max_residual:
                ans = again
            method = "ipm"  # (the solver option is set back below)
        if method != "simplex":
            lp._h.setOptionValue("solver", "simplex")
        for k in tight:
            lp.set_row_bounds(k, -np.inf, self.c[k])
        if separation:
            for j in range(len(self.sep_c)):
                lp.set_row_bounds(self.R + j, -np.inf, np.inf)
        if ans.status == "optimal":
            for key, val in zip(
                RESIDUAL_NAMES,
                (ans.primal_residual, ans.dual_residual, ans.stationarity_residual,
                 ans.complementarity_residual),
                strict=True,
            ):
                self.worst[key] = max(self.worst[key], val)
        return ans


def solve_highs(cs: ConstraintSet, has_periodic_part: bool, intervals, adjacency: bool,
                separation: bool, log=None, reason=None) -> PathOutcome:
    """Every LP by HiGHS (the reference path); ``cs`` nondimensional.

    On a dense constraint set (the reference path) every interval is computed exactly.  On a
    sparse one, ``intervals="lam1"`` computes the intervals ``lam1`` needs (family points,
    capped LPs sharing their tight rows, incumbent pruning: :mod:`.highs_pruning`); ``"all"`` /
    ``True``: every interval exactly.  ``log``: a :class:`~.provenance.StageLog` (stages and
    LP counts); ``reason``: why the dense path did not run (its LPs then count as fallbacks)."""
    n = cs.n_nodes
    R = len(cs.c)  # 2N in 2-D
    eng = HighsModel(cs)
    if log is None:
        from .provenance import StageLog

        log = StageLog()
    eng.log, eng.reason = log, reason
    log.start("lam2")
    scale_m = np.abs(cs.m).max(initial=0.0)
    messages = []

    sparse = sp.issparse(cs.G)
    # a large sparse model: interior point + crossover from cold (2.8x faster than the dual
    # simplex at N = 1000, and 30x smaller residuals), then simplex warm starts
    main = eng.run("max", method="ipm" if sparse else "simplex")
    lam2 = value(main)
    status = "bounded"
    v_at_lam2 = main.x[:n].copy() if main.status == "optimal" else np.zeros(0)
    certificate = main.row_dual[:R].copy() if main.status == "optimal" else np.zeros(0)
    if main.status.startswith("unbounded"):
        # distinguish "unbounded" from "infeasible" (HiGHS may report either way)
        feas = eng.run("min")
        lam2 = np.nan if feas.status == "infeasible" else np.inf
    if np.isnan(lam2):
        status = "infeasible"
        messages.append(
            "no safe slip state for any lam >= 0: the static load alone violates friction "
            "(gross slip) or the constraints are inconsistent"
        )
    elif np.isinf(lam2):
        if not has_periodic_part or scale_m == 0.0:
            status = "unbounded_no_periodic_part"
            messages.append("the load has no periodic part: a safe state exists for every lam")
        elif np.all(cs.m >= 0):
            status = "unbounded_periodic_never_excludes"
            messages.append("the periodic part never tightens a constraint (m >= 0)")
        else:
            status = "unbounded"
            messages.append("a safe state exists for every lam (the safe region moves with lam)")
    out = PathOutcome(lam1=np.nan, lam2=lam2, status=status, messages=messages,
                      lam_low=np.full(R, np.nan), lam_high=np.full(R, np.nan),
                      v_at_lam2=v_at_lam2, certificate=certificate)
    sep_answer = None
    if sparse and separation and status != "infeasible":  # next to the lam2 basis: cheap
        log.start("separation")
        sep_answer = eng.run("max", separation=True)
    pruned = None
    if intervals and status != "infeasible":
        log.start("lam_high")
    if intervals == "lam1" and sparse and status == "bounded" and main.status == "optimal":
        pruned = intervals_pruned(eng, cs, lam2, v_at_lam2)
    if pruned is not None:
        out.lam_low, out.lam_high, out.hi_exact = pruned
        out.lam1, out.limiting = lam1_from_intervals(
            cs.labels(), out.lam_low, np.where(out.hi_exact, out.lam_high, np.inf), lam2,
            messages)
    elif intervals and status != "infeasible":
        tight_at_end = np.zeros(R, bool)
        if main.status == "optimal":
            # constraints tight at the lam2 optimum are active up to lam2 (can't go higher)
            tight_at_end[tight_rows(cs, v_at_lam2, lam2)] = True
        for k in range(R):
            if tight_at_end[k]:
                out.lam_high[k] = lam2
            else:
                out.lam_high[k] = value(eng.run("max", tight=(k,)))
        log.start("lam_low")
        for k in range(R):
            if np.isnan(out.lam_high[k]):
                continue  # never active
            out.lam_low[k] = value(eng.run("min", tight=(k,)))
        out.hi_exact = np.ones(R, bool)
        out.lam1, out.limiting = lam1_from_intervals(cs.labels(), out.lam_low, out.lam_high, lam2,
                                                     messages)
    if adjacency and status != "infeasible":
        log.start("adjacency")
        out.lam_adj = np.inf
        for j, pair in enumerate(cs.adjacency_pairs()):  # 2-D: (I_j, II_j)
            a = value(eng.run("min", tight=tuple(int(k) for k in pair)))
            if np.isfinite(a) and a < out.lam_adj:
                out.lam_adj, out.adj_node = a, j
    if separation and status != "infeasible":
        if sep_answer is None:
            log.start("separation")
            sep_answer = eng.run("max", separation=True)
        out.lam_sep, out.sep_nodes = separation_outcome(sep_answer, lam2, n, rows=R)
    log.stop()
    out.stages = log.records()
    out.residuals = dict(eng.worst)
    out.n_lps = eng.lp.n_solves
    out.iterations = eng.lp.total_iterations
    return out
