"""Closed-form references for FE checks: the infinite layer's uniform modes (seed 001).

A layer of height ``h`` (``0 < y < h``) held at ``y = h``, its bottom displaced uniformly.
In the bottom frame of :mod:`shakedown.fe.condense` (``t = +x``, ``-n = +y``) the bottom
displacement is ``(u_x, u_y) = (v, w)`` and the reactions on the body are ``(q, p)``.
With ``d/dx = 0`` the fields depend on ``y`` only; the in-plane stresses on y-faces are
``(sig_xy, sig_yy) = Dt u'(y)`` with ``Dt = [[D44, D24], [D24, D22]]`` (plane strain or stress
``D`` in Voigt order), and the motion ``u e^(lam t)`` obeys ``Dt u'' = rho lam^2 u``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .materials import Material


def layer_uniform_stiffness(material: Material, height: float, s: float = 0.0) -> np.ndarray:
    """Reactions per unit length of the bottom of a layer for uniform ``(v, w)``, shape (2, 2).

    ``[q, p] = Z(s) [v, w]`` with ``Z(s) = Dt Kappa coth(Kappa h)``, ``Kappa = sqrtm(s rho Dt^-1)``
    (``s = lam^2 >= 0``); ``Z(0) = Dt / h``.  Hence ``mu_cr = Z_00 / |Z_01|`` at ``s = 0``
    (``D44 / |D24|``, seed 001) and the divergence condition of a layer whose bottom is in
    impending slip, ``chi Z_00(s) + mu Z_10(s) = 0``, for the uniform mode.

    Parameters
    ----------
    material : Material
    height : float
        Layer height ``h`` [length].
    s : float
        ``lam^2`` [1 / time^2] (``>= 0``).
    """
    D = material.D
    Dt = np.array([[D[2, 2], D[1, 2]], [D[1, 2], D[1, 1]]])
    h = float(height)
    if s == 0.0:
        return Dt / h
    Kap = np.real(sla.sqrtm(float(s) * material.density * np.linalg.inv(Dt)))
    coth = sla.coshm(Kap * h) @ np.linalg.inv(sla.sinhm(Kap * h))
    Z = Dt @ Kap @ coth
    return 0.5 * (Z + Z.T)
