"""Influence coefficients of uniform tractions on square cells of two elastic half-spaces.

Geometry and signs (MODEL.md s.8, s.8.5).  Body 1 lies above the common surface ``z = 0``,
body 2 below.  The window is cut into square cells of side ``h``; on cell ``j`` body 2 exerts on
body 1 uniform tractions ``(q_jx, q_jy) / h^2`` (shear) and ``p_j / h^2`` (pressure,
compression positive); body 2 carries the opposite tractions.  The work-conjugate displacements
are the cell *means* of the slip ``v = u_t^(1) - u_t^(2)`` and of the gap
``w = g - d + u_n^(1) + u_n^(2)`` (``u_n`` into each body).

Point-load solutions on a half-space (Johnson, *Contact Mechanics*, 1985, eqs. 3.19 and 3.22,
Boussinesq and Cerruti; ``G`` shear modulus, ``r`` distance from the load): a normal load ``P``
gives ``u_n = (1 - nu) P / (2 pi G r)`` and a radial displacement ``-(1 - 2 nu) P / (4 pi G r)``
toward the load; a tangential load ``Q`` along ``x`` gives
``u_x = Q / (4 pi G) [2 (1 - nu) / r + 2 nu x^2 / r^3]``, ``u_y = Q / (4 pi G) 2 nu x y / r^3``,
``u_n = (1 - 2 nu) Q x / (4 pi G r^2)`` (the last by Betti from the radial one).  Adding the two
bodies, for a unit force at the origin and a field point ``(x, y)``::

    v_x = (1/(pi E*)) / r + (b / 2 pi) x^2 / r^3     v_y = (b / 2 pi) x y / r^3   (q_x = 1)
    w   = (1/(pi E*)) / r                              (p = 1)
    w   = +(beta / (pi E*)) x / r^2   (q_x = 1),       v = -(beta / (pi E*)) (x, y) / r^2   (p = 1)

with ``1/E* = sum (1 - nu_k^2)/E_k``, ``b = sum nu_k / G_k`` and Dundurs'
``beta = E* [(1 - 2 nu_1)/(4 G_1) - (1 - 2 nu_2)/(4 G_2)]`` (the 2-D value of
:mod:`shakedown.models.half_plane`; ``beta = 0`` for similar materials: uncoupled).

Cell means in closed form
-------------------------
Uniform traction on cell ``j`` and the mean over cell ``i`` give ``(1/h^4) int_i int_j k(x - s)``,
a function of the offset ``d = x_i - x_j`` only: the kernel against the separable tent (the
convolution of two cells).  For ``Phi`` with ``d_x^2 d_y^2 Phi = k`` it is the double second
difference ``(1/h^4) D_x^2 D_y^2 Phi(d)`` (``D^2 f(u) = f(u + h) - 2 f(u) + f(u - h)``), the 3-D
counterpart of the half-plane formula.  The kernels are derivatives of ``r`` and ``ln r``
(``x^2/r^3 = d_y^2 r``, ``x y/r^3 = -d_x d_y r``, ``x/r^2 = d_x ln r``), whence (terms affine in
``x`` or in ``y`` are dropped: the differences annihilate them)::

    Phi[x^2/r^3] = r^3/6 + (y^2/2) (x asinh(x/|y|) - r)
    Phi[x y/r^3] = -[x y r/3 + (y^3/6) asinh(x/|y|) + (x^3/6) asinh(y/|x|)]
    Phi[1/r]     = Phi[x^2/r^3] + Phi[y^2/r^3]
    Phi[x/r^2]   = -(x^2 |y|/2) atan(x/|y|) + (|y|^3/6) atan(x/|y|)
                   + (x y^2/4 - x^3/12) ln(x^2 + y^2) + (pi/4) x |x| |y|

(obtained with sympy and checked against brute-force quadrature in ``tests/models/
test_half_space_influence.py``; the ``1/r`` case is the cell mean of Love's (1929) rectangle
solution).  The kernels are homogeneous of degree ``-1``, so the coefficients are those of
``h = 1`` divided by ``h``.  The differences of ``Phi ~ r^3`` lose ``~ eps d^4`` relative
accuracy at offsets ``d`` (in cells); beyond ``FAR`` cells the tent integral is instead
evaluated by Gauss-Legendre quadrature (``2 x 6`` points per direction, error
``< (1 / 2 FAR)^12 ~ 1e-16`` relative, the kernel being analytic within ``d - 1`` cells), so every
coefficient is accurate to about ``1e-12`` of the largest one (the self-coefficient;
measured: ``1.1e-13``).
"""

from __future__ import annotations

import numpy as np

#: Offsets (in cells, max norm) from which the tent integral is done by quadrature.
FAR = 12
_GX, _GW = np.polynomial.legendre.leggauss(6)


def _asinh_ratio(a, b):
    """``asinh(a / |b|)`` with the limit 0 where ``b = 0`` (it is always multiplied by ``b^k``)."""
    ab = np.abs(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ab > 0, np.arcsinh(a / np.where(ab > 0, ab, 1.0)), 0.0)


def _phi_xx(x, y):
    """Fourth antiderivative of ``x^2 / r^3`` (``d_x^2 d_y^2 Phi = x^2/r^3``)."""
    r = np.hypot(x, y)
    return r**3 / 6 + 0.5 * y * y * (x * _asinh_ratio(x, y) - r)


def _phi_xy(x, y):
    """Fourth antiderivative of ``x y / r^3``."""
    r = np.hypot(x, y)
    return -(x * y * r / 3 + y**3 / 6 * _asinh_ratio(x, y) + x**3 / 6 * _asinh_ratio(y, x))


def _phi_x_r2(x, y):
    """Fourth antiderivative of ``x / r^2``."""
    ay = np.abs(y)
    r2 = x * x + y * y
    with np.errstate(divide="ignore", invalid="ignore"):
        at = np.where(ay > 0, np.arctan(x / np.where(ay > 0, ay, 1.0)), 0.5 * np.pi * np.sign(x))
        lg = np.where(r2 > 0, np.log(np.where(r2 > 0, r2, 1.0)), 0.0)
    return (-0.5 * x * x * ay * at + ay**3 / 6 * at + (x * y * y / 4 - x**3 / 12) * lg
            + 0.25 * np.pi * x * np.abs(x) * ay)


_PHI = {
    "xx": _phi_xx,
    "yy": lambda x, y: _phi_xx(y, x),
    "xy": _phi_xy,
    "inv_r": lambda x, y: _phi_xx(x, y) + _phi_xx(y, x),
    "x_r2": _phi_x_r2,
    "y_r2": lambda x, y: _phi_x_r2(y, x),
}

_KERNEL = {
    "xx": lambda x, y: x * x / np.hypot(x, y) ** 3,
    "yy": lambda x, y: y * y / np.hypot(x, y) ** 3,
    "xy": lambda x, y: x * y / np.hypot(x, y) ** 3,
    "inv_r": lambda x, y: 1.0 / np.hypot(x, y),
    "x_r2": lambda x, y: x / (x * x + y * y),
    "y_r2": lambda x, y: y / (x * x + y * y),
}

#: The kernel names: ``x^2/r^3``, ``y^2/r^3``, ``x y/r^3``, ``1/r``, ``x/r^2``, ``y/r^2``.
KERNELS = tuple(_KERNEL)


def _second_differences(phi, dx, dy):
    """``D_x^2 D_y^2 phi`` at offsets ``(dx, dy)`` (unit cells)."""
    out = np.zeros(np.broadcast(dx, dy).shape)
    for sx, cx in ((1, 1.0), (0, -2.0), (-1, 1.0)):
        for sy, cy in ((1, 1.0), (0, -2.0), (-1, 1.0)):
            out += cx * cy * phi(dx + sx, dy + sy)
    return out


def _tent_quadrature(kernel, dx, dy):
    """``int k(d + u) T(u_x) T(u_y) du`` by Gauss-Legendre on each half of the tent ``1 - |u|``."""
    # nodes on [0, 1] with the weight (1 - u): Gauss on [0, 1] times the linear weight (exact)
    u = 0.5 * (_GX + 1.0)
    w = 0.5 * _GW * (1.0 - u)
    nodes = np.concatenate([u, -u])
    weights = np.concatenate([w, w])
    out = np.zeros(np.broadcast(dx, dy).shape)
    for ux, wx in zip(nodes, weights, strict=True):
        for uy, wy in zip(nodes, weights, strict=True):
            out += wx * wy * kernel(dx + ux, dy + uy)
    return out


def cell_kernel(name: str, dx, dy):
    """Cell-mean kernel ``(1/h^4) int_i int_j k(x - s) ds dx`` for ``h = 1``, at integer offsets.

    Parameters
    ----------
    name : str
        One of :data:`KERNELS`.
    dx, dy : array_like of int
        Offsets ``x_i - x_j`` in cells (broadcast together).

    Returns
    -------
    ndarray
        The coefficients (multiply by ``1/h`` for cells of side ``h``).
    """
    dx = np.asarray(dx, float)
    dy = np.asarray(dy, float)
    dx, dy = np.broadcast_arrays(dx, dy)
    far = np.maximum(np.abs(dx), np.abs(dy)) >= FAR
    out = np.empty(dx.shape)
    near = ~far
    out[near] = _second_differences(_PHI[name], dx[near], dy[near])
    out[far] = _tent_quadrature(_KERNEL[name], dx[far], dy[far])
    return out


def material_constants(materials):
    """``(e_star, beta, b)`` of two bodies ``((E1, nu1), (E2, nu2))`` (``E = inf``: rigid).

    ``b = sum nu_k / G_k = sum 2 nu_k (1 + nu_k) / E_k`` [length^2/force] weights the
    ``x^2/r^3`` part of Cerruti's solution.  Validation is that of the half-plane model.
    """
    from ..half_plane.model import _materials

    e_star, beta = _materials(materials)
    (E1, nu1), (E2, nu2) = materials
    b = sum(0.0 if np.isinf(float(E)) else 2.0 * nu * (1.0 + nu) / float(E)
            for E, nu in ((E1, nu1), (E2, nu2)))
    return e_star, beta, b


def offset_kernels(n: int, h: float, e_star: float, beta: float, b: float) -> dict:
    """Influence of a unit cell force on the cell means, at every offset of an ``n x n`` grid.

    Returns a dict of arrays of shape ``(2n - 1, 2n - 1)`` indexed by ``(di + n - 1, dj + n - 1)``
    (``di``, ``dj`` offsets along ``x`` and ``y`` of the field cell from the loaded cell), in
    length per force: ``"xx"``, ``"xy"``, ``"yy"`` (slip due to shear), ``"zz"`` (gap due to
    pressure), ``"zx"``, ``"zy"`` (gap due to shear ``q_x``, ``q_y``; the slip due to pressure is
    ``-zx``, ``-zy``, by Betti).
    """
    d = np.arange(-(n - 1), n, dtype=float)
    dx, dy = np.meshgrid(d, d, indexing="ij")
    inv_r = cell_kernel("inv_r", dx, dy)
    c_n = 1.0 / (np.pi * e_star * h)
    c_b = b / (2.0 * np.pi * h)
    out = {
        "zz": c_n * inv_r,
        "xx": c_n * inv_r + c_b * cell_kernel("xx", dx, dy),
        "yy": c_n * inv_r + c_b * cell_kernel("yy", dx, dy),
        "xy": c_b * cell_kernel("xy", dx, dy),
    }
    c_c = beta / (np.pi * e_star * h)
    out["zx"] = c_c * cell_kernel("x_r2", dx, dy)
    out["zy"] = c_c * cell_kernel("y_r2", dx, dy)
    # exact parity (F symmetric to the last bit): even kernels, odd coupling kernels
    for k in ("zz", "xx", "yy", "xy"):
        out[k] = 0.5 * (out[k] + out[k][::-1, ::-1])
    for k in ("zx", "zy"):
        out[k] = 0.5 * (out[k] - out[k][::-1, ::-1])
    return out


def dense_compliance(kernels: dict, n: int) -> np.ndarray:
    """Dense cell compliance ``F``, shape (3N, 3N), ``N = n^2`` cells numbered ``i n + j``.

    Order of unknowns and forces (MODEL.md s.8): ``(v_1x, v_1y, ..., v_Nx, v_Ny, w_1, ..., w_N)``
    and ``(q_1x, q_1y, ..., p_1, ...)``; ``u = F r`` up to the rigid-body terms.  Symmetric.
    """
    N = n * n
    ii, jj = np.divmod(np.arange(N), n)
    DI = ii[:, None] - ii[None, :] + n - 1
    DJ = jj[:, None] - jj[None, :] + n - 1
    F = np.empty((3 * N, 3 * N))
    F[0:2 * N:2, 0:2 * N:2] = kernels["xx"][DI, DJ]
    F[1:2 * N:2, 1:2 * N:2] = kernels["yy"][DI, DJ]
    F[0:2 * N:2, 1:2 * N:2] = kernels["xy"][DI, DJ]
    F[1:2 * N:2, 0:2 * N:2] = kernels["xy"][DI, DJ]
    F[2 * N:, 2 * N:] = kernels["zz"][DI, DJ]
    F[2 * N:, 0:2 * N:2] = kernels["zx"][DI, DJ]
    F[2 * N:, 1:2 * N:2] = kernels["zy"][DI, DJ]
    F[0:2 * N:2, 2 * N:] = -kernels["zx"][DI, DJ]
    F[1:2 * N:2, 2 * N:] = -kernels["zy"][DI, DJ]
    return F
