"""A sufficient friction bound for a unique 3-D incremental step (MODEL.md s.8.4).

The 3-D counterpart of :meth:`DiscreteSystem.critical_friction`: the step of a ``dim = 3``
system has *at most one* solution for every load increment when, with
``S = A - B C^-1 B^T`` (the slip stiffness with the gaps free) and ``F = diag(f_max,i)``
(``f_max,i = max(f_x,i, f_y,i)``),

    lambda_max(F C F) < 4 lambda_min(S).

Proof (a monotonicity argument; the 2-D analogue is the P-matrix route of Klarbring 1990).  Let
``(u1, r1)``, ``(u2, r2)`` solve the same step, ``du = (dv, dw) = u1 - u2``, ``dr = (dq, dp) =
K du``.  Per node the law reads ``-q = p s`` with ``s`` in the subdifferential of the gauge
``h(dv) = |F_i dv|`` (``h`` is the support function of the ellipse ``|F_i^-1 q| <= 1``), so
``s_1 . dv_2 <= h(dv_2)`` and

    -(q1 - q2) . (dv1 - dv2) = p1 (h1 - s1 . dv2) + p2 (h2 - s2 . dv1)
                            >= (p1 - p2)(h1 - h2) >= -f_max |p1 - p2| |dv1 - dv2|,

and ``(p1 - p2)(w1 - w2) = -p1 w2 - p2 w1 <= 0``.  Summing, ``du^T K du = dr . du <=
sum_i f_i |dp_i| |dv_i| <= |F dp| |dv|``.  With ``z = dp = B^T dv + C dw``,
``du^T K du = dv^T S dv + z^T C^-1 z >= s |dv|^2 + |F z|^2 / c`` (``s = lambda_min(S)``,
``c = lambda_max(F C F)``) ``>= 2 sqrt(s / c) |dv| |F z|``.  If ``c < 4 s`` the two bounds
contradict unless ``du = 0``: there is at most one solution.  The bound says nothing about
existence (discussed for discrete frictional contact by Klarbring & Pang 1998, SIAM J. Optim.
8(2), 414-442); the step solver reports ``"failed"`` when it finds no verified solution.

For ``B = 0`` the normal problem does not depend on the slips (an LCP with ``C`` positive
definite, unique ``w``) and the tangential one is strictly convex: unique for every friction.
Restricted to a 2-D system (``y`` unloaded and uncoupled) the bound is at most the exact 2-D
single-node value ``A_jj / |B_jj|`` (equal when ``A_jj C_jj = 2 B_jj^2``).

Computation (certified, no full eigendecomposition).  ``lambda_min(S)`` is bounded from below
and ``lambda_max(F C F)`` from above, each by an estimate (a dense eigensolver for small
systems, Lanczos above :data:`DENSE_EIG_MAX` unknowns) proven by one Cholesky factorisation of
the shifted matrix with Rump's margin for its rounding (:mod:`.verified`); the factor is
computed from the proven bounds, so it is never larger than the exact one.  A wrong estimate
makes the factorisation fail: no bound (factor 0) rather than a wrong one.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla
from scipy.linalg.blas import dsyrk

from .critical import CriticalFriction
from .verified import EPS, certified_lower_eig, certified_upper_eig, gamma


def critical_friction_3d(system) -> CriticalFriction:
    """The 3-D counterpart of :func:`~.critical.critical_friction_2d` (see module docstring):
    ``factor`` is the sufficient multiplier ``alpha_s`` (``exact`` only when ``B = 0`` or the
    friction vanishes, where the step is unique for every friction), ``value = alpha_s *
    max(f)``, ``upper_bound = inf`` (no necessary bound is computed in 3-D),
    ``method = "sufficient-bound-3d"`` / ``"uncoupled"`` / ``"frictionless"``."""
    fxy = system.friction_xy
    factor, exact, method = sufficient_factor_3d(system.A, system.B, system.C, fxy)
    fmax = float(fxy.max()) if fxy.size else 0.0
    return CriticalFriction(factor=float(factor),
                            value=float(factor * fmax) if fmax > 0 else float("inf"),
                            exact=exact, upper_bound=float("inf"), method=method,
                            well_posed=bool(factor > 1.0))


def sufficient_factor_3d(A, B, C, friction_xy):
    """Largest multiplier ``alpha`` of the friction profile keeping the bound of the module
    docstring: ``alpha_s = 2 sqrt(s_lo / c_up)`` with *proven* ``s_lo <= lambda_min(S)`` and
    ``c_up >= lambda_max(F C F)`` (:func:`schur_lower_eig`, :func:`fcf_upper_eig`), so the
    factor never exceeds the exact ``2 sqrt(lambda_min(S) / lambda_max(F C F))``.

    Parameters
    ----------
    A, B, C : array_like or sparse, shapes (2N, 2N), (2N, N), (N, N) [force / length]
    friction_xy : array_like, shape (N, 2)

    Returns
    -------
    factor : float
        ``inf`` for ``B = 0`` or zero friction; ``0`` when no positive ``s_lo`` is proven.
    exact : bool
        True only for the uncoupled / frictionless cases (there the step is unique for every
        friction); else the bound is sufficient only.
    method : str
        ``"uncoupled"``, ``"frictionless"`` or ``"sufficient-bound-3d"``.
    """
    A, B, C = (np.asarray(M.toarray() if hasattr(M, "toarray") else M, float) for M in (A, B, C))
    fmax = np.asarray(friction_xy, float).max(axis=1)
    if not np.any(B != 0):
        return float("inf"), True, "uncoupled"
    if not np.any(fmax > 0):
        return float("inf"), True, "frictionless"
    s = schur_lower_eig(A, B, C)
    if not s > 0:
        return 0.0, False, "sufficient-bound-3d"
    c = fcf_upper_eig(C, fmax)
    return 2.0 * float(np.sqrt(s / c)) * (1 - 4 * EPS), False, "sufficient-bound-3d"


#: Up to this size the estimates come from the dense symmetric eigensolver; above it from
#: Lanczos (ARPACK), which needs only products (with ``S^-1`` by its Cholesky factor, or with
#: ``F C F``).  The estimate is then proven (or refused) by a Cholesky factorisation.
DENSE_EIG_MAX = 400
#: Relative shifts below the estimate tried by the proof (of the matrix's largest diagonal).
SLACK = (1e-14, 1e-11, 1e-10, 1e-9, 1e-8, 1e-6, 1e-4)


def schur_lower_eig(A, B, C) -> float:
    """A proven lower bound of ``lambda_min(A - B C^-1 B^T)`` (``-inf`` if none is proven).

    The proof is one Cholesky factorisation of ``[[C - d I, B^T], [B, A - sigma I]]``, done in
    two stages (``L_C``, ``Y = L_C^-1 B^T``, then ``T - sigma I`` with ``T = A - Y^T Y``: the
    operations of a blocked Cholesky).  Its backward error is at most ``m = 2 gamma_{3N+1}
    (trace A + trace C)`` in norm (:mod:`shakedown.model.verified`); with the shift ``d >= m``
    of the ``C`` block, success proves ``[[C, B^T], [B, A - (sigma - m) I]] >= 0``, i.e.
    ``lambda_min(S) >= sigma - m`` for the exact data (no inverse of ``C`` is trusted).  The
    estimate ``sigma`` comes from the eigenvalues of the computed ``T`` (dense solver, or
    Lanczos on ``T^-1``).
    """
    N, n2 = C.shape[0], A.shape[0]
    tr = float(np.trace(A)) + float(np.trace(C))
    dmax = max(float(np.abs(np.diag(A)).max()), float(np.abs(np.diag(C)).max()))
    m = 2.0 * (gamma(3 * N + 1) * tr * (1 + gamma(3 * N)) + 2 * EPS * dmax)
    Cs = np.array(C, order="F", copy=True)
    Cs[np.diag_indices(N)] -= m
    try:
        L = sla.cholesky(Cs, lower=True, overwrite_a=True, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return -np.inf
    Y = sla.solve_triangular(L, B.T, lower=True, check_finite=False)  # (N, 2N)
    T = dsyrk(-1.0, Y, beta=1.0, c=np.array(A, order="F", copy=True), trans=1, lower=0,
              overwrite_c=1)  # A - Y^T Y, upper triangle
    if n2 <= DENSE_EIG_MAX:  # only the upper triangle of T is read from here on
        est = float(sla.eigvalsh(T, lower=False, subset_by_index=[0, 0], check_finite=False)[0])
    else:
        try:
            R = sla.cholesky(T, lower=False, check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            return -np.inf  # T is not positive definite: no positive bound to prove

        def inv(x):  # T^-1 x = R^-1 R^-T x
            y = sla.solve_triangular(R, x, trans="T", check_finite=False)
            return sla.solve_triangular(R, y, check_finite=False)

        op = spla.LinearOperator((n2, n2), dtype=float, matvec=inv)
        # tol 1e-6 on the Ritz vector gives the value to ~1e-11 (its error is quadratic);
        # the proof below tolerates any estimate error up to its slack
        top = float(spla.eigsh(op, k=1, which="LA", tol=1e-6, v0=np.ones(n2),
                               return_eigenvectors=False)[0])
        est = 1.0 / top
    lb = certified_lower_eig(T, est, slack=SLACK)  # T - sigma I by Cholesky: T's own proof
    return float(lb - m) if np.isfinite(lb) else -np.inf


def fcf_upper_eig(C, fmax) -> float:
    """A proven upper bound of ``lambda_max(F C F)`` (``inf`` if none is proven): the estimate
    (dense solver, or Lanczos) proven by a Cholesky factorisation of ``t I - fl(F C F)``, plus
    the rounding of the products (``|fl(F C F) - F C F| <= 2.01 u |F C F|`` entrywise, at most
    ``2.01 u ||F C F||_F`` in norm)."""
    N = C.shape[0]
    M = fmax[:, None] * C * fmax[None, :]
    if N <= DENSE_EIG_MAX:
        est = float(sla.eigvalsh(M, subset_by_index=[N - 1, N - 1], check_finite=False)[0])
    else:
        est = float(spla.eigsh(M, k=1, which="LA", tol=1e-10, return_eigenvectors=False)[0])
    up = certified_upper_eig(M, est, slack=SLACK)
    fro = float(np.sqrt(np.einsum("ij,ij->", M, M))) * (1 + gamma(N * N))
    return float((up + 2.01 * EPS * fro) * (1 + 4 * EPS))


__all__ = ["sufficient_factor_3d", "critical_friction_3d", "schur_lower_eig", "fcf_upper_eig"]
