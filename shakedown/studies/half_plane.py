"""Experiments on the half-plane model: loading paths ``OA``, bounds, the ``beta`` study.

* :func:`oa_state` follows an initial loading path ``OA`` in ``(P, Q)`` space (seed ``002``
  Fig. 13) with implicit steps and returns the slips and gaps at ``A``: initial states for
  :func:`shakedown.solve_cycles` that a real loading history can produce.
* :func:`random_oa_paths` draws such paths inside the friction cone, reproducibly.
* :func:`contact_subsystem` condenses out the nodes that are open under a static load (exact
  while they stay open: their reactions vanish), so that the no-separation theory of the
  bounds (MODEL.md s.3) applies to the remaining nodes.
* :func:`beta_study` runs, for each Dundurs ``beta``, cycles from many ``OA`` paths and the
  bounds ``lam1``, ``lam2``, ``lam_adj``, and tabulates how the steady state depends on ``OA``.
"""

from __future__ import annotations

import numpy as np

from ..bounds import shakedown_bounds
from ..evolution import solve_cycles, solve_step
from ..model import DiscreteSystem, LoadCycle, SolverError
from ..models.half_plane.model import half_plane_model, rigid_indenter_materials


def oa_state(model, P_path, Q_path, substeps: int = 10):
    """Slips and gaps after the loading path ``(P_path[k], Q_path[k])`` from the virgin state.

    The path starts at ``P = Q = 0`` (not included) and is refined into ``substeps`` implicit
    steps per segment.  Returns ``(slip, gap)``, shape (N-1,) each.
    """
    P = np.concatenate([[0.0], np.asarray(P_path, float)])
    Q = np.concatenate([[0.0], np.asarray(Q_path, float)])
    s = model.system
    v = np.zeros(s.n_nodes)
    res = None
    for k in range(1, P.size):
        for a in np.arange(1, substeps + 1) / substeps:
            qw, pw = model.welded(Q[k - 1] + a * (Q[k] - Q[k - 1]), P[k - 1] + a * (P[k] - P[k - 1]))
            res = solve_step(s, v, qw, pw, guess=None if res is None else res.active_set)
            if not res.success:
                raise SolverError(f"OA path: step failed ({res.message})", partial=res)
            v = res.slip
    return v, res.gap


def random_oa_paths(n_paths: int, end, friction: float, P_scale: float, rng=None,
                    n_points: int = 3):
    """``n_paths`` random paths ``OA`` ending at ``end = (P_A, Q_A)``; path 0 is the straight line.

    Intermediate points have ``P`` uniform in ``[0.3, 1.6] P_scale`` and ``Q`` uniform in
    ``(-0.9, 0.9) f P`` (inside the friction cone).  Returns a list of ``(P, Q)`` arrays.
    """
    gen = np.random.default_rng(rng)
    PA, QA = float(end[0]), float(end[1])
    paths = [(np.array([PA]), np.array([QA]))]
    for _ in range(int(n_paths) - 1):
        P = gen.uniform(0.3, 1.6, n_points) * P_scale
        Q = gen.uniform(-0.9, 0.9, n_points) * friction * P
        paths.append((np.append(P, PA), np.append(Q, QA)))
    return paths


def stick_margins(model, table, P_of_t, Q_of_t):
    """Per cell (shape (N,), reference included), ``min_t (f p - |q|) / max_t P`` over ``table``.

    Separated instants count as margin 0.  The reference cell's reactions come from the
    resultants.
    """
    tab = table.sort_values(["t", "node"])
    ts = np.array(sorted(tab["t"].unique()))
    n = model.system.n_nodes
    q = tab["q"].to_numpy().reshape(ts.size, n)
    p = tab["p"].to_numpy().reshape(ts.size, n)
    qm, pm = model.reference_reactions(q, p, Q_of_t(ts), P_of_t(ts))
    q, p = model.full(q, 0.0), model.full(p, 0.0)
    q[:, model.reference], p[:, model.reference] = qm, pm
    scale = np.max(np.abs(P_of_t(ts)))
    return np.min(model.friction * p - np.abs(q), axis=0) / scale


def choose_reference(model_factory, load_factory, P_of_t, Q_of_t, *, steps_per_cycle=100,
                     max_cycles=150, iterations=3):
    """Move the reference cell to the cell with the largest stick margin of the steady cycle.

    ``model_factory(reference_x)`` builds a model (``None``: default reference),
    ``load_factory(model)`` its load.  Starting from the default, run from the virgin state,
    compute :func:`stick_margins` and rebuild with the reference at the best cell, until the
    reference cell's own margin is the best or ``iterations`` runs were made.  Returns the
    model; for ``beta = 0`` this is the default (the centre has the largest margin).
    """
    m = model_factory(None)
    for _ in range(int(iterations)):
        run = solve_cycles(m.system, load_factory(m), 1.0, steps_per_cycle=steps_per_cycle,
                              max_cycles=max_cycles)
        if not run.success:
            return m
        marg = stick_margins(m, run.steady_table, P_of_t, Q_of_t)
        best = int(np.argmax(marg))
        if best == m.reference or marg[m.reference] >= marg[best] - 1e-12:
            return m
        m = model_factory(float(m.x_cells[best]))
    return m


def oa_runs(model, load, paths, *, lam=1.0, steps_per_cycle=100, max_cycles=150):
    """:func:`shakedown.solve_cycles` from the end state of each loading path ``OA``."""
    runs = []
    for Pp, Qp in paths:
        v, w = oa_state(model, Pp, Qp)
        runs.append(solve_cycles(model.system, load, lam, initial_slip=v, initial_gap=w,
                                    steps_per_cycle=steps_per_cycle, max_cycles=max_cycles))
    return runs


def compare_runs(runs):
    """How much the steady cycles of ``runs`` (same model and load) differ.

    Returns a dict: ``W`` (array), ``W_spread`` (``(max - min)/max``), ``stuck_sets`` (number of
    distinct permanently stuck sets), ``time_varying_spread`` (largest spread across runs of
    ``q``, ``p`` minus their cycle means, over nodes and times, relative to ``max |p|``),
    ``slip_tv_spread`` (the same for the slips, relative to the largest slip range),
    ``locked_spread`` (spread of the cycle-mean slip of the stuck nodes, relative to the largest
    slip range), ``cycles_to_steady`` (array).
    """
    tabs = [r.steady_table.sort_values(["t", "node"]) for r in runs]
    n = min(len(t) for t in tabs)

    def tv(t, col):
        x = t[col].to_numpy()[:n]
        return x - t.groupby("node")[col].transform("mean").to_numpy()[:n]

    pmax = max(np.abs(t["p"]).max() for t in tabs)
    srange = max(t.groupby("node")["slip"].agg(np.ptp).max() for t in tabs)
    qp = np.array([np.concatenate([tv(t, "q"), tv(t, "p")]) for t in tabs])
    sl = np.array([tv(t, "slip") for t in tabs])
    stuck = [tuple(r.stuck_nodes) for r in runs]
    common = sorted(set.intersection(*map(set, stuck))) if stuck else []
    locked = np.array([t.groupby("node")["slip"].mean().to_numpy()[common] for t in tabs])
    W = np.array([r.steady_dissipation for r in runs])
    return {"W": W, "W_spread": float(np.ptp(W) / W.max()), "stuck_sets": len(set(stuck)),
            "time_varying_spread": float(np.ptp(qp, axis=0).max() / pmax),
            "slip_tv_spread": float(np.ptp(sl, axis=0).max() / srange),
            "locked_spread": float(np.ptp(locked, axis=0).max() / srange) if common else 0.0,
            "cycles_to_steady": np.array([r.cycles_to_steady for r in runs])}


def contact_subsystem(model, load, P_static: float, Q_static: float = 0.0):
    """Condense out the nodes open under the static load ``(Q_static, P_static)``.

    Returns ``(system, load, nodes)``: the stiffness ``K_cc - K_co K_oo^-1 K_oc`` and welded
    reactions ``r_c - K_co K_oo^-1 r_o`` of the closed nodes ``nodes`` (indices into
    ``model.x``), exact as long as the other nodes stay open (zero reactions).
    """
    s = model.system
    qw, pw = model.welded(Q_static, P_static)
    res = solve_step(s, np.zeros(s.n_nodes), qw, pw)
    closed = np.flatnonzero(res.p > 1e-9 * np.max(np.abs(res.p)))  # round-off: open nodes ~1e-20
    n = s.n_nodes
    c = np.concatenate([closed, n + closed])
    o = np.setdiff1d(np.arange(2 * n), c)
    K = s.K
    X = np.linalg.solve(K[np.ix_(o, o)], K[np.ix_(o, c)])  # K_oo^-1 K_oc
    Kc = K[np.ix_(c, c)] - K[np.ix_(c, o)] @ X
    Kc = 0.5 * (Kc + Kc.T)
    m = closed.size
    sub = DiscreteSystem(Kc[:m, :m], Kc[:m, m:], Kc[m:, m:], s.friction[closed])

    def cond(q, p):
        r = np.concatenate([q, p], axis=-1)
        rc = r[..., c] - r[..., o] @ X
        return rc[..., :m], rc[..., m:]

    q0, p0 = cond(load.q0, load.p0)
    parts = {k: cond(getattr(load, f"q_{k}"), getattr(load, f"p_{k}")) for k in ("cos", "sin")}
    sub_load = LoadCycle.from_harmonics(q0, p0, q_cos=parts["cos"][0], p_cos=parts["cos"][1],
                                           q_sin=parts["sin"][0], p_sin=parts["sin"][1])
    return sub, sub_load, closed


def beta_study(betas, *, n_nodes=31, friction=0.5, P0=1e-3, P1=0.3e-3, Q1=0.3e-3, phase=0.6,
               n_paths=6, rng=0, steps_per_cycle=100, max_cycles=150, bounds_Q1=None,
               choose_ref=True):
    """Steady cycles from ``n_paths`` loading paths ``OA`` for each ``beta``; bounds at constant ``P0``.

    Body 1 elastic (``E = 1``), body 2 rigid (:func:`rigid_indenter_materials`), Hertz profile
    ``R = 1``, window ``2.4 a(P0 + P1)``.  Returns a ``pandas.DataFrame``, one row per ``beta``:
    ``W_min``, ``W_max``, ``W_spread`` (relative), ``tv_spread`` (time-varying reactions, see
    :func:`compare_runs`), ``n_stuck_min``, ``n_stuck_max``,
    ``stuck_sets`` (distinct permanently stuck sets), ``cycles_max``, ``period_max``,
    ``reference_ok`` (eq. (5) exact on every run), ``reference_excess`` (largest
    ``(|q_m| - f p_m) / P`` of the reference cell, > 0: eq. (5) is not exact), ``lam1``,
    ``lam2``, ``lam_adj`` of the closed nodes at constant ``P0`` with
    ``Q = lam bounds_Q1 cos(2 pi t)`` (default ``Q1``), ``reference_x`` (reference cell /
    ``a(P0 + P1)``; chosen by :func:`choose_reference` when ``choose_ref``).
    """
    import pandas as pd

    from ..models.half_plane.continuum import hertz_half_width

    rows = []
    for beta in betas:
        mats = rigid_indenter_materials(beta)
        e_star = mats[0][0] / (1 - mats[0][1] ** 2)
        a_max = float(hertz_half_width(P0 + P1, 1.0, e_star))
        def factory(ref_x, mats=mats, a_max=a_max):
            return half_plane_model(radius=1.0, n_nodes=n_nodes, width=2.4 * a_max,
                                    friction=friction, materials=mats, reference_x=ref_x)

        def load_of(m):
            return m.load_cycle(P0=P0, P1=P1, Q1=Q1, phase=phase)

        def P_of_t(t):
            return P0 + P1 * np.cos(2 * np.pi * t + phase)

        def Q_of_t(t):
            return Q1 * np.cos(2 * np.pi * t)

        m = factory(None)
        if choose_ref:
            m = choose_reference(factory, load_of, P_of_t, Q_of_t,
                                 steps_per_cycle=steps_per_cycle, max_cycles=max_cycles)
        load = load_of(m)
        end = (P0 + P1 * np.cos(phase), Q1)
        paths = random_oa_paths(n_paths, end, friction, P0, rng=rng)
        runs = oa_runs(m, load, paths, steps_per_cycle=steps_per_cycle, max_cycles=max_cycles)
        ok, worst = [], []
        for run in runs:
            chk = m.check_reference(run.steady_table, P_of_t, Q_of_t)
            ok.append(run.success and chk[0])
            worst.append(chk[1])
        cmp = compare_runs(runs)
        sub, sub_load, _ = contact_subsystem(m, m.load_cycle(P0=P0, Q1=bounds_Q1 or Q1), P0)
        b = shakedown_bounds(sub, sub_load, adjacency=True)  # lam_adj is opt-in
        Ws = cmp["W"]
        rows.append({
            "beta": float(beta), "W_min": Ws.min(), "W_max": Ws.max(),
            "W_spread": cmp["W_spread"], "tv_spread": cmp["time_varying_spread"],
            "n_stuck_min": min(len(r.stuck_nodes) for r in runs),
            "n_stuck_max": max(len(r.stuck_nodes) for r in runs),
            "stuck_sets": cmp["stuck_sets"], "cycles_max": int(cmp["cycles_to_steady"].max()),
            "period_max": max(r.period for r in runs),
            "reference_x": float(m.x_cells[m.reference]) / a_max, "reference_ok": all(ok),
            "reference_excess": max(worst), "lam1": b.lam1, "lam2": b.lam2, "lam_adj": b.lam_adj,
        })
    return pd.DataFrame(rows)
