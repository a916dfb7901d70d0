"""How far a cycle run's verdict can be trusted: the load's sampling error and overflow.

Implicit steps (and the event path of a harmonic load) see the load only at
``t = k / steps_per_cycle``; between samples the welded reactions are linear, so the peaks of a
harmonic load are cut by up to ``lam * a_k (1 - cos(pi k / S))`` per harmonic
(:meth:`~shakedown.LoadCycle.sampling_error`).  A run that *shakes down* on the sampled load may
slip under the exact one when the margin it keeps is smaller than that (MODEL.md s.3: the
extreme constraints ``I_j``, ``II_j`` use the exact extremes).  This module measures both and
words the flag; :func:`~shakedown.evolution.cycles.solve_cycles` attaches them to its result.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SamplingCheck:
    """Sampling error of a run's load and whether its verdict lies within it.

    Attributes
    ----------
    error : float
        ``lam * max_j max(err_q_j, err_p_j)`` [force]: the largest amount by which the sampled
        welded reactions miss the exact ones (0 when the run saw the load exactly).
    within : bool
        ``True`` when the run shook down but the exact load breaks a stick constraint at the
        final state (or, if nodes separate, the smallest stick margin is below the error):
        the verdict is not decided by this run.
    message : str
        The flag in words ('' when ``within`` is False).
    """

    error: float
    within: bool
    message: str


def check_sampling(system, exact_load, lam, n_samples, v, w, shook_down, orbit, force_scale,
                   tol_force) -> SamplingCheck:
    """Sampling error of ``exact_load`` at ``n_samples`` and the flag of a shakedown verdict.

    Parameters
    ----------
    system : DiscreteSystem
    exact_load : LoadCycle
        The load the user gave (before any ``to_samples``).
    lam : float
        Load factor.
    n_samples : int
        Samples (implicit steps) per period the run used.
    v, w : ndarray, shape (N,)
        Final state.
    shook_down : bool
        The run's verdict.
    orbit : list of CycleRecord
        The steady orbit (its ``q``, ``p``, ``w`` per point).
    force_scale : float
        ``F`` of the run [force].
    tol_force : float
        Feasibility tolerance of the steps [force]; violations below it are round-off.
    """
    err_q, err_p = exact_load.sampling_error(n_samples)
    error = float(lam * max(err_q.max(initial=0.0), err_p.max(initial=0.0)))
    if not shook_down or error <= tol_force or not orbit:
        return SamplingCheck(error, False, "")
    f = system.friction
    gaps = np.concatenate([r.w for r in orbit])
    if np.all(gaps == 0):
        # exact: the state is fixed, so each stick margin is an offset plus lam * a closed-form
        # minimum of the exact periodic part (MODEL.md s.2-3)
        q = exact_load.q0 + system.A @ v + system.B @ w
        p = exact_load.p0 + system.B.T @ v + system.C @ w
        m_back = f * p - q + lam * exact_load.periodic_min(-1.0, f)[0]   # I_j: f p - q >= 0
        m_fwd = f * p + q + lam * exact_load.periodic_min(1.0, f)[0]     # II_j: f p + q >= 0
        margins = np.minimum(m_back, m_fwd)
        worst = int(np.argmin(margins))
        if margins[worst] >= -tol_force:
            return SamplingCheck(error, False, "")
        which = "I" if m_back[worst] <= m_fwd[worst] else "II"
        detail = (f"the final state breaks constraint {which}_{worst + 1} of the exact load by "
                  f"{-margins[worst]:.3g} ({-margins[worst] / force_scale:.2g} of the force "
                  "scale)")
    else:
        contact = np.concatenate([r.w for r in orbit]) == 0
        P = np.concatenate([r.p for r in orbit])
        Q = np.concatenate([r.q for r in orbit])
        margin = np.where(contact, f * P - np.abs(Q), np.inf).min(axis=0)
        budget = lam * ((1.0 + f) * np.maximum(err_q, err_p))
        short = np.flatnonzero(margin < budget)
        if short.size == 0:
            return SamplingCheck(error, False, "")
        worst = int(short[np.argmin(margin[short] - budget[short])])
        detail = (f"node {worst + 1} keeps a stick margin of only {margin[worst]:.3g}, below "
                  f"what the sampling can hide ({budget[worst]:.3g})")
    return SamplingCheck(error, True, (
        f"shook down on the load sampled at {n_samples} points per period, but {detail}: the "
        f"verdict lies within the load's sampling error ({error:.3g}); rerun with more "
        "steps_per_cycle"))


def non_finite_message(force_scale: float, system) -> str:
    """Why a run's numbers overflowed, and the fix."""
    k = float(np.abs(system.diagonal()).min())
    return (f"the result is not finite: forces of order F = {force_scale:.3g} over stiffnesses "
            f"of order {k:.3g} give energies ~F^2/k beyond the floating-point range; lower the "
            "load factor or express forces in larger units")


def trust(run, system, exact_load, orbit, solver):
    """``run`` with overflow made a failure and a shakedown within the load's sampling error
    flagged (``within_sampling_error``, message).

    ``exact_load`` is the load the user gave, ``orbit`` the steady orbit's records.
    """
    from dataclasses import replace

    numbers = (run.dissipation, run.final_slip, run.final_gap, [run.force_scale])
    if not all(np.all(np.isfinite(x)) for x in numbers) or (
            run.period and not np.isfinite(run.steady_dissipation)):
        return replace(run, status="non_finite", shook_down=False,
                       message=non_finite_message(run.force_scale, system) + "; " + run.message)
    if run.method == "events" and exact_load.kind == "samples":
        return run  # the exact path of the given samples: nothing was sampled
    chk = check_sampling(system, exact_load, run.lam, run.steps_per_cycle, run.final_slip,
                         run.final_gap, run.shook_down, orbit, run.force_scale,
                         solver.feas_tol * run.force_scale)
    msg = run.message + ("; " + chk.message if chk.within else "")
    return replace(run, sampling_error=chk.error, within_sampling_error=chk.within, message=msg)
