""":func:`cone_bounds`: the 3-D shakedown bounds (``shakedown_bounds`` for ``system.dim == 3``).

``lam2`` on the friction cones by cutting planes with exact separation and a certified
bracket (:mod:`.melan`); optionally the polyhedral lower-bound candidates ``lam1_cone``,
``lam_adj_cone`` on inscribed ``k``-gons by the 2-D LP engine (:mod:`.polygon`).
"""

from __future__ import annotations

import time

import numpy as np

from ...model import citations
from ...model.errors import InputError
from ..quantities import parse_only
from .certify import ConeCertificate, check_safe_state
from .data import cone_data
from .melan import BRACKET_RTOL, melan_lam2
from .result import ConeBounds
from .rounds import check_solver

#: What ``only=`` may name in 3-D.


def cone_bounds(system, load, *, lam=None, only=None, facets=None, intervals="lam1",
                adjacency=False, rtol=BRACKET_RTOL, max_rounds=60, solver="auto",
                _fail=None) -> ConeBounds:
    """3-D shakedown load factors with certificates (MODEL.md s.8.3).

    Parameters
    ----------
    system : DiscreteSystem
        ``dim = 3``: ``A`` (2N, 2N), ``B`` (2N, N), ``friction_xy`` (N, 2), every ``f > 0``.
    load : LoadCycle
        ``dim = 3``: ``q0`` (N, 2); harmonic or sampled.
    lam : float, optional
        Load factor of the returned ``safe_state`` (default ``lam2_lower / 2``).
    only : iterable of str, optional
        ``"lam1"`` / ``"lam_adj"`` ask for the polyhedral candidates (``"lam2"`` is always
        computed).  Overrides ``intervals`` and ``adjacency``.
    facets : int, optional
        ``k`` (even, >= 4) facets per node of the inscribed polygons; default 8 when the
        polyhedral candidates are asked for.  ``None`` with ``intervals=False`` and
        ``adjacency=False``: only ``lam2``.
    intervals, adjacency : see :func:`shakedown.shakedown_bounds` (on the polygon's rows).
    rtol : float
        Relative width of the certified bracket of ``lam2``.
    max_rounds : int
        Most SOCP solves of the cutting-plane loop.
    solver : {"auto", "dense", "clarabel"}
        ``"dense"``: the SOCPs of a coupled system by the dense interior point, each answer
        checked by its own conditions, Clarabel where a check fails (:mod:`.rounds`; recorded
        in ``socp_paths`` / ``fallbacks``); ``"clarabel"``: Clarabel only; ``"auto"``:
        ``"dense"`` from :data:`.rounds.DENSE_MIN_NODES` (150) nodes on, where it is faster.
    _fail : callable, optional
        Test hook applied to every dense answer before its check (forces the fallback).

    Returns
    -------
    ConeBounds
    """
    citations.register("melan1936", "klarbring2007")
    t0 = time.perf_counter()
    if only is not None:
        intervals, adjacency, _ = parse_only(only)
    check_solver(solver)
    data = cone_data(system, load)
    n = data.n_nodes
    if lam is not None:
        try:
            lam = float(lam)
        except (TypeError, ValueError) as exc:
            raise InputError(f"lam must be a number >= 0; got {lam!r}") from exc
        if not np.isfinite(lam) or lam < 0:
            raise InputError(f"lam must be finite and >= 0; got {lam}")
    L, F = data.load_factor, data.force
    if not load.has_periodic_part:
        out = melan_lam2(data, rtol=rtol, max_rounds=1, solver=solver, fail=_fail)
        status = "infeasible" if out.status == "infeasible" else "unbounded_no_periodic_part"
        lo = hi = np.nan if status == "infeasible" else np.inf
        msg = "; ".join(out.messages) if status == "infeasible" else \
            "the load has no periodic part: a safe state exists for every lam"
    else:
        out = melan_lam2(data, rtol=rtol, max_rounds=max_rounds, solver=solver, fail=_fail)
        status, lo, hi = out.status, out.lam_lo * L, out.lam_hi * L
        msg = "; ".join(out.messages)
    v_lam2 = data.slip(out.u_safe, system) if out.margin > -np.inf else np.zeros(0)
    # a safe state at lam by convexity: between (u0, 0) [margin tau0] and (u_safe, lam_lo)
    if lam is None:
        safe_lam = 0.5 * lo if np.isfinite(lo) else 0.0
    else:
        safe_lam = lam
    safe_state, margin = np.zeros(0), -np.inf
    if status != "infeasible" and out.history:
        theta = safe_lam / lo if np.isfinite(lo) and lo > 0 else 0.0
        if theta <= 1.0:
            uc = theta * out.u_safe + (1 - theta) * out.u0
            safe_state = data.slip(uc, system)
            _, worst, _ = check_safe_state(system, load, safe_state, safe_lam, data=data)
            margin = -worst * F
    elif status == "unbounded_no_periodic_part":
        safe_state = data.slip(out.u_safe, system)
        margin = out.margin * F
    _, _, tw = (check_safe_state(system, load, v_lam2, lo, data=data)
                if v_lam2.size and np.isfinite(lo) else (None, None, np.full(n, np.nan)))
    cert = ConeCertificate(out.cut_nodes, out.cut_times, out.z, 0.0)
    res = ConeBounds(
        lam2=float(lo), lam2_lower=float(lo), lam2_upper=float(hi), status=status, message=msg,
        safe_lam=float(safe_lam), safe_state=safe_state, safe_margin=float(margin),
        state_at_lam2=v_lam2, certificate=cert, residuals=dict(out.residuals),
        n_socps=int(out.rounds), n_cuts=int(len(out.cut_nodes)), iterations=int(out.iterations),
        solve_time=0.0, n_nodes=n, history=list(out.history), worst_times=tw,
        socp_paths=tuple(out.log.paths), fallbacks=tuple(out.log.fallbacks))
    if facets is not None or intervals or adjacency:
        from .polygon import polygon_bounds

        res = polygon_bounds(system, load, res, facets=8 if facets is None else facets,
                             intervals=intervals, adjacency=adjacency)
    object.__setattr__(res, "solve_time", time.perf_counter() - t0)
    return res
