"""Continuum reference for uncoupled (``beta = 0``) half-plane contact (seed ``002`` s.4.2).

Normal problem: Hertz (``a^2 = 4 P R / (pi E*)``, ``p = p0 sqrt(1 - x^2/a^2)``,
``p0 = 2 P / (pi a)``) and, for any symmetric convex profile, the half-width from the
bounded-pressure condition ``P(a) = (E*/2) int_{-a}^{a} x g'(x) / sqrt(a^2 - x^2) dx``
(Barber, *Contact Mechanics*, 2018, s.2.4).

Tangential problem: the Ciavarella-Jager superposition.  Every shear distribution reached by an
uncoupled half-plane contact is a superposition of normal pressures ``p(x; P')`` of smaller
loads::

    q(x, t) = int_0^{P(t)} rho(P', t) d/dP' p(x; P') dP',   |rho| <= f                (6)

(``rho = 1`` for all ``P' < P`` gives ``p`` itself).  Shell ``P'`` is the ring
``a(P'-) < |x| < a(P')``.  A slip zone ``a(P_c) < |x| < a(P)`` has ``rho = +-f`` on
``(P_c, P)``; a stick zone leaves ``rho`` unchanged (the increment of each shell produces no
displacement gradient inside it).  So the history is a one-dimensional Masing model in ``P'``
(:func:`shell_history`):

* shells leaving the contact (``dP < 0``) are forgotten;
* shells entering the contact (``dP > 0``) take ``rho = dQ/dP`` if ``|dQ/dP| <= f`` (no slip
  anywhere: the seed's condition (6)),
* otherwise the outermost shells ``(P_c, P)`` take ``rho = sigma f`` with ``P_c`` fixed by
  ``Q = int_0^P rho dP'``.

Cattaneo-Mindlin follows (``P_c = P - Q/f``, ``c/a = sqrt(1 - Q/(f P))`` for Hertz) and the seed's
tangent construction: the shells that never change in the steady cycle are
``P' < P_T = [min_t (f P + Q) + min_t (f P - Q)] / (2 f)``, the normal load at the point ``T``
where the tangents of slope ``-f`` and ``+f`` to the loading curve meet; ``A_T = a(P_T)``.

Dissipation: the tangential rigid shift of body 1 (measured at a stuck centre) is
``s = (2/(pi E*)) int ln|x| q dx = (2/(pi E*)) int rho(P') ln(a(P')/2) dP'``, because at fixed
contact width the pressure increment of *any* symmetric profile is the flat-punch distribution
``dp/dP' = 1/(pi sqrt(a'^2 - x^2))`` and ``int ln|x| dp/dP' dx = ln(a'/2)``; and
``W = closed integral of s dQ`` (the normal work is an exact differential when ``beta = 0``).
:func:`hertz_cycle` uses ``a ~ sqrt(P')`` in closed form, :func:`profile_cycle` a table of
``a(P')`` for any symmetric convex profile.
"""

from __future__ import annotations

import numpy as np

from ...model import InputError, citations


def hertz_half_width(P, radius, e_star):
    """Hertz half-width ``a = sqrt(4 P R / (pi E*))`` [length] (plane strain, per unit thickness)."""
    return np.sqrt(4.0 * np.asarray(P, float) * radius / (np.pi * e_star))


def hertz_pressure(x, P, radius, e_star):
    """Hertz pressure ``p0 sqrt(1 - x^2/a^2)``, ``p0 = 2 P/(pi a)`` [force/length^2]."""
    a = hertz_half_width(P, radius, e_star)
    return 2.0 * P / (np.pi * a) * np.sqrt(np.clip(1.0 - (np.asarray(x) / a) ** 2, 0.0, None))


def contact_load(a, gap_function, e_star, n_quad: int = 400):
    """Normal load ``P(a)`` of a symmetric convex profile for contact half-width ``a``."""
    th = (np.arange(n_quad) + 0.5) * np.pi / n_quad  # midpoint rule in theta, x = a cos(theta)
    x = a * np.cos(th)
    dx = 1e-6 * max(a, 1e-300)
    gp = (gap_function(x + dx) - gap_function(x - dx)) / (2 * dx)
    return 0.5 * e_star * float(np.sum(x * gp)) * np.pi / n_quad


def contact_half_width(P, gap_function, e_star, a_max):
    """Half-width ``a`` with ``contact_load(a) = P`` (bisection on ``(0, a_max]``)."""
    lo, hi = 0.0, float(a_max)
    if contact_load(hi, gap_function, e_star) < P:
        raise InputError(f"the contact for P = {P:g} is wider than a_max = {a_max:g}")
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if contact_load(mid, gap_function, e_star) < P else (lo, mid)
    return 0.5 * (lo + hi)


def cattaneo_mindlin_ratio(Q, P, friction):
    """Stick-zone ratio ``c/a = sqrt(1 - |Q|/(f P))`` (Hertz, monotonic ``Q`` at constant ``P``)."""
    citations.register("cattaneo1938", "mindlin1949")
    r = 1.0 - np.abs(Q) / (friction * P)
    if np.any(r < 0):
        raise InputError(f"|Q| must be <= f P for partial slip; got Q = {Q}, f P = {friction * P}")
    return np.sqrt(r)


def ellipse_construction(P0, P1, Q1, phase, friction, lam: float = 1.0):
    """The seed's tangent construction for ``P = P0 + lam P1 cos(2pi t + phase)``, ``Q = lam Q1 cos(2pi t)``.

    Returns a dict: ``P_T``, ``Q_T`` (the point ``T``), ``t_plus``, ``t_minus`` (times in cycles of
    the tangent points of slope ``+f`` and ``-f``, i.e. the minima of ``f P - Q`` and ``f P + Q``),
    ``min_fP_minus_Q``, ``min_fP_plus_Q``, and ``gross_slip`` (``|Q| >= f P`` somewhere).
    """
    citations.register("barber2011")
    f = float(friction)
    cP = lam * P1 * np.exp(1j * phase)
    out = {}
    for key, s in (("minus", -1.0), ("plus", 1.0)):
        c = f * cP + s * lam * Q1  # f P + s Q = f P0 + Re(c e^{2 pi i t})
        out[f"min_fP_{key}_Q"] = f * P0 - abs(c)
        out[f"t_{'plus' if s < 0 else 'minus'}"] = ((np.pi - np.angle(c)) / (2 * np.pi)) % 1.0
    a_m, a_p = out["min_fP_minus_Q"], out["min_fP_plus_Q"]
    out["P_T"] = (a_m + a_p) / (2 * f)
    out["Q_T"] = (a_p - a_m) / 2
    out["gross_slip"] = bool(min(a_m, a_p) <= 0)
    return out


class _Shells:
    """Piecewise-constant ``rho`` on ``[0, P]``: edges ``e`` (K+1,), values ``r`` (K,)."""

    def __init__(self):
        self.e = np.array([0.0])
        self.r = np.zeros(0)

    def Q(self):
        return float(np.sum(self.r * np.diff(self.e)))

    def truncate(self, P):
        """Forget the shells beyond ``P`` (they leave the contact)."""
        k = int(np.searchsorted(self.e, P, side="left"))  # e[k-1] < P <= e[k]
        self.e = np.append(self.e[:k], P)
        self.r = self.r[:k]

    def saturate(self, Q, sigma_f):
        """Set ``rho = sigma_f`` on ``(P_c, P)`` so that the total is ``Q``; return ``P_c``."""
        e, r = self.e, self.r
        cum = np.concatenate([[0.0], np.cumsum(r * np.diff(e))])  # int_0^{e_k} rho
        tot = cum + sigma_f * (e[-1] - e)  # resultant if the shells beyond e_k saturate
        s = np.sign(sigma_f)  # s * tot is non-increasing in k because |rho| <= f
        k = int(np.flatnonzero(s * tot >= s * Q - 1e-15 * abs(sigma_f) * e[-1])[-1])
        k = min(k, r.size - 1)
        slope = r[k] - sigma_f
        Pc = e[k] if slope == 0 else e[k] + (Q - tot[k]) / slope
        Pc = float(np.clip(Pc, e[k], e[k + 1]))
        edges = np.concatenate([e[: k + 1], [Pc, e[-1]]])
        vals = np.concatenate([r[: k + 1], [sigma_f]])
        keep = np.diff(edges) > 0
        self.e = np.concatenate([[0.0], edges[1:][keep]])
        self.r = vals[keep]
        return Pc


def shell_history(P, Q, friction):
    """Follow the Ciavarella-Jager shell model (eq. (6)) along samples ``P[k], Q[k]``.

    Parameters
    ----------
    P, Q : array_like, shape (T,)
        The load path [force per unit thickness], ``P > 0``, ``|Q| < f P``; starts from the
        virgin state with ``rho = Q[0]/P[0]``.
    friction : float

    Returns
    -------
    stick_load : ndarray, shape (T,)
        ``P_c``: the load whose contact area is the stick zone at each sample (``P`` when nothing
        slips).
    states : list of (edges, values)
        ``rho`` after each sample.
    """
    citations.register("ciavarella1998", "jager1998")
    P = np.asarray(P, float)
    Q = np.asarray(Q, float)
    f = float(friction)
    if np.any(P <= 0) or np.any(np.abs(Q) >= f * P):
        raise InputError("the path must keep P > 0 and |Q| < f P (no gross slip)")
    sh = _Shells()
    sh.e = np.array([0.0, P[0]])
    sh.r = np.array([Q[0] / P[0]])
    stick = np.empty(P.size)
    stick[0] = P[0]
    states = [(sh.e.copy(), sh.r.copy())]
    for k in range(1, P.size):
        Pn, Qn = P[k], Q[k]
        if Pn <= sh.e[-1]:
            sh.truncate(Pn)
            trial = None
        else:
            trial = (Qn - sh.Q()) / (Pn - sh.e[-1])
            if abs(trial) <= f:
                sh.e = np.append(sh.e, Pn)
                sh.r = np.append(sh.r, trial)
                stick[k] = Pn
                states.append((sh.e.copy(), sh.r.copy()))
                continue
        dq = Qn - sh.Q() if trial is None else trial
        if trial is not None:
            sh.e = np.append(sh.e, Pn)
            sh.r = np.append(sh.r, np.sign(trial) * f)
        if abs(Qn - sh.Q()) <= 1e-14 * f * Pn:
            stick[k] = Pn
        else:
            sign = np.sign(dq) if trial is not None else np.sign(Qn - sh.Q())
            stick[k] = sh.saturate(Qn, sign * f)
        states.append((sh.e.copy(), sh.r.copy()))
    return stick, states


def hertz_shift(states, e_star):
    """Tangential rigid shift ``s`` of body 1 for each shell state [length], up to ``c Q``.

    ``s = (1/(pi E*)) int rho(P') ln(P') dP'`` (the ``ln(a/2)`` of the module docstring with
    ``a ~ sqrt(P')``; the constant part multiplies ``Q`` and drops out of ``closed int s dQ``).
    """
    out = np.empty(len(states))
    for i, (e, r) in enumerate(states):
        # int ln(P') dP' over (e_k, e_{k+1}) = [P ln P - P]
        F = np.where(e > 0, e * np.log(np.where(e > 0, e, 1.0)) - e, 0.0)
        out[i] = np.sum(r * np.diff(F)) / (np.pi * e_star)
    return out


def profile_shift_table(gap_function, e_star, a_max, n: int = 3000):
    """``(P, Lambda)`` with ``Lambda(P) = int_0^P ln a(P') dP'`` for a symmetric convex profile.

    The shift of body 1 is ``s = (2/(pi E*)) sum_k rho_k [Lambda(e_{k+1}) - Lambda(e_k)]`` up to
    ``c Q``: at fixed contact width the pressure increment is the flat-punch distribution
    ``dp/dP = 1/(pi sqrt(a^2 - x^2))`` for *any* profile, and ``int ln|x| dp/dP dx = ln(a/2)``.
    """
    a = a_max * np.linspace(1e-4, 1.0, n) ** 2
    P = np.array([contact_load(ai, gap_function, e_star) for ai in a])
    P = np.maximum.accumulate(P)
    lam = np.concatenate([[0.0], np.cumsum(0.5 * (np.log(a[1:]) + np.log(a[:-1])) * np.diff(P))])
    return P, lam


def _shift(states, e_star, table):
    P, lam = table
    out = np.empty(len(states))
    for i, (e, r) in enumerate(states):
        out[i] = 2.0 / (np.pi * e_star) * np.sum(r * np.diff(np.interp(e, P, lam)))
    return out


def profile_cycle(P0, P1, Q1, phase, friction, e_star, gap_function, a_max, *, lam: float = 1.0,
                  steps: int = 2000, cycles: int = 3):
    """:func:`hertz_cycle` for any symmetric convex gap ``g(x)`` (contacts up to ``a_max``)."""
    table = profile_shift_table(gap_function, e_star, a_max)
    if table[0][-1] < P0 + abs(lam * P1):
        raise InputError(f"a_max = {a_max:g} is too small for P = {P0 + abs(lam * P1):g}")
    return hertz_cycle(P0, P1, Q1, phase, friction, e_star, lam=lam, steps=steps, cycles=cycles,
                       _table=table)


def hertz_cycle(P0, P1, Q1, phase, friction, e_star, *, lam: float = 1.0, steps: int = 2000,
                cycles: int = 3, _table=None):
    """Continuum steady cycle of the Hertz contact under the elliptic load (``beta = 0``).

    Starts from ``P = P0 + lam P1 cos(phase)`` applied with ``Q = 0`` and ``Q`` raised to its
    ``t = 0`` value at constant ``P``, then follows ``cycles`` periods in ``steps`` samples each.
    Returns a dict with ``dissipation`` (``W`` of the last period, force^2/stiffness per unit
    thickness), ``dissipation_per_cycle`` (all periods), ``P_T`` (the largest load whose shells
    never change in the last period), ``stick_load`` and ``t``.
    """
    t = np.arange(cycles * steps + 1) / steps
    P = P0 + lam * P1 * np.cos(2 * np.pi * t + phase)
    Q = lam * Q1 * np.cos(2 * np.pi * t)
    pre = np.linspace(0.0, 1.0, 50)
    Pp = np.concatenate([np.full(50, P[0]), P])
    Qp = np.concatenate([pre * Q[0], Q])
    stick, states = shell_history(Pp, Qp, friction)
    stick, states = stick[50:], states[50:]
    s = hertz_shift(states, e_star) if _table is None else _shift(states, e_star, _table)
    dW = 0.5 * (s[1:] + s[:-1]) * np.diff(Q)
    per = np.add.reduceat(dW, np.arange(0, cycles * steps, steps))
    last = slice((cycles - 1) * steps, cycles * steps + 1)
    return {"dissipation": float(per[-1]), "dissipation_per_cycle": per,
            "P_T": float(stick[last].min()), "stick_load": stick, "t": t, "P": P, "Q": Q}
