"""Linear-case eigen-solves of the pencil and the active-set method.

When every slip node slips in the mode (``x > 0``), MCEIP reduces to the linear generalized
eigenproblem ``K0 x = -mu K1 x``: a real eigenvalue ``mu > 0`` whose eigenvector has one
sign *is* a complementarity solution (``y = 0``).  With ``nu = 1 / mu`` the problem reads
``-K1 x = nu K0 x`` (``K0`` SPD, so ``nu`` is finite); ARPACK finds the few ``nu`` of largest
modulus, i.e. the ``mu`` of smallest modulus, from the operator ``x -> -K0^-1 K1 x``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from ..model.errors import InputError, ShapeError
from ..model.validation import real_array
from .pencil import SlipPencil
from .result import SUPPORT_RTOL, VERIFY_TOL, MCEIPResult, make_result, no_solution

#: An eigenvalue ``nu`` counts as real when ``abs(Im nu) <= IMAG_RTOL * max(1, abs(nu))``
#: (LAPACK returns real eigenvalues of real pencils with an exactly zero imaginary part
#: unless they are nearly defective; 1e-9 accepts those too).
IMAG_RTOL = 1e-9


#: Eigenvalues ``nu = 1/mu`` below ``NU_RTOL * ||K1|| / ||K0||`` are round-off of a zero
#: coupling (e.g. ``mu ~ 1e14`` for an isotropic layer's uniform mode) and are discarded.
NU_RTOL = 1e-11


def _pairs_from(nu, V, sign_rtol, nu_min=0.0):
    """(mu, x, single_signed) for the real positive eigenvalues ``nu`` (mu = 1 / nu)."""
    out = []
    for k in range(nu.size):
        z = nu[k]
        if not np.isfinite(z) or abs(z.imag) > IMAG_RTOL * max(1.0, abs(z)) or z.real <= nu_min:
            continue
        v = np.real(V[:, k])
        i = int(np.argmax(np.abs(v)))
        if v[i] == 0:
            continue
        v = v / v[i]
        out.append((1.0 / z.real, v, bool(v.min() >= -sign_rtol)))
    out.sort(key=lambda t: t[0])
    return out


def restricted_eigenpairs(K0, K1, support=None, *, sign_rtol: float = SUPPORT_RTOL):
    """Real ``mu > 0`` with ``(K0 + mu K1)_JJ x_J = 0`` (dense generalized eigen-solve).

    Returns
    -------
    list of (mu, x_J, single_signed)
        Sorted by ``mu``; ``x_J`` scaled so that its largest entry is ``+1``;
        ``single_signed`` when ``min(x_J) >= -sign_rtol``.
    """
    K0, K1 = real_array("K0", K0), real_array("K1", K1)
    if K0.ndim != 2 or K0.shape[0] != K0.shape[1] or K1.shape != K0.shape:
        raise ShapeError(f"K0 and K1 must be square of one shape; got {K0.shape}, {K1.shape}")
    if not (np.all(np.isfinite(K0)) and np.all(np.isfinite(K1))):
        raise InputError("K0 and K1 must be finite; got a NaN or inf entry")
    nu_min = NU_RTOL * np.abs(K1).max(initial=0.0) / max(np.abs(K0).max(initial=0.0), 1e-300)
    if support is not None:
        J = np.asarray(support, dtype=int)
        ix = np.ix_(J, J)
        K0, K1 = K0[ix], K1[ix]
    if K0.shape[0] == 1:
        k1 = K1[0, 0]
        if -k1 / K0[0, 0] > nu_min:
            return [(-K0[0, 0] / k1, np.ones(1), True)]
        return []
    nu, V = sla.eig(-K1, K0, check_finite=False)  # checked finite above
    return _pairs_from(nu, V, sign_rtol, nu_min)


def linear_dense(pencil: SlipPencil, *, tol: float = VERIFY_TOL) -> MCEIPResult:
    """Smallest real ``mu > 0`` of ``K0 x = -mu K1 x`` with a one-signed eigenvector (dense QZ).

    The answer is a verified complementarity solution with full support; it need not be the
    smallest MCEIP solution (a partial-slip mode may come first): ``minimal`` is ``False``.
    """
    pairs = restricted_eigenpairs(pencil.K0, pencil.K1)
    return _pick(pencil, pairs, "linear-dense", tol)


def _pick(pencil, pairs, method, tol, iterations=0):
    good = [p for p in pairs if p[2]]
    note = ""
    if pairs and not pairs[0][2]:
        mu0, x0 = pairs[0][0], pairs[0][1]
        note = (
            f"the smallest real eigenvalue mu = {mu0:.6g} has a mode with both signs "
            f"(min x = {x0.min():.3g}): not a complementarity solution; "
        )
    if not good:
        return no_solution(
            pencil, method=method, iterations=iterations,
            message=note + "no real positive eigenvalue with a one-signed mode (the linear "
            "case has no solution; a partial-slip mode may still exist)",
        )
    mu, x, _ = good[0]
    return make_result(pencil, mu, np.clip(x, 0.0, None), method=method, tol=tol,
                       iterations=iterations, message=note + "full-support (linear) solution")


def linear_arpack(pencil: SlipPencil, *, k: int = 6, tol: float = VERIFY_TOL,
                  arpack_tol: float = 0.0) -> MCEIPResult:
    """As :func:`linear_dense` with ARPACK on ``x -> -K0^-1 K1 x`` (``k`` largest ``|nu|``).

    ``k`` is doubled until a one-signed real eigenvector is among the computed ones or the
    size makes ARPACK pointless (then the dense solve is used).
    """
    n = pencil.size
    if n < 8:
        return linear_dense(pencil, tol=tol)
    cho = sla.cho_factor(pencil.K0)
    K1 = np.asarray(pencil.K1)
    op = spla.LinearOperator((n, n), matvec=lambda v: sla.cho_solve(cho, -(K1 @ v)),
                             dtype=float)
    v0 = np.ones(n)
    kk = min(k, n - 2)
    while True:
        try:
            nu, V = spla.eigs(op, k=kk, which="LM", v0=v0, tol=arpack_tol)
        except spla.ArpackNoConvergence as exc:
            nu, V = exc.eigenvalues, exc.eigenvectors
        pairs = _pairs_from(nu, V, SUPPORT_RTOL)
        if any(p[2] for p in pairs) or kk >= n - 2 or kk >= 64:
            break
        kk = min(2 * kk, n - 2)
    if not any(p[2] for p in pairs):
        res = linear_dense(pencil, tol=tol)
        return _replace_method(res, "linear-arpack (dense fallback)")
    return _pick(pencil, pairs, "linear-arpack", tol, iterations=kk)


def _replace_method(res: MCEIPResult, method: str) -> MCEIPResult:
    from dataclasses import replace

    return replace(res, method=method)


def active_set(pencil: SlipPencil, *, support=None, tol: float = VERIFY_TOL,
               maxiter: int | None = None) -> MCEIPResult:
    """Active-set search for a partial-slip solution.

    Start from ``support`` (default: every slip node).  On the current support ``J`` take the
    smallest real ``mu > 0`` of ``(K0 + mu K1)_JJ``: if its mode is one-signed and
    ``y >= 0`` off ``J`` it is a solution; if some ``y_j < 0`` off ``J``, node ``j`` would be
    pushed outside its cone and joins ``J``; if the mode has both signs the nodes with
    ``x_j < 0`` (which would slip backwards, forbidden) leave ``J``.  Supports are never
    revisited.  Every answer is verified; minimality is not certified.
    """
    n = pencil.size
    J = np.arange(n) if support is None else np.unique(np.asarray(support, dtype=int))
    maxiter = 4 * n + 10 if maxiter is None else maxiter
    seen = set()
    for it in range(1, maxiter + 1):
        key = J.tobytes()
        if key in seen or J.size == 0:
            break
        seen.add(key)
        pairs = restricted_eigenpairs(pencil.K0, pencil.K1, J)
        if not pairs:
            break
        good = [p for p in pairs if p[2]]
        if good and (not pairs[0][2]) and good[0][0] > 10 * pairs[0][0]:
            good = []  # far above the first eigenvalue: drop the wrong-signed nodes instead
        if good:
            mu, xJ, _ = good[0]
            x = np.zeros(n)
            x[J] = np.clip(xJ, 0, None)
            M = pencil.matrix(mu)
            y = M @ x
            norm = np.abs(M).sum(axis=1).max()
            out = np.setdiff1d(np.arange(n), J)
            viol = out[y[out] < -tol * norm]
            if viol.size == 0:
                return make_result(pencil, mu, x, method="active-set", tol=tol, iterations=it)
            J = np.union1d(J, [viol[np.argmin(y[viol])]])
        else:
            mu, xJ, _ = pairs[0]
            keep = xJ > SUPPORT_RTOL
            J = J[keep]
    return no_solution(pencil, method="active-set", iterations=len(seen),
                       message="no verified solution reached (support cycled or emptied)")
