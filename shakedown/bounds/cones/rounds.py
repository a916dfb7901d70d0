"""One relaxation of the cutting-plane loop, by the dense interior point or Clarabel, checked.

:func:`solve_round` solves the SOCP on the current cuts with the dense interior point
(:mod:`.dense_ipm`, coupled systems) and accepts its answer only when it passes its own
conditions: the state satisfies every cut (to :data:`PRIMAL_TOL` of the force scale), the
multipliers lie in their cones and are stationary to the engine's ``DUAL_TOL`` (a quality
screen: the bound :func:`.socp.dual_bound` computes from them is valid whatever their
residuals, :mod:`.dual`) and that bound is not below the state's value (weak duality); the
cutting-plane loop re-solves by Clarabel a round whose gap is too wide to close the bracket
(:func:`.melan.melan_lam2`).  Otherwise Clarabel solves the
same SOCP (:func:`.socp.solve_cuts`) and the reason is recorded.  :class:`SocpLog` keeps which
path answered each SOCP (the 3-D counterpart of :mod:`shakedown.bounds.provenance`).

:func:`active_cuts` keeps the cuts whose multipliers carry the relaxation (the exchange step of
the loop: the dense path re-solves only those and the new worst times).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .dense_ipm import solve_dense
from .socp import CutAnswer, dual_bound, solve_cuts, static_margin

#: Largest violation of a cut by an accepted dense answer (units of the force scale).
PRIMAL_TOL = 1e-7
#: A cut is kept for the next round when its normal multiplier exceeds this fraction of the
#: largest one.
ACTIVE_REL = 1e-7

SOLVERS = ("auto", "dense", "clarabel")
#: ``solver="auto"`` takes the dense path from this many nodes on (coupled systems): below it
#: Clarabel's sparse factorisation is as fast (measured: ``benchmarks/RESULTS_3d_bounds.md``).
DENSE_MIN_NODES = 150


@dataclass
class SocpLog:
    """Which path answered each SOCP of a 3-D ``lam2`` and why the dense path fell back.

    Attributes
    ----------
    paths : list of str
        Per SOCP in order (the static-margin SOCP first): ``"dense"`` (the dense interior
        point, checked) or ``"clarabel"``.
    fallbacks : list of str
        ``"SOCP k: reason"`` for every SOCP that the dense path tried and Clarabel answered.
    """

    paths: list = field(default_factory=list)
    fallbacks: list = field(default_factory=list)

    def record(self, path, reason=None):
        self.paths.append(path)
        if reason is not None:
            self.fallbacks.append(f"SOCP {len(self.paths) - 1}: {reason}")

    @property
    def path(self) -> str:
        """``"dense"``, ``"clarabel"`` or ``"dense+clarabel"``."""
        return "+".join(p for p in ("dense", "clarabel") if p in self.paths) or "none"


def check_solver(solver):
    from ...model.errors import InputError

    if solver not in SOLVERS:
        raise InputError(f"solver must be one of {SOLVERS} for a 3-D system; got {solver!r} "
                         "('dense': the dense interior point, checked, Clarabel where it fails; "
                         f"'auto': dense from {DENSE_MIN_NODES} nodes on)")


def resolve_solver(solver, data) -> str:
    """``"dense"`` or ``"clarabel"``: the path of a coupled system of ``N`` nodes (uncoupled
    systems always take Clarabel: their SOCP is sparse)."""
    check_solver(solver)
    if not data.coupled or solver == "clarabel":
        return "clarabel"
    return "dense" if solver == "dense" or data.n_nodes >= DENSE_MIN_NODES else "clarabel"


def _cut_violation(data, nodes, times, u, lam):
    a1, b1 = data.periodic(times, nodes)
    a = data.a0[nodes] + u[nodes] + lam * a1
    b = data.b0[nodes] + data.coupling(u)[nodes] + lam * b1
    return float(np.max(np.linalg.norm(a, axis=1) - b, initial=-np.inf))


def check_round(data, nodes, times, ans, *, dual_tol):
    """Why the answer ``ans`` of the relaxation on these cuts is not acceptable (``None``: it
    is), and the bound ``(hi, residuals)`` its multipliers prove (module docstring)."""
    if ans.status not in ("optimal", "inaccurate"):
        return f"status {ans.status}", (np.inf, {})
    viol = _cut_violation(data, nodes, times, ans.u, ans.lam)
    hi, res = dual_bound(data, nodes, times, ans.z, ans.y_cap)
    if not viol <= PRIMAL_TOL:
        return f"the state violates a cut by {viol:.3g}", (hi, res)
    if not max(res.values()) <= dual_tol:
        return f"multipliers not certified (residuals {max(res.values()):.3g})", (hi, res)
    if hi < ans.lam * (1 - 1e-9) - PRIMAL_TOL:
        return f"bound {hi:.12g} below the value {ans.lam:.12g}", (hi, res)
    return None, (hi, res)


def solve_round(data, nodes, times, *, solver, start, dual_tol, log, fail=None, split=False):
    """The relaxation on the cuts ``(nodes, times)`` (module docstring).

    Parameters
    ----------
    start : tuple of (ndarray (N, 2), float)
        Starting state and load factor of the interior point.
    log : SocpLog
    fail : callable, optional
        Test hook: applied to the dense answer before it is checked (to force the fallback).
    split : bool
        The late Newton systems in the split augmented form (:mod:`.ipm_split`): for rounds
        that must prove a bracket tighter than the normal equations allow.

    Returns
    -------
    ans : CutAnswer
    bound : tuple (hi, residuals) or None
        The bound of the accepted dense answer (``None`` after Clarabel: the caller computes it).
    """
    if solver == "dense" and data.coupled:
        a1, b1 = data.periodic(times, nodes)
        ans = solve_dense(data.E, nodes, a1, b1, data.a0, data.b0, u0=start[0], lam0=start[1],
                          split=split)
        if fail is not None:
            ans = fail(ans)
        why, bound = check_round(data, nodes, times, ans, dual_tol=dual_tol)
        if why is None:
            log.record("dense")
            # an inaccurate (stalled) answer is as good as an optimal one here: its state is
            # checked on the cuts, its multipliers by their residuals; only the bracket's width
            # depends on its accuracy (the loop re-solves a round that cannot close it)
            return CutAnswer("optimal", ans.lam, ans.u, ans.z, ans.y_cap, ans.iterations), bound
        log.record("clarabel", f"dense interior point: {why}")
    else:
        log.record("clarabel")
    return solve_cuts(data, nodes, times), None


def margin_state(data, *, solver, log, fail=None):
    """:func:`.socp.static_margin` (the state farthest inside every cone at ``lam = 0``) by the
    dense interior point when it gives a positive margin, else by Clarabel.  The margin is
    recomputed from the state in both cases, so the path does not matter for correctness."""
    if solver == "dense" and data.coupled:
        n = data.n_nodes
        nodes = np.arange(n)
        u = -data.a0
        tau0 = float(np.min(data.b0 + data.coupling(u))) - 1.0  # a strictly interior start
        ans = solve_dense(data.E, nodes, np.zeros((n, 2)), -np.ones(n), data.a0, data.b0,
                          u0=u, lam0=tau0, cap=1.0)
        if fail is not None:
            ans = fail(ans)
        if ans.status == "optimal" and np.all(np.isfinite(ans.u)):
            u = ans.u
            tau = float(np.min(data.b0 + data.coupling(u) - np.linalg.norm(data.a0 + u, axis=1)))
            if tau > 0 and tau >= ans.lam - 1e-6 * max(1.0, abs(ans.lam)):
                log.record("dense")
                return u, tau
        log.record("clarabel", "dense interior point: no positive static margin")
    else:
        log.record("clarabel")
    return static_margin(data)


def active_cuts(nodes, times, z, keep_nodes, keep_times):
    """The cuts whose normal multiplier exceeds :data:`ACTIVE_REL` of the largest, and the cuts
    ``(keep_nodes, keep_times)`` (every node's current worst time, so no node is left free)."""
    z0 = np.asarray(z, float).reshape(-1, 3)[:, 0]
    on = z0 > ACTIVE_REL * max(float(z0.max(initial=0.0)), 1e-300)
    nn = np.concatenate([nodes[on], keep_nodes])
    tt = np.concatenate([times[on], keep_times])
    key = np.round(tt * 2 ** 40).astype(np.int64)
    _, first = np.unique(np.column_stack([nn, key]), axis=0, return_index=True)
    first = np.sort(first)
    return nn[first], tt[first]
