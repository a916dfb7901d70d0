"""Analytic reference: the infinite layer of seed 001 (Agwa & Pinto da Costa 2007).

A layer ``0 <= y <= h`` (plane strain, homogeneous, in-plane stiffness ``D`` in Voigt order
``(xx, yy, xy)``), top ``y = h`` fixed, bottom ``y = 0`` on a rigid obstacle, every bottom
point in impending slip with direction ``chi`` (tangent ``+x``, normal ``+y`` into the body as
in MODEL.md s.1).  For the *uniform* mode ``u = U(y) e^(lam t)`` (no ``x`` dependence,
``eps_xx = 0``) the stresses on ``y``-faces are

    (sig_xy, sig_yy) = Dm U',   Dm = [[D44, D24], [D24, D22]],   (D44 = D[2,2], D24 = D[1,2])

and the momentum balance is the 2x2 ODE ``Dm U'' = rho lam^2 U`` with ``U(h) = 0``.  With
``Dm = E diag(d) E^T`` the solution is ``U(y) = sum_i a_i e_i sinh(k_i (h - y))``,
``k_i = sqrt(rho s / d_i)``, ``s = lam^2``, and the bottom reactions per unit area
``(q, p) = -(sig_xy, sig_yy)(0)`` follow from the bottom displacement ``U(0)`` through the
*layer dynamic stiffness*

    Z(s) = E diag(d_i k_i coth(k_i h)) E^T     (Z(0) = Dm / h).

The bottom stays closed (``u_y(0) = 0``) and slips (``x = chi u_x(0) > 0``) with
``y = chi q' + mu p' = 0``: ``(Z_xx + mu chi Z_yx) x = 0``, hence

    mu(s) = -Z_xx(s) / (chi Z_xy(s)),   mu_cr = mu(0) = D44 / |D24|  (chi = -sign(D24)),

the seed's formula; an isotropic layer has ``D24 = 0``: never unstable.  The growth rates at a
given ``mu`` are the roots ``lam`` of ``mu(lam^2) = mu`` (a transcendental equation through the
``coth``).  Seed 001 does not give ``h`` and ``rho``; ``lam`` scales as ``sqrt(d / rho) / h``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..model import citations
from ..model.errors import InputError
from ..model.validation import check_positive, check_stiffness, real_array


def _Dm(D):
    D = real_array("D", D)
    if D.shape != (3, 3):
        raise InputError(f"D must be the (3, 3) in-plane stiffness (xx, yy, xy); got {D.shape}")
    D = check_stiffness("D", D)
    return np.array([[D[2, 2], D[1, 2]], [D[1, 2], D[1, 1]]])


def layer_critical_friction(D) -> tuple[float, float]:
    """``(mu_cr, chi)``: ``D44 / |D24|`` and the unstable slip direction ``-sign(D24)``.

    ``(inf, 0)`` when ``D24 = 0`` (e.g. isotropic).
    """
    citations.register("agwa2007")
    Dm = _Dm(D)
    if abs(Dm[0, 1]) <= 1e-14 * np.abs(Dm).max():
        return float("inf"), 0.0
    return float(Dm[0, 0] / abs(Dm[0, 1])), float(-np.sign(Dm[0, 1]))


def layer_dynamic_stiffness(D, s: float, height: float = 1.0, density: float = 1.0):
    """``Z(s)`` (2x2, per unit area, order (tangential, normal)) of the layer's bottom face."""
    Dm = _Dm(D)
    height = check_positive("height", height, unit=" [length]")
    density = check_positive("density", density, unit=" [mass / volume]")
    if not (np.isfinite(s) and s >= 0):
        raise InputError(f"s = lam^2 must be finite and >= 0; got {s}")
    if s == 0:
        return Dm / height
    d, E = np.linalg.eigh(Dm)
    k = np.sqrt(density * s / d)
    kh = k * height
    coth = np.where(kh > 20, 1.0, 1.0 / np.tanh(np.minimum(kh, 20) + (kh > 20)))
    return (E * (d * k * coth)) @ E.T


def layer_mu(D, lam, chi: float, height: float = 1.0, density: float = 1.0) -> np.ndarray:
    """``mu(lam) = -Z_xx / (chi Z_xy)`` for the uniform mode (``nan`` where not positive)."""
    lam = np.atleast_1d(np.asarray(lam, dtype=float))
    out = np.full(lam.shape, np.nan)
    for i, L in enumerate(lam):
        Z = layer_dynamic_stiffness(D, L * L, height, density)
        if chi * Z[0, 1] < 0:
            out[i] = -Z[0, 0] / (chi * Z[0, 1])
    return out


def layer_growth_rates(D, mu: float, *, chi: float | None = None, height: float = 1.0,
                       density: float = 1.0, lam_max: float | None = None,
                       n_scan: int = 2000) -> np.ndarray:
    """All growth rates ``lam >= 0`` of the uniform mode at friction ``mu`` (roots of
    ``mu(lam) = mu`` on ``[0, lam_max]``, scanned on ``n_scan`` points, refined by Brent).

    ``chi`` defaults to the unstable direction ``-sign(D24)``; ``lam_max`` to
    ``50 sqrt(max d / rho) / h``.
    """
    citations.register("agwa2007")
    mu_cr, chi0 = layer_critical_friction(D)
    if chi is None:
        chi = chi0
    if chi == 0:
        return np.zeros(0)
    Dm = _Dm(D)
    if lam_max is None:
        lam_max = 50.0 * np.sqrt(np.linalg.eigvalsh(Dm).max() / density) / height
    grid = np.linspace(0.0, lam_max, n_scan)
    f = layer_mu(D, grid, chi, height, density) - mu
    roots = []
    for a, b, fa, fb in zip(grid[:-1], grid[1:], f[:-1], f[1:], strict=True):
        if np.isfinite(fa) and np.isfinite(fb) and fa * fb <= 0 and fa != fb:
            roots.append(brentq(lambda L: layer_mu(D, L, chi, height, density)[0] - mu, a, b,
                                xtol=1e-14 * lam_max, rtol=1e-14))
    # a root found from both sides of a grid point counts once (relative to the range scanned)
    roots = np.sort(np.array(roots))
    return roots[np.concatenate([[True], np.diff(roots) > 1e-12 * lam_max])] if roots.size \
        else roots
