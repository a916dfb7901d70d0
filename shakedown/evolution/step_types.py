"""Data types and constants of the implicit step (MODEL.md s.4): node-state codes, the
feasibility tolerance, :class:`StepResult` and the internal records of the active-set method.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

STICK, FORWARD, BACKWARD, SEPARATED = 0, 1, 2, 3
STATE_NAMES = ("stick", "forward", "backward", "separation")

#: Default relative feasibility tolerance: a force is "zero" below ``FEAS_TOL * force_scale``,
#: a slip or gap of node ``j`` below ``FEAS_TOL * force_scale / K_jj``.  LU solves of the
#: systems met here are accurate to ~1e-13 relative; 1e-9 leaves room for ill-conditioning
#: (stiffness ratios 1e8) without accepting visible sign violations.
FEAS_TOL = 1e-9

ALL_ALLOWED = np.ones(4, bool)


@dataclass(frozen=True, eq=False)
class StepResult:
    """One implicit step (see module docstring).

    Attributes
    ----------
    slip, gap : ndarray, shape (N,)
        ``v = v_prev + dv`` and ``w`` at the end of the step [length].
    slip_increment : ndarray, shape (N,)
        ``dv``.
    q, p : ndarray, shape (N,)
        Tangential and normal reactions at the end of the step [force] (compression ``p > 0``).
    states : ndarray of int8, shape (N,)
        Kinematic node states (codes of :data:`STATE_NAMES`): separated if ``w_j`` exceeds its
        tolerance, else forward/backward if ``|dv_j|`` does, else stick.
    active_set : ndarray of int8, shape (N,)
        The state assignment whose linear system produced the answer (a node at the friction
        limit with ``dv = 0`` may be "forward" here and "stick" in ``states``); pass it as
        ``guess`` to the next step.
    success : bool
        A solution was found and verified.
    status : str
        ``"unique"`` (guaranteed by friction below critical, or by enumeration),
        ``"solved"`` (found; uniqueness not guaranteed: friction above the sufficient bound of a
        large system), ``"multiple_solutions"`` (enumeration found several; ``slip`` is the one
        the active-set path reached, the others are in ``alternative_slips``),
        ``"no_solution"`` (enumeration proves none exists), ``"failed"`` (none found, existence
        undecided).
    message : str
    residual : float
        ``max(complementarity_residual, equilibrium_residual)``.  An answer is accepted when it
        is at most ``feas_tol``, or ``10 feas_tol`` for the Lemke fallback (``method ==
        "lemke"``, the steps the active set cannot finish: it pivots on a dense ``K^-1`` and
        keeps its round-off, ~1e-9 at ``cond(K) = 1e6``).
    complementarity_residual : float
        Largest natural residual ``|min(x, y)|`` over the pairs ``(w, p)``, ``(dv+, f p + q)``,
        ``(dv-, f p - q)``, forces scaled by ``force_scale``, slips and gaps of node ``j`` by
        ``force_scale / K_jj`` (dimensionless).
    equilibrium_residual : float
        ``max |(q, p) - (q_w, p_w) - K (v, w)| / force_scale``, recomputed independently.
    force_scale : float
        ``max |(q_w, p_w, q_w + A v_prev, p_w + B^T v_prev)|``.
    method : {"active_set", "lemke", "enumeration", "none"}
    iterations, lemke_pivots, factorizations, updates, cache_hits : int
        Active-set iterations, Lemke pivots, fresh LU factorizations, low-rank (Woodbury)
        solves and LU-cache hits spent on this step.
    n_solutions : int
        Distinct solutions found by enumeration, ``-1`` when not enumerated.
    alternative_slips : tuple of ndarray
        The other solutions' slips when several exist.
    """

    slip: np.ndarray
    gap: np.ndarray
    slip_increment: np.ndarray
    q: np.ndarray
    p: np.ndarray
    states: np.ndarray
    active_set: np.ndarray
    success: bool
    status: str
    message: str
    residual: float
    complementarity_residual: float
    equilibrium_residual: float
    force_scale: float
    method: str
    iterations: int = 0
    lemke_pivots: int = 0
    factorizations: int = 0
    updates: int = 0
    cache_hits: int = 0
    n_solutions: int = -1
    alternative_slips: tuple = field(default=(), repr=False)

    def __repr__(self) -> str:
        from ..model.results import short_repr

        names = np.asarray(self.state_names)
        return short_repr(self, ("status", "success", "method", "iterations", "residual"),
                          {"n_nodes": int(names.size),
                           "n_slip": int(np.count_nonzero((names != "stick")
                                                          & (names != "separation"))),
                           "n_open": int(np.count_nonzero(names == "separation"))})

    def verdict(self) -> str:
        """The step's answer in one sentence: its status, which nodes slip or open (numbered
        from 1), and its verified residual."""
        from ..model.numbers import sig

        if not self.success:
            return f"The step has no verified answer ({self.status}): {self.message}."
        names = np.asarray(self.state_names)
        parts = []
        for name in dict.fromkeys(names[names != "stick"]):
            nodes = np.flatnonzero(names == name) + 1
            shown = ", ".join(map(str, nodes[:8])) + (", ..." if nodes.size > 8 else "")
            word = {"forward": "slip forward", "backward": "slip backward",
                    "separation": "open"}.get(str(name), str(name))
            parts.append(f"{nodes.size} {word} (node{'s' * (nodes.size > 1)} {shown})")
        what = "; ".join(parts) if parts else "every node sticks"
        return (f"Step answer ({self.status}): {what}; residual {sig(self.residual)} (relative to the "
                f"force scale {sig(self.force_scale)}).")

    @property
    def state_names(self) -> np.ndarray:
        """``states`` as strings (:data:`STATE_NAMES`)."""
        return np.asarray(STATE_NAMES)[self.states]


@dataclass
class _Factor:
    key: bytes
    s: np.ndarray  # assignment
    free: np.ndarray  # indices into z = (dv, w) of the unknowns (= indices of the K-rows)
    coef: np.ndarray  # per free a-row: 0 (separated) or +-f (slip)
    jv: np.ndarray  # nodes with a slip unknown
    jw: np.ndarray  # nodes with a gap unknown
    lu: tuple
    nbytes: int
    krows: np.ndarray | None = None  # K[free], shape (m, 2N): reactions of a solve, lazily


@dataclass
class MixedSolution:
    """Raw answer of :meth:`StepSolver.solve_mixed` (internal; fields as in StepResult)."""

    s: np.ndarray
    z: np.ndarray
    q: np.ndarray
    p: np.ndarray
    success: bool
    method: str
    iterations: int
    lemke_pivots: int
    counters: dict


def kinematic_states(dv, w, dtol):
    """State codes from increments: separated if ``w > dtol_w``, else by the sign of ``dv``.

    ``dtol`` has shape (2N,) (slip tolerances, then gap tolerances).
    """
    n = dv.shape[-1]
    st = (dv > dtol[..., :n]).astype(np.int8)  # FORWARD = 1, else STICK = 0
    st[dv < -dtol[..., :n]] = BACKWARD
    st[w > dtol[..., n:]] = SEPARATED
    return st
