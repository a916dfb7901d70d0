"""Uniqueness experiments: the evolution from many initial states (seed 002 sections 2-3).

:func:`uniqueness_study` runs :func:`shakedown.solve_cycles` (or the direct
:func:`shakedown.steady.steady_cycle`) from many initial slip states, in parallel over local
processes, and gives a verdict on the uniqueness of the steady dissipation and of the
time-varying part of the steady response.  Results do not depend on the number of processes.
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..model import citations
from ..model.errors import InputError, ShapeError
from ..model.results import short_repr
from .steady import _check_common, natural_slip_scale, sample_initial_slips, steady_cycle
from .steady_maps import tangential_stiffness

__all__ = ["UniquenessStudy", "uniqueness_study"]



# ------------------------------------------------------------------ uniqueness experiments
#: Samples per load period of the steady histories compared across runs (linear interpolation
#: of each run's steady table, so implicit runs with any step count and event-driven runs
#: with event times of their own are compared on one grid).
HISTORY_SAMPLES = 64


@dataclass(frozen=True)
class UniquenessStudy:
    """Result of :func:`uniqueness_study`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per initial state (in the given order): ``state`` (index), ``steady_dissipation``,
        ``shook_down``, ``stuck`` (the permanently stuck nodes as ``"0,3"``; ``""`` for none),
        ``n_stuck``, ``cycles_to_steady``, ``n_cycles`` (periods simulated), ``period``,
        ``status``, ``initial_slip_<j>`` and ``steady_slip_<j>`` (slips at the start of the steady
        cycle) for every node ``j`` (3-D: ``initial_slip_<j>_x``, ``initial_slip_<j>_y``, ...;
        slip and reaction spreads then over both components).
    lam : float
    unique_dissipation : bool
        Every run reached a steady cycle and ``dissipation_spread <= w_tol``.
    dissipation_spread : float
        ``max - min`` of the steady ``W`` over the runs that reached a steady cycle.
    w_tol : float
        Tolerance of the dissipation verdict: ``w_rtol * max(max|W|, W_scale)`` with
        ``W_scale = F s``, ``F = max_k (f_k |p0_k| + |q0_k| + lam amplitude_k)`` (the force
        scale) and ``s`` the largest natural slip (:func:`natural_slip_scale`).
    slip_spread, reaction_spread : float
        Largest spread across runs (``max - min`` over runs, maximised over nodes and
        ``HISTORY_SAMPLES`` times per period) of the time-varying part of the steady slip
        [slip units] and reactions ``q``, ``p`` [force] (history minus its cycle mean).
    time_varying_spread : float
        ``max(slip_spread * max_j A_jj, reaction_spread) / F``: the two spreads relative to
        the force scale ``F`` (dimensionless).  Period-2 runs are compared in
        the phase whose first period has the larger total slip path; period-1 runs are
        repeated once.
    fraction_shook_down, fraction_steady : float
    n_states : int
    summary_text : str
    """

    table: pd.DataFrame = field(repr=False)
    lam: float
    unique_dissipation: bool
    dissipation_spread: float
    w_tol: float
    slip_spread: float
    reaction_spread: float
    time_varying_spread: float
    fraction_shook_down: float
    fraction_steady: float
    n_states: int

    def __repr__(self) -> str:
        return short_repr(self, ("lam", "n_states", "unique_dissipation", "dissipation_spread",
                                 "w_tol", "fraction_shook_down", "fraction_steady"))

    def verdict(self, energy: str = "[force x length]") -> str:
        """Whether the steady dissipation depends on the initial state, in one sentence."""
        from .verdicts import uniqueness_verdict

        return uniqueness_verdict(self, energy)

    def summary(self) -> str:
        """A few lines: the verdict and the range of outcomes."""
        t = self.table
        W = t["steady_dissipation"].to_numpy(float)
        ok = np.isfinite(W)
        rng = f"[{np.min(W[ok]):.6g}, {np.max(W[ok]):.6g}]" if ok.any() else "[none]"
        stuck = sorted(set(t["stuck"]))
        lines = [
            f"uniqueness study at lam = {self.lam:.6g}: {self.n_states} initial states, "
            f"{100 * self.fraction_steady:.0f}% reached a steady cycle, "
            f"{100 * self.fraction_shook_down:.0f}% shook down",
            f"steady W in {rng}; spread {self.dissipation_spread:.3g} "
            f"(tolerance {self.w_tol:.3g}) -> "
            f"{'unique' if self.unique_dissipation else 'NOT unique'} dissipation",
            f"time-varying part: slip spread {self.slip_spread:.3g}, reaction spread "
            f"{self.reaction_spread:.3g} (relative {self.time_varying_spread:.3g})",
            f"periods seen: {sorted(set(int(p) for p in t['period']))}; stuck sets seen "
            "(nodes numbered from 1): "
            + ", ".join("{" + _from_one(s) + "}" for s in stuck[:8]) + (" ..." if len(stuck) > 8 else ""),
        ]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()


def _from_one(stuck: str) -> str:
    """A table's 0-based ``"0,3"`` as a person reads it, ``"1,4"``."""
    return ",".join(str(int(j) + 1) for j in stuck.split(",")) if stuck else ""


_WORKER = {}


def _init_worker(system, load, lam, solver, kw):
    _WORKER.update(system=system, load=load, lam=lam, solver=solver, kw=kw)


def _columns(system):
    """The steady-table columns compared across runs: slips first, then reactions."""
    if getattr(system, "dim", 2) == 3:
        return ("slip_x", "slip_y", "q_x", "q_y", "p"), 2
    return ("slip", "q", "p"), 1


def _histories(run, n_grid: int, n: int, cols=("slip", "q", "p"), n_slip=1):
    """Centred steady histories (the ``cols`` of the steady table, slips first) on
    ``2 * n_grid`` times, shape (len(cols), 2 n_grid, N)."""
    tab = run.steady_table
    per = int(run.period)
    out = np.full((len(cols), 2 * n_grid, n), np.nan)
    if per == 0 or tab is None or len(tab) == 0:
        return out
    t = tab["t"].to_numpy(float)
    t = t - t.min()  # the table starts at the orbit's start (an integer time)
    node = tab["node"].to_numpy(int)
    grid = (np.arange(per * n_grid) + 1.0) / n_grid
    for k, col in enumerate(cols):
        vals = tab[col].to_numpy(float)
        h = np.empty((per * n_grid, n))
        for j in range(n):
            sel = node == j
            h[:, j] = np.interp(grid, t[sel], vals[sel], period=per)
        if per == 1:
            h = np.concatenate([h, h])
        out[k] = h
    if per == 2:
        sl = out[:n_slip]
        path = np.sqrt((np.diff(np.concatenate([sl[:, -1:], sl], axis=1), axis=1) ** 2).sum(
            axis=0)).sum(axis=1)
        if path[n_grid:].sum() > path[:n_grid].sum():
            out = np.roll(out, -n_grid, axis=1)
    return out - out.mean(axis=1, keepdims=True)


def _one_state(args):
    index, v0 = args
    w = _WORKER
    system, n = w["system"], w["system"].n_nodes
    cols, n_slip = _columns(system)
    shape = (n, 2) if getattr(system, "dim", 2) == 3 else (n,)
    try:
        if w["solver"] == "steady":
            sc = steady_cycle(system, w["load"], w["lam"], v0, **w["kw"])
            run, n_cycles, status = sc.run, sc.n_evaluations, sc.status
            start = sc.slip
        else:
            from .cycles import solve_cycles

            run = solve_cycles(system, w["load"], w["lam"], initial_slip=v0, **w["kw"])
            n_cycles, status = int(run.n_cycles), str(run.status)
            starts = np.asarray(run.cycle_start_slips)
            per = int(run.period)
            start = starts[-per - 1] if per and len(starts) > per else np.asarray(run.final_slip)
    except (ValueError, RuntimeError, ArithmeticError) as exc:
        row = dict(steady_dissipation=np.nan, shook_down=False, stuck="", n_stuck=0,
                   cycles_to_steady=-1, n_cycles=0, period=0, status=f"error: {exc}"[:300])
        return index, row, np.full(shape, np.nan), np.full((len(cols), 2 * HISTORY_SAMPLES, n),
                                                           np.nan)
    per = int(run.period)
    stuck = np.asarray(run.stuck_nodes, int) if per else np.zeros(0, int)
    cts = getattr(run, "cycles_to_steady", -1)
    row = dict(
        steady_dissipation=float(run.steady_dissipation) if per else np.nan,
        shook_down=bool(run.shook_down) if per else False,
        stuck=",".join(str(int(j)) for j in stuck),
        n_stuck=int(stuck.size),
        cycles_to_steady=int(cts) if cts is not None and np.isfinite(cts) else -1,
        n_cycles=int(n_cycles),
        period=per,
        status=status,
    )
    return index, row, np.asarray(start, float), _histories(run, HISTORY_SAMPLES, n, cols,
                                                             n_slip)


def uniqueness_study(system, load, lam: float, initial_slips=16, *, rng=None,
                     n_jobs: int | None = None, method: str = "implicit",
                     steps_per_cycle: int = 200, max_cycles: int = 200, tol: float = 1e-10,
                     solver: str = "cycles", scale: float = 2.0, w_rtol: float = 1e-6,
                     progress=None, mp_context=None) -> UniquenessStudy:
    """Steady cycles from many initial states: is the steady response unique?

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lam : float
    initial_slips : array_like, shape (n_states, N) (3-D: (n_states, N, 2)), or int
        The initial slips, or how many to sample with :func:`sample_initial_slips` (state 0 is
        ``v = 0``, the others uniform in a box of ``scale`` natural slips, every node closed).
    rng : int, numpy.random.Generator or None
        Seed of the sampling (ignored when the states are given).
    n_jobs : int or None
        Local worker processes (``None``: ``os.cpu_count()``; 1: serial, in this process).  The
        table does not depend on it.
    method, steps_per_cycle, max_cycles, tol
        Passed to :func:`shakedown.solve_cycles` (``max_cycles`` is the evaluation budget when
        ``solver == "steady"``).
    solver : {"cycles", "steady"}
        Plain evolution (:func:`solve_cycles`) or the direct solver (:func:`steady_cycle`).
    scale : float
        Box size of the sampling, in natural slips.
    w_rtol : float
        Relative tolerance of the unique-dissipation verdict (see ``UniquenessStudy.w_tol``).
        The default ``1e-6`` is far above the solver's ``tol`` (1e-10) times the number of
        steps, and far below any physically distinct dissipation.
    progress : callable, optional
        ``progress(iterable, total=..., desc=...)`` wrapper (e.g. ``tqdm`` or the CLI's); it is
        advanced as runs finish.
    mp_context : multiprocessing context, optional

    Returns
    -------
    UniquenessStudy
    """
    citations.register("barber2011")
    n = system.n_nodes
    lam = _check_common(system, load, lam)
    if solver not in ("cycles", "steady"):
        raise InputError(f"solver must be 'cycles' or 'steady'; got {solver!r}")
    if isinstance(initial_slips, (int, np.integer)) and not isinstance(initial_slips, bool):
        states = sample_initial_slips(system, load, int(initial_slips), rng, scale=scale)
    else:
        try:
            states = np.array(initial_slips, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(
                f"initial_slips must be a count or an array (n_states, {n}); got {initial_slips!r}"
            ) from exc
        want = (n, 2) if getattr(system, "dim", 2) == 3 else (n,)
        if states.ndim == 1 and n == 1 and want == (1,):
            states = states[:, None]
        if states.shape[1:] != want or states.shape[0] < 1:
            raise ShapeError(
                f"initial_slips must have shape (n_states, {', '.join(map(str, want))}) with "
                f"n_states >= 1; got {states.shape}"
            )
        if not np.all(np.isfinite(states)):
            raise InputError("initial_slips must be finite")
    if n_jobs is None:
        n_jobs = os.cpu_count() or 1
    if (not isinstance(n_jobs, (int, np.integer)) or isinstance(n_jobs, (bool, np.bool_))
            or int(n_jobs) < 1):
        raise InputError(f"n_jobs must be an integer >= 1 (or None for all cores); got "
                         f"{type(n_jobs).__name__} {n_jobs!r}")
    n_jobs = min(int(n_jobs), len(states))
    kw = dict(method=method, steps_per_cycle=steps_per_cycle, tol=tol)
    if solver == "steady":
        kw["max_evaluations"] = max_cycles
    else:
        kw["max_cycles"] = max_cycles
    tasks = list(enumerate(states))
    results = [None] * len(tasks)

    def wrap(it):
        return progress(it, total=len(tasks), desc=f"uniqueness lam={lam:g}") if progress else it

    if n_jobs == 1:
        _init_worker(system, load, lam, solver, kw)
        try:
            for res in wrap(map(_one_state, tasks)):
                results[res[0]] = res
        finally:
            _WORKER.clear()
    else:
        with ProcessPoolExecutor(max_workers=n_jobs, mp_context=mp_context,
                                 initializer=_init_worker,
                                 initargs=(system, load, lam, solver, kw)) as ex:
            chunk = max(1, len(tasks) // (4 * n_jobs))
            for res in wrap(ex.map(_one_state, tasks, chunksize=chunk)):
                results[res[0]] = res
    return _verdict(system, load, lam, states, results, w_rtol)


def _verdict(system, load, lam, states, results, w_rtol):
    n = system.n_nodes
    rows = []
    hist = np.array([r[3] for r in results])  # (S, 3, 2G, N)
    dim3 = getattr(system, "dim", 2) == 3
    _, n_slip = _columns(system)
    for (i, row, start, _), v0 in zip(results, states, strict=True):
        row = {"state": i, **row}
        if dim3:  # 3-D: initial_slip_<j>_x, initial_slip_<j>_y, ...
            for name, arr in (("initial_slip", v0), ("steady_slip", start)):
                row.update({f"{name}_{j}_{c}": float(arr[j][a]) for j in range(n)
                            for a, c in enumerate("xy")})
        else:
            row.update({f"initial_slip_{j}": float(v0[j]) for j in range(n)})
            row.update({f"steady_slip_{j}": float(start[j]) for j in range(n)})
        rows.append(row)
    table = pd.DataFrame(rows)
    W = table["steady_dissipation"].to_numpy(float)
    steady = table["period"].to_numpy(int) > 0
    Wok = W[steady & np.isfinite(W)]
    spread = float(Wok.max() - Wok.min()) if Wok.size else float("nan")
    s_nat = natural_slip_scale(system, load, lam)
    slip_scale = float(np.max(s_nat))
    k_t = tangential_stiffness(system)
    force = float(np.max(s_nat * k_t))  # largest friction / tangential load
    w_tol = float(w_rtol) * max(float(np.max(np.abs(Wok))) if Wok.size else 0.0,
                                force * slip_scale)
    if steady.sum() >= 1:
        h = hist[steady]
        rng_ = np.nanmax(h, axis=0) - np.nanmin(h, axis=0)  # (3, 2G, N)
        sl, rc = rng_[:n_slip], rng_[n_slip:]
        slip_spread = float(np.nanmax(sl)) if np.isfinite(sl).any() else float("nan")
        reac_spread = float(np.nanmax(rc)) if np.isfinite(rc).any() else float("nan")
    else:
        slip_spread = reac_spread = float("nan")
    tv = max(slip_spread * float(np.max(k_t)), reac_spread) / force
    return UniquenessStudy(
        table=table,
        lam=float(lam),
        unique_dissipation=bool(steady.all() and spread <= w_tol),
        dissipation_spread=spread,
        w_tol=w_tol,
        slip_spread=slip_spread,
        reaction_spread=reac_spread,
        time_varying_spread=float(tv),
        fraction_shook_down=float(table["shook_down"].mean()),
        fraction_steady=float(steady.mean()),
        n_states=len(table),
    )
