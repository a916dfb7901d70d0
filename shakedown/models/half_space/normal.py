"""Frictionless normal contact on the half-space grid: Polonsky & Keer's projected CG with FFT.

Unknowns: cell forces ``p >= 0`` (all ``n^2`` cells) and the approach ``d``, with::

    gap = g + F_zz p - d >= 0,   p >= 0,   p . gap = 0,   sum p = P

(``F_zz`` the normal block of :mod:`.influence`, applied by FFT).  The algorithm is the
conjugate-gradient iteration of Polonsky & Keer (*Wear* 231, 1999, 206-219): CG on the cells in
contact with the mean gap there as the multiplier of the load constraint, a projection onto
``p >= 0``, reactivation of overlapping cells and a restart, rescaling to ``sum p = P``.  It is
independent of the step engines (no stiffness ``K``) and serves the Hertz convergence study.
With ``beta != 0`` the frictionless normal problem ignores the coupling (``q = 0``, slip free).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model import InputError
from .operators import _circulant_fft, fft_size


@dataclass(frozen=True)
class NormalContact:
    """Answer of :func:`normal_contact`.

    Attributes
    ----------
    p : ndarray, shape (n^2,)
        Cell forces [force] (pressure ``p / h^2``).
    gap : ndarray, shape (n^2,)
        Cell gaps ``g + F_zz p - d`` [length] (0 in contact, to the tolerance).
    approach : float
        ``d`` [length].
    iterations : int
    residual : float
        Complementarity residual of :func:`check_normal_contact` (dimensionless).
    """

    p: np.ndarray
    gap: np.ndarray
    approach: float
    iterations: int
    residual: float

    @property
    def contact(self) -> np.ndarray:
        """Cells in contact (``p > 0``), boolean (n^2,)."""
        return self.p > 0

    def __repr__(self) -> str:
        from ...model.results import short_repr

        return short_repr(self, ("approach", "iterations", "residual"),
                          {"n_contact_cells": int(np.count_nonzero(self.contact)),
                           "P": float(np.sum(self.p))})

    def verdict(self) -> str:
        """The normal contact in one sentence."""
        from ...model.numbers import sig

        return (f"Normal contact: {int(np.count_nonzero(self.contact))} of {self.p.size} cells "
                f"carry P = {sig(float(np.sum(self.p)))} [force] at the approach "
                f"d = {sig(self.approach)} [length] (complementarity residual "
                f"{sig(self.residual)}, {self.iterations} iterations).")


def _zz_operator(model):
    n = model.n
    hat = _circulant_fft(model.kernels["zz"], n)
    s = (fft_size(n),) * 2

    def apply(p):
        return np.fft.irfft2(hat * np.fft.rfft2(p.reshape(n, n), s=s), s=s)[:n, :n].ravel()
    return apply


def check_normal_contact(model, p, approach, P, extra_gap=None):
    """Dimensionless residual of the frictionless contact conditions for ``(p, d)``.

    ``extra_gap`` (n^2,) [length] is added to the initial gap (the gap the shear forces open
    for dissimilar materials, ``F_zt q``).

    ``max`` of: ``-min p / P``, the load error ``|sum p - P| / P``, the largest interpenetration
    and the largest gap where ``p > 0`` (both over the approach ``|d|`` plus the gap's spread),
    and the complementarity ``sum p |gap| / (P scale)``.
    """
    p = np.asarray(p, float)
    g0 = model.gap if extra_gap is None else model.gap + extra_gap
    gap = g0 + _zz_operator(model)(p) - approach
    g_scale = abs(approach) + np.ptp(g0) + np.finfo(float).tiny
    on = p > 0
    return float(max(-min(p.min(), 0.0) / P, abs(p.sum() - P) / P,
                     -min(gap.min(), 0.0) / g_scale,
                     np.abs(gap[on]).max(initial=0.0) / g_scale,
                     float(np.sum(p * np.abs(gap))) / (P * g_scale)))


def normal_contact(model, P, rtol: float = 1e-10, maxiter: int = 5000, *, extra_gap=None,
                   p_init=None, apply=None) -> NormalContact:
    """Frictionless normal contact of a :class:`.model.HalfSpaceModel` under normal force ``P``.

    Parameters
    ----------
    model : HalfSpaceModel
    P : float
        Normal force ``> 0`` [force].
    rtol : float
        Stop when the relative change of ``p`` in an iteration is below ``rtol``.
    maxiter : int
    extra_gap : ndarray, shape (n^2,), optional
        Added to the initial gap [length] (``F_zt q`` of dissimilar materials).
    p_init : ndarray, shape (n^2,), optional
        Starting cell forces (a warm start, e.g. the previous step's), rescaled to ``P``; cells
        with ``p_init = 0`` start open.  Default: uniform.
    apply : callable, optional
        ``F_zz`` products (n^2,) -> (n^2,) (default: built from the model's kernels).

    Returns
    -------
    NormalContact
    """
    P = float(P)
    if not np.isfinite(P) or P <= 0:
        raise InputError(f"P must be a finite normal force > 0, got {P!r}")
    apply = _zz_operator(model) if apply is None else apply
    g0 = model.gap if extra_gap is None else model.gap + np.asarray(extra_gap, float)
    N = g0.size
    p = np.full(N, P / N)
    if p_init is not None and np.sum(p_init) > 0:
        p = np.maximum(np.asarray(p_init, float), 0.0) * (P / float(np.sum(np.maximum(p_init, 0.0))))
    t = np.zeros(N)
    G_old = 1.0
    delta = 0.0
    it = 0
    while it < maxiter:
        it += 1
        gap = g0 + apply(p)
        on = p > 0
        gap = gap - gap[on].mean()
        G = float(np.sum(gap[on] ** 2))
        t = np.where(on, gap + delta * (G / G_old) * t, 0.0)
        G_old = G
        r = apply(t)
        r = r - r[on].mean()
        denom = float(np.sum(r[on] * t[on]))
        tau = float(np.sum(gap[on] * t[on])) / denom if denom != 0 else 0.0
        p_old = p
        p = p - tau * t
        p = np.where(on, np.maximum(p, 0.0), p)
        ol = (p <= 0) & (gap < 0)
        if np.any(ol):
            delta = 0.0
            p = np.where(ol, p - tau * gap, p)
        else:
            delta = 1.0
        p = np.maximum(p, 0.0)
        p *= P / p.sum()
        if np.sum(np.abs(p - p_old)) <= rtol * P:
            break
    gap = g0 + apply(p)
    on = p > 0
    d = float(np.mean(gap[on]))
    return NormalContact(p=p, gap=gap - d, approach=d, iterations=it,
                         residual=check_normal_contact(model, p, d, P, extra_gap))
