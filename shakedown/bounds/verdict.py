"""The answer of :func:`~shakedown.shakedown_bounds` in plain sentences (issue 9).

``bounds_verdict(b)`` states the answer first ("shakes down from every initial state for
lam < lam1 = ...") and then explains what is unusual: ``lam_adj`` below ``lam1``, and why a load
factor is 0, ``nan`` or ``inf``.  Numbers are rounded to 4 significant digits for reading
(``to_dict()`` and the JSON keep full precision); two load factors that agree to the engine's
tolerance ``LAM_RTOL`` are said to be equal rather than printed as two numbers.  Nodes are
numbered from 1, as everywhere a person reads.
"""

from __future__ import annotations

import numpy as np

from ..model.numbers import sig
from ..model.results import bounds_claim
from .provenance import costly_fallback

#: Two load factors closer than this (relative) are reported as equal; the LP answers are
#: accurate to HiGHS's feasibility tolerance 1e-7 (``engine.LAM_RTOL``).
SAME_RTOL = 1e-7


def fmt(x: float, digits: int = 4) -> str:
    """A number for reading: ``digits`` significant digits, trailing zeros kept
    (:func:`shakedown.model.numbers.sig`); ``inf``/``nan`` spelled out."""
    return sig(x, digits)


def every_state_status(b) -> tuple[bool, str]:
    """Whether "shakes down from every initial state for lam < lam1" is proved for ``b``'s
    system, and the words for its status (:func:`shakedown.model.results.bounds_claim`)."""
    return bounds_claim(b)


def _same(a: float, b: float) -> bool:
    return bool(np.isfinite(a) and np.isfinite(b)
                and abs(a - b) <= SAME_RTOL * max(abs(a), abs(b), 1e-300))


def constraint_name(k: int, n: int) -> str:
    """Name of extreme constraint ``k`` (0-based row) with its node numbered from 1."""
    return f"{'I' if k < n else 'II'}_{k % n + 1}"


def _static_load(b):
    """``(q0, f p0, p0)`` recovered from the constraint offsets (engine module docstring)."""
    cs = b.constraints
    n = cs.n_nodes
    cI, cII = cs.c[:n], cs.c[n:]
    return 0.5 * (cII - cI), 0.5 * (cI + cII), np.asarray(cs.sep_c, float)


def _nodes(mask) -> str:
    idx = [str(j + 1) for j in np.flatnonzero(mask)]
    return ("node " if len(idx) == 1 else "nodes ") + ", ".join(idx[:12]) + (
        ", ..." if len(idx) > 12 else "")


def bounds_verdict(b, adjacency: bool = False) -> str:
    """Plain sentences stating what ``b`` (a :class:`ShakedownBounds`) means.

    Parameters
    ----------
    b : ShakedownBounds
    adjacency : bool
        ``lam_adj`` was computed (``shakedown_bounds(..., adjacency=True)``), so an infinite
        value means that no node's two extreme constraints ever meet (``b`` alone cannot tell
        that from "not computed").

    Returns
    -------
    str
        One paragraph: the answer first, then explanations of special values.

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    >>> load = sd.LoadCycle.from_harmonics([0.0], [2.0], q_cos=[1.0])
    >>> print(bounds_verdict(sd.shakedown_bounds(s, load)))  # doctest: +ELLIPSIS
    Shakes down from every initial state for lam < lam1 = lam2 = 1.000 (proved for one ...
    """
    lam1, lam2, lam_adj = float(b.lam1), float(b.lam2), float(b.lam_adj)
    n = b.n_nodes
    proved, status = every_state_status(b)
    q0, fp0, p0 = _static_load(b)
    scale = max(float(np.max(np.abs(np.concatenate([q0, p0])), initial=0.0)), 1e-300)
    tensile = p0 < -1e-12 * scale  # relative to the static load's own size
    out = []
    if b.status == "infeasible":
        out.append("No safe state exists even at lam = 0, so lam1 and lam2 are undefined (nan): "
                   "the static load alone makes the system slip without bound.")
        if tensile.any():
            out.append(
                f"The static normal reaction p0 is tensile (p0 < 0, compression positive) at "
                f"{_nodes(tensile)}: under the static load alone that node would separate from "
                "the obstacle, which these bounds (every node in contact) do not model. Check "
                "the sign of p0 (MODEL.md: p is the reaction of the obstacle, compression "
                "positive).")
        else:
            over = np.abs(q0) > fp0 + 1e-12 * scale
            if over.any():
                out.append(f"|q0| exceeds friction x p0 at {_nodes(over)}.")
        return " ".join(out)
    if b.status.startswith("unbounded"):
        why = {
            "unbounded_no_periodic_part": "the load has no periodic part (r1 = 0)",
            "unbounded_periodic_never_excludes": "the periodic load never tightens a friction "
                                                 "constraint",
        }.get(b.status, "a safe state exists at every load factor")
        out.append(f"Shakes down at every load factor: {why}, so lam2 = inf"
                   + (" and lam1 = inf." if np.isinf(lam1) else f"; lam1 = {fmt(lam1)}."))
    elif _same(lam1, lam2):
        out.append(f"Shakes down from every initial state for lam < lam1 = lam2 = {fmt(lam1)} "
                   f"({status}); never above (cyclic slip from every initial state: no safe "
                   "state exists, proved): the initial state never decides.")
    elif (not proved and np.isfinite(lam_adj) and lam_adj < lam1
          and not _same(lam_adj, lam1)):
        node = int(b.adjacency_node) + 1
        first = (f"Shakes down from every initial state for lam < lam_adj = {fmt(lam_adj)} in "
                 "every run so far (numerical evidence, not a proof); " if lam_adj > 0 else "")
        span = "between lam_adj and" if lam_adj > 0 else "For lam <"
        out.append(
            f"{first}{span} lam1 = {fmt(lam1)} every extreme constraint is still "
            "active (the criterion for shakedown from every initial state, proven for two "
            f"nodes and for B = 0), but the two extreme constraints of node {node} (I_{node}, "
            f"II_{node}) already meet in the safe region, and in coupled systems with three or "
            "more nodes some initial states were seen to slip cyclically there (numerical "
            "evidence, README 'Findings'); from some initial states only for "
            f"{fmt(lam1)} < lam < lam2 = {fmt(lam2)}; never above lam2 (cyclic slip from every "
            "initial state).")
    else:
        first = (f"Shakes down from every initial state for lam < lam1 = {fmt(lam1)} "
                 f"({status}); " if lam1 > 0 else "")
        out.append(
            f"{first}from some initial states only for {fmt(lam1)} < lam < lam2 = {fmt(lam2)} "
            "(there the initial state decides); never above lam2 (cyclic slip from every "
            "initial state).")
        if np.isnan(lam_adj) and not proved and lam1 > 0:
            out.append(
                "lam_adj was not computed (shakedown_bounds(..., adjacency=True)): in coupled "
                "systems with three or more nodes some initial states were seen to slip "
                "cyclically between lam_adj and lam1 (README 'Findings'), so shakedown from "
                "every initial state is certain only below lam_adj.")
    k = int(b.limiting_constraint)
    if lam1 == 0 and k >= 0:
        out.append(
            f"lam1 = 0 because constraint {constraint_name(k, n)} is already inactive at lam = 0 "
            "(the safe region of the static load does not touch it), so the criterion for "
            "shakedown from every initial state does not hold at any lam > 0.")
    if lam_adj == 0 and lam1 > 0 and b.adjacency_node >= 0:
        j = int(b.adjacency_node)
        why = (" (f p0 = 0 there: the node has no friction capacity under the static load)"
               if abs(fp0[j]) <= 1e-12 * scale else "")
        out.append(f"lam_adj = 0: the two extreme constraints of node {j + 1} meet in the safe "
                   f"region already under the static load{why}.")
    elif np.isfinite(lam_adj) and _same(lam_adj, lam1):
        out.append(f"lam_adj = lam1 (node {int(b.adjacency_node) + 1}): the two extreme "
                   "constraints of that node meet exactly where the first becomes inactive.")
    elif adjacency and np.isinf(lam_adj) and b.adjacency_node < 0 and np.isfinite(lam2):
        out.append("lam_adj = inf: the two extreme constraints of no node meet in the safe "
                   "region.")
    if tensile.any():
        out.append(f"Note: the static normal reaction p0 is tensile at {_nodes(tensile)} "
                   "(compression positive): that node would separate under the static load.")
    sep = float(b.lam_separation)
    if np.isfinite(sep) and np.isfinite(lam2) and sep < lam2 and not _same(sep, lam2):
        out.append(f"Above lam = {fmt(sep)} every safe state needs a tensile normal reaction at "
                   f"{_nodes(np.isin(np.arange(n), list(b.separation_nodes)))}: contact "
                   "would open there.")
    if fallback := costly_fallback(getattr(b, "stages", ()), float(b.solve_time)):  # issue 26
        out.append(fallback)
    return " ".join(out)
