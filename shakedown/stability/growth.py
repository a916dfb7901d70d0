"""MCEIP-lam: divergence growth rates at a given friction and the curves ``lam(mu)``.

With mass, a perturbation growing like ``e^(lam t)`` satisfies the MCEIP of the dynamic
stiffness ``K(s) = K + s M`` condensed onto the contact nodes, ``s = lam^2`` (seed 000 eq.
(40), seed 001 eq. (7)).  For each ``lam`` on a grid, every MCEIP-mu solution is computed
(all supports for small slip sets); solutions are linked into branches ``mu_b(lam)`` by
continuity (same support first, then nearest ``mu``).  The growth rates at a friction ``mu``
are the roots of ``mu_b(lam) = mu`` on every branch, refined by Brent's method on the
eigenvalue of the branch's support and verified on the full pencil.  A *returning point*
(seed 000 Figs. 9, 12) is a local extremum of ``mu_b(lam)`` along a branch (two growth rates
merge there) or two branches ending together (a fold in ``lam``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ..model.errors import InputError
from ..model.numbers import sig
from ..model.results import short_repr
from .classify import NodePartition
from .enumerate import MAX_ENUMERATION_NODES
from .linear import restricted_eigenpairs
from .mceip import mceip_mu_all
from .pencil import as_dynamic_stiffness, slip_pencil
from .result import VERIFY_TOL, MCEIPResult, make_result

#: Largest relative jump of ``mu`` (against the extrapolated branch) between grid points for a
#: solution with the branch's support.
SAME_SUPPORT_RTOL = 0.5


@dataclass(frozen=True, eq=False)
class Branch:
    """One continuous branch ``mu(lam)``: arrays ``lam``, ``mu`` and the supports."""

    lam: np.ndarray
    mu: np.ndarray
    supports: tuple

    @property
    def support_changes(self) -> int:
        return sum(a != b for a, b in zip(self.supports[:-1], self.supports[1:], strict=True))


@dataclass(frozen=True, eq=False)
class ReturningPoint:
    """A returning point: ``kind`` is ``"max"``/``"min"`` (extremum of ``mu`` along a branch)
    or ``"fold"`` (two branches end together)."""

    lam: float
    mu: float
    kind: str
    branches: tuple


@dataclass(frozen=True, eq=False)
class LamMuCurves:
    """Branches of ``mu(lam)`` for a partition, with their returning points.

    Attributes
    ----------
    lam : ndarray
        The grid of growth rates.
    branches : tuple of Branch
    returning_points : tuple of ReturningPoint
    nodes, chi : ndarray
        Slip nodes of the partition and their directions.
    """

    lam: np.ndarray
    branches: tuple
    returning_points: tuple
    nodes: np.ndarray
    chi: np.ndarray
    solver: dict = field(default_factory=dict, repr=False)

    def table(self):
        """Long ``pandas.DataFrame``: branch, lam, mu, support size."""
        import pandas as pd

        rows = [
            {"branch": b, "lam": L, "mu": m, "support_size": len(s)}
            for b, br in enumerate(self.branches)
            for L, m, s in zip(br.lam, br.mu, br.supports, strict=True)
        ]
        return pd.DataFrame(rows, columns=["branch", "lam", "mu", "support_size"])


@dataclass(frozen=True, eq=False)
class GrowthRates:
    """Growth rates ``lam >= 0`` at friction ``mu`` (MCEIP-lam), all branches.

    Attributes
    ----------
    mu : float
    lam : ndarray
        Sorted growth rates (empty: no divergence instability up to ``lam_max``).
    modes : tuple of MCEIPResult
        The verified mode at each rate (``modes[k].lam == lam[k]``).
    branch : ndarray of int
        Branch of each rate in ``curves``.
    curves : LamMuCurves
    status : str
        ``"found"``, ``"none"`` or ``"unverified"`` (some root failed its verification).
    message : str
    """

    mu: float
    lam: np.ndarray
    modes: tuple
    branch: np.ndarray
    curves: LamMuCurves
    status: str
    message: str

    @property
    def max_rate(self) -> float:
        return float(self.lam.max()) if self.lam.size else 0.0

    def __repr__(self) -> str:
        return short_repr(self, ("mu", "status"), {"n_rates": int(self.lam.size),
                                                   "max_rate": self.max_rate})

    def verdict(self) -> str:
        """The growth rates at friction ``mu`` in one sentence (``s`` [1/time])."""
        if self.lam.size:
            return (f"At friction {sig(self.mu)} the largest growth rate is s = "
                    f"{sig(self.max_rate)} [1/time] ({self.lam.size} rate"
                    f"{'s' * (self.lam.size != 1)} in all; status {self.status}).")
        return (f"At friction {sig(self.mu)} no growth rate was found in the scanned range "
                f"(status {self.status}): no divergence there.")


def _support_key(r: MCEIPResult) -> tuple:
    return tuple(r.support.tolist())


def _link(lams, sols_per_lam, link_rtol):
    """Greedy continuation of the solutions into branches.

    A solution continues a branch when its ``mu`` is within ``link_rtol`` (relative) of the
    branch's linear extrapolation, or within ``SAME_SUPPORT_RTOL`` when it has the branch's
    support (a fixed support gives a smooth eigenvalue curve).
    """
    open_b: list[dict] = []
    closed = []
    for L, sols in zip(lams, sols_per_lam, strict=True):
        used = set()
        new_open = []
        for br in open_b:
            last_sup = br["sup"][-1]
            if len(br["mu"]) >= 2:
                l0, l1 = br["lam"][-2:]
                m0, m1 = br["mu"][-2:]
                pred = m1 + (m1 - m0) * (L - l1) / (l1 - l0)
            else:
                pred = br["mu"][-1]
            pred = pred if pred > 0 else br["mu"][-1]
            best, bd = None, np.inf
            for i, r in enumerate(sols):
                if i in used:
                    continue
                d = abs(r.mu - pred) / max(abs(pred), 1e-300)
                same = _support_key(r) == last_sup
                if d <= (SAME_SUPPORT_RTOL if same else link_rtol):
                    d_eff = d if same else d + 1.0
                    if d_eff < bd:
                        best, bd = i, d_eff
            if best is None:
                closed.append(br)
                continue
            used.add(best)
            r = sols[best]
            br["lam"].append(L)
            br["mu"].append(r.mu)
            br["sup"].append(_support_key(r))
            new_open.append(br)
        for i, r in enumerate(sols):
            if i not in used:
                new_open.append({"lam": [L], "mu": [r.mu], "sup": [_support_key(r)]})
        open_b = new_open
    closed.extend(open_b)
    closed.sort(key=lambda b: (b["lam"][0], b["mu"][0]))
    return [Branch(np.array(b["lam"]), np.array(b["mu"]), tuple(b["sup"])) for b in closed]


def _mu_on_support(Kfun, partition, profile, lam, J, target):
    pen = slip_pencil(Kfun, partition, lam=lam, friction_profile=profile)
    pairs = restricted_eigenpairs(pen.K0, pen.K1, list(J))
    if not pairs:
        return np.nan, pen, None
    pos = [p for p in pairs if p[2]] or pairs
    mu, xJ, _ = min(pos, key=lambda p: abs(p[0] - target))
    return mu, pen, xJ


def lam_mu_curves(
    stiffness,
    partition: NodePartition,
    lams,
    *,
    mass=None,
    friction_profile=None,
    max_enumeration: int = MAX_ENUMERATION_NODES,
    n_starts: int = 0,
    link_rtol: float = 0.1,
    refine: bool = True,
    tol: float = VERIFY_TOL,
    progress=None,
) -> LamMuCurves:
    """All MCEIP branches ``mu(lam)`` on the grid ``lams`` and their returning points.

    Parameters
    ----------
    stiffness
        Anything accepted by :func:`as_dynamic_stiffness`; must provide ``K(s)`` for ``s > 0``
        (a condensed FE model's ``dynamic_stiffness``, a callable, or an array with ``mass``).
    partition : NodePartition
    lams : array_like
        Increasing grid of growth rates ``>= 0``.
    mass, friction_profile
        See :func:`slip_pencil`.
    max_enumeration, n_starts
        Passed to :func:`mceip_mu_all` (exact enumeration for small slip sets; otherwise the
        linear solutions, the active set, and ``n_starts`` power iterations).
    link_rtol : float
        Largest relative jump of ``mu`` between grid points within one branch.
    refine : bool
        Locate the returning points by maximising / minimising the support's eigenvalue.
    progress : callable, optional
        A wrapper ``progress(iterable, total=, desc=)`` (e.g. the CLI's ``ctx.progress``).
    """
    lams = np.asarray(lams, dtype=float)
    if lams.ndim != 1 or lams.size < 2 or np.any(np.diff(lams) <= 0) or lams[0] < 0:
        raise InputError("lams must be an increasing 1-D grid of at least 2 values >= 0")
    Kfun = as_dynamic_stiffness(stiffness, mass)
    it = lams if progress is None else progress(lams, total=lams.size, desc="lam scan")
    sols = [
        mceip_mu_all(Kfun, partition, lam=L, friction_profile=friction_profile,
                     max_enumeration=max_enumeration, tol=tol, n_starts=n_starts)
        for L in it
    ]
    branches = _link(lams, sols, link_rtol)
    rps = []
    for b, br in enumerate(branches):
        for k in range(1, br.lam.size - 1):
            d0, d1 = br.mu[k] - br.mu[k - 1], br.mu[k + 1] - br.mu[k]
            if d0 * d1 < 0:
                kind = "max" if d0 > 0 else "min"
                L, m = br.lam[k], br.mu[k]
                if refine:
                    sgn = -1.0 if kind == "max" else 1.0
                    J = br.supports[k]
                    opt = minimize_scalar(
                        lambda x, J=J, m=m, sgn=sgn: sgn * _mu_on_support(Kfun, partition,
                                                                 friction_profile, x, J, m)[0],
                        bounds=(br.lam[k - 1], br.lam[k + 1]), method="bounded",
                        options={"xatol": 1e-10 * br.lam[k + 1]},  # relative: lam has units
                    )
                    if np.isfinite(opt.fun):
                        L, m = float(opt.x), float(sgn * opt.fun)
                rps.append(ReturningPoint(float(L), float(m), kind, (b,)))
    # folds in lam: two branches ending at the same grid point with close mu
    ends = [(b, br) for b, br in enumerate(branches) if br.lam[-1] < lams[-1]]
    for i, (b1, br1) in enumerate(ends):
        for b2, br2 in ends[i + 1:]:
            if br1.lam[-1] == br2.lam[-1] and abs(br1.mu[-1] - br2.mu[-1]) <= link_rtol * abs(
                br1.mu[-1]
            ):
                rps.append(ReturningPoint(float(br1.lam[-1]), 0.5 * (br1.mu[-1] + br2.mu[-1]),
                                          "fold", (b1, b2)))
    pen0 = slip_pencil(Kfun, partition, lam=float(lams[0]), friction_profile=friction_profile)
    return LamMuCurves(lams, tuple(branches), tuple(rps), pen0.nodes, pen0.chi,
                       {"max_enumeration": max_enumeration, "n_starts": n_starts})


def growth_rates(
    stiffness,
    partition: NodePartition,
    mu: float,
    *,
    lam_max: float | None = None,
    n_lam: int = 41,
    lams=None,
    curves: LamMuCurves | None = None,
    mass=None,
    friction_profile=None,
    tol: float = VERIFY_TOL,
    **curve_options,
) -> GrowthRates:
    """All divergence growth rates ``lam >= 0`` at friction ``mu`` (MCEIP-lam).

    Scans ``lam`` on ``lams`` (default ``linspace(0, lam_max, n_lam)``) or reuses ``curves``,
    then solves ``mu_b(lam) = mu`` on every branch by Brent's method on the eigenvalue of
    the branch's support; every root is verified as a complementarity solution of the full
    pencil at that ``lam``.  Rates beyond the scanned range are not found.
    """
    if not (np.isfinite(mu) and mu > 0):
        raise InputError(f"mu must be a positive number; got {mu!r}")
    Kfun = as_dynamic_stiffness(stiffness, mass)
    if curves is None:
        if lams is None:
            if lam_max is None:
                raise InputError("give lam_max (with n_lam) or lams, or precomputed curves")
            lams = np.linspace(0.0, float(lam_max), int(n_lam))
        curves = lam_mu_curves(Kfun, partition, lams, friction_profile=friction_profile,
                               tol=tol, **curve_options)
    found = []
    for b, br in enumerate(curves.branches):
        f = br.mu - mu
        for k in range(br.lam.size - 1):
            if f[k] == 0:
                found.append((b, br.lam[k], br.supports[k], br.mu[k]))
            elif f[k] * f[k + 1] < 0:
                J = br.supports[k] if len(br.supports[k]) >= len(br.supports[k + 1]) else \
                    br.supports[k + 1]

                def g(L, J=J, k=k, br=br):
                    target = np.interp(L, br.lam[k:k + 2], br.mu[k:k + 2])
                    return _mu_on_support(Kfun, partition, friction_profile, L, J, target)[0] - mu

                try:
                    # xtol relative to the scanned range: growth rates carry units (1 / time)
                    L = brentq(g, br.lam[k], br.lam[k + 1], rtol=1e-12,
                               xtol=1e-13 * float(abs(curves.lam[-1])))
                except ValueError:  # support changed inside the interval: interpolate
                    L = float(np.interp(0.0, f[k:k + 2] * np.sign(f[k + 1] - f[k]),
                                        br.lam[k:k + 2]))
                found.append((b, L, J, None))
        if f[-1] == 0:
            found.append((b, br.lam[-1], br.supports[-1], br.mu[-1]))
    rates, modes, branch = [], [], []
    ok = True
    for b, L, J, _ in found:
        mu_J, pen, xJ = _mu_on_support(Kfun, partition, friction_profile, L, J, mu)
        x = np.zeros(pen.size)
        if xJ is not None:
            x[list(J)] = np.clip(xJ, 0.0, None)
        res = make_result(pen, mu, x, method="mceip-lam", tol=max(tol, 1e-7),
                          message=f"growth rate lam = {L:.10g} on branch {b}")
        ok &= res.verified
        rates.append(float(L))
        modes.append(res)
        branch.append(b)
    order = np.argsort(rates)
    rates = np.array(rates)[order] if rates else np.zeros(0)
    modes = tuple(modes[i] for i in order)
    branch = np.array(branch, int)[order] if branch else np.zeros(0, int)
    if not rates.size:
        status, msg = "none", f"no growth rate in [{curves.lam[0]:g}, {curves.lam[-1]:g}]"
    else:
        status = "found" if ok else "unverified"
        msg = f"{rates.size} growth rate(s) on {np.unique(branch).size} branch(es)"
    return GrowthRates(float(mu), rates, modes, branch, curves, status, msg)
