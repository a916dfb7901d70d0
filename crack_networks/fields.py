"""Closed-form elastic field of a straight crack loaded by face tractions (plane strain).

Conventions (MODEL.md s.6)
--------------------------
Stresses are tension positive.  A crack has centre ``c``, half-length ``a`` and angle ``alpha``
from the x axis; tangent ``t = (cos alpha, sin alpha)``, normal ``n = (-sin alpha, cos alpha)``
(``t`` rotated by +90 degrees).  The displacement discontinuity is ``[u] = u(+) - u(-)``, the
``+`` face being on the ``n`` side: opening ``n.[u]``, slip ``t.[u]``.

Unit loads (Kachanov 1987)
--------------------------
"Crack ``j`` carries a uniform face traction ``s = (s_n, s_t)``" means: the crack opens and slips
as the isolated crack under a remote stress with ``n.S.n = s_n`` and ``t.S.n = s_t``, and the
field it produces is that solution *minus* the remote stress (the perturbation, vanishing at
infinity).  On its own faces the perturbation stress is ``-s`` and the displacement discontinuity
is elliptical,

    n.[u] = 2 (1 - nu) s_n sqrt(a^2 - x^2) / mu,  mean  c s_n,  c = pi a (1 - nu) / (2 mu)

(same for the slip with ``s_t``).  A positive ``s_n`` opens the crack, a positive ``s_t`` moves
the ``+`` face along ``+t``.

Higher modes (used by :mod:`crack_networks.bem`): mode ``k >= 0`` of crack ``j`` is the crack
whose faces carry the perturbation stress ``-U_k(x / a)`` (Chebyshev polynomial of the second
kind) in one component; its discontinuity is ``2 (1 - nu) a / (mu (k + 1)) sqrt(1 - x^2/a^2)
U_k(x / a)``, whose mean is zero for ``k >= 1``.  Mode 0 is the uniform load above.

Formulas
--------
In the crack's frame with ``zeta = (z - c) exp(-i alpha) / a`` and ``R = sqrt(zeta^2 - 1)``
(branch cut on the crack, ``R ~ zeta`` at infinity), the Westergaard function of mode ``k`` is

    Z_k = (zeta - R)^(k+1) / R,      Z_k' = -(zeta - R)^(k+1) ((k + 1) R + zeta) / R^3

(``zeta - R = 1 / (zeta + R)`` is used to avoid cancellation far away).  On the faces
``Re Z_k = -U_k``.  With ``eta = Im zeta``:

* normal (mode I):  ``sxx = Re Z - eta Im Z'``, ``syy = Re Z + eta Im Z'``, ``sxy = -eta Re Z'``;
* shear (mode II):  ``sxx = 2 Im Z + eta Re Z'``, ``syy = -eta Re Z'``, ``sxy = Re Z - eta Im Z'``.

Segment averages in closed form: with Kolosov-Muskhelishvili potentials ``phi``, ``psi`` the
force across an arc from ``A`` to ``B`` is ``-i [phi + z conj(phi') + conj(psi)]_A^B`` (Muskhelishvili
s.33), the normal of the arc pointing to the *right* of the direction of travel.  For mode 0
(``z = a zeta`` in the crack frame):

* normal: ``phi = a (R - zeta) / 2``, ``phi' = Z / 2``, ``psi = -a / (2 R)``;
* shear:  ``phi = -i a (R - zeta) / 2``, ``phi' = -i Z / 2``, ``psi = i a (R - zeta) + i a / (2 R)``.

The potentials are single valued outside the cut (the face loads are self-equilibrated), so the
average traction on a segment that does not meet the crack is exact to rounding, however close
the segment passes to a tip.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "crack_stress",
    "mode_stress_local",
    "segment_average_traction",
    "isolated_compliance",
]


def isolated_compliance(half_length, shear_modulus: float, poisson_ratio: float):
    """Mean displacement discontinuity per unit uniform face traction of an isolated crack.

    ``c = pi a (1 - nu) / (2 mu)`` (plane strain) [length / stress], shape of ``half_length``.
    """
    a = np.asarray(half_length, dtype=float)
    return np.pi * a * (1.0 - poisson_ratio) / (2.0 * shear_modulus)


def _root(zeta):
    """``R = sqrt(zeta - 1) sqrt(zeta + 1)``: cut on [-1, 1], ``R ~ zeta`` at infinity."""
    return np.sqrt(zeta - 1.0) * np.sqrt(zeta + 1.0)


def _to_local(points, centre, half_length, angle):
    z = np.asarray(points[..., 0], float) + 1j * np.asarray(points[..., 1], float)
    c = centre[..., 0] + 1j * centre[..., 1]
    return (z - c) * np.exp(-1j * angle) / half_length


def mode_stress_local(zeta, n_modes: int = 1):
    """Local stresses of the first ``n_modes`` unit modes at normalised points ``zeta``.

    Parameters
    ----------
    zeta : complex ndarray, shape S
        Points in the crack frame divided by the half-length (not on the cut).
    n_modes : int
        Number of Chebyshev modes ``k = 0 .. n_modes - 1``.

    Returns
    -------
    ndarray, shape S + (n_modes, 2, 3)
        ``[..., k, d, :]`` = ``(sxx, sxy, syy)`` in the crack frame for mode ``k`` of component
        ``d`` (0 = normal load, 1 = shear load), per unit load (dimensionless).
    """
    zeta = np.asarray(zeta, dtype=complex)
    R = _root(zeta)
    w = 1.0 / (zeta + R)  # = zeta - R
    eta = zeta.imag[..., None]
    k1 = np.arange(1, n_modes + 1)
    wk = np.cumprod(np.broadcast_to(w[..., None], w.shape + (n_modes,)), axis=-1)  # w^(k+1)
    Rm = R[..., None]
    Z = wk / Rm
    dZ = -wk * (k1 * Rm + zeta[..., None]) / Rm**3
    out = np.empty(zeta.shape + (n_modes, 2, 3))
    out[..., 0, 0] = Z.real - eta * dZ.imag
    out[..., 0, 1] = -eta * dZ.real
    out[..., 0, 2] = Z.real + eta * dZ.imag
    out[..., 1, 0] = 2.0 * Z.imag + eta * dZ.real
    out[..., 1, 1] = Z.real - eta * dZ.imag
    out[..., 1, 2] = -eta * dZ.real
    return out


def _rotate_stress(s_local, angle):
    """Rotate ``(sxx, sxy, syy)`` from a frame at ``angle`` to the global frame."""
    c, s = np.cos(angle), np.sin(angle)
    xx, xy, yy = s_local[..., 0], s_local[..., 1], s_local[..., 2]
    gxx = c * c * xx - 2 * c * s * xy + s * s * yy
    gyy = s * s * xx + 2 * c * s * xy + c * c * yy
    gxy = c * s * (xx - yy) + (c * c - s * s) * xy
    return np.stack([gxx, gxy, gyy], axis=-1)


def crack_stress(points, centre, half_length, angle, load=(1.0, 0.0)):
    """Perturbation stress of one crack carrying a uniform face traction, at given points.

    Parameters
    ----------
    points : array_like, shape (..., 2)
        Field points (global coordinates) [length]; not on the crack itself.
    centre : array_like, shape (2,)
    half_length : float
    angle : float
        Crack angle from the x axis [rad].
    load : (float, float)
        Uniform face traction ``(s_n, s_t)`` in Kachanov's sense (module docstring) [stress].

    Returns
    -------
    ndarray, shape (..., 3)
        ``(sxx, sxy, syy)`` in global axes [stress], tension positive.

    Examples
    --------
    >>> import numpy as np
    >>> s = crack_stress(np.array([[2.0, 0.0]]), (0.0, 0.0), 1.0, 0.0, load=(1.0, 0.0))
    >>> bool(np.isclose(s[0, 2], 2 / np.sqrt(3) - 1))   # syy = x / sqrt(x^2 - a^2) - 1
    True
    """
    pts = np.asarray(points, dtype=float)
    zeta = _to_local(pts, np.asarray(centre, float), float(half_length), float(angle))
    modes = mode_stress_local(zeta, 1)[..., 0, :, :]  # (..., 2, 3)
    sn, st = load
    local = sn * modes[..., 0, :] + st * modes[..., 1, :]
    return _rotate_stress(local, float(angle))


def _potential_combination(zeta):
    """``phi + z conj(phi') + conj(psi)`` divided by ``a`` for mode 0, normal and shear."""
    R = _root(zeta)
    w = 1.0 / (zeta + R)  # zeta - R
    Z = w / R
    cZ, cw, cRi = np.conj(Z), np.conj(w), np.conj(1.0 / R)
    f_n = -0.5 * w + 0.5 * zeta * cZ - 0.5 * cRi
    f_t = 0.5j * w + 0.5j * zeta * cZ + 1j * cw - 0.5j * cRi
    return f_n, f_t


def segment_average_traction(
    src_centre, src_half_length, src_angle, seg_centre, seg_half_length, seg_angle
):
    """Average traction on target segments from unit uniform loads on source cracks (closed form).

    All arguments broadcast together (source ``j``: ``src_*``; target line ``i``: ``seg_*``;
    centres with a trailing axis of 2).

    Returns
    -------
    ndarray, shape (..., 2, 2)
        ``[..., r, d]``: average over the target segment of its normal (``r = 0``, ``n.S.n``)
        or shear (``r = 1``, ``t.S.n``) traction (tension positive, target frame) caused by a
        unit uniform load of component ``d`` (0 normal, 1 shear) on the source crack.  Exact
        (up to rounding) when the segment does not meet the source crack.
    """
    cj = np.asarray(src_centre, float)
    aj = np.asarray(src_half_length, float)
    alj = np.asarray(src_angle, float)
    ci = np.asarray(seg_centre, float)
    ai = np.asarray(seg_half_length, float)
    ali = np.asarray(seg_angle, float)
    ti = np.exp(1j * ali)
    zc = ci[..., 0] + 1j * ci[..., 1]
    rot = np.exp(-1j * alj)
    cjz = cj[..., 0] + 1j * cj[..., 1]
    zA = (zc - ai * ti - cjz) * rot / aj
    zB = (zc + ai * ti - cjz) * rot / aj
    fA_n, fA_t = _potential_combination(zA)
    fB_n, fB_t = _potential_combination(zB)
    # force across the segment (normal to the right of A->B, i.e. -n_i), source frame, / a_j
    back = np.exp(1j * alj) * aj / (2.0 * ai)
    # average traction on the n_i side convention: T = sigma . n_i = -F / (2 a_i)
    T_n = 1j * (fB_n - fA_n) * back
    T_t = 1j * (fB_t - fA_t) * back
    ni = 1j * ti
    out = np.empty(np.broadcast(zA, zB).shape + (2, 2))
    for d, T in enumerate((T_n, T_t)):
        out[..., 0, d] = (T * np.conj(ni)).real
        out[..., 1, d] = (T * np.conj(ti)).real
    return out
