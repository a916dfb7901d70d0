"""Second-order-cone programs of the cone engine, solved by Clarabel (MODEL.md s.8.3).

Variables ``x = (u (2N), lam, ph (N))`` in the units of :mod:`.data` (``ph = E u`` only for a
coupled system).  A *cut* ``(i, t)`` is node ``i``'s cone at time ``t``:

    ( b0_i + ph_i + lam b1_i(t),  a0_i + u_i + lam a1_i(t) )  in  SOC_3 .

:func:`solve_cuts` maximises ``lam`` over a finite set of cuts (a relaxation of the
semi-infinite problem: its value bounds ``lam2`` from above) and returns the primal answer and
the dual multipliers; :func:`dual_bound` recomputes the upper bound from the multipliers alone, by
weak duality made valid for inexact multipliers (:mod:`.dual`), and reports their residuals
(cone membership and stationarity); :func:`static_margin` finds
the state farthest inside every cone at ``lam = 0`` (the strictly safe anchor of the lower
bound).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ...model import citations
from ...model.errors import MissingDependencyError
from .dual import certified_bound

#: Largest nondimensional load factor of a relaxation; reaching it means "unbounded".
LAM_CAP = 1e6
#: Clarabel's tolerances (its defaults are 1e-8).
SOLVER_TOL = 1e-10


@dataclass(frozen=True)
class CutAnswer:
    """One relaxation solve.

    Attributes
    ----------
    status : str
        ``"optimal"``, ``"unbounded"`` (``lam`` reached :data:`LAM_CAP`), ``"infeasible"`` or
        Clarabel's status name.
    lam : float
    u : ndarray, shape (N, 2)
    z : ndarray, shape (M, 3)
        Multipliers of the cuts (each in ``SOC_3``).
    y_cap : float
        Multiplier of ``lam <= LAM_CAP``.
    iterations : int
    """

    status: str
    lam: float
    u: np.ndarray
    z: np.ndarray
    y_cap: float
    iterations: int


def _clarabel():
    try:
        import clarabel
    except ImportError as exc:  # pragma: no cover - a core dependency
        raise MissingDependencyError("the 3-D bounds need clarabel: pip install clarabel") from exc
    citations.register("goulart2024")
    return clarabel


def _settings(clarabel, tol=SOLVER_TOL):
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = tol
    s.tol_ktratio = 1e-8
    s.max_iter = 200
    s.presolve_enable = False  # keep every cut row, so the multipliers line up with the cuts
    return s


def cut_rows(data, nodes, times):
    """Sparse rows ``-M`` and offsets ``h`` of the cuts: ``h - M x`` in ``SOC_3`` per cut.

    Returns ``(rows, cols, vals, h)`` for ``3 M`` rows over ``x = (u, lam, ph)``.
    """
    n = data.n_nodes
    m = len(nodes)
    a1, b1 = data.periodic(times, nodes)
    r0 = 3 * np.arange(m)
    lam_col = 2 * n
    rows = [r0, r0 + 1, r0 + 2, r0 + 1, r0 + 2]
    cols = [np.full(m, lam_col), 2 * nodes, 2 * nodes + 1, np.full(m, lam_col), np.full(m, lam_col)]
    vals = [-b1, -np.ones(m), -np.ones(m), -a1[:, 0], -a1[:, 1]]
    if data.coupled:
        rows.append(r0)
        cols.append(2 * n + 1 + nodes)
        vals.append(-np.ones(m))
    h = np.column_stack([data.b0[nodes], data.a0[nodes]]).reshape(-1)
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), h


def _n_vars(data):
    return 3 * data.n_nodes + 1 if data.coupled else 2 * data.n_nodes + 1


def _assemble(data, nodes, times, extra_cols=0):
    """Constraint matrix and cones: [ph = E u], [lam >= 0, lam <= cap], cuts."""
    clarabel = _clarabel()
    n = data.n_nodes
    nv = _n_vars(data) + extra_cols
    blocks, h, cones = [], [], []
    if data.coupled:  # ph - E u = 0
        Z = sp.hstack([-sp.csr_matrix(data.E), sp.csr_matrix((n, 1)), sp.identity(n),
                       sp.csr_matrix((n, extra_cols))])
        blocks.append(Z)
        h.append(np.zeros(n))
        cones.append(clarabel.ZeroConeT(n))
    lam_rows = sp.csr_matrix(([-1.0, 1.0], ([0, 1], [2 * n, 2 * n])), shape=(2, nv))
    blocks.append(lam_rows)
    h.append(np.array([0.0, LAM_CAP]))
    cones.append(clarabel.NonnegativeConeT(2))
    r, c, v, hc = cut_rows(data, nodes, times)
    blocks.append(sp.csr_matrix((v, (r, c)), shape=(3 * len(nodes), nv)))
    h.append(hc)
    cones.extend([clarabel.SecondOrderConeT(3)] * len(nodes))
    return sp.vstack(blocks, format="csc"), np.concatenate(h), cones


def solve_cuts(data, nodes, times) -> CutAnswer:
    """``max lam`` over the cuts ``(nodes[m], times[m])`` (module docstring)."""
    clarabel = _clarabel()
    n = data.n_nodes
    nv = _n_vars(data)
    M, h, cones = _assemble(data, nodes, times)
    q = np.zeros(nv)
    q[2 * n] = -1.0
    P = sp.csc_matrix((nv, nv))
    sol = clarabel.DefaultSolver(P, q, M, h, cones, _settings(clarabel)).solve()
    status = str(sol.status).split(".")[-1]
    x, z = np.asarray(sol.x), np.asarray(sol.z)
    off = n if data.coupled else 0
    zc = z[off + 2:].reshape(-1, 3) if z.size else np.zeros((0, 3))
    if status in ("Solved", "AlmostSolved"):
        lam = float(x[2 * n])
        st = "unbounded" if lam >= 0.999 * LAM_CAP else "optimal"
        return CutAnswer(st, lam, x[: 2 * n].reshape(n, 2), zc, float(z[off + 1]),
                         int(sol.iterations))
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
        return CutAnswer("infeasible", np.nan, np.zeros((n, 2)), zc, 0.0, int(sol.iterations))
    return CutAnswer(status, np.nan, np.zeros((n, 2)), zc, 0.0, int(sol.iterations))


def dual_bound(data, nodes, times, z, y_cap=0.0):
    """Upper bound on ``lam2`` (nondimensional) proven by cut multipliers ``z`` (M, 3).

    Weak duality, valid whatever the multipliers (:func:`.dual.certified_bound`): ``z`` is
    moved into its cones, and the stationarity residual ``r`` of the ``u`` rows (``sum_{m at
    i} z_m12 + (E^T y)_i``, ``y_i = sum_{m at i} z_m0``) enters the bound through an a-priori
    bound on the state instead of being neglected.  Exact multipliers prove
    ``(h . z + cap y_cap) / D`` with ``D = y_cap - (lam-column of M^T z)``; inexact ones a
    slightly larger value, wrong ones a much larger one or ``inf``; never a value below
    ``lam2``.

    Returns
    -------
    bound : float
    residuals : dict
        Of the multipliers as given (their quality, not their validity):
        ``"cone"``: largest ``max(|z_12| - z_0, 0)`` and ``"stationarity"``: largest ``u``-row
        residual, both relative to ``max |z|`` (unit-free); ``"sign"``: ``max(-D, 0)``.
    """
    z = np.asarray(z, float).reshape(-1, 3)
    n = data.n_nodes
    nodes = np.asarray(nodes)
    a1, b1 = data.periodic(times, nodes)
    zs = max(float(np.abs(z).max(initial=0.0)), 1e-300)
    cone = float(np.max(np.linalg.norm(z[:, 1:], axis=1) - z[:, 0], initial=0.0)) / zs
    ru = np.zeros((n, 2))
    np.add.at(ru, nodes, z[:, 1:])
    if data.coupled:
        y = np.zeros(n)
        np.add.at(y, nodes, z[:, 0])
        ru = ru + (data.E.T @ y).reshape(n, 2)
    stat = float(np.abs(ru).max(initial=0.0)) / zs
    D = float(y_cap) - float(b1 @ z[:, 0] + np.einsum("mc,mc->", a1, z[:, 1:]))
    sign = max(-D, 0.0) / zs
    bound, _ = certified_bound(data, nodes, times, z, y_cap, cap=LAM_CAP)
    return float(bound), {"cone": cone, "stationarity": stat, "sign": sign}


def naive_bound(data, nodes, times, z, y_cap=0.0):
    """``(h . z + cap y_cap) / D``: the bound of *exact* multipliers, with the residuals
    ignored (the former rule; kept to show, in the tests, what it would accept)."""
    z = np.asarray(z, float).reshape(-1, 3)
    a1, b1 = data.periodic(times, np.asarray(nodes))
    D = float(y_cap) - float(b1 @ z[:, 0] + np.einsum("mc,mc->", a1, z[:, 1:]))
    h = np.column_stack([data.b0[nodes], data.a0[nodes]])
    num = float(np.einsum("mc,mc->", h, z)) + LAM_CAP * float(y_cap)
    return num / D if D > 0 else np.inf


def static_margin(data):
    """State farthest inside every cone at ``lam = 0``: ``max tau`` s.t. ``|a0_i + u_i| + tau <=
    b0_i + (E u)_i`` (``tau <= 1``).  Returns ``(u (N, 2), tau)``; ``tau`` recomputed exactly
    from ``u`` (``-inf`` when the solver fails)."""
    clarabel = _clarabel()
    n = data.n_nodes
    nodes = np.arange(n)
    nv = _n_vars(data) + 1  # tau last
    M, h, cones = _assemble(data, nodes, np.zeros(n), extra_cols=1)
    M = M.tolil()
    off = n if data.coupled else 0
    cut0 = off + 2
    for i in range(n):
        M[cut0 + 3 * i, nv - 1] = 1.0  # s0 = b0 + ph - tau
    # lam <= 0 (with lam >= 0: lam = 0) and tau <= 1 (the force scale: bounded)
    M = sp.vstack([M.tocsc(), sp.csr_matrix(([1.0, 1.0], ([0, 1], [2 * n, nv - 1])),
                                           shape=(2, nv))], format="csc")
    h = np.concatenate([h, [0.0, 1.0]])
    cones = cones + [clarabel.NonnegativeConeT(2)]
    q = np.zeros(nv)
    q[-1] = -1.0
    sol = clarabel.DefaultSolver(sp.csc_matrix((nv, nv)), q, M, h, cones,
                                 _settings(clarabel)).solve()
    x = np.asarray(sol.x)
    if x.size != nv or not np.all(np.isfinite(x)):
        return np.zeros((n, 2)), -np.inf
    u = x[: 2 * n].reshape(n, 2)
    tau = float(np.min(data.b0 + data.coupling(u) - np.linalg.norm(data.a0 + u, axis=1)))
    return u, tau
