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
        final state even after the slips at its extreme times (every node in contact), or, if
        nodes separate, the smallest stick margin is below the error: the verdict is not
        decided by this run.
    message : str
        The flag in words, with the advice that decides it; or, when the slips at the exact
        extreme times settled it, how far they moved the final state ('' when nothing was
        needed).
    """

    error: float
    within: bool
    message: str


def check_sampling(system, exact_load, lam, n_samples, v, w, shook_down, orbit, force_scale,
                   tol_force, solver=None) -> SamplingCheck:
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
    solver : StepSolver, optional
        Solver of the extra steps at the exact load's extreme times (built if omitted).
    """
    err_q, err_p = exact_load.sampling_error(n_samples)
    error = float(lam * max(err_q.max(initial=0.0), err_p.max(initial=0.0)))
    if not shook_down or error <= tol_force or not orbit:
        return SamplingCheck(error, False, "")
    if solver is None:
        from .complementarity import StepSolver

        solver = StepSolver(system)
    f = system.friction
    gaps = np.concatenate([r.w for r in orbit])
    if np.all(gaps == 0):
        return _settle_at_extremes(system, exact_load, lam, n_samples, v, error, force_scale,
                                   tol_force, solver)
    contact = gaps == 0
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
    if margin[worst] > tol_force:
        # the budget falls like 1 - cos(pi k / S); the first S' whose budget is below the margin
        S2 = n_samples
        while S2 < 2 ** 24 and budget[worst] * _loss(exact_load, S2) / _loss(exact_load,
                                                                             n_samples) >= margin[worst]:
            S2 *= 2
        advice = (f"a run with steps_per_cycle >= {S2} decides it if it ends in this state "
                  "(the error falls like 1 / steps_per_cycle^2)")
    else:
        advice = ("the node sits at its friction limit, so no number of steps decides it (the "
                  "margin stays ~0 while the error shrinks); the shakedown holds for the load "
                  f"sampled at {n_samples} points, and for the exact load only if lam < lam1 "
                  "(shakedown bounds)")
    return SamplingCheck(error, True, (
        f"shook down on the load sampled at {n_samples} points per period, but {detail}: the "
        f"verdict lies within the load's sampling error ({error:.3g}); {advice}"))


def _loss(load, S):
    """Sampling loss ``1 - cos(pi / S)`` of the first harmonic (1 for sampled loads)."""
    return 1.0 - np.cos(np.pi / S) if load.kind == "harmonic" else 1.0


def _exact_margins(system, load, lam, v, minima=None):
    """Smallest stick margins over the period of the exact load at the fixed state ``(v, 0)``:
    ``(margin_I, t_I, margin_II, t_II)``, each shape (N,) (closed form, MODEL.md s.2-3).

    ``minima``, the load's ``(periodic_min(-1, f), periodic_min(1, f))``, which do not depend on
    the state, may be passed to skip recomputing them."""
    f = system.friction
    q = load.q0 + system.A @ v
    p = load.p0 + system.B.T @ v
    if minima is None:
        minima = (load.periodic_min(-1.0, f), load.periodic_min(1.0, f))
    (mI, tI), (mII, tII) = minima   # I_j: f p - q >= 0; II_j: f p + q >= 0
    return f * p - q + lam * mI, tI, f * p + q + lam * mII, tII


def _settle_at_extremes(system, load, lam, n_samples, v, error, force_scale, tol_force, solver,
                        max_rounds=None):
    """Decide a shakedown found on sampled loads for the exact load.

    With every node in contact, a stuck state's stick margins are an offset plus ``lam`` times
    the exact minimum of the load's periodic part, and that minimum is reached at a known time
    ``t*`` (:meth:`~shakedown.LoadCycle.periodic_min`).  If the final state breaks a constraint
    of the exact load, the exact evolution slips there up to ``t*``: one step from the state to
    the exact load at ``t*``.  Repeating this for the worst constraint until every exact margin
    holds gives a state that provably stays stuck under the exact load at all times; what the
    sampling error affected is then only the final state (by the slips of these steps), not the
    verdict.  If a step opens a gap, fails, leaves the state where it was (a fixed point: the
    rounds would repeat it) or the rounds run out (``4 N + 4``), the verdict is not decided
    (``within = True``).
    """
    n = system.n_nodes
    rounds = 4 * n + 4 if max_rounds is None else max_rounds
    v0 = np.asarray(v, float)
    cur = v0.copy()
    f = system.friction
    minima = (load.periodic_min(-1.0, f), load.periodic_min(1.0, f))  # state-independent
    done, why = rounds, ""
    for k in range(rounds + 1):
        mI, tI, mII, tII = _exact_margins(system, load, lam, cur, minima)
        margins = np.minimum(mI, mII)
        worst = int(np.argmin(margins))
        if margins[worst] >= -tol_force:
            if k == 0:
                return SamplingCheck(error, False, "")
            shift = np.abs(cur - v0) * system.diagonal()[:n] / force_scale
            j = int(np.argmax(shift))
            return SamplingCheck(error, False, (
                f"the exact load (its extremes in closed form, not the {n_samples} samples) "
                f"stays stuck after {k} further slip step(s) at its extreme times, of at most "
                f"{abs(cur[j] - v0[j]):.3g} at node {j + 1}: the shakedown holds for the exact "
                "load; the sampling affects only the final slips, by that much"))
        if k == rounds:
            break
        t_star = float(tI[worst] if mI[worst] <= mII[worst] else tII[worst])
        q_w, p_w = load.evaluate(t_star, lam)
        r = solver.solve(cur, q_w, p_w, None)
        if not r.success or np.any(r.gap != 0):
            done, why = k + 1, "; the last step failed or opened a gap"
            break
        if np.array_equal(r.slip, cur):
            # the step leaves the state where it was (the violation is within the step's own
            # tolerance): a fixed point, every further round would repeat this one (issue 25:
            # up to 4 N + 4 identical step solves saved)
            done, why = k + 1, "; the last step left the state where it was"
            break
        cur = np.asarray(r.slip, float)
    which = "I" if mI[worst] <= mII[worst] else "II"
    return SamplingCheck(error, True, (
        f"shook down on the load sampled at {n_samples} points per period, but the exact load "
        f"breaks constraint {which}_{worst + 1} by {-margins[worst]:.3g} "
        f"({-margins[worst] / force_scale:.2g} of the force scale) even after slipping at its "
        f"extreme times ({done} round(s){why}): the verdict lies within the load's sampling error "
        f"({error:.3g}) and this run cannot decide it. The bounds can: above lam2 of the exact "
        "load no state stays stuck (cyclic slip from every initial state)"))


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
                         solver.feas_tol * run.force_scale, solver)
    msg = run.message + ("; " + chk.message if chk.message else "")
    return replace(run, sampling_error=chk.error, within_sampling_error=chk.within, message=msg,
                   sampling_note=chk.message)
