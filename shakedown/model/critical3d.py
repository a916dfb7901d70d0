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
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .critical import CriticalFriction


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
    docstring: ``alpha_s = 2 sqrt(lambda_min(S) / lambda_max(F C F))``.

    Parameters
    ----------
    A, B, C : array_like or sparse, shapes (2N, 2N), (2N, N), (N, N) [force / length]
    friction_xy : array_like, shape (N, 2)

    Returns
    -------
    factor : float
        ``inf`` for ``B = 0`` or zero friction.
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
    S = A - B @ sla.cho_solve(sla.cho_factor(C), B.T)
    S = 0.5 * (S + S.T)
    s = float(sla.eigvalsh(S, subset_by_index=[0, 0])[0])
    FCF = fmax[:, None] * C * fmax[None, :]
    c = float(sla.eigvalsh(0.5 * (FCF + FCF.T), subset_by_index=[C.shape[0] - 1,
                                                                  C.shape[0] - 1])[0])
    if s <= 0:
        return 0.0, False, "sufficient-bound-3d"
    return 2.0 * float(np.sqrt(s / c)), False, "sufficient-bound-3d"


__all__ = ["sufficient_factor_3d", "critical_friction_3d"]
