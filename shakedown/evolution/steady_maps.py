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
def tangential_stiffness(system) -> np.ndarray:
    """Per node the stiffness that measures its slip, shape (N,): ``A_jj`` (2-D) or the mean
    of the node's two diagonal entries of ``A`` (3-D) [force / length]."""
    a = np.asarray(system.A.diagonal(), float)
    return 0.5 * (a[0::2] + a[1::2]) if getattr(system, "dim", 2) == 3 else a


def slip_measure(system, x) -> np.ndarray:
    """``|v_j|`` per node of a slip vector ``x``: (N,) for 2-D; a flat (2N,) or (N, 2) 3-D slip
    gives its Euclidean norm per node."""
    x = np.asarray(x, float)
    if getattr(system, "dim", 2) == 3:
        return np.hypot(*x.reshape(-1, 2).T)
    return np.abs(x)


def _natural_slip_scale_3d(system, load, lam):
    f = system.friction_xy.max(axis=1)
    t = np.arange(256) / 256.0
    q1, p1 = load.evaluate(t, 1.0)
    q0, p0 = load.evaluate(t, 0.0)
    qmax = np.hypot(*(q1 - q0).transpose(2, 0, 1)).max(axis=0)  # sampled: a scale, not a bound
    pmax = np.abs(p1 - p0).max(axis=0)
    force = f * np.abs(load.p0) + np.hypot(*load.q0.T) + float(lam) * (qmax + f * pmax)
    fallback = max(float(np.max(np.abs(load.p0))), float(np.max(np.abs(load.q0))), 1.0)
    return np.where(force > 0, force, fallback) / tangential_stiffness(system)


def natural_slip_scale(system, load, lam: float = 0.0) -> np.ndarray:
    """Per node, the slip whose elastic reaction equals the largest friction/tangential load.

    ``s_k = (f_k |p0_k| + |q0_k| + lam * (max_t |q1_k| + f_k max_t |p1_k|)) / A_kk``, shape (N,)
    [slip units]; never zero (falls back to ``1 / A_kk`` times the largest welded reaction, or
    1).
    """
    if getattr(system, "dim", 2) == 3:  # 3-D: |q|, k_j the node's tangential stiffness
        return _natural_slip_scale_3d(system, load, lam)
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
    A 3-D system gets shape (n_states, N, 2): both components of node ``k`` in the box of
    ``f_max,k |p0_k| / k_k`` (``k_k``: :func:`tangential_stiffness`), one draw of shape
    ``(n_states - 1, 2N)``.
    """
    n = system.n_nodes
    n_states = int(n_states)
    if n_states < 1:
        raise InputError(f"initial_slips as a count must be >= 1; got {n_states}")
    if not np.isfinite(scale) or scale <= 0:
        raise InputError(f"scale must be a positive number; got {scale}")
    gen = np.random.default_rng(rng)
    p0 = np.asarray(load.p0, float)
    dim3 = getattr(system, "dim", 2) == 3
    a = tangential_stiffness(system)
    f = system.friction_xy.max(axis=1) if dim3 else system.friction
    s = f * np.abs(p0) / a
    fallback = max(float(np.max(np.abs(p0))), float(np.max(np.abs(load.q0))), 1.0)
    s = np.where(s > 0, s, fallback / a)
    if dim3:  # 3-D: both slip components of node k in the box, shape (n_states, N, 2)
        n, s = 2 * n, np.repeat(s, 2)
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
    return out.reshape(n_states, -1, 2) if dim3 else out


class _PeriodMap:
    """``x -> P^p(x)`` through :func:`solve_cycles`, counting simulated periods."""

    def __init__(self, system, load, lam, solver_kw):
        from .cycles import solve_cycles

        self._solve = solve_cycles
        self.system, self.load, self.lam, self.kw = system, load, lam, solver_kw
        self.count = 0

        # 3-D: the map acts on flat slips (2N,), reshaped to (N, 2) for solve_cycles
        self.shape = (system.n_nodes, 2) if getattr(system, "dim", 2) == 3 else (
            system.n_nodes,)

    def run(self, x, cycles):
        run = self._solve(self.system, self.load, self.lam,
                          initial_slip=np.array(x, float).reshape(self.shape),
                          max_cycles=int(cycles), **self.kw)
        self.count += int(run.n_cycles)
        return run

    def __call__(self, x, p):
        run = self.run(x, p)
        starts = np.asarray(run.cycle_start_slips)
        if len(starts) < p + 1:  # the run stopped early (steady within p periods)
            return np.asarray(run.final_slip, float).ravel(), run
        return np.asarray(starts[p], float).ravel(), run


def _check_common(system, load, lam):
    check_same_nodes(system, load)
    return check_load_factor(lam, load)


def _check_slip(name, value, n, dim=2):
    """A node vector of slips, flat: (N,) in 2-D, (N, 2) given and (2N,) returned in 3-D."""
    if dim == 3:
        x = np.array(value, dtype=float)
        if x.shape != (n, 2) or not np.all(np.isfinite(x)):
            raise InputError(f"{name} of a 3-D system must be a finite array of shape ({n}, 2); "
                             f"got shape {x.shape}")
        return x.ravel()
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


