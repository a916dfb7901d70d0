"""Dense interior point for ``max e.x  s.t.  A x <= b`` and the basis identification after it.

:func:`ipm` is a Mehrotra predictor-corrector method on the normal equations ``A^T D A``
(``D = Z S^-1``; one ``dsyrk`` + Cholesky per iteration, ``O(R n^2)``).  It only has to bring the
iterate close enough to the optimal face for :func:`identify_basis` / :func:`complete_basis` to
name an optimal basis; the dual simplex then finishes and certifies the answer
(:mod:`.dual_simplex`).

Why the stopping test is "best iterate, stagnation-aware" (issue 13/14: the stall on the
100-crack default LP ``201 x 101``): that LP has a non-degenerate optimal vertex, but one
multiplier is ``2.2e-7`` against a largest ``0.52`` (a constraint that is barely active).  As
``mu -> 0`` the normal matrix's condition number grows like ``(z_max / z_min)^2 / mu`` and
reaches ``1e14`` (the Cholesky regularisation level) near ``mu = 1e-11``; from there the
Newton directions lose the barely active row, the dual residual stops at ``~1e-7`` and then
*grows* (to ``2e-5``) while ``mu`` keeps falling to ``1e-100``.  The former test demanded
primal, dual and gap residuals ``< 1e-8`` simultaneously at the *current* iterate: at
iteration 14 the dual residual was ``2e-9`` but the gap ``1.7e-7``; at 15 the gap was
``1.2e-8`` but the dual residual ``6.6e-8``; never both, so every LP fell back to HiGHS.  Now:
one step of iterative refinement of the normal equations (against the unregularised matrix),
the best iterate (smallest ``max(rp, rd, gap)``) is kept, the loop stops once that merit has
not improved for a few iterations, and an iterate whose merit is below ``APPROX_TOL`` is handed
to the crossover (which certifies or rejects it; nothing uncertified is returned).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from ..model import citations

#: Merit (max of the relative primal, dual and gap residuals) at which the interior point stops.
IPM_TOL = 1e-9
#: Largest merit of a stalled iterate still handed to the crossover (which certifies it or
#: rejects it).  1e-3 since issue 14: on condensed FE interfaces (a strip on an obstacle, 500
#: contact nodes) the merit stalls between 1e-5 and 1e-4, the old limit sent every LP to HiGHS
#: (36 s), and the crossover from that iterate ends certified (residual 6e-12, 0.3 s).
APPROX_TOL = 1e-3
#: Iterations without a 2x improvement of the best merit after which the loop stops.
STALL_ITERS = 4
#: Once the best merit is within this factor of ``tol``, one such iteration ends the loop.
#: Issue 26 (the ``lam2`` LPs of the 2000-crack networks i = 2 and 11 of
#: ``bench_bounds_realizations.py``): the best merit reached 1.5e-9 and 3.0e-9, the optimal
#: basis was identified from that iterate to within 2 and 0 rows, and the next 4 iterations
#: (~0.55 s each) only raised the dual residual as ``mu`` fell to 1e-20.
NEAR_TOL = 10.0


def ipm(A, b, e, *, tol=IPM_TOL, max_iter=80, stop=None, correctors=0):  # noqa: C901
    """Mehrotra predictor-corrector for ``max e.x s.t. A x + s = b, s >= 0`` (dense).

    Parameters
    ----------
    A : ndarray, shape (R, n)
        Rows of unit norm (the callers scale them).
    b : ndarray, shape (R,)
    e : ndarray, shape (n,)
    tol : float
        Target merit ``max(|rp| / (1 + |b|), |rd| / (1 + |e|), gap)`` (relative).
    max_iter : int
    stop : callable, optional
        ``stop(x, s, z)``, asked at each iterate whose merit is at most :data:`APPROX_TOL`:
        ``True`` ends the loop with that iterate (the caller has what it needs, e.g. a Chebyshev
        centre certified by its own test; status as for the merit reached).
    correctors : int
        Gondzio's centrality correctors per iteration at most (:func:`_centrality`).  0 (plain
        Mehrotra) for an LP whose answer is a vertex found by the crossover from a stalled
        iterate: on a 2000-node FE strip (``bench_bounds_realizations.py --kind fe``, i = 4)
        the corrected iterate stalled at another point, from which no basis was identified
        (the crossover then spent 222 s in :func:`complete_basis`'s ``linprog``); 2 for the
        Chebyshev centre, whose iterate is accepted by its own certificate (fewer iterations),
        and for the second try of an LP whose first crossover failed
        (:data:`~.dense_lp.RETRY_CORRECTORS`).

    Returns
    -------
    x, s, z : ndarray
        The best iterate (smallest merit); ``z >= 0`` are the multipliers (``A^T z ~ e``).
    status : str
        ``"converged"`` (merit ``<= tol``), ``"approximate"`` (stalled with merit
        ``<= APPROX_TOL``: good enough to identify a basis) or ``"failed"`` (unbounded,
        infeasible or numerical trouble).
    iterations : int
    """
    R, n = A.shape
    x = np.zeros(n)
    s = np.maximum(b - A @ x, 1.0)
    z = np.ones(R)
    bn = 1.0 + np.abs(b).max(initial=0.0)
    en = 1.0 + np.abs(e).max(initial=0.0)
    best = (np.inf, x, s, z)
    since = 0
    it = 0
    As = np.empty_like(A)  # the scaled rows and the normal matrix, reused by every iteration:
    M = np.zeros((n, n), order="F")  # fresh ones cost ~0.06 s of page faults each (N = 2000)
    while it < max_iter:
        it += 1
        rp = A @ x + s - b
        rd = A.T @ z - e
        mu = float(s @ z) / R
        gap = abs(float(b @ z - e @ x)) / (1.0 + abs(float(e @ x)))
        merit = max(np.abs(rp).max() / bn, np.abs(rd).max() / en, gap)
        if merit < 0.5 * best[0]:
            best, since = (merit, x, s, z), 0
        else:
            since += 1
        if best[0] <= tol or since >= STALL_ITERS or (since and best[0] <= NEAR_TOL * tol):
            break
        if stop is not None and merit <= APPROX_TOL and stop(x, s, z):
            best = (merit, x, s, z)
            break
        d = z / s
        # normal matrix A^T D A (upper triangle, symmetric rank-k update: half a GEMM); the
        # transpose of the C-ordered scaled rows is Fortran-ordered: no copy of A (a
        # transposing copy of the 4001 x 2001 A took a fifth of the interior point, N = 2000)
        np.multiply(A, np.sqrt(d)[:, None], out=As)
        M = sla.blas.dsyrk(1.0, As.T, trans=0, c=M, overwrite_c=1)
        M[np.diag_indices(n)] += 1e-14 * M.diagonal().max()
        try:  # (the factor overwrites M: it is formed anew by the next iteration)
            cf = sla.cho_factor(M, lower=False, check_finite=False, overwrite_a=True)
        except np.linalg.LinAlgError:
            break

        def solve(rhs, cf=cf, d=d):
            dx = sla.cho_solve(cf, rhs, check_finite=False)
            # one step of iterative refinement against the unregularised A^T D A
            return dx + sla.cho_solve(cf, rhs - A.T @ (d * (A @ dx)), check_finite=False)

        dx, ds, dz = _direction(A, solve, rd, rp, s, z, np.zeros(R))
        ap, ad = _step(s, ds), _step(z, dz)
        mu_aff = float((s + ap * ds) @ (z + ad * dz)) / R
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        dx2, ds2, dz2 = _direction(A, solve, rd, rp, s, z, sigma * mu - ds * dz)
        if correctors:
            dx2, ds2, dz2 = _centrality(A, solve, s, z, sigma * mu, (dx2, ds2, dz2), correctors)
        ap, ad = 0.99 * _step(s, ds2), 0.99 * _step(z, dz2)
        x = x + ap * dx2
        s = s + ap * ds2
        z = z + ad * dz2
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
            break
        if np.abs(x).max(initial=0.0) > 1e15 * bn or z.max() > 1e15 * en:
            break  # diverging: unbounded primal or dual
    merit, x, s, z = best
    if merit <= tol:
        status = "converged"
    elif merit <= APPROX_TOL:
        status = "approximate"
    else:
        status = "failed"
    return x, s, z, status, it


def _centrality(A, solve, s, z, target, direction, correctors):
    """Gondzio's multiple centrality correctors: up to ``correctors`` corrections of the
    predictor-corrector ``direction`` toward a point whose complementarity products
    ``s_i z_i`` lie in ``[BETA_MIN, BETA_MAX] * target``, each one solve with the factor at hand
    (no new normal matrix), kept while it lengthens the step by at least
    ``GAMMA * STEP_AIM``.

    Issue 26 (2000-crack networks, LPs of 4001 x 2001): without them the steps of the ``lam2``
    LP were 0.25-0.7 for 18 iterations (a few badly centred pairs block them), 30 iterations of
    ~0.8 s, 26 with them; the Chebyshev centre's LP 21 -> 18 iterations.  Used for the centre
    and for a second try after a failed crossover (see ``correctors`` in :func:`ipm`).
    Reference: J. Gondzio, Multiple centrality corrections in a primal-dual method for linear
    programming, Computational Optimization and Applications 6 (1996) 137-156."""
    dx, ds, dz = direction
    ap, ad = _step(s, ds), _step(z, dz)
    zero = np.zeros(len(s))
    for _ in range(correctors):
        if min(ap, ad) >= 1.0:
            break
        ap_t, ad_t = min(1.0, ap + STEP_AIM), min(1.0, ad + STEP_AIM)
        v = (s + ap_t * ds) * (z + ad_t * dz)
        lo, hi = BETA_MIN * target, BETA_MAX * target
        t = np.where(v < lo, lo - v, np.where(v > hi, np.maximum(hi - v, -hi), 0.0))
        cx, cs, cz = _direction(A, solve, zero[: A.shape[1]], zero, s, z, t + s * z)
        nx, ns, nz = dx + cx, ds + cs, dz + cz
        ap_n, ad_n = _step(s, ns), _step(z, nz)
        if min(ap_n, ad_n) < min(ap, ad) + GAMMA * STEP_AIM:
            break
        dx, ds, dz, ap, ad = nx, ns, nz, ap_n, ad_n
    return dx, ds, dz


#: How much longer a step each corrector aims at, and the gain it must bring (a fraction).
STEP_AIM, GAMMA = 0.2, 0.1
#: The box of complementarity products the correctors aim at, relative to ``sigma mu``.
BETA_MIN, BETA_MAX = 0.1, 10.0


def _direction(A, solve, rd, rp, s, z, rc):
    """Newton direction with complementarity target ``s z -> rc`` (``S dz + Z ds = rc - s z``)."""
    rhs = -rd - A.T @ ((rc - s * z + z * rp) / s)
    dx = solve(rhs)
    ds = -rp - A @ dx
    dz = (rc - s * z - z * ds) / s
    return dx, ds, dz


def _step(v, dv):
    neg = dv < 0
    return min(1.0, float(np.min(-v[neg] / dv[neg], initial=np.inf)))


def identify_basis(A, z, s, n):
    """Guess the optimal basis: the ``n`` rows with the largest ``z / s`` when they are
    non-singular; at a degenerate vertex (more than ``n`` active rows, the leading ``n``
    dependent) the first ``n`` independent rows in that order (:func:`_independent_rows`).
    ``None`` when no ``n`` independent rows are found."""
    order = np.argsort(-(z / np.maximum(s, 1e-300)), kind="stable")
    T = np.sort(order[:n])
    if _nonsingular(A[T]):
        return T
    T = _independent_rows(A, order, n)
    return T if T is not None and _nonsingular(A[T]) else None


def _nonsingular(M) -> bool:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(M, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return False
    d = np.abs(np.diag(lu[0]))
    return bool(d.min() > 1e-12 * d.max())


def _independent_rows(A, order, n, rtol=1e-9, floor=0.0, block=64):
    """The first ``n`` rows of ``A`` in ``order`` each independent of those before it
    (Gram-Schmidt, orthogonalised twice: the remainder longer than ``rtol`` times the row's
    length or ``floor``, whichever is larger), sorted; ``None`` if fewer than ``n`` exist.

    Blocked (``block`` rows at a time): each block is orthogonalised twice against the rows
    picked before it by two matrix products, then row by row against those picked within the
    block (classical Gram-Schmidt with reorthogonalisation, block form).  The row-by-row loop over
    every picked row took 33 s per call on the 4001 x 2001 ``lam2`` LP of a 2000-node FE strip
    whose crossover fails (issue 26, ``bench_bounds_realizations.py --kind fe``, i = 13)."""
    order = np.asarray(order, dtype=int)
    Q = np.empty((n, A.shape[1]))
    picked = []
    for start in range(0, len(order), block):
        rows = order[start : start + block]
        B = np.array(A[rows], dtype=float)
        lengths = np.linalg.norm(B, axis=1)
        k0 = len(picked)
        if k0:
            for _ in range(2):
                B -= (B @ Q[:k0].T) @ Q[:k0]
        for j, i in enumerate(rows):
            if lengths[j] == 0.0:
                continue
            r = B[j]
            k = len(picked)
            if k > k0:
                for _ in range(2):
                    r = r - (r @ Q[k0:k].T) @ Q[k0:k]
            nr = np.linalg.norm(r)
            if nr > rtol * max(lengths[j], floor):
                Q[k] = r / nr
                picked.append(int(i))
                if len(picked) == n:
                    return np.sort(np.asarray(picked, dtype=int))
    return None


def strongly_active(z, s, n, max_missing=None):
    """The strongly active rows at an interior-point iterate (sorted): the rows whose ``z / s``
    lie above the largest relative gap among the ``n + 1`` largest values (at least
    ``n - max_missing`` of them when ``max_missing`` is given).  :func:`complete_basis`
    completes them to a basis; ``n`` minus their number is the size of its completion LP."""
    r = z / np.maximum(s, 1e-300)
    order = np.argsort(-r, kind="stable")
    top = np.maximum(r[order[: n + 1]], 1e-300)
    lo = 1 if max_missing is None else max(1, n - max_missing)
    gaps = np.log(top[lo - 1 : n]) - np.log(top[lo : n + 1])
    m = lo + int(np.argmax(gaps))  # the cut with the largest relative drop
    return np.sort(order[:m])


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

    C = strongly_active(z, s, n, max_missing)
    m = len(C)
    k = n - m
    if k <= 0:
        return None
    Q, rd = _null_space(A[C].T)
    # rank of A_C from the triangular factor at hand (an SVD of A_C took 3-9 s at N = 2000)
    if not rd.min() > rd.max() * max(A.shape) * np.finfo(float).eps:
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
            # one incremental Gram-Schmidt pass (formerly a matrix_rank SVD per candidate:
            # 849 SVDs, 60 s, on the Chebyshev LP of a 500-node FE strip, issue 26)
            # (projections of unit rows: independence measured against 1, not against the
            # projection's own length: a projection shorter than 1e-9 leaves the completed
            # basis numerically singular whatever its direction)
            picked = _independent_rows(P, np.r_[nz, others[piv]], k, floor=1.0)
            if picked is None:
                return None
            chosen = rest[picked]
    T = np.r_[C, chosen].astype(int)
    if len(np.unique(T)) != n:
        return None
    return np.sort(np.asarray(T, dtype=int))


def _null_space(X):
    """``(Q, |diag R|)``: the last ``n - m`` columns of the complete Householder QR of ``X``
    (``n x m``, ``m < n``: an orthonormal basis of ``null(X^T)``) and the magnitudes of its
    triangular factor's diagonal.  The reflectors are applied to ``[0; I]`` (LAPACK ``ormqr``)
    instead of forming the whole ``n x n`` factor (N = 2000, ``m`` = 1950: 0.37 s against
    0.85 s; the same columns to 4e-16)."""
    n, m = X.shape
    (qr, tau), _ = sla.qr(X, mode="raw", check_finite=False)
    Z = np.zeros((n, n - m), order="F")
    Z[m:] = np.eye(n - m)
    ormqr = sla.get_lapack_funcs("ormqr", (qr,))
    work = ormqr("L", "N", qr, tau, Z, lwork=-1)[1]
    Q, _, info = ormqr("L", "N", qr, tau, Z, lwork=max(int(work[0].real), 1), overwrite_c=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"ormqr failed (info = {info})")
    return Q, np.abs(np.diag(qr[:m, :m]))
