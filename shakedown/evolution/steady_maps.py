"""Internals of :func:`~.steady.steady_cycle`: initial slips, the one-period map, the
finite-difference Newton step on its affine piece and the Anderson update (MODEL.md s.4;
seed 002 sections 2-3).  Slips in length units; every tolerance relative to the slip scale.
"""

from __future__ import annotations

import numpy as np

from ..model.errors import InputError
from ..model.validation import check_load_factor, check_node_vector, check_same_nodes

#: Relative finite-difference step of the affine-piece identification, in units of the slip
#: scale.  The period map is exactly affine within a piece, so the step only has to be small
#: enough to stay inside the piece and large enough that the step solver's rounding
#: (~1e-15 relative) stays far below it: the Jacobian is then accurate to ~1e-9.
FD_STEP = 1e-6


# ------------------------------------------------------------------ scales and sampling
def natural_slip_scale(system, load, lam: float = 0.0) -> np.ndarray:
    """Per node, the slip whose elastic reaction equals the largest friction/tangential load.

    ``s_k = (f_k |p0_k| + |q0_k| + lam * (max_t |q1_k| + f_k max_t |p1_k|)) / A_kk``, shape (N,)
    [slip units]; never zero (falls back to ``1 / A_kk`` times the largest welded reaction, or
    1).
    """
    f = system.friction
    a = system.A.diagonal()
    qmax = np.maximum(-load.periodic_min(1.0, 0.0)[0], -load.periodic_min(-1.0, 0.0)[0])
    pmax = np.maximum(-load.periodic_min(0.0, 1.0)[0], -load.periodic_min(0.0, -1.0)[0])
    force = f * np.abs(load.p0) + np.abs(load.q0) + float(lam) * (qmax + f * pmax)
    fallback = max(float(np.max(np.abs(load.p0))), float(np.max(np.abs(load.q0))), 1.0)
    return np.where(force > 0, force, fallback) / a


def sample_initial_slips(system, load, n_states: int, rng=None, *, scale: float = 2.0):
    """Initial slips for a uniqueness study, shape (n_states, N).

    State 0 is the virgin state ``v = 0``.  State ``j >= 1`` is uniform in the box
    ``|v_k| <= scale * f_k |p0_k| / A_kk`` (``f |p0| / A_kk``: the slip whose elastic reaction
    equals the static friction limit; ``1 / A_kk`` times the largest welded reaction for a
    frictionless or unloaded node).  Every state must start with the nodes closed: if the slips
    would take away more than half of a node's static normal reaction (``(B^T v)_k < -p0_k / 2``)
    the vector is shrunk towards 0 until none does.  This is the same box as
    :func:`shakedown.sweep.initial_slips`, drawn from ``numpy.random.default_rng(rng)`` in one
    call ``rng.uniform(-1, 1, (n_states - 1, N))`` so that the states depend on the seed only.
    """
    n = system.n_nodes
    n_states = int(n_states)
    if n_states < 1:
        raise InputError(f"initial_slips as a count must be >= 1; got {n_states}")
    if not np.isfinite(scale) or scale <= 0:
        raise InputError(f"scale must be a positive number; got {scale}")
    gen = np.random.default_rng(rng)
    p0 = np.asarray(load.p0, float)
    s = system.friction * np.abs(p0) / system.A.diagonal()
    fallback = max(float(np.max(np.abs(p0))), float(np.max(np.abs(load.q0))), 1.0)
    s = np.where(s > 0, s, fallback / system.A.diagonal())
    out = np.zeros((n_states, n))
    u = gen.uniform(-1.0, 1.0, (n_states - 1, n))
    for j in range(1, n_states):
        v = float(scale) * u[j - 1] * s
        dp = v @ system.B  # (B^T v)_k, change of the normal reaction
        need = dp < 0
        if np.any(need):
            room = 0.5 * np.maximum(p0[need], 0.0) / -dp[need]
            v = v * min(1.0, float(room.min()))
        out[j] = v
    return out


class _PeriodMap:
    """``x -> P^p(x)`` through :func:`solve_cycles`, counting simulated periods."""

    def __init__(self, system, load, lam, solver_kw):
        from .cycles import solve_cycles

        self._solve = solve_cycles
        self.system, self.load, self.lam, self.kw = system, load, lam, solver_kw
        self.count = 0

    def run(self, x, cycles):
        run = self._solve(self.system, self.load, self.lam, initial_slip=np.array(x, float),
                          max_cycles=int(cycles), **self.kw)
        self.count += int(run.n_cycles)
        return run

    def __call__(self, x, p):
        run = self.run(x, p)
        starts = np.asarray(run.cycle_start_slips)
        if len(starts) < p + 1:  # the run stopped early (steady within p periods)
            return np.asarray(run.final_slip, float), run
        return np.asarray(starts[p], float), run


def _check_common(system, load, lam):
    check_same_nodes(system, load)
    return check_load_factor(lam, load)


def _check_slip(name, value, n):
    return check_node_vector(name, value, n, what="slip")


def _newton_step(P, x, y, p, h, scale):
    """Fixed point of the affine piece of ``P^p`` at ``x`` (finite-difference identification).

    Returns the new state and the spectral radius of the piece's ``M`` on the free coordinates
    (``> 1``: the fixed point of this piece repels, plain cycling would not stay there).

    Coordinates that ``P^p`` leaves exactly unchanged and that no perturbation moves (nodes
    stuck over the whole period in this piece: their rows of ``I - M`` vanish) keep their
    locked-in values; the other coordinates solve ``(I - M)_FF dx_F = g_F`` by least squares
    (minimum-norm: the fixed point nearest to ``x`` when ``I - M`` is singular).
    """
    n = x.size
    g = y - x
    M = np.empty((n, n))
    for j in range(n):
        xj = x.copy()
        xj[j] += h
        M[:, j] = (P(xj, p)[0] - y) / h
    exact = np.abs(g) <= 1e-14 * scale
    unit_row = np.all(np.abs(M - np.eye(n)) <= 1e-7, axis=1)
    free = ~(exact & unit_row)
    dx = np.zeros(n)
    rho = 0.0
    if np.any(free):
        J = (np.eye(n) - M)[np.ix_(free, free)]
        dx[free] = np.linalg.lstsq(J, g[free], rcond=1e-10)[0]
        rho = float(np.max(np.abs(np.linalg.eigvals(M[np.ix_(free, free)]))))
    return x + dx, rho


def _anderson(X, G, y):
    """Anderson (type II) update from iterates ``X`` and residuals ``G = P(X) - X``."""
    if len(X) < 2:
        return y
    dG = np.diff(np.array(G), axis=0).T  # (n, m)
    dX = np.diff(np.array(X), axis=0).T
    gamma = np.linalg.lstsq(dG, G[-1], rcond=1e-12)[0]
    return y - (dX + dG) @ gamma
