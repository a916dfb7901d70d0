"""Experiments on the half-space model: static loading paths, Cattaneo-Mindlin, fretting cycles.

* :func:`static_path` follows a path of resultants ``(Q_x, Q_y, P)`` from the virgin state with
  implicit 3-D steps (:class:`shakedown.evolution.cone_step.ConeStepSolver`): monotonic
  Cattaneo-Mindlin loading, or an initial loading path ``OA`` whose end state starts a run of
  :func:`shakedown.solve_cycles`.
* :func:`full_reactions` adds the reference cell (its reactions from the resultants).
* :func:`stick_radius` measures the Cattaneo-Mindlin stick radius by the second moment of the
  traction deficit ``f p - q_x`` (``= f P_c`` times a Hertz distribution of radius ``c`` in
  Mindlin's solution, so ``int rho^2 (f p - q_x) dA = (2/5) c^2 (f P - Q)``): a smooth measure
  that converges with the grid, where the count of stuck cells moves in steps of ``h``.
* :func:`tangential_displacement`: Mindlin's tangential displacement ``delta`` (in the direction
  of ``Q``) from the reference cell, stuck at zero slip: ``0 = v_m = s + (F r)_m`` (eq. (1) of
  :mod:`shakedown.models.half_space.model`) with ``s`` the rigid shift of body 1's distant points
  against body 2's; body 1 carries ``-Q`` there, so ``delta = -s = (F r)_m``.
* :func:`fretting_run` runs the cycle of a constant ``P`` and a tangential ``Q(t)`` and returns
  the loop ``(Q_x(t), Q_y(t), delta(t))`` beside the run; :func:`fretting_run_fft` does the same
  with the matrix-free steps of :mod:`shakedown.models.half_space.matrix_free` (any grid size).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..evolution import solve_cycles
from ..evolution.cone_step import ConeStepSolver
from ..model import SolverError


def full_reactions(model, q, p, Qx, Qy, P):
    """Reactions of all cells: ``q`` (..., N-1, 2), ``p`` (..., N-1) -> (..., n^2, 2), (..., n^2)."""
    qm, pm = model.reference_reactions(q, p, Qx, Qy, P)
    q_full = np.insert(np.asarray(q, float), model.reference, qm, axis=-2)
    p_full = np.insert(np.asarray(p, float), model.reference, pm, axis=-1)
    return q_full, p_full


def static_path(model, path, substeps: int = 5, solver=None):
    """States along a path of resultants ``path[k] = (Q_x, Q_y, P)`` from the virgin state.

    Each segment (the first from ``(0, 0, 0)``) is cut into ``substeps`` implicit steps.
    Returns a list with, per path point, ``(result, q_full, p_full)``: the
    :class:`~shakedown.evolution.cone_step.ConeStepResult` and the reactions of all cells.
    """
    path = np.atleast_2d(np.asarray(path, float))
    solver = ConeStepSolver(model.system) if solver is None else solver
    prev = np.zeros(3)
    v = np.zeros((model.system.n_nodes, 2))
    out = []
    res = None
    for R in path:
        for a in np.arange(1, substeps + 1) / substeps:
            Rk = prev + a * (R - prev)
            qw, pw = model.welded(*Rk)
            res = solver.solve(v, qw, pw)
            if not res.success:
                raise SolverError(f"static path: step to {Rk} failed ({res.message})", partial=res)
            v = res.slip
        out.append((res, *full_reactions(model, res.q, res.p, *R)))
        prev = R
    return out


def stick_radius(model, q_full, p_full, Q, P):
    """Stick radius ``c`` [length] of a Cattaneo-Mindlin state with ``Q`` along ``x``.

    ``c^2 = (5/2) sum_j (f p_j - q_jx)(rho_j^2 + h^2/6) / (f P - Q)`` (the cell's own second
    moment ``h^2/6`` added to its centre's).
    """
    f = model.friction
    rho2 = np.sum(model.xy_cells**2, axis=1) + model.h**2 / 6
    deficit = f * np.asarray(p_full) - np.asarray(q_full)[..., 0]
    return np.sqrt(2.5 * np.sum(deficit * rho2, axis=-1) / (f * P - Q))


def stuck_area_radius(model, result):
    """``sqrt(A / pi)`` of the cells in contact that stick (the reference cell included)."""
    states = np.insert(np.asarray(result.states), model.reference, 0)
    return np.sqrt(np.count_nonzero(states == 0) * model.h**2 / np.pi)


def tangential_displacement(model, q_full, p_full):
    """Mindlin's ``delta`` [length], shape (..., 2): ``(F r)_m`` over the reference cell's
    tangential rows, from the offset kernels (``delta . Q > 0`` on first loading)."""
    n, k = model.n, model.kernels
    i, j = divmod(model.reference, n)
    ci, cj = np.divmod(np.arange(model.n_cells), n)
    di, dj = i - ci + n - 1, j - cj + n - 1
    q = np.asarray(q_full, float)
    p = np.asarray(p_full, float)
    vx = q[..., 0] @ k["xx"][di, dj] + q[..., 1] @ k["xy"][di, dj] - p @ k["zx"][di, dj]
    vy = q[..., 0] @ k["xy"][di, dj] + q[..., 1] @ k["yy"][di, dj] - p @ k["zy"][di, dj]
    return np.stack([vx, vy], axis=-1)


def run_arrays(model, run, P_of_t, Qx_of_t, Qy_of_t):
    """Steady-orbit arrays of a run: ``t`` (T,), ``q_full`` (T, n^2, 2), ``p_full`` (T, n^2),
    ``states`` (T, n^2) (reference cell: 0, stuck by construction), and ``Q`` (T, 2)."""
    tab = run.steady_table
    t = np.unique(tab["t"].to_numpy())
    n1 = model.n_cells - 1
    srt = tab.sort_values(["t", "node"])
    q = srt[["q_x", "q_y"]].to_numpy().reshape(t.size, n1, 2)
    p = srt["p"].to_numpy().reshape(t.size, n1)
    states = srt["state"].to_numpy().reshape(t.size, n1)
    Qx, Qy, P = Qx_of_t(t), Qy_of_t(t), P_of_t(t)
    qf, pf = full_reactions(model, q, p, Qx, Qy, P)
    st = np.insert(states.astype(object), model.reference, "stick", axis=1)
    return t, qf, pf, st, np.stack([Qx, Qy], axis=-1)


def fretting_run(model, P0, Qx, Qy=0.0, *, steps_per_cycle: int = 40, max_cycles: int = 10,
                 initial_slip=None, initial_gap=None, tol: float = 1e-9):
    """Cycle of constant ``P0`` and ``Q = (Qx cos 2 pi t, Qy sin 2 pi t)`` from a given state.

    The run starts from ``initial_slip`` (default: the state under ``P0`` at ``Q = (Qx, 0)``
    reached by a monotonic path, Mindlin's first loading).  Returns ``(run, loop)`` with
    ``loop`` a dict of the steady orbit: ``t``, ``Q`` (T, 2), ``delta`` (T, 2), ``q_full``,
    ``p_full``, ``states``, and ``W`` (the run's steady dissipation) and ``W_loop``
    (``-closed integral of delta . dQ`` by the trapezoidal rule, a cross-check of ``W``).
    """
    if initial_slip is None:
        res = static_path(model, [(0.0, 0.0, P0), (Qx, 0.0, P0)])[-1][0]
        initial_slip, initial_gap = res.slip, res.gap
    load = model.load_cycle(P0=P0, Qx=Qx, Qy=Qy)
    run = solve_cycles(model.system, load, 1.0, initial_slip=initial_slip,
                       initial_gap=initial_gap, steps_per_cycle=steps_per_cycle,
                       max_cycles=max_cycles, tol=tol)
    t, qf, pf, st, Q = run_arrays(model, run, lambda t: np.full_like(t, P0),
                                  lambda t: Qx * np.cos(2 * np.pi * t),
                                  lambda t: Qy * np.sin(2 * np.pi * t))
    delta = tangential_displacement(model, qf, pf)
    # W = closed integral of Q . d(delta) (the work of the tangential load on the relative
    # displacement of the distant points); trapezoidal over the orbit's instants
    dd = np.diff(delta, axis=0)
    Qm = 0.5 * (Q[1:] + Q[:-1])
    W_loop = float(np.sum(Qm * dd))
    return run, dict(t=t, Q=Q, delta=delta, q_full=qf, p_full=pf, states=st,
                     W=run.steady_dissipation, W_loop=W_loop)


def _loop_dict(model, t, Q, qf, pf, states, W):
    delta = tangential_displacement(model, qf, pf)
    # W = closed integral of Q . d(delta) (the work of the tangential load on the relative
    # displacement of the distant points); trapezoidal over the orbit's instants
    W_loop = float(np.sum(0.5 * (Q[1:] + Q[:-1]) * np.diff(delta, axis=0)))
    return dict(t=t, Q=Q, delta=delta, q_full=qf, p_full=pf, states=states, W=W, W_loop=W_loop)


def fretting_run_fft(model, P0, Qx, Qy=0.0, *, steps_per_cycle: int = 40, max_cycles: int = 10,
                     tol: float = 1e-9):
    """:func:`fretting_run` with the matrix-free steps (FFT products only; any grid size).

    The run starts from Mindlin's first loading (``P0``, then ``Q = (Qx, 0)``, by
    :func:`~shakedown.models.half_space.matrix_free.path_fft`).  Returns ``(run, loop)``: ``run`` a
    namespace with ``dissipation`` (per cycle), ``steady_dissipation``, ``cycles_to_steady``,
    ``period`` (1), ``status``, ``stuck_cells`` (cells in contact sticking throughout the last
    cycle, the reference cell included), ``residual``, ``iterations``; ``loop`` as in
    :func:`fretting_run`, with ``states`` ``"slip"`` where ``|q_i| = f p_i`` (to ``1e-6``),
    ``"separation"`` where ``p_i = 0``, else ``"stick"``.
    """
    from ..models.half_space.matrix_free import fretting_cycles_fft, path_fft

    S = int(steps_per_cycle)
    t = (np.arange(S) + 1) / S
    q0, p0 = path_fft(model, [(0.0, 0.0, P0), (Qx, 0.0, P0)])[-1]
    Q = np.stack([Qx * np.cos(2 * np.pi * t), Qy * np.sin(2 * np.pi * t)], axis=-1)
    out = fretting_cycles_fft(model, P0, Q[:, 0], Q[:, 1], max_cycles=max_cycles, tol=tol,
                              q0=q0, p0=p0)
    # the orbit closed: the instant t = 0 is the last one (t = 1)
    t, Q = np.r_[0.0, t], np.concatenate([Q[-1:], Q])
    qf = np.concatenate([out["q"][-1:], out["q"]])
    pf = np.concatenate([out["p"][-1:], out["p"]])
    rim = np.hypot(qf[..., 0], qf[..., 1]) >= model.friction * pf * (1 - 1e-6)
    states = np.where(pf <= 0, "separation", np.where(rim, "slip", "stick")).astype(object)
    W = out["W"]
    periodic = out["status"] == "periodic"
    run = SimpleNamespace(dissipation=W, steady_dissipation=float(W[-1]),
                          cycles_to_steady=len(W) - 1 if periodic else -1, period=1,
                          status=out["status"], stuck_cells=out["stuck"], residual=out["residual"],
                          iterations=out["iterations"])
    return run, _loop_dict(model, t, Q, qf, pf, states, run.steady_dissipation)
