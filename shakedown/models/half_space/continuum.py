"""Continuum references for a sphere on a flat (two half-spaces), MODEL.md s.8.5.

Hertz (Johnson, *Contact Mechanics*, 1985, eqs. 4.22-4.23; ``R`` the relative radius,
``1/E* = sum (1 - nu_k^2)/E_k``)::

    a = (3 P R / (4 E*))^(1/3),   p0 = 3 P / (2 pi a^2),   delta = a^2 / R,
    p(rho) = p0 sqrt(1 - rho^2 / a^2)

Cattaneo-Mindlin (Johnson s.7.2, eqs. 7.40-7.50), ``Q`` increased monotonically at constant
``P`` with ``|Q| < f P``: stick radius ``c = a (1 - Q / (f P))^(1/3)`` and tangential compliance
``delta_t(Q) = (3 f P C_t / (16 a)) [1 - (1 - Q/(f P))^(2/3)]``, ``C_t = sum (2 - nu_k)/G_k``.
Mindlin-Deresiewicz (1953; Johnson eqs. 7.55-7.58): under ``Q`` between ``+-Q*`` the unloading
and reloading branches are the loading curve scaled by two (Masing), and the energy dissipated
per cycle is::

    W = (9 (f P)^2 C_t / (10 a)) [1 - (1 - X)^(5/3) - (5 X / 6)(1 + (1 - X)^(2/3))],  X = Q*/(f P)
      ~ C_t Q*^3 / (36 a f P)      (X -> 0, the cubic law)

Where these are approximate.  Mindlin assumes the shear tractions stay parallel to ``Q``
(``q = q(rho) e_x``); with Cerruti's kernel this leaves a small transverse slip unless
``nu = 0`` in both bodies, where the tangential kernel equals the normal one (``b = 0`` in
:mod:`.influence`) and the Ciavarella-Jager superposition makes the solution exact (Munisamy,
Hills & Nowell 1994 quantify the error for ``nu != 0``: a slightly elliptical stick zone).
Dissimilar materials (``beta != 0``) couple ``p`` and ``q`` and none of these formulas applies.
"""

from __future__ import annotations

import numpy as np

from ...model import InputError, citations


def hertz_radius(P, radius, e_star):
    """Hertz contact radius ``a = (3 P R / (4 E*))^(1/3)`` [length]."""
    return np.cbrt(3.0 * np.asarray(P, float) * radius / (4.0 * e_star))


def hertz_peak_pressure(P, radius, e_star):
    """Hertz peak pressure ``p0 = 3 P / (2 pi a^2)`` [force/length^2]."""
    a = hertz_radius(P, radius, e_star)
    return 3.0 * np.asarray(P, float) / (2.0 * np.pi * a * a)


def hertz_approach(P, radius, e_star):
    """Hertz approach of distant points ``delta = a^2 / R`` [length]."""
    return hertz_radius(P, radius, e_star) ** 2 / radius


def hertz_pressure(rho, P, radius, e_star):
    """Hertz pressure ``p0 sqrt(1 - rho^2 / a^2)`` at radius ``rho`` [force/length^2]."""
    a = hertz_radius(P, radius, e_star)
    return hertz_peak_pressure(P, radius, e_star) * np.sqrt(
        np.clip(1.0 - (np.asarray(rho, float) / a) ** 2, 0.0, None))


def _ratio(Q, P, friction):
    X = np.abs(np.asarray(Q, float)) / (friction * np.asarray(P, float))
    if np.any(X > 1):
        raise InputError(f"|Q| must be <= f P for partial slip; got Q = {Q}, f P = {friction * P}")
    return X


def cattaneo_mindlin_radius(Q, P, friction, a):
    """Stick radius ``c = a (1 - |Q| / (f P))^(1/3)`` [length] (monotonic ``Q``, constant ``P``)."""
    citations.register("cattaneo1938", "mindlin1949")
    return a * np.cbrt(1.0 - _ratio(Q, P, friction))


def tangential_compliance_constant(materials):
    """``C_t = sum (2 - nu_k) / G_k = sum 2 (2 - nu_k)(1 + nu_k) / E_k`` [length^2/force]."""
    out = 0.0
    for E, nu in materials:
        E = float(E)
        if not np.isinf(E):
            out += 2.0 * (2.0 - nu) * (1.0 + nu) / E
    return out


def mindlin_displacement(Q, P, friction, a, c_t):
    """Tangential approach ``delta_t(Q)`` on first loading [length] (Johnson eq. 7.50)."""
    citations.register("mindlin1949")
    X = _ratio(Q, P, friction)
    return np.sign(Q) * 3.0 * friction * P * c_t / (16.0 * a) * (1.0 - (1.0 - X) ** (2.0 / 3.0))


def mindlin_deresiewicz_loop(Q_amplitude, P, friction, a, c_t, n: int = 201):
    """The steady hysteresis loop under ``Q`` between ``-Q*`` and ``Q*`` (Masing from eq. 7.50).

    Returns ``(Q_down, d_down, Q_up, d_up)``, each shape (n,): the unloading branch from
    ``(Q*, delta*)`` to ``(-Q*, -delta*)`` and the reloading branch back [force, length].
    """
    Qs = float(Q_amplitude)
    ds = float(mindlin_displacement(Qs, P, friction, a, c_t))
    Qd = np.linspace(Qs, -Qs, n)
    dd = ds - 2.0 * mindlin_displacement((Qs - Qd) / 2.0, P, friction, a, c_t)
    return Qd, dd, -Qd, -dd


def mindlin_deresiewicz_dissipation(Q_amplitude, P, friction, a, c_t):
    """Energy dissipated per cycle ``W`` (Johnson eq. 7.58 with ``C_t``) [force x length]."""
    citations.register("mindlin1949")
    X = _ratio(Q_amplitude, P, friction)
    fP = friction * np.asarray(P, float)
    return 0.9 * fP**2 * c_t / a * (1.0 - (1.0 - X) ** (5.0 / 3.0)
                                    - (5.0 * X / 6.0) * (1.0 + (1.0 - X) ** (2.0 / 3.0)))


def mindlin_cubic_dissipation(Q_amplitude, P, friction, a, c_t):
    """Small-amplitude law ``W ~ C_t Q*^3 / (36 a f P)`` [force x length]."""
    return c_t * np.abs(np.asarray(Q_amplitude, float)) ** 3 / (36.0 * a * friction * np.asarray(P, float))
