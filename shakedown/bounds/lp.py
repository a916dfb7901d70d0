"""A reusable HiGHS linear program with verified answers.

One ``highspy.Highs`` model is built once; row bounds, column bounds, costs and the sense are
changed between solves so that the simplex method restarts from the previous optimal basis
(warm start).  Every answer carries its own optimality certificate: primal feasibility,
dual feasibility (signs), stationarity and complementary slackness, evaluated here from the
returned primal and dual values (not trusted from the solver's status alone).
"""

from __future__ import annotations

from dataclasses import dataclass

import highspy
import numpy as np
import scipy.sparse as sp

from ..model import citations

INF = highspy.kHighsInf

_BANNER_SHOWN = False


def quiet_highs() -> highspy.Highs:
    """A ``highspy.Highs`` model that prints nothing.

    HiGHS prints its banner ("Running HiGHS ...") to the C-level standard output when the first
    model of a process is constructed, before ``output_flag`` can be set; later models print
    nothing.  The first construction therefore runs with file descriptor 1 sent to the null
    device (C buffers flushed before it is restored), so the banner reaches neither a terminal,
    a notebook, nor the stdout of ``shakedown bounds``.
    """
    global _BANNER_SHOWN
    if not _BANNER_SHOWN:
        import ctypes
        import os
        import sys

        sys.stdout.flush()
        libc = ctypes.CDLL(None)
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                h = highspy.Highs()
                libc.fflush(None)
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        _BANNER_SHOWN = True
    else:
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    return h


@dataclass(frozen=True)
class LPAnswer:
    """One LP solve.

    Attributes
    ----------
    status : str
        ``"optimal"``, ``"infeasible"``, ``"unbounded"`` or the HiGHS status name.
    objective : float
        Optimal objective (``+-inf`` when unbounded, ``nan`` when infeasible).
    x : ndarray
        Primal column values.
    row_dual, col_dual : ndarray
        HiGHS duals; stationarity reads ``cost - A^T row_dual - col_dual = 0``.
    primal_residual, dual_residual, stationarity_residual, complementarity_residual : float
        Scaled certificate residuals (0 for an exact optimum); ``nan`` unless optimal.
    iterations : int
        Simplex iterations of this solve.
    """

    status: str
    objective: float
    x: np.ndarray
    row_dual: np.ndarray
    col_dual: np.ndarray
    primal_residual: float
    dual_residual: float
    stationarity_residual: float
    complementarity_residual: float
    iterations: int

    @property
    def max_residual(self) -> float:
        return float(
            max(
                self.primal_residual,
                self.dual_residual,
                self.stationarity_residual,
                self.complementarity_residual,
            )
        )


class ReusableLP:
    """``opt cost . x`` subject to ``row_lo <= M x <= row_hi``, ``col_lo <= x <= col_hi``.

    Parameters
    ----------
    M : array_like or sparse matrix, shape (m, n)
    row_lo, row_hi, col_lo, col_hi : array_like
        Bounds (``+-numpy.inf`` allowed).
    cost : array_like, shape (n,)
    time_limit : float, optional
        Seconds per solve.
    """

    def __init__(self, M, row_lo, row_hi, col_lo, col_hi, cost, *, time_limit: float = 600.0):
        M = sp.csc_matrix(M)
        self.M = M
        self.n_rows, self.n_cols = M.shape
        self.row_lo = np.asarray(row_lo, float).copy()
        self.row_hi = np.asarray(row_hi, float).copy()
        self.col_lo = np.asarray(col_lo, float).copy()
        self.col_hi = np.asarray(col_hi, float).copy()
        self.cost = np.asarray(cost, float).copy()
        self.sense = "max"
        self.n_solves = 0
        self.total_iterations = 0
        citations.register("huangfu2018")
        h = quiet_highs()
        h.setOptionValue("presolve", "off")  # keep the basis between solves
        h.setOptionValue("solver", "simplex")
        h.setOptionValue("time_limit", float(time_limit))
        lp = highspy.HighsLp()
        lp.num_col_ = self.n_cols
        lp.num_row_ = self.n_rows
        lp.col_cost_ = self.cost
        lp.col_lower_ = _h(self.col_lo)
        lp.col_upper_ = _h(self.col_hi)
        lp.row_lower_ = _h(self.row_lo)
        lp.row_upper_ = _h(self.row_hi)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = M.indptr.astype(np.int32)
        lp.a_matrix_.index_ = M.indices.astype(np.int32)
        lp.a_matrix_.value_ = M.data.astype(float)
        lp.sense_ = highspy.ObjSense.kMaximize
        h.passModel(lp)
        self._h = h
        self._row_scale = np.maximum(abs(M).max(axis=1).toarray().ravel(), 1e-300)

    # ------------------------------------------------------------------ modifications
    def set_row_bounds(self, i: int, lo: float, hi: float) -> None:
        self.row_lo[i], self.row_hi[i] = lo, hi
        self._h.changeRowBounds(int(i), _h1(lo), _h1(hi))

    def set_col_bounds(self, j: int, lo: float, hi: float) -> None:
        self.col_lo[j], self.col_hi[j] = lo, hi
        self._h.changeColBounds(int(j), _h1(lo), _h1(hi))

    def set_objective(self, cost, sense: str) -> None:
        cost = np.asarray(cost, float)
        changed = np.flatnonzero(cost != self.cost)
        for j in changed:
            self._h.changeColCost(int(j), float(cost[j]))
        self.cost = cost.copy()
        if sense != self.sense:
            self._h.changeObjectiveSense(
                highspy.ObjSense.kMaximize if sense == "max" else highspy.ObjSense.kMinimize
            )
            self.sense = sense

    # ------------------------------------------------------------------ solve
    def solve(self) -> LPAnswer:
        h = self._h
        h.run()
        self.n_solves += 1
        st = h.getModelStatus()
        info = h.getInfo()
        iters = int(max(info.simplex_iteration_count, 0))
        self.total_iterations += iters
        nan = float("nan")
        if st == highspy.HighsModelStatus.kOptimal:
            sol = h.getSolution()
            x = np.array(sol.col_value)
            y = np.array(sol.row_dual)
            z = np.array(sol.col_dual)
            res = self._residuals(x, y, z)
            return LPAnswer("optimal", float(self.cost @ x), x, y, z, *res, iters)
        if st in (
            highspy.HighsModelStatus.kUnbounded,
            highspy.HighsModelStatus.kUnboundedOrInfeasible,
        ):
            # an LP of this package always has a feasible point when it is called unbounded
            # or the caller checks feasibility separately
            name = "unbounded" if st == highspy.HighsModelStatus.kUnbounded else "unbounded_or_infeasible"
            obj = np.inf if self.sense == "max" else -np.inf
            e = np.zeros(0)
            return LPAnswer(name, obj, e, e, e, nan, nan, nan, nan, iters)
        if st == highspy.HighsModelStatus.kInfeasible:
            e = np.zeros(0)
            return LPAnswer("infeasible", nan, e, e, e, nan, nan, nan, nan, iters)
        e = np.zeros(0)
        return LPAnswer(h.modelStatusToString(st), nan, e, e, e, nan, nan, nan, nan, iters)

    def _residuals(self, x, y, z):
        """Scaled optimality residuals of (x, y, z) for the current bounds and objective."""
        Mx = self.M @ x
        xs = max(1.0, float(np.abs(x).max(initial=0.0)))
        rs = self._row_scale * xs + np.abs(_fin(self.row_hi)) + np.abs(_fin(self.row_lo))
        viol = np.maximum(Mx - self.row_hi, 0) + np.maximum(self.row_lo - Mx, 0)
        cviol = np.maximum(x - self.col_hi, 0) + np.maximum(self.col_lo - x, 0)
        primal = float(max((viol / np.maximum(rs, 1.0)).max(initial=0), cviol.max(initial=0) / xs))
        ys = max(1.0, float(np.abs(y).max(initial=0.0)), float(np.abs(self.cost).max(initial=0)))
        stat = self.cost - self.M.T @ y - z
        stationarity = float(np.abs(stat).max(initial=0) / ys)
        # dual signs: max => y >= 0 on an active upper bound, <= 0 on an active lower bound
        s = 1.0 if self.sense == "max" else -1.0
        dual = 0.0
        for val, lo, hi in ((y, self.row_lo, self.row_hi), (z, self.col_lo, self.col_hi)):
            free_up = ~np.isfinite(hi)
            free_lo = ~np.isfinite(lo)
            # a positive (max-sense) dual needs a finite upper bound, a negative one a lower bound
            bad = np.where(free_up, np.maximum(s * val, 0), 0) + np.where(
                free_lo, np.maximum(-s * val, 0), 0
            )
            dual = max(dual, float(bad.max(initial=0) / ys))
        # complementary slackness: y_i (Mx - hi) = 0 for y_i s > 0, y_i (Mx - lo) = 0 for y_i s < 0
        comp = 0.0
        for val, act, lo, hi, scale in (
            (y, Mx, self.row_lo, self.row_hi, np.maximum(rs, 1.0)),
            (z, x, self.col_lo, self.col_hi, np.full(x.shape, xs)),
        ):
            up = np.where(s * val > 0, np.abs(val) * np.abs(_fin(hi) - act) / scale, 0)
            dn = np.where(s * val < 0, np.abs(val) * np.abs(act - _fin(lo)) / scale, 0)
            comp = max(comp, float(np.maximum(up, dn).max(initial=0) / ys))
        return primal, dual, stationarity, comp


def _fin(a):
    return np.where(np.isfinite(a), a, 0.0)


def _h(a):
    a = np.asarray(a, float)
    return np.clip(a, -INF, INF)


def _h1(v):
    return float(min(max(v, -INF), INF))
