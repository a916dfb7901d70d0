"""Verdicts of the cyclic solver's results in plain sentences (issue 25).

:func:`cycles_verdict` (``CycleRun.verdict()``), :func:`uniqueness_verdict`
(``UniquenessStudy.verdict()``) and :func:`steady_verdict` (``SteadyCycle.verdict()``): the
answer first, numbers to 4 significant digits (:func:`shakedown.model.numbers.sig`), nodes and
initial states numbered from 1.  A shakedown is stated for the load the run saw; when that was a
sampled harmonic load the verdict says what the check against the exact load found
(:mod:`.sampling`), and, when that check could not decide, what the bounds of the exact load
decide.
"""

from __future__ import annotations

import numpy as np

from ..model.numbers import sig
from ..model.results import bounds_claim

__all__ = ["cycles_verdict", "uniqueness_verdict", "steady_verdict"]


def _slipping_nodes(run) -> list[int]:
    """Nodes (numbered from 1) that slip somewhere in the steady cycle."""
    t = run.steady_table
    if t is None or len(t) == 0 or "state" not in t:
        return []
    slipping = t[t["state"].isin(["forward", "backward", "slip"])]["node"].unique()
    return sorted(int(j) + 1 for j in slipping)


def _node_list(nodes) -> str:
    nodes = [str(j) for j in nodes]
    word = "node" if len(nodes) == 1 else "nodes"
    return f"{word} {', '.join(nodes[:12])}" + (", ..." if len(nodes) > 12 else "")


def _exact_load_sentence(run, lam, bounds) -> str:
    """What the bounds of the exact load say about a shakedown that the run could not check
    against it (``run.within_sampling_error``)."""
    if bounds is None:
        return (" Whether the exact load shakes down is not decided by this run: the bounds "
                "decide it when lam > lam2 (never) or lam < lam1 (from every initial state).")
    lam1, lam2 = float(bounds.lam1), float(bounds.lam2)
    if lam > lam2:
        return (f" The bounds of the exact load decide it: lam > lam2 = {sig(lam2)}, so no state "
                "stays stuck under the exact load (proved): cyclic slip from every initial "
                f"state; the run shook down only on the load sampled at {run.steps_per_cycle} "
                "points.")
    proved, status = bounds_claim(bounds)
    if lam < lam1:
        return (f" The bounds of the exact load decide it: lam < lam1 = {sig(lam1)}, so it shakes "
                f"down from every initial state ({status}); the sampling affects only the "
                "final slips.")
    return (f" The bounds of the exact load leave it open: lam1 = {sig(lam1)} < lam < lam2 = "
            f"{sig(lam2)}, where the initial state decides.")


def cycles_verdict(run, lam: float, energy: str = "[force x length]", study=None,
                   bounds=None) -> str:
    """Plain sentences: shook down after k cycles / cyclic slip with W per cycle / no steady state.

    Parameters
    ----------
    run : CycleRun
    lam : float
        Load factor of the run.
    energy : str
        Unit of energy (force x length) for ``W``.
    study : UniquenessStudy, optional
        Adds a sentence on whether the dissipation depends on the initial state.
    bounds : ShakedownBounds, optional
        Bounds of the exact load: they decide a shakedown that lies within the load's sampling
        error (``run.within_sampling_error``) when ``lam > lam2`` or ``lam < lam1``.

    Numbers have 4 significant digits (:func:`shakedown.model.numbers.sig`), spreads 3.
    """
    at = f"At lam = {sig(lam)}"
    if run.status == "periodic" and run.shook_down:
        k = max(int(run.cycles_to_steady), 0)
        when = "from the first cycle on" if k == 0 else f"after {k} cycle{'s' * (k != 1)}"
        text = f"{at}, it shook down {when}: no node slips in the steady state (W = 0)."
        note = getattr(run, "sampling_note", "")
        if getattr(run, "within_sampling_error", False):  # issue 10 item 9, issue 25
            text += (f" But this lies within the load's sampling error "
                     f"({sig(run.sampling_error, 3)}): {note}." + _exact_load_sentence(
                         run, lam, bounds))
        elif note:
            text += f" Checked against the exact load: {note}."
    elif run.status == "periodic":
        slip = _slipping_nodes(run)
        n = int(np.shape(run.final_slip)[0])
        which = ""
        if len(slip) > 12:
            which = f", {len(slip)} of {n} nodes slip ({_node_list(slip)})"
        elif slip:
            which = f", {_node_list(slip)} slip{'s' * (len(slip) == 1)}"
        text = (f"{at}, cyclic slip: W = {sig(run.steady_dissipation)} {energy} per cycle, "
                f"period {int(run.period)}{which}.")
    elif run.status == "not_converged":
        W = np.asarray(run.dissipation, float)
        last = f" (last cycle: W = {sig(W[-1])} {energy})" if W.size else ""
        n = int(run.n_cycles)
        text = (f"{at}, it did not reach a steady state in {n} cycle{'s' * (n != 1)}{last}; "
                "raise max_cycles to go on.")
    else:
        text = f"{at}, the run stopped before a steady state: {run.message}"
    if study is not None:
        text += " " + uniqueness_verdict(study, energy, lead=False)
    return text


def uniqueness_verdict(study, energy: str = "[force x length]", lead: bool = True) -> str:
    """Whether the steady dissipation depends on the initial state, in one sentence (``lead``:
    starting with the load factor)."""
    W = study.table["steady_dissipation"].to_numpy(float)
    n = int(study.n_states)
    at = (f"At lam = {sig(study.lam)}, from" if lead else "From") + \
        f" {n} initial state{'s' * (n != 1)}"
    if study.unique_dissipation:
        return (f"{at} the steady dissipation is the same (spread "
                f"{sig(study.dissipation_spread, 3)} {energy}, tolerance {sig(study.w_tol, 3)}).")
    if np.isfinite(W).any():
        return (f"{at} the steady dissipation differs: W from {sig(np.nanmin(W))} to "
                f"{sig(np.nanmax(W))} {energy} per cycle ({study.fraction_shook_down:.0%} of them "
                "shook down); the initial state matters.")
    return f"{at} none reached a steady state."


def steady_verdict(sc, energy: str = "[force x length]") -> str:
    """The direct steady-cycle solver's answer: the verification run's verdict and the solver's
    status."""
    how = (f"direct steady-cycle solver ({sc.method}): {sc.status} after {sc.n_evaluations} "
           f"periods, residual {sig(sc.residual, 3)}")
    if sc.run is None:
        return f"No steady cycle: {how}; {sc.message}"
    return f"{cycles_verdict(sc.run, sc.run.lam, energy)} ({how})."
