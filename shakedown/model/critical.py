"""Critical friction of the incremental problem (Klarbring's P-matrix criterion, MODEL.md s.4)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from . import sparse as _sparse


@dataclass(frozen=True)
class CriticalFriction:
    """Critical friction of the incremental problem (Klarbring's P-matrix criterion).

    Attributes
    ----------
    factor : float
        Critical multiplier ``alpha_c`` of the friction *profile*: the incremental problem has a
        unique solution for every load increment when the friction is ``alpha * friction`` with
        ``alpha < alpha_c``.  For a uniform friction this is ``f_c / f``.  ``inf`` when no
        friction level can make the problem ill-posed (e.g. ``B = 0``).
    value : float
        ``alpha_c * max(friction)``: the critical value expressed as a friction coefficient
        (exact for uniform friction).
    exact : bool
        ``True`` when ``factor`` is the exact critical multiplier (single node, uncoupled
        system, or full enumeration of principal minors); ``False`` when it is only a
        *sufficient* bound (below it uniqueness is guaranteed; the true value may be larger).
    upper_bound : float
        A necessary bound on ``factor`` from the 2 x 2 single-node minors (the true critical
        factor is at most this).
    method : str
        ``"uncoupled"``, ``"enumeration"``, ``"single-node"`` or ``"sufficient-bound"``.
    well_posed : bool
        ``factor > 1``: the system's actual friction is below critical.
    """

    factor: float
    value: float
    exact: bool
    upper_bound: float
    method: str
    well_posed: bool

    def __repr__(self) -> str:
        from .results import short_repr

        return short_repr(self, ("factor", "value", "exact", "upper_bound", "method",
                                 "well_posed"))

    def verdict(self) -> str:
        """Whether every implicit step has a unique answer, in one or two sentences (numbers to 4
        significant digits; ``factor`` exact or a sufficient bound, ``upper_bound`` necessary)."""
        from .numbers import sig

        kind = "exact" if self.exact else "a sufficient bound"
        if self.well_posed:
            return (f"Every implicit step has a unique answer: the friction is below critical "
                    f"(critical multiplier of the friction profile alpha_c = {sig(self.factor)} "
                    f"> 1, {kind}; {self.method}).")
        if self.exact or self.upper_bound <= 1.0:
            bound = (f"alpha_c = {sig(self.factor)}, exact" if self.exact else
                     f"alpha_c <= {sig(self.upper_bound)}, a necessary bound")
            return (f"Steps may have several answers: the friction is at or above critical "
                    f"({bound}; {self.method}).")
        return (f"Uniqueness of the steps is not guaranteed: the sufficient bound alpha_c >= "
                f"{sig(self.factor)} is not above 1, and the necessary bound alpha_c <= "
                f"{sig(self.upper_bound)} does not decide it ({self.method}).")

    def __str__(self) -> str:
        kind = "exact" if self.exact else "sufficient bound"
        return (
            f"critical friction factor {self.factor:.6g} ({kind}, {self.method}); "
            f"necessary upper bound {self.upper_bound:.6g}; "
            f"{'well-posed' if self.well_posed else 'NOT well-posed'} at the given friction"
        )



def critical_friction_2d(system, max_exact_nodes: int) -> CriticalFriction:
    """Klarbring's critical friction of a 2-D system (see ``DiscreteSystem.critical_friction``)."""
    n = system.n_nodes
    f = system.friction
    fmax = float(f.max()) if n else 0.0
    diagB = np.abs(system.B.diagonal())
    with np.errstate(divide="ignore", invalid="ignore"):
        node_bounds = np.where((diagB > 0) & (f > 0), system.A.diagonal() / (diagB * f), np.inf)
    upper = float(node_bounds.min())

    def result(factor, exact, method):
        return CriticalFriction(
            factor=float(factor),
            value=float(factor * fmax) if fmax > 0 else float("inf"),
            exact=exact,
            upper_bound=upper,
            method=method,
            well_posed=bool(factor > 1.0),
        )

    if not system.is_coupled or fmax == 0.0:
        # block-triangular M_S with SPD diagonal blocks: P for every alpha
        return result(np.inf, True, "uncoupled" if not system.is_coupled else "frictionless")
    if n == 1:
        return result(upper, True, "single-node")
    if n <= max_exact_nodes:
        if system.is_sparse:
            return critical_friction_2d(system.to_dense(), max_exact_nodes)
        return result(_critical_factor_by_enumeration(system), True, "enumeration")
    if system.is_sparse:
        # (A - B C^-1 B^T)^-1 is the leading block of K^-1: Lanczos with solves, no dense Schur
        lmin, lmax = _sparse.critical_eigenvalues(system, f)
        return result(min(np.sqrt(max(lmin, 0.0) / lmax), upper), False, "sufficient-bound")
    schur = system.A - system.B @ np.linalg.solve(system.C, system.B.T)
    lmin = float(np.linalg.eigvalsh(0.5 * (schur + schur.T))[0])
    lmax = float(np.linalg.eigvalsh(f[:, None] * system.C * f[None, :])[-1])
    return result(min(np.sqrt(max(lmin, 0.0) / lmax), upper), False, "sufficient-bound")



def _critical_factor_by_enumeration(system) -> float:
    n = system.n_nodes
    A, B, C, F = system.A, system.B, system.C, np.diag(system.friction)
    best = np.inf
    zero = np.zeros((n, n))
    for s in itertools.product((-1.0, 1.0), repeat=n):
        S = np.diag(s)
        M0 = np.block([[C, B.T @ S], [S @ B, S @ A @ S]])
        M1 = np.block([[zero, zero], [F @ C, F @ B.T @ S]])
        for size in range(1, 2 * n + 1):
            for J in itertools.combinations(range(2 * n), size):
                # the sign of an x-node that is not in J is irrelevant: count each once
                x_nodes = [j - n for j in J if j >= n]
                if any(s[k] < 0 for k in range(n) if k not in x_nodes):
                    continue
                M1J = M1[np.ix_(J, J)]
                if not np.any(M1J):
                    continue
                # det(M0 + a M1) = 0  <=>  M1 x = mu (-M0) x with a = 1 / mu
                ev = sla.eigvals(M1J, -M0[np.ix_(J, J)])
                with np.errstate(divide="ignore", invalid="ignore"):
                    alphas = 1.0 / ev
                real = np.abs(alphas.imag) <= 1e-9 * np.maximum(1.0, np.abs(alphas.real))
                cand = alphas.real[real & np.isfinite(alphas.real) & (alphas.real > 0)]
                if cand.size:
                    best = min(best, float(cand.min()))
    return best
