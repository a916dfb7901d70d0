"""Stability margin along a cyclic evolution (tie-in with ``solve_cycles``, MODEL.md s.4-5).

At every change of the node partition (or at chosen snapshot times) the nodes of the
snapshot are classified (free / stick / impending slip with its direction) and MCEIP-mu is
solved for that partition with the system's friction *profile*: node ``j`` gets friction
``alpha f_j`` and the critical factor ``alpha*`` is found (``mu* = alpha* max f``; for a
uniform friction ``alpha* = mu* / f``).  ``alpha* > 1``: the actual friction is below the
critical one, no quasi-static bifurcation; ``alpha* <= 1``: the snapshot admits one.  Nodes
that are actually slipping are on their friction cone, so they count as "impending slip"
here: the check is then the static bifurcation check of the (moving) partition.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import InputError
from ..model.numbers import sig
from ..model.results import short_repr
from ..model.validation import real_array
from .classify import CLASSIFY_RTOL, SLIP, classify_nodes
from .mceip import mceip_mu

#: Words of the ``state`` column (``shakedown.complementarity.STATE_NAMES`` and variants)
#: mapped to the coarse states used for the cross-check with the classification.
_STATE_WORDS = {
    "stick": "closed", "forward": "closed", "backward": "closed", "slip+": "closed",
    "slip-": "closed", "slip": "closed", "separation": "free", "open": "free", "free": "free",
    "separated": "free",
}

_COLUMNS = ("t", "node", "gap", "q", "p")


@dataclass(frozen=True, eq=False)
class CycleStability:
    """Stability margin at snapshots of a cycle.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per snapshot: ``t``, ``n_free``, ``n_stick``, ``n_slip``, ``borderline``,
        ``alpha`` (critical friction factor ``alpha*``, ``inf`` without slip nodes or
        solution), ``mu_star`` (``alpha* max f``), ``friction`` (``max f``), ``margin``
        (``alpha* - 1``), ``unstable`` (``alpha* <= 1``), ``support`` (nodes slipping in the
        mode), ``residual``, ``method``, ``status``, ``state_mismatch`` (nodes whose ``state``
        column disagrees with the classification about being open).
    results : tuple of MCEIPResult
        The MCEIP answer per snapshot (``None`` when no node is in impending slip).
    min_margin : float
        Smallest ``alpha* - 1`` over the snapshots.
    """

    table: object
    results: tuple
    min_margin: float

    @property
    def ever_unstable(self) -> bool:
        return bool(self.min_margin <= 0)

    def __repr__(self) -> str:
        return short_repr(self, ("min_margin", "ever_unstable"),
                          {"n_snapshots": int(len(self.table))})

    def verdict(self) -> str:
        """Stable along the cycle or not, with the smallest margin ``alpha* - 1``."""
        n = int(len(self.table))
        if not np.isfinite(self.min_margin):
            return (f"Stable at all {n} snapshots of the cycle: no node was in impending slip "
                    "with a divergence mode (alpha* = inf).")
        if self.ever_unstable:
            t = self.table
            first = float(t.loc[t["unstable"].astype(bool), "t"].min())
            return (f"Unstable during the cycle: the smallest margin alpha* - 1 = "
                    f"{sig(self.min_margin)} <= 0, first at t = {sig(first)} (of {n} snapshots).")
        return (f"Stable at all {n} snapshots of the cycle: the smallest margin alpha* - 1 = "
                f"{sig(self.min_margin)} > 0.")


def stability_along_cycle(
    system,
    run,
    *,
    times=None,
    every_change: bool = True,
    rtol: float = CLASSIFY_RTOL,
    method: str = "auto",
    progress=None,
    **options,
) -> CycleStability:
    """Critical friction of the current node partition along a cycle.

    Parameters
    ----------
    system : DiscreteSystem
        The system that was evolved (its ``K`` and ``friction``).
    run : CycleRun or pandas.DataFrame
        A result of :func:`shakedown.solve_cycles` (its ``steady_table``), or a table with the
        columns ``t, node, gap, q, p`` (and optionally ``slip``, ``state``) in long format.
    times : array_like, optional
        Snapshot times; the nearest tabulated time is used for each.
    every_change : bool
        Also take a snapshot at every time where the classified partition changes (the first
        row of the table always counts).  With ``times`` and ``every_change=False`` only the
        given times are used.
    rtol : float
        Classification tolerance (see :func:`classify_nodes`).
    method : str
        MCEIP method (see :func:`mceip_mu`).
    progress : callable, optional
        ``progress(iterable, total=, desc=)`` wrapper.
    **options
        Passed to :func:`mceip_mu`.

    Returns
    -------
    CycleStability
    """
    import pandas as pd

    tab = getattr(run, "steady_table", run)
    if not isinstance(tab, pd.DataFrame):
        raise InputError(
            f"run must be a CycleRun (with .steady_table) or a DataFrame; got {type(run).__name__}"
        )
    missing = [c for c in _COLUMNS if c not in tab.columns]
    if missing:
        raise InputError(f"the table lacks the columns {missing}; it needs {list(_COLUMNS)}")
    n = system.n_nodes
    f = np.asarray(system.friction, float)
    fmax = float(f.max())
    if fmax <= 0:
        raise InputError("the system is frictionless (max friction 0): no friction margin")
    profile = f / fmax
    groups = {t: g.sort_values("node") for t, g in tab.groupby("t", sort=True)}
    all_t = np.array(sorted(groups))
    for t, g in groups.items():
        if g["node"].to_numpy().tolist() != list(range(n)):
            raise InputError(f"at t = {t} the table must list nodes 0..{n - 1} exactly once")
    chosen = set()
    if times is not None:
        times = real_array("times", times)
        if times.ndim > 1 or not np.all(np.isfinite(times)):
            raise InputError("times must be a finite number or a 1-D array of times [cycles]")
        for t in np.atleast_1d(times):
            chosen.add(float(all_t[np.argmin(np.abs(all_t - t))]))
    parts = {}
    prev = None
    for t in all_t:
        g = groups[t]
        part = classify_nodes(g["gap"].to_numpy(), g["q"].to_numpy(), g["p"].to_numpy(), f,
                              rtol=rtol)
        parts[t] = part
        if every_change and (prev is None or part.key() != prev):
            chosen.add(float(t))
        prev = part.key()
    if not chosen:
        chosen.add(float(all_t[0]))
    snaps = sorted(chosen)
    cache: dict = {}
    rows, results = [], []
    it = snaps if progress is None else progress(snaps, total=len(snaps), desc="stability")
    for t in it:
        part = parts[t]
        g = groups[t]
        mismatch = 0
        if "state" in g.columns:
            coarse = [_STATE_WORDS.get(str(s).lower()) for s in g["state"]]
            is_free = part.states == "free"
            mismatch = sum(
                c is not None and (c == "free") != bool(fr)
                for c, fr in zip(coarse, is_free, strict=True)
            )
        key = part.key()
        if not np.any(part.states == SLIP):
            res = None
        elif key in cache:
            res = cache[key]
        else:
            res = mceip_mu(system.K, part, method=method, friction_profile=profile, **options)
            cache[key] = res
        # the pencil's friction is mu * profile_j = mu f_j / max f: alpha* = mu* / max f
        alpha = res.mu / fmax if (res is not None and res.found) else np.inf
        c = part.counts()
        rows.append({
            "t": t, "n_free": c["free"], "n_stick": c["stick"], "n_slip": c["slip"],
            "borderline": int(part.borderline.size), "alpha": alpha,
            "mu_star": alpha * fmax, "friction": fmax, "margin": alpha - 1.0,
            "unstable": bool(alpha <= 1.0),
            "support": "" if res is None or not res.found else
            " ".join(str(j) for j in res.nodes[res.support]),
            "residual": np.nan if res is None else res.residual,
            "method": "" if res is None else res.method,
            "status": "no slip node" if res is None else res.status,
            "state_mismatch": int(mismatch),
        })
        results.append(res)
    table = pd.DataFrame(rows)
    return CycleStability(table, tuple(results), float(table["margin"].min()))


