"""Exact influence coefficients of piecewise-constant surface tractions on two half-planes.

Geometry and signs (MODEL.md s.1, s.6).  Body 1 occupies ``y > 0``, body 2 ``y < 0``; the
common surface is ``y = 0`` and ``x`` runs left to right.  The window ``[-L, L]`` is cut into
``N`` cells of width ``h = 2 L / N`` centred at ``x_j``.  On cell ``j`` body 2 exerts on body 1
a uniform pressure ``p_j / h`` (compression positive) and a uniform shear ``q_j / h`` in ``+x``;
``q_j, p_j`` are forces per unit thickness.  The work-conjugate displacements are the cell
means of the slip ``v = u_x^(1) - u_x^(2)`` and of the gap ``w = g - d + u_y^(1) - u_y^(2)``.

Surface displacements of a half-plane under a line load (Johnson, *Contact Mechanics*, 1985,
eqs. 2.19-2.20; ``z`` into the solid): a normal load ``P`` gives
``u_z = -(2 (1 - nu^2) / (pi E)) P ln|x| + const``, ``u_x = -k P sgn(x)``; a tangential load ``Q``
gives ``u_x = -(2 (1 - nu^2) / (pi E)) Q ln|x| + const``, ``u_z = +k Q sgn(x)``, with
``k = (1 - 2 nu)(1 + nu) / (2 E)``.  Adding the two bodies (body 2 carries ``-q``)::

    v(x) = s + (1/E*) int [ -(2/pi) ln|x - s| q(s) - beta sgn(x - s) p(s) ] ds      (1)
    w(x) = g(x) - d + (1/E*) int [ -(2/pi) ln|x - s| p(s) + beta sgn(x - s) q(s) ] ds   (2)

with ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` and Dundurs' ``beta = E* (k1 - k2)``
(``= [mu2 (kappa1 - 1) - mu1 (kappa2 - 1)] / [mu2 (kappa1 + 1) + mu1 (kappa2 + 1)]``,
``kappa = 3 - 4 nu``).  ``s`` (tangential shift) and ``d`` (approach) are rigid-body unknowns.

Cell means of (1)-(2) under piecewise-constant tractions are double integrals of the kernels
over two cells, exact in closed form: for a kernel ``k(u)`` with ``Phi'' = k``,
``int_cell_i int_cell_j k(x - s) ds dx = Phi(d + h) - 2 Phi(d) + Phi(d - h)``, ``d = x_i - x_j``;
``Phi(u) = u^2 ln|u| / 2 - 3 u^2 / 4`` for ``ln|u|`` and ``Psi(u) = u |u| / 2`` for ``sgn(u)``.
The log kernel depends on the length unit only through a constant times ``1 1^T``, which the
rigid-body unknowns absorb (see :mod:`.model`).
"""

from __future__ import annotations

import numpy as np


def _phi_log(u):
    """``u^2 ln|u| / 2 - 3 u^2 / 4`` (0 at 0): second antiderivative of ``ln|u|``."""
    u = np.asarray(u, float)
    au = np.abs(u)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(au > 0, 0.5 * u * u * np.log(np.where(au > 0, au, 1.0)) - 0.75 * u * u, 0.0)
    return out


def _psi_sign(u):
    """``u |u| / 2``: second antiderivative of ``sgn(u)``."""
    u = np.asarray(u, float)
    return 0.5 * u * np.abs(u)


def cell_kernels(n_cells: int, h: float):
    """Cell-averaged log and sign kernels, shape (N, N) each, for unit cell *forces*.

    ``G[i, j] = (1/h^2) int_i int_j ln(|x - s| / h) ds dx`` (dimensionless: lengths in units of
    ``h``) and ``S[i, j] = (1/h^2) int_i int_j sgn(x - s) ds dx`` (antisymmetric, 0 on the
    diagonal).  A unit force spread over cell ``j`` (traction ``1/h``) thus produces mean
    displacements ``-(2 / (pi E*)) G`` and ``beta / E* * S`` in (1)-(2), up to a constant.
    """
    d = np.arange(n_cells)[:, None] - np.arange(n_cells)[None, :]  # (x_i - x_j) / h
    d = d.astype(float)
    G = _phi_log(d + 1.0) - 2.0 * _phi_log(d) + _phi_log(d - 1.0)
    S = _psi_sign(d + 1.0) - 2.0 * _psi_sign(d) + _psi_sign(d - 1.0)
    return G, S


def compliance(n_cells: int, h: float, e_star: float, beta: float) -> np.ndarray:
    """Full cell compliance ``F``, shape (2N, 2N), ordered ``(q_1..q_N, p_1..p_N)``.

    Mean displacements ``(v, w) = (s 1, g - d 1) + F (q, p)`` [length per force per unit
    thickness], eqs. (1)-(2) up to the rigid-body constant ``(ln h) 1 1^T`` absorbed by ``s, d``.
    Symmetric (Betti): the coupling blocks are ``-beta S / E*`` and ``(-beta S / E*)^T``.
    """
    G, S = cell_kernels(n_cells, h)
    L = -(2.0 / (np.pi * e_star)) * G
    cpl = (beta / e_star) * S  # w due to q; v due to p is its transpose (S antisymmetric)
    return np.block([[L, cpl.T], [cpl, L]])
