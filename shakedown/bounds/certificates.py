"""Answers of the dense LP solvers and their optimality certificates.

Every dense answer ``max e.x s.t. A x <= b`` (some rows possibly required to hold with
equality) is checked by its own optimality conditions: primal feasibility, sign of the
multipliers, stationarity ``A^T y = e`` and complementary slackness, each relative to the row's
scale.  An answer whose worst residual exceeds :data:`CERT_TOL` is not trusted: the caller
re-solves it with HiGHS.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Feasibility tolerance, relative to the row scale ``|a_i| |x| + |b_i|`` (nondimensional LPs).
FEAS_TOL = 1e-9
#: Smallest pivot ``|alpha_r|`` accepted in the ratio test (rows are scaled to unit norm).
PIVOT_TOL = 1e-9
#: Largest certificate residual accepted without falling back to HiGHS.
CERT_TOL = 1e-7


@dataclass(frozen=True)
class DenseAnswer:
    """One dense LP answer ``max e.x s.t. A x <= b``.

    Attributes
    ----------
    status : str
        ``"optimal"``, ``"infeasible"`` (a Farkas ray was found), or ``"failed"`` (iteration
        cap, singular basis, or not certified: solve it with HiGHS instead).
    x : ndarray, shape (n,)
    y : ndarray, shape (R,)
        Multipliers, ``e = A^T y``, ``y >= 0`` except on equality rows.
    basis : ndarray, shape (n,)
        Row indices of the optimal basis.
    iterations : int
        Pivots (simplex) or Newton steps (interior point).
    residuals : tuple of 4 floats
        Primal, dual-sign, stationarity and complementarity residuals (scaled).
    """

    status: str
    x: np.ndarray
    y: np.ndarray
    basis: np.ndarray
    iterations: int
    residuals: tuple

    @property
    def objective_value(self):
        return self.x


def _scale_x(x):
    """``|x|`` for the row scales; 1 for ``x = 0`` (the LPs are nondimensional)."""
    s = np.abs(x).max(axis=-1, initial=0.0)
    return np.where(s > 0, s, 1.0)


def kkt_residuals(A, b, e, x, y, equal=(), rownorm=None):
    """Scaled residuals (primal, dual sign, stationarity, complementarity) of ``(x, y)``.

    ``equal`` lists rows that must hold with equality (their multiplier has any sign).  Row
    ``i`` is scaled by ``|a_i| |x| + |b_i|`` and the multipliers by ``|y|``, so the residuals do
    not change when ``A``, ``b`` or ``e`` are multiplied by positive factors.
    """
    if rownorm is None:
        rownorm = np.linalg.norm(A, axis=1)
    act = A @ x
    scale = np.maximum(rownorm * _scale_x(x) + np.abs(b), 1e-300)
    r = (act - b) / scale
    eq = np.zeros(len(b), bool)
    eq[list(equal)] = True
    primal = float(np.max(np.where(eq, np.abs(r), np.maximum(r, 0.0)), initial=0.0))
    ys = _scale_x(y)
    dual = float(np.max(np.where(eq, 0.0, np.maximum(-y, 0.0)), initial=0.0) / ys)
    en = max(float(np.abs(e).max(initial=0.0)), 1e-300)
    stat = float(np.abs(e - A.T @ y).max(initial=0.0) / max(ys * rownorm.max(), en))
    comp = float(np.max(np.abs(y) * np.abs(np.minimum(r, 0.0)), initial=0.0) / ys)
    return primal, dual, stat, comp


def batch_residuals(A, b, e, X, Y, eqmask):
    """:func:`kkt_residuals` for many ``(x, y)`` pairs (rows of ``X``, ``Y``); unit-norm rows."""
    act = X @ A.T
    scale = np.maximum(_scale_x(X)[:, None] + np.abs(b)[None, :], 1e-300)
    r = (act - b) / scale
    primal = np.where(eqmask, np.abs(r), np.maximum(r, 0.0)).max(axis=1)
    ys = _scale_x(Y)
    dual = np.where(eqmask, 0.0, np.maximum(-Y, 0.0)).max(axis=1) / ys
    en = max(float(np.abs(e).max(initial=0.0)), 1e-300)
    stat = np.abs(e[None, :] - Y @ A).max(axis=1) / np.maximum(ys, en)
    comp = (np.abs(Y) * np.abs(np.minimum(r, 0.0))).max(axis=1) / ys
    return np.stack([primal, dual, stat, comp], axis=1)
