"""Matrix-free implicit steps and cycles of the half-space contact (FFT products only).

The state of the contact is the cell forces ``(q, p)`` at the last instant (all ``n^2`` cells,
the reference cell included).  The step of MODEL.md s.8.4 to the resultants ``(Q, P)`` of the
next instant has, in compliance form (:mod:`.model` eq. (1)), a normal and a tangential part:

* normal: ``gap = g + F_zz p + F_zt q - d >= 0``, ``p >= 0``, ``p . gap = 0``, ``sum p = P``
  -- frictionless contact with the extra gap ``F_zt q`` (:func:`.normal.normal_contact`,
  Polonsky-Keer conjugate gradients, warm-started from the last ``p``);
* tangential: with ``p`` known, the convex problem of :mod:`.tangential` (FISTA), the pressure
  change entering as the slip ``c = -F_tz (p - p_k)``.

For similar materials (``beta = 0``) ``F_zt = F_tz = 0``: the normal part does not depend on
``q`` and one pass is exact (with a constant ``P`` the normal problem is solved once).  For
dissimilar materials (``beta != 0``) the two parts are alternated to a fixed point
(block Gauss-Seidel: normal with the last ``q``, tangential with the new ``p``) until ``p`` and
``q`` change by less than ``coupling_tol`` of ``P`` and ``f max p``; ``P(t)`` may vary in both
cases.  Every step is checked by the residuals of both parts (:func:`.tangential.step_residual`,
:func:`.normal.check_normal_contact`), independently of the iterations.  These are the steps
of the dense cone engine on :attr:`.model.HalfSpaceModel.system` (where its reference cell
sticks), so the dissipation ``W = sum_k -q_{k+1} . dv_k`` matches it
(``tests/models/test_half_space_matrix_free.py``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ...model import InputError, SolverError
from .normal import check_normal_contact, normal_contact
from .tangential import SurfaceCompliance, project_resultant, solve_tangential_step, step_residual

#: The tangential compliance operator (``F_tt`` products by FFT), by its former name.
TangentialCompliance = SurfaceCompliance

__all__ = ["FFTStepper", "TangentialCompliance", "fretting_cycles_fft", "path_fft",
           "project_resultant", "step_residual"]

#: Largest accepted step residual (tangential and normal, dimensionless).
STEP_RESIDUAL_MAX = 1e-6


@dataclass
class StepOutcome:
    """One matrix-free step: forces ``q`` (N, 2), ``p`` (N,) [force], slip increment ``dv``
    (N, 2) [length], ``residual`` (dimensionless), FISTA ``iterations``, normal/tangential
    ``passes`` (1 for similar materials)."""

    q: np.ndarray
    p: np.ndarray
    dv: np.ndarray
    residual: float
    iterations: int
    passes: int


class FFTStepper:
    """Implicit steps of a :class:`.model.HalfSpaceModel` with FFT products only (module docstring).

    Parameters
    ----------
    model : HalfSpaceModel
    step_tol : float
        FISTA stops when its gradient mapping is below ``step_tol * f max p``.
    coupling_tol : float
        Dissimilar materials: the alternation stops when ``p`` changes by less than
        ``coupling_tol * P`` and ``q`` by less than ``coupling_tol * f max p``.
    max_passes : int
        Most normal/tangential passes of a coupled step.
    """

    def __init__(self, model, *, step_tol: float = 1e-10, coupling_tol: float = 1e-10,
                 max_passes: int = 200):
        self.model = model
        self.ops = SurfaceCompliance(model)
        self.coupled = self.ops.coupled
        self.L = 1.05 * self.ops.lipschitz()
        self.step_tol, self.coupling_tol, self.max_passes = step_tol, coupling_tol, max_passes
        self._normal_cache = {}

    def normal(self, P, q, p_init):
        """Normal contact at ``P`` with the gap of the shear forces ``q``: ``(p, approach)``."""
        if not self.coupled and P in self._normal_cache:  # similar materials: p depends on P only
            return self._normal_cache[P]
        sol = normal_contact(self.model, P, rtol=1e-12, p_init=p_init,
                             extra_gap=self.ops.zt(q) if self.coupled else None, apply=self.ops.zz)
        if not self.coupled and len(self._normal_cache) < 1024:
            self._normal_cache[P] = (sol.p, sol.approach)
        return sol.p, sol.approach

    def step(self, q_prev, p_prev, Q, P, guesses=()) -> StepOutcome:
        """The step from ``(q_prev, p_prev)`` to the resultants ``Q`` (2,), ``P`` [force]."""
        f = self.model.friction
        q, p_old, its, passes, change = q_prev, p_prev, 0, 0, np.inf
        guesses = list(guesses)
        while True:
            passes += 1
            # inexact alternation: the inner tolerance follows the last change of the fixed point
            inner = max(self.step_tol, min(1e-6, 1e-2 * change)) if self.coupled else self.step_tol
            p, d = self.normal(P, q, p_old if np.any(p_old > 0) else None)
            radius = f * p
            if np.linalg.norm(Q) >= radius.sum():
                raise InputError(f"|Q| = {np.linalg.norm(Q):.4g} must stay below f P = "
                                 f"{radius.sum():.4g} (gross slip) in a matrix-free step")
            c = self.ops.tz(p - p_prev) if self.coupled else None
            q_new, ds, k = solve_tangential_step(self.ops.tt, q_prev, radius, Q, self.L, c=c,
                                                 guesses=guesses if passes == 1 else [q],
                                                 tol=inner)
            its += k
            scale_q = max(float(radius.max()), 1e-300)
            change = max(np.max(np.abs(q_new - q)) / scale_q, np.max(np.abs(p - p_old)) / P)
            q, p_old = q_new, p
            if not self.coupled or (change <= self.coupling_tol and inner == self.step_tol):
                break
            if passes >= self.max_passes:
                raise SolverError(f"matrix-free coupled step: the normal/tangential alternation did "
                                  f"not settle in {passes} passes (change {change:.1e})", partial=q)
        scale_v = scale_q * self.L
        res_t, dv = step_residual(self.ops.tt, q, q_prev, radius, Q, ds, scale_q, scale_v, c=c)
        res_n = 0.0
        if self.coupled:
            res_n = check_normal_contact(self.model, p, d + 0.0, P, self.ops.zt(q))
        return StepOutcome(q, p, dv, max(res_t, res_n), its, passes)


def path_fft(model, path, substeps: int = 5, stepper=None):
    """States ``(q, p)`` (all cells) along resultants ``path[k] = (Q_x, Q_y, P)`` from the virgin
    state, each segment in ``substeps`` matrix-free steps (the counterpart of
    :func:`shakedown.studies.half_space.static_path`)."""
    stepper = FFTStepper(model) if stepper is None else stepper
    N = model.n_cells
    q, p, prev = np.zeros((N, 2)), np.zeros(N), np.zeros(3)
    out = []
    for R in np.atleast_2d(np.asarray(path, float)):
        for a in np.arange(1, substeps + 1) / substeps:
            Rk = prev + a * (R - prev)
            st = stepper.step(q, p, Rk[:2], Rk[2])
            if st.residual > STEP_RESIDUAL_MAX:
                raise SolverError(f"matrix-free path: step to {Rk} has residual {st.residual:.1e}",
                                  partial=st)
            q, p = st.q, st.p
        out.append((q, p))
        prev = R
    return out


def fretting_cycles_fft(model, P0, Qx_samples, Qy_samples=None, *, P_samples=None,
                        max_cycles: int = 10, tol: float = 1e-9, step_tol: float = 1e-10,
                        coupling_tol: float = 1e-10, q0=None, p0=None, progress=None):
    """Cycles of ``Q(t_k) = (Qx_samples[k], Qy_samples[k])`` and ``P(t_k)``, matrix-free.

    Parameters
    ----------
    model : HalfSpaceModel
        Similar or dissimilar materials.
    P0 : float
        Normal force of the initial state [force] (and of every instant without ``P_samples``).
    Qx_samples, Qy_samples : array_like, shape (S,)
        The tangential resultant at ``t = k / S`` [force] (one implicit step each; the first
        step goes to ``t = 1 / S`` if the samples are given at ``(k + 1) / S``).
    P_samples : array_like, shape (S,), optional
        The normal force at the same instants [force] (default: ``P0`` throughout).
    q0, p0 : ndarray, shape (n^2, 2) and (n^2,), optional
        Initial cell forces (default: ``q = 0`` and the frictionless contact under ``P0``, the
        state after ``P0`` alone for similar materials; for dissimilar ones pass a state, e.g.
        from :func:`path_fft`).
    tol : float
        Steady when the state changes by at most ``tol`` over a cycle (``max |dq| / (f max p)``).
    step_tol, coupling_tol : float
        See :class:`FFTStepper`.

    Returns
    -------
    dict
        ``W`` (per cycle), ``state_change`` (per cycle), ``q`` (S, n^2, 2) and ``p`` (S, n^2) of the
        last cycle, ``stuck`` (cells in contact and sticking through the last cycle),
        ``residual`` (largest step residual), ``iterations`` (FISTA iterations per step),
        ``passes`` (normal/tangential passes per step), ``wall_time`` [s], ``status``
        ("periodic" or "not_converged").
    """
    t0 = time.perf_counter()
    Qx = np.asarray(Qx_samples, float)
    Qy = np.zeros_like(Qx) if Qy_samples is None else np.asarray(Qy_samples, float)
    Ps = np.full(Qx.shape, float(P0)) if P_samples is None else np.asarray(P_samples, float)
    if Qx.ndim != 1 or Qy.shape != Qx.shape or Ps.shape != Qx.shape or Qx.size < 1:
        raise InputError(f"Qx_samples, Qy_samples and P_samples must be 1-D of one length, got "
                         f"shapes {Qx.shape}, {Qy.shape}, {Ps.shape}")
    if not np.all(Ps > 0):
        raise InputError("P_samples must be > 0 (the contact must stay closed somewhere)")
    Qs = np.column_stack([Qx, Qy])
    stepper = FFTStepper(model, step_tol=step_tol, coupling_tol=coupling_tol)
    N = model.n_cells
    q = np.zeros((N, 2)) if q0 is None else np.array(q0, float)
    p = stepper.normal(float(P0), q, None)[0] if p0 is None else np.array(p0, float)
    if np.max(np.hypot(*Qs.T) / (model.friction * Ps)) >= 1:
        raise InputError("|Q| must stay below f P (gross slip) for the fretting cycle")
    W, change, worst, iters, passes = [], [], 0.0, [], []
    status, prev_period, q_before = "not_converged", None, None
    for cyc in range(max_cycles):
        q_start = q.copy()
        hist_q, hist_p, Wc = [], [], 0.0
        slipped, closed = np.zeros(N, bool), np.ones(N, bool)
        for k in range(len(Qs)):
            guesses = []
            if prev_period is not None:
                guesses.append(prev_period[k])
            if q_before is not None:
                guesses.append(2 * q - q_before)
            st = stepper.step(q, p, Qs[k], float(Ps[k]), guesses)
            if st.residual > STEP_RESIDUAL_MAX:
                raise SolverError(f"matrix-free step {k} of cycle {cyc + 1}: residual "
                                  f"{st.residual:.1e}", partial=st)
            worst = max(worst, st.residual)
            iters.append(st.iterations)
            passes.append(st.passes)
            Wc += float(-np.sum(st.q * st.dv))
            scale_v = model.friction * float(st.p.max()) * stepper.L
            slipped |= np.hypot(*st.dv.T) > 1e-7 * scale_v
            closed &= st.p > 0
            q_before, q, p = q, st.q, st.p
            hist_q.append(q)
            hist_p.append(p)
        prev_period = hist_q
        W.append(Wc)
        change.append(float(np.max(np.abs(q - q_start)) / (model.friction * float(p.max()))))
        if progress is not None:
            progress(cyc + 1, max_cycles, Wc)
        if change[-1] <= tol:
            status = "periodic"
            break
    return dict(W=np.array(W), state_change=np.array(change), q=np.array(hist_q),
                p=np.array(hist_p), stuck=np.flatnonzero(~slipped & closed), residual=worst,
                iterations=iters, passes=passes, wall_time=time.perf_counter() - t0,
                status=status)
