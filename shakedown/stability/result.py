"""Result object of MCEIP and the verification of every returned eigenpair."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.numbers import sig
from ..model.results import short_repr
from .pencil import SlipPencil

#: Default tolerance of the verification (relative residuals, see :func:`verify_eigenpair`).
#: Dense eigen-solves reach ~1e-13; iterative answers are polished on their support before
#: verification, so 1e-8 separates real solutions from failures with a wide margin.
VERIFY_TOL = 1e-8

#: ``x_j > SUPPORT_RTOL * max(x)`` puts node ``j`` in the support of the mode.
SUPPORT_RTOL = 1e-9


@dataclass(frozen=True, eq=False)
class MCEIPResult:
    """A (verified) solution of ``x >= 0, y = (K0 + mu K1) x >= 0, x . y = 0, x != 0``.

    Attributes
    ----------
    mu : float
        The friction coefficient (``inf`` when no solution was found).
    lam : float
        Growth rate at which the pencil was taken (0 for MCEIP-mu).
    mode : ndarray, shape (n,)
        ``x = chi v'`` on the slip nodes, scaled to ``max(x) = 1`` (empty when none).
    y : ndarray, shape (n,)
        ``(K0 + mu K1) x`` [force / length]: the unloading of the friction cone.
    support : ndarray of int
        Positions (into ``nodes``) where ``x > 0``: the nodes that slip; the others unload.
    nodes : ndarray of int
        Global indices of the slip nodes of the partition (the pencil's nodes).
    chi : ndarray
        Their slip directions; the slip rates are ``chi * mode``.
    residual : float
        ``max_J abs(y) / ||K0 + mu K1||_inf`` (eigen-equation on the support).
    sign_violation : float
        ``max(0, -min x, -min_{not J} y / ||K0 + mu K1||_inf)``.
    complementarity : float
        ``max_j abs(x_j y_j) / ||K0 + mu K1||_inf``.
    verified : bool
        All three residuals ``<= tol``.
    minimal : bool
        ``True`` when ``mu`` is certified the smallest solution (full support enumeration).
    status : str
        ``"found"``, ``"none"`` (no solution exists: certified by enumeration, or none found by
        the method), ``"not-converged"`` or ``"unverified"``.
    message : str
    method : str
        ``"enumeration"``, ``"linear-dense"``, ``"linear-arpack"``, ``"power"``,
        ``"active-set"``.
    iterations : int
        Outer iterations (power / active set), or supports examined (enumeration).
    history : tuple of float
        The iterates ``mu_n`` of the power iteration (seed 000 Fig. 6, left).
    """

    mu: float
    lam: float
    mode: np.ndarray
    y: np.ndarray
    support: np.ndarray
    nodes: np.ndarray
    chi: np.ndarray
    residual: float
    sign_violation: float
    complementarity: float
    verified: bool
    minimal: bool
    status: str
    message: str
    method: str
    iterations: int = 0
    history: tuple = field(default=(), repr=False)

    def __repr__(self) -> str:
        return short_repr(self, ("status", "mu", "lam", "method", "verified", "minimal",
                                 "residual"),
                          {"n_slip_nodes": int(np.size(self.nodes)),
                           "n_slipping_in_mode": int(np.size(self.support))})

    def verdict(self, friction: float | None = None) -> str:
        """The answer in plain sentences: the critical friction ``mu*`` (computed; certified
        the smallest when ``minimal``), and, given the system's ``friction``, stable or not."""
        n = int(np.size(self.nodes))
        who = f"{n} slipping node{'s' * (n != 1)}"
        if self.status != "found" or not np.isfinite(self.mu):
            text = (f"No critical friction found for this partition ({who}; status "
                    f"{self.status}): {self.message}")
            return text if friction is None else f"Stable at friction {sig(friction)}: {text}"
        how = ("certified the smallest by enumeration" if self.minimal
               else f"found by the {self.method} method, not certified the smallest")
        text = (f"Critical friction mu* = {sig(self.mu)} ({who}, {how}; "
                f"{int(np.size(self.support))} of them slip in the divergence mode).")
        if friction is None:
            return text
        word = ("Stable: friction {f} is below" if friction < self.mu
                else "Unstable: friction {f} is at or above")
        return word.format(f=sig(friction)) + " the critical friction. " + text

    @property
    def found(self) -> bool:
        return self.status == "found"

    @property
    def is_linear(self) -> bool:
        """Every slip node slips (full support): the linear eigenproblem's case."""
        return self.found and self.support.size == self.nodes.size

    @property
    def unloading_nodes(self) -> np.ndarray:
        """Global indices of slip nodes that unload (``x = 0``) in the mode."""
        mask = np.ones(self.nodes.size, bool)
        mask[self.support] = False
        return self.nodes[mask]

    def slip_rates(self, n_nodes: int) -> np.ndarray:
        """``v'`` on all ``n_nodes`` nodes (zero off the slip set), shape (n_nodes,)."""
        v = np.zeros(n_nodes)
        if self.found:
            v[self.nodes] = self.chi * self.mode
        return v

    def __str__(self) -> str:
        if not self.found:
            return f"MCEIP ({self.method}): {self.status}: {self.message}"
        return (
            f"MCEIP ({self.method}): mu = {self.mu:.10g} at lam = {self.lam:g}, "
            f"support {self.support.size}/{self.nodes.size}, residuals "
            f"{self.residual:.1e}/{self.sign_violation:.1e}/{self.complementarity:.1e}, "
            f"{'verified' if self.verified else 'NOT verified'}"
            f"{', certified minimal' if self.minimal else ''}"
        )


def residuals(pencil: SlipPencil, mu: float, x) -> tuple:
    """``(x, y, support, residual, sign_violation, complementarity)`` for a candidate.

    ``x`` is rescaled to ``max(abs(x)) = 1``; see :class:`MCEIPResult` for the definitions.
    """
    x = np.asarray(x, dtype=float)
    xmax = np.abs(x).max(initial=0.0)
    if not np.isfinite(mu) or xmax == 0:
        return x, x * 0, np.zeros(0, int), np.inf, np.inf, np.inf
    x = x / xmax
    M = pencil.matrix(mu)
    norm = max(float(np.abs(M).sum(axis=1).max()), 1e-300)
    y = M @ x
    J = x > SUPPORT_RTOL
    res = float(np.abs(y[J]).max(initial=0.0) / norm)
    yout = y[~J] / norm
    sign = float(max(0.0, -x.min(), -yout.min(initial=0.0)))
    comp = float(np.abs(x * y).max() / norm)
    return x, y, np.flatnonzero(J), res, sign, comp


def make_result(pencil, mu, x, *, method, tol=VERIFY_TOL, minimal=False, iterations=0,
                history=(), message="") -> MCEIPResult:
    """Verify a candidate and wrap it (status ``"found"`` or ``"unverified"``)."""
    x, y, J, res, sign, comp = residuals(pencil, mu, x)
    ok = bool(max(res, sign, comp) <= tol and mu > 0)
    if not message:
        message = "verified" if ok else f"residuals exceed tol = {tol:g}"
    return MCEIPResult(
        mu=float(mu), lam=pencil.lam, mode=x, y=y, support=J, nodes=pencil.nodes,
        chi=pencil.chi, residual=res, sign_violation=sign, complementarity=comp,
        verified=ok, minimal=bool(minimal and ok), status="found" if ok else "unverified",
        message=message, method=method, iterations=int(iterations), history=tuple(history),
    )


def no_solution(pencil, *, method, status="none", message="", iterations=0, history=(),
                minimal=False) -> MCEIPResult:
    """A result without a solution (``mu = inf``)."""
    n0 = np.zeros(0)
    return MCEIPResult(
        mu=float("inf"), lam=pencil.lam, mode=n0, y=n0, support=np.zeros(0, int),
        nodes=pencil.nodes, chi=pencil.chi, residual=np.inf, sign_violation=np.inf,
        complementarity=np.inf, verified=False, minimal=minimal, status=status,
        message=message, method=method, iterations=int(iterations), history=tuple(history),
    )
