"""Dense linear programs ``max e.x  s.t.  A x <= b`` (``x`` free) for the bounds engine.

Two solvers that exploit the small, dense structure of the shakedown LPs (``R = 2N + 1`` rows,
``n = N + 1`` columns, every entry non-zero):

* :func:`ipm` -- a Mehrotra predictor-corrector interior-point method on the normal equations
  ``A^T D A`` (BLAS-3, ``O(R n^2)`` per iteration) followed by a basis identification
  (the ``n`` rows with the largest multipliers), used for the master LPs at large ``N``;
* :func:`batch_dual_simplex` -- the dual simplex method in inequality form, run in lock-step on
  many LPs that share ``A``, ``b`` and a dual-feasible starting basis ``T0`` and differ by
  rows that must hold with equality (the activity-interval and adjacency LPs).  A basis is a
  set ``T`` of ``n`` rows with ``A_T`` non-singular, ``x = A_T^-1 b_T`` and multipliers
  ``y_T = A_T^-T e >= 0``.  A violated row enters, the ratio test ``y_r / alpha_r`` with
  ``alpha = A_T^-T a_p`` picks the row that leaves.  The inverse is kept in product form
  ``A_T^-1 = A_T0^-1 E_1 ... E_t`` (one eta vector per pivot), the tableau
  ``W = A_T0^-T A^T`` is formed once, and the row activities ``A x`` are updated with
  ``W^T u`` for all LPs of a round in one matrix product.  ``O(n R)`` per pivot and LP.

Every answer is checked by its own optimality conditions (:func:`kkt_residuals`): primal
feasibility, sign of the multipliers, stationarity ``A_T^T y = e`` and complementarity; a caller
falls back to HiGHS when an answer is not certified (status ``"failed"``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..model import citations

#: Feasibility tolerance, relative to the row scale ``|a_i| (1 + |x|) + |b_i|``.
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


def kkt_residuals(A, b, e, x, y, equal=(), rownorm=None):
    """Scaled residuals (primal, dual sign, stationarity, complementarity) of ``(x, y)``.

    ``equal`` lists rows that must hold with equality (their multiplier has any sign).
    """
    if rownorm is None:
        rownorm = np.linalg.norm(A, axis=1)
    act = A @ x
    scale = rownorm * max(1.0, float(np.abs(x).max(initial=0.0))) + np.abs(b)
    scale = np.maximum(scale, 1e-300)
    r = (act - b) / scale
    eq = np.zeros(len(b), bool)
    eq[list(equal)] = True
    primal = float(np.max(np.where(eq, np.abs(r), np.maximum(r, 0.0)), initial=0.0))
    ys = max(1.0, float(np.abs(y).max(initial=0.0)))
    dual = float(np.max(np.where(eq, 0.0, np.maximum(-y, 0.0)), initial=0.0) / ys)
    stat = float(np.abs(e - A.T @ y).max(initial=0.0) / max(ys * rownorm.max(), 1e-300))
    comp = float(np.max(np.abs(y) * np.abs(np.minimum(r, 0.0)), initial=0.0) / ys)
    return primal, dual, stat, comp


# ---------------------------------------------------------------------- interior point
def ipm(A, b, e, *, tol=1e-8, max_iter=60):  # noqa: C901
    """Mehrotra predictor-corrector for ``max e.x s.t. A x + s = b, s >= 0`` (dense).

    Returns ``(x, s, z, converged, iterations)``; ``z >= 0`` are the multipliers
    (``A^T z = e``).  Unbounded or infeasible LPs do not converge (``converged = False``).
    """
    R, n = A.shape
    x = np.zeros(n)
    s = np.maximum(b - A @ x, 1.0)
    z = np.ones(R)
    bn = 1.0 + np.abs(b).max(initial=0.0)
    en = 1.0 + np.abs(e).max(initial=0.0)
    for it in range(1, max_iter + 1):
        rp = A @ x + s - b
        rd = A.T @ z - e
        mu = float(s @ z) / R
        gap = abs(float(b @ z - e @ x)) / (1.0 + abs(float(e @ x)))
        if (np.abs(rp).max() / bn < tol and np.abs(rd).max() / en < tol and gap < tol):
            return x, s, z, True, it
        d = z / s
        # normal matrix A^T D A (upper triangle, symmetric rank-k update: half a GEMM)
        As = np.asfortranarray(A * np.sqrt(d)[:, None])
        M = sla.blas.dsyrk(1.0, As, trans=1)
        M[np.diag_indices(n)] += 1e-14 * M.diagonal().max()
        try:
            cf = sla.cho_factor(M, lower=False, check_finite=False)
        except np.linalg.LinAlgError:
            return x, s, z, False, it

        dx, ds, dz = _direction(A, cf, rd, rp, s, z, np.zeros(R))
        ap, ad = _step(s, ds), _step(z, dz)
        mu_aff = float((s + ap * ds) @ (z + ad * dz)) / R
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        dx2, ds2, dz2 = _direction(A, cf, rd, rp, s, z, sigma * mu - ds * dz)
        ap, ad = 0.99 * _step(s, ds2), 0.99 * _step(z, dz2)
        x = x + ap * dx2
        s = s + ap * ds2
        z = z + ad * dz2
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
            return x, s, z, False, it
        if np.abs(x).max(initial=0.0) > 1e15 or z.max() > 1e15:
            return x, s, z, False, it
    return x, s, z, False, max_iter


def _direction(A, cf, rd, rp, s, z, rc):
    """Newton direction with complementarity target ``s z -> rc`` (``S dz + Z ds = rc - s z``)."""
    rhs = -rd - A.T @ ((rc - s * z + z * rp) / s)
    dx = sla.cho_solve(cf, rhs, check_finite=False)
    ds = -rp - A @ dx
    dz = (rc - s * z - z * ds) / s
    return dx, ds, dz


def _step(v, dv):
    neg = dv < 0
    return min(1.0, float(np.min(-v[neg] / dv[neg], initial=np.inf)))


def identify_basis(A, z, s, n):
    """Guess the optimal basis: the ``n`` rows with the largest ``z / s`` (non-singular)."""
    order = np.argsort(-(z / np.maximum(s, 1e-300)))
    T = np.sort(order[:n])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(A[T], check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None
    d = np.abs(np.diag(lu[0]))
    if d.min() <= 1e-12 * d.max():
        return None
    return T


def complete_basis(A, z, s, e, n, max_missing=None):
    """A dual-feasible basis at a degenerate interior-point optimum.

    The strongly active rows ``C`` (the ``z / s`` values above the largest gap in their sorted
    sequence) carry the multipliers; when ``|C| < n`` the basis must be completed with
    ``k = n - |C|`` more rows whose multipliers are non-negative.  With ``Q`` an orthonormal
    basis of ``null(A_C)``, the completion multipliers ``y`` satisfy ``Q^T A_R^T y = Q^T e``:
    a ``k``-row LP ``min 1.y`` with ``y >= 0`` whose basic solution picks at most ``k`` rows
    (padded by the rows of smallest slack that keep the basis non-singular).  Returns the
    sorted basis, or ``None`` when no such completion is found.
    """
    from scipy.optimize import linprog

    r = z / np.maximum(s, 1e-300)
    order = np.argsort(-r)
    top = np.maximum(r[order[: n + 1]], 1e-300)
    lo = 1 if max_missing is None else max(1, n - max_missing)
    gaps = np.log(top[lo - 1 : n]) - np.log(top[lo : n + 1])
    m = lo + int(np.argmax(gaps))  # |C|: the cut with the largest relative drop
    C = np.sort(order[:m])
    k = n - m
    if k <= 0:
        return None
    Qf, _ = np.linalg.qr(A[C].T, mode="complete")
    Q = Qf[:, m:]
    if np.linalg.matrix_rank(A[C]) < m:
        return None
    rest = np.setdiff1d(np.arange(A.shape[0]), C)
    P = A[rest] @ Q  # projections of the candidate rows, (R - m, k)
    target = Q.T @ e
    # e in span(A_C) up to the interior point's accuracy: the completion rows carry (near) zero
    # multipliers; pick the k best-conditioned ones (column-pivoted QR of the projections)
    if np.abs(target).max() <= 1e-6 * (1.0 + np.abs(e).max()):
        _, _, piv = sla.qr(P.T, mode="economic", pivoting=True)
        chosen = rest[piv[:k]]
    else:
        citations.register("huangfu2018")  # scipy linprog(method="highs")
        res = linprog(np.ones(len(rest)), A_eq=P.T, b_eq=target, bounds=(0, None),
                      method="highs")
        if res.status != 0:
            return None
        nz = np.flatnonzero(res.x > 1e-12 * max(1.0, res.x.max()))
        chosen = rest[nz]
        if len(chosen) < k:  # pad with the best-conditioned remaining projections
            others = np.setdiff1d(np.arange(len(rest)), nz)
            _, _, piv = sla.qr(P[others].T, mode="economic", pivoting=True)
            picked = list(nz)
            for j in others[piv]:
                if len(picked) == k:
                    break
                if np.linalg.matrix_rank(P[picked + [j]]) == len(picked) + 1:
                    picked.append(int(j))
            chosen = rest[np.asarray(picked, dtype=int)]
    T = np.r_[C, chosen].astype(int)
    if len(np.unique(T)) != n:
        return None
    return np.sort(np.asarray(T, dtype=int))


# ---------------------------------------------------------------------- dual simplex
class Tableau:
    """The shared data of a family of LPs: rows ``A`` (unit-norm), ``b``, start basis ``T0``.

    Parameters
    ----------
    A : ndarray, shape (R, n)
    b : ndarray, shape (R,)
    e : ndarray, shape (n,)
        Objective (maximised).
    T0 : ndarray of int, shape (n,)
        Starting basis; ``A_T0^-T e >= 0`` up to rounding (dual feasible) is required.
    """

    def __init__(self, A, b, e, T0):
        self.rownorm = np.linalg.norm(A, axis=1)
        self.rownorm[self.rownorm == 0] = 1.0
        self.A = A / self.rownorm[:, None]
        self.b = b / self.rownorm
        self.e = np.asarray(e, float)
        self.T0 = np.asarray(T0, int)
        R, n = self.A.shape
        self.R, self.n = R, n
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(self.A[self.T0], check_finite=False)
        d = np.abs(np.diag(lu[0]))
        self.singular = bool(not d.min() > 1e-13 * d.max())
        if self.singular:
            self.y0 = np.full(n, -np.inf)
            return
        self.Binv = sla.lu_solve(lu, np.eye(n), check_finite=False)  # A_T0^-1
        self.y0 = self.Binv.T @ self.e
        self.W = self.Binv.T @ self.A.T  # (n, R): row i = coefficients in the basis rows
        self.x0 = self.Binv @ self.b[self.T0]
        self.act0 = self.A @ self.x0
        self.scale_x = 1.0 + np.abs(self.x0).max(initial=0.0)

    @property
    def dual_feasible(self) -> bool:
        return bool(self.y0.min(initial=0.0) >= -1e-9 * max(1.0, np.abs(self.y0).max()))


def batch_dual_simplex(tab: Tableau, equal_rows, *, max_pivots=None, chunk=None):
    """Solve ``max e.x s.t. A x <= b`` plus, for LP ``l``, ``A_k x = b_k`` for ``k`` in
    ``equal_rows[l]``, all from the basis ``tab.T0``, in lock-step.

    Returns a list of :class:`DenseAnswer` (one per LP; multipliers in the caller's row units).
    """
    n, R = tab.n, tab.R
    L = len(equal_rows)
    if max_pivots is None:
        max_pivots = max(60, 3 * n)
    if chunk is None:
        # keep the eta storage (chunk * etas * n floats) and the activities moderate
        chunk = int(max(8, min(512, 2e7 / (n * 64 + R))))
    out = []
    for start in range(0, L, chunk):
        out.extend(_batch(tab, equal_rows[start : start + chunk], max_pivots))
    return out


def _batch(tab, eqs, max_pivots):
    n, R = tab.n, tab.R
    L = len(eqs)
    A, b, W = tab.A, tab.b, tab.W
    tolx = FEAS_TOL * tab.scale_x
    # working state of the active LPs (compacted as LPs finish)
    ids = np.arange(L)
    bas = np.tile(tab.T0, (L, 1))
    sgn = np.ones((L, n))
    eqmask = np.zeros((L, R), bool)
    for l, rows in enumerate(eqs):
        eqmask[l, list(rows)] = True
    free = eqmask[np.arange(L)[:, None], bas]
    inbasis = np.zeros((L, R), bool)
    inbasis[np.arange(L)[:, None], bas] = True
    y = np.tile(tab.y0, (L, 1))
    act = np.tile(tab.act0, (L, 1))
    cap = 8
    D = np.zeros((L, cap, n))  # eta vectors (alpha - e_r) / alpha_r
    Rr = np.zeros((L, cap), int)
    npiv = 0  # lock-step: every active LP has made the same number of pivots
    # final state, by LP id
    out_bas = np.zeros((L, n), int)
    out_sgn = np.ones((L, n))
    out_y = np.zeros((L, n))
    out_x = np.zeros((L, n))
    out_piv = np.zeros(L, int)
    status = np.array(["running"] * L, dtype=object)

    def retire(mask, st):
        nonlocal ids, bas, sgn, eqmask, free, inbasis, y, act, D, Rr
        if not mask.any():
            return
        k = ids[mask]
        status[k] = st
        out_bas[k], out_sgn[k], out_y[k], out_piv[k] = bas[mask], sgn[mask], y[mask], npiv
        # x = A_T0^-1 E_1 ... E_t b_T
        bT = sgn[mask] * b[bas[mask]]
        rr = np.arange(bT.shape[0])
        for t in range(npiv - 1, -1, -1):
            dot = np.einsum("ij,ij->i", D[mask, t], bT)
            bT[rr, Rr[mask, t]] -= dot
        out_x[k] = bT @ tab.Binv.T
        keep = ~mask
        ids, bas, sgn, eqmask = ids[keep], bas[keep], sgn[keep], eqmask[keep]
        free, inbasis, y, act = free[keep], inbasis[keep], y[keep], act[keep]
        D, Rr = D[keep], Rr[keep]

    while ids.size:
        if npiv >= max_pivots:
            retire(np.ones(ids.size, bool), "failed")
            break
        l = ids.size
        idx = np.arange(l)
        # ---- pricing: pending equalities first, then the most violated inequality
        viol = act - b
        pend = eqmask & ~inbasis
        eqv = np.where(pend, np.abs(viol), 0.0)
        ineq = np.where(inbasis | eqmask, -np.inf, viol)
        p_eq = np.argmax(eqv, axis=1)
        has_eq = eqv[idx, p_eq] > tolx
        p_in = np.argmax(ineq, axis=1)
        vin = ineq[idx, p_in] > tolx
        pend_any = pend.any(axis=1)
        # an equality row already satisfied still enters (it becomes basic and free)
        done = ~(has_eq | vin | pend_any)
        retire(done, "optimal")
        if done.any():
            keep = ~done
            p_eq, p_in, has_eq, vin = p_eq[keep], p_in[keep], has_eq[keep], vin[keep]
            l = ids.size
            idx = np.arange(l)
            if not l:
                break
        p = np.where(has_eq, p_eq, np.where(vin, p_in, p_eq))
        zero_eq = ~(has_eq | vin)
        sp = np.where(eqmask[idx, p] & (act[idx, p] < b[p]), -1.0, 1.0)  # entering row sign
        # ---- alpha = E_t^T ... E_1^T (sp W[:, p])
        alpha = W[:, p].T * sp[:, None]
        for t in range(npiv):
            alpha -= D[:, t] * alpha[idx, Rr[:, t]][:, None]
        # ---- ratio test over non-free positions with alpha > tol
        flip = zero_eq & ~np.any((alpha > PIVOT_TOL) & ~free, axis=1)
        sp[flip] *= -1.0
        alpha[flip] *= -1.0
        ok = (alpha > PIVOT_TOL) & ~free
        ratio = np.where(ok, np.maximum(y, 0.0) / np.where(ok, alpha, 1.0), np.inf)
        tmin = ratio.min(axis=1)
        infeas = ~np.isfinite(tmin)
        if infeas.any():
            # Farkas: the entering row cannot be satisfied; a satisfied equality that no pivot
            # can bring in is implied by the free rows (rare: let HiGHS decide)
            retire(infeas & ~zero_eq, "infeasible")
            go = ~(infeas & ~zero_eq)
            p, sp, alpha, ratio, tmin, ok = p[go], sp[go], alpha[go], ratio[go], tmin[go], ok[go]
            zinf = infeas[go]
            retire(zinf, "failed")
            go = ~zinf
            p, sp, alpha, ratio, tmin, ok = p[go], sp[go], alpha[go], ratio[go], tmin[go], ok[go]
            l = ids.size
            idx = np.arange(l)
            if not l:
                break
        # Harris-style tie break: among ratios within a small tolerance take the largest alpha
        near = ok & (ratio <= tmin[:, None] + 1e-12 * (1 + np.abs(tmin[:, None])))
        r = np.argmax(np.where(near, alpha, -np.inf), axis=1)
        ar = alpha[idx, r]
        t_dual = np.maximum(y[idx, r], 0.0) / ar
        # ---- primal step along -A_T^-1 e_r until row p is tight
        s = sp * (act[idx, p] - b[p]) / ar
        u = np.zeros((l, n))
        u[idx, r] = 1.0
        for t in range(npiv - 1, -1, -1):
            u[idx, Rr[:, t]] -= np.einsum("ij,ij->i", D[:, t], u)
        act -= s[:, None] * (u @ W)
        # ---- dual and basis update
        y -= t_dual[:, None] * alpha
        y[idx, r] = t_dual
        inbasis[idx, bas[idx, r]] = False
        inbasis[idx, p] = True
        bas[idx, r] = p
        sgn[idx, r] = sp
        free[idx, r] = eqmask[idx, p]
        if npiv >= D.shape[1]:
            D = np.concatenate([D, np.zeros_like(D)], axis=1)
            Rr = np.concatenate([Rr, np.zeros_like(Rr)], axis=1)
        dvec = alpha / ar[:, None]
        dvec[idx, r] -= 1.0 / ar
        D[:, npiv] = dvec
        Rr[:, npiv] = r
        npiv += 1
    # ---- certificates, checked for all LPs at once (matrix products)
    Y = np.zeros((L, R))
    rows = np.arange(L)[:, None]
    np.add.at(Y, (np.broadcast_to(rows, out_bas.shape), out_bas), out_y * out_sgn)
    eqm = np.zeros((L, R), bool)
    for l, rows_l in enumerate(eqs):
        eqm[l, list(rows_l)] = True
    res = batch_residuals(A, b, tab.e, out_x, Y, eqm)
    answers = []
    for l in range(L):
        st = status[l]
        if st == "optimal" and max(res[l]) > CERT_TOL:
            st = "failed"
        r = tuple(float(v) for v in res[l]) if st == "optimal" else (np.nan,) * 4
        answers.append(
            DenseAnswer(st, out_x[l], Y[l] / tab.rownorm, out_bas[l].copy(), int(out_piv[l]), r)
        )
    return answers


def batch_residuals(A, b, e, X, Y, eqmask):
    """:func:`kkt_residuals` for many ``(x, y)`` pairs (rows of ``X``, ``Y``); unit-norm rows."""
    act = X @ A.T
    scale = np.maximum(1.0, np.abs(X).max(axis=1))[:, None] + np.abs(b)[None, :]
    r = (act - b) / scale
    primal = np.where(eqmask, np.abs(r), np.maximum(r, 0.0)).max(axis=1)
    ys = np.maximum(1.0, np.abs(Y).max(axis=1))
    dual = np.where(eqmask, 0.0, np.maximum(-Y, 0.0)).max(axis=1) / ys
    stat = np.abs(e[None, :] - Y @ A).max(axis=1) / ys
    comp = (np.abs(Y) * np.abs(np.minimum(r, 0.0))).max(axis=1) / ys
    return np.stack([primal, dual, stat, comp], axis=1)


def solve_max(A, b, e, *, max_iter=60):
    """``max e.x s.t. A x <= b``: interior point, basis identification, dual simplex clean-up.

    Returns ``(answer, tableau)`` with the tableau of the optimal basis (for warm starts), or
    ``(None, None)`` when the interior point does not converge (unbounded or infeasible LP, or
    trouble): the caller then uses HiGHS.
    """
    R, n = A.shape
    rn = np.linalg.norm(A, axis=1)
    rn[rn == 0] = 1.0
    As, bs = A / rn[:, None], b / rn
    x, s, z, conv, it = ipm(As, bs, e, max_iter=max_iter)
    if not conv:
        return None, None
    T = identify_basis(As, z, s, n)
    tab = Tableau(A, b, e, T) if T is not None else None
    if tab is None or tab.singular or not tab.dual_feasible:
        # degenerate optimum (fewer than n strongly active rows): complete the active set so
        # that the multipliers stay non-negative, then let the dual simplex finish
        T = complete_basis(As, z, s, e, n)
        if T is None:
            return None, None
        tab = Tableau(A, b, e, T)
        ymax = max(1.0, float(np.abs(tab.y0).max()))
        if not tab.singular and tab.y0.min() >= -1e-6 * ymax:
            # multipliers that are zero up to the interior point's accuracy; the final
            # answer is certified again below, so this cannot pass a wrong optimum
            tab.y0 = np.maximum(tab.y0, 0.0)
    if tab.singular or not tab.dual_feasible:
        return None, None
    ans = batch_dual_simplex(tab, [()])[0]
    if ans.status != "optimal":
        return None, None
    if ans.iterations:
        tab = Tableau(A, b, e, ans.basis)
    ans = DenseAnswer(ans.status, ans.x, ans.y, ans.basis, ans.iterations + it, ans.residuals)
    return ans, tab
