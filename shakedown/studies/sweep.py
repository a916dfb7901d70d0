"""Monte Carlo sweeps of frictional systems: any system over lam x initial states, and the
crack-network study of issue 4 (seed 002 section 4.1, Fig. 11).

Built on the generic engine of :mod:`shakedown.store` (:class:`Task`, :func:`run_tasks`:
resumable store, local processes or Dask, progress), re-exported here.

* :func:`system_sweep` -- one :class:`~shakedown.DiscreteSystem` over load factors x initial
  slips (:func:`initial_slips`), one row per run (:func:`run_row`).
* :class:`SweepSpec`, :func:`run_sweep` -> :class:`SweepResult` -- the crack-network study:
  realisations x load factors x initial states; per realisation ``lam1``, ``lam2``; per run the
  steady ``W* = W mu / (4 (1 - nu) p0^2 abar^2)`` (MODEL.md s.7), cycles to steady state, the
  fractions of cracks that slip and that open in the steady cycle; per (realisation, lam) the
  minimum and maximum ``W*`` over initial states; bands over realisations.

Determinism: every random draw comes from ``numpy.random.SeedSequence(seed, spawn_key=...)``
(the same children as ``SeedSequence(seed).spawn``), named by the task, never from a stream
shared between tasks: realisation ``r`` draws its cracks from ``spawn_key=(r, 0)`` and its
initial state ``j`` from ``spawn_key=(r, 1, j)``.  Each task is self-contained, so its rows do not
depend on the number of workers or on the order in which tasks finish.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable
from dataclasses import asdict, dataclass, fields
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from ..model.errors import InputError
from .store import KEY, Task, TaskRun, Workers, open_store, run_tasks

__all__ = [
    "Task",
    "TaskRun",
    "Workers",
    "run_tasks",
    "system_sweep",
    "initial_slips",
    "run_row",
    "SweepSpec",
    "SweepResult",
    "run_sweep",
    "realisation_model",
    "lam_grid",
    "study_tasks",
]


# ------------------------------------------------------------------ generic system sweep
def initial_slips(system, load, n_states: int, seed, *, scale: float = 2.0) -> np.ndarray:
    """Initial slips for a sweep: the zero state, then random slips in a box, one seed each.

    State 0 is ``v = 0`` (the virgin state).  State ``j >= 1`` is uniform in the box
    ``|v_k| <= scale * f_k |p0_k| / A_kk`` (the natural slip scale: the slip whose elastic
    reaction equals the static friction limit; for a crack, the mean slip of the isolated crack
    under the shear traction ``f p0``), shrunk if needed so that every node keeps at least half
    its static normal reaction (every state starts closed): the box of
    :func:`shakedown.steady.sample_initial_slips`.  Unlike that function, state ``j`` is drawn
    from its own child seed ``SeedSequence(seed, spawn_key=(j,))``, so it does not depend on
    ``n_states`` nor on which worker draws it.

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    n_states : int
    seed : int or tuple of int
        Entropy of ``numpy.random.SeedSequence``; a tuple ``(entropy, *spawn_key)`` places the
        states under a sweep's child seed.
    scale : float
        Size of the box in natural slip scales.

    Returns
    -------
    ndarray, shape (n_states, N)
    """
    return np.array([initial_slip(system, load, j, seed, scale=scale) for j in range(n_states)])


def initial_slip(system, load, j: int, seed, *, scale: float = 2.0) -> np.ndarray:
    """State ``j`` of :func:`initial_slips` alone, shape (N,)."""
    from ..evolution.steady import sample_initial_slips

    if j == 0:
        return np.zeros(system.n_nodes)
    if isinstance(seed, tuple | list):
        entropy, key = int(seed[0]), tuple(int(k) for k in seed[1:])
    else:
        entropy, key = int(seed), ()
    rng = np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=(*key, int(j))))
    return sample_initial_slips(system, load, 2, rng=rng, scale=scale)[1]


def run_row(system, load, lam: float, slip, solver: dict) -> dict:
    """Solve one (system, load, lam, initial slip) cycle run; the row of its steady outcome.

    Columns: ``W`` (steady dissipation per period, nan when no steady orbit was reached),
    ``cycles_to_steady`` (-1 if none), ``n_cycles``, ``period`` (0, 1 or 2), ``shook_down``,
    ``frac_slip`` / ``frac_open`` / ``frac_active`` (fractions of nodes that slip / separate /
    do either at some step of the steady orbit, nan if none), ``max_residual`` and
    ``status`` (``CycleRun.status``: ``"periodic"``, ``"not_converged"``, ``"step_failed"``).
    An exception (bad input, a bug) propagates: it is not a result, so it is not stored and
    the task runs again when the sweep is resumed.
    """
    from ..evolution.complementarity import FEAS_TOL, STATE_NAMES, StepSolver
    from ..evolution.cycles import solve_cycles

    n = system.n_nodes
    # A fresh step solver per run: the shared one keeps LU factors and low-rank updates from
    # earlier runs, and answers then depend (in the last bits) on which runs the same process
    # did before -- i.e. on the number of workers.  Rebuilding costs a few factorizations.
    run = solve_cycles(system, load, float(lam), initial_slip=np.asarray(slip, float),
                       solver=StepSolver(system), **solver)
    row = dict(W=float(run.steady_dissipation), cycles_to_steady=int(run.cycles_to_steady),
               n_cycles=int(run.n_cycles), period=int(run.period),
               shook_down=bool(run.shook_down), frac_slip=np.nan, frac_open=np.nan,
               frac_active=np.nan, max_residual=float(run.max_residual), status=str(run.status))
    if run.period > 0:
        # slip: the node's slip moves over the orbit by more than the solver's own zero
        # (FEAS_TOL * force_scale / A_jj, as in CycleRun.shook_down); open: a separated step
        tab = run.steady_table.sort_values(["node", "t"], kind="stable")
        node = tab["node"].to_numpy(int)
        travel = np.zeros(n)
        np.add.at(travel, node[1:], np.where(node[1:] == node[:-1],
                                             np.abs(np.diff(tab["slip"].to_numpy(float))), 0.0))
        zero = FEAS_TOL * float(run.force_scale) / np.diag(system.A)
        slips = travel > zero
        opens = np.zeros(n, bool)
        opens[node[(tab["state"].astype(str) == STATE_NAMES[3]).to_numpy()]] = True
        row.update(frac_slip=slips.mean(), frac_open=opens.mean(),
                   frac_active=(slips | opens).mean())
    return row


def _system_task(system, load, lam, slip, solver):
    return run_row(system, load, lam, slip, solver)


def system_sweep(system, load, lams: Iterable[float], slips, store, *, solver: dict | None = None,
                 **run_options) -> pd.DataFrame:
    """Sweep one system over load factors x initial slips (any model, not only cracks).

    Parameters
    ----------
    system : DiscreteSystem
    load : LoadCycle
    lams : iterable of float
    slips : array_like, shape (n_states, N)
        Initial slips, e.g. from :func:`initial_slips`.
    store : path or store
    solver : dict, optional
        Keyword arguments of :func:`shakedown.solve_cycles` (``method``, ``steps_per_cycle``,
        ``max_cycles``, ``tol``).
    **run_options
        Passed to :func:`run_tasks` (``n_workers``, ``scheduler``, ``progress``, ...).

    Returns
    -------
    pandas.DataFrame
        One row per (lam, state): ``lam_index``, ``lam``, ``state`` and the columns of
        :func:`run_row`.  The system is pickled with every task: fine up to a few hundred nodes.
    """
    slips = np.atleast_2d(np.asarray(slips, float))
    if slips.shape[1] != system.n_nodes:
        raise InputError(f"slips must have shape (n_states, {system.n_nodes}); got {slips.shape}")
    solver = dict(solver or {})
    tasks = []
    for i, lam in enumerate(lams):
        for j, v in enumerate(slips):
            tasks.append(Task(f"l{i}-s{j}", _tagged, (_system_task, dict(
                lam_index=i, lam=float(lam), state=j)), dict(
                system=system, load=load, lam=float(lam), slip=v, solver=solver)))
    return run_tasks(tasks, store, **run_options).rows


def _tagged(func, tags: dict, **kwargs):
    row = dict(tags)
    row.update(func(**kwargs))
    return row


# ------------------------------------------------------------------ the crack-network study
_SOLVER_FIELDS = ("method", "steps_per_cycle", "max_cycles", "tol")
_SAMPLER_FIELDS = ("density", "half_length", "orientation", "min_spacing")
_MODEL_FIELDS = ("n_cracks", *_SAMPLER_FIELDS, "seed", "shear_modulus", "poisson_ratio",
                 "friction")


@dataclass(frozen=True)
class SweepSpec:
    """The Monte Carlo crack-network study (issue 4; seed 002 section 4.1).

    Crack sets (one per realisation) are drawn by ``crack_networks.sample_crack_set`` and turned
    into a discrete system by ``crack_networks.kachanov_model``; the far field is
    ``S(t) = static + lam cyclic cos(2 pi t)`` (``(sxx, sxy, syy)``, tension positive).

    Parameters
    ----------
    n_cracks : int
    density, half_length, orientation, min_spacing
        Passed to ``sample_crack_set`` (``None``: its default; ``orientation="uniform"``:
        angles uniform in ``[0, pi)``).
    shear_modulus, poisson_ratio, friction : float
    static, cyclic : tuple of 3 floats
        Far-field stresses ``(sxx, sxy, syy)``; default the seed's ``S0 = p0 (-1, 0, -1)``,
        ``S1 = p0 (0, 1, 0)`` with ``p0 = 1``.
    n_realisations : int
    lams : "auto" or tuple of float
        Load factors.  ``"auto"``: ``n_lams`` values evenly spaced from
        ``lam_span[0] * min(lam1)`` to ``lam_span[1] * max(lam2)`` over the realisations (one
        common grid, so realisations can be averaged).
    n_lams : int
    lam_span : tuple of 2 floats
    n_states : int
        Initial states per (realisation, lam): the zero state and ``n_states - 1`` random slips
        (:func:`initial_slip`, box of ``state_scale`` natural slip scales), the same states at
        every ``lam``.
    state_scale : float
    seed : int
        Root of every random draw.
    method, steps_per_cycle, max_cycles, tol
        Passed to :func:`shakedown.solve_cycles`.
    stress_scale : float, optional
        ``p0`` of the normalisation of ``W*``; default ``max|static|`` (or ``max|cyclic|`` when
        the static stress is zero).
    """

    n_cracks: int = 100
    density: float | None = 0.1
    half_length: float | None = None
    orientation: str | float | None = None
    min_spacing: float | None = None
    shear_modulus: float = 1.0
    poisson_ratio: float = 0.25
    friction: float = 0.6
    static: tuple = (-1.0, 0.0, -1.0)
    cyclic: tuple = (0.0, 1.0, 0.0)
    n_realisations: int = 1
    lams: str | tuple = "auto"
    n_lams: int = 12
    lam_span: tuple = (0.5, 2.0)
    n_states: int = 4
    state_scale: float = 2.0
    seed: int = 0
    method: str = "implicit"
    steps_per_cycle: int = 64
    max_cycles: int = 200
    tol: float = 1e-10
    stress_scale: float | None = None

    def __post_init__(self):
        def setv(name, value):
            object.__setattr__(self, name, value)

        for name in ("static", "cyclic"):
            v = tuple(float(x) for x in np.ravel(getattr(self, name)))
            if len(v) != 3 or not np.all(np.isfinite(v)):
                raise InputError(f"{name} must be 3 finite stresses (sxx, sxy, syy); got {v}")
            setv(name, v)
        if not isinstance(self.lams, str):
            lams = tuple(float(x) for x in np.ravel(self.lams))
            if not lams or not all(np.isfinite(x) and x >= 0 for x in lams):
                raise InputError(f"lams must be 'auto' or a list of load factors >= 0; got {lams}")
            setv("lams", lams)
        elif self.lams != "auto":
            raise InputError(f"lams must be 'auto' or a list of numbers; got {self.lams!r}")
        span = tuple(float(x) for x in np.ravel(self.lam_span))
        if len(span) != 2 or not 0 <= span[0] < span[1]:
            raise InputError(f"lam_span must be (low, high) with 0 <= low < high; got {span}")
        setv("lam_span", span)
        for name in ("half_length", "orientation"):
            if isinstance(getattr(self, name), list):
                setv(name, tuple(float(x) for x in getattr(self, name)))
        for name in ("n_cracks", "n_realisations", "n_lams", "n_states", "max_cycles"):
            v = getattr(self, name)
            if not isinstance(v, int | np.integer) or isinstance(v, bool) or v < 1:
                raise InputError(f"{name} must be an integer >= 1; got {v!r}")
            setv(name, int(v))
        if self.method not in ("implicit", "events"):
            raise InputError(f"method must be 'implicit' or 'events'; got {self.method!r}")
        for name in ("shear_modulus", "state_scale"):
            if not float(getattr(self, name)) > 0:
                raise InputError(f"{name} must be > 0; got {getattr(self, name)!r}")
        if not max(map(abs, self.cyclic)) > 0:
            raise InputError("cyclic must not be zero: the study sweeps the cyclic load factor")

    @classmethod
    def from_scene(cls, model: dict, load: dict, options: dict | None = None) -> SweepSpec:
        """A spec from a scene's ``[model]`` (``kind = "crack_network"``, the keys of
        :mod:`shakedown.builders.crack_network`), ``[load]`` and ``[analyses.sweep]`` tables.

        The geometry and material keys are taken from ``[model]`` (``orientation_deg`` is
        converted to radians); the solver and sweep keys from ``options``.  A crack set read
        from a ``file``, the BEM model and per-crack friction are refused: the study draws
        random Kachanov networks.
        """
        model = {k: v for k, v in model.items() if k != "kind"}
        if "file" in model:
            raise InputError("[model] file: the sweep draws random crack sets (one per "
                             "realisation); give n_cracks, density, ... instead of a file")
        if model.get("method", "kachanov") != "kachanov":
            raise InputError(f"[model] method = {model['method']!r}: the sweep uses the "
                             "Kachanov model; remove the key or set it to 'kachanov'")
        if model.get("weighting", "uniform") != "uniform":
            raise InputError(f"[model] weighting = {model['weighting']!r}: the sweep uses "
                             "Kachanov's uniform averages; remove the key")
        if isinstance(model.get("friction"), list):
            raise InputError("[model] friction: the sweep needs one friction coefficient")
        kw = {k: model[k] for k in _MODEL_FIELDS if k in model}
        if "orientation_deg" in model:
            kw["orientation"] = np.radians(model["orientation_deg"]).tolist()
        for k in ("static", "cyclic"):
            if k in load:
                kw[k] = load[k]
        known = {f.name for f in fields(cls)} - set(_MODEL_FIELDS)
        for k, v in (options or {}).items():
            if k in known and v is not None:
                kw[k] = v
        return cls(**kw)

    @property
    def p0(self) -> float:
        """The stress scale of ``W*``."""
        if self.stress_scale is not None:
            return float(self.stress_scale)
        return max(map(abs, self.static)) or max(map(abs, self.cyclic))

    def solver_options(self) -> dict:
        return {k: getattr(self, k) for k in _SOLVER_FIELDS}

    def to_dict(self) -> dict:
        d = asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}


@lru_cache(maxsize=2)
def realisation_model(spec: SweepSpec, r: int):
    """``(cracks, model, load)`` of realisation ``r`` of a study (cached per process).

    The cracks are drawn with ``numpy.random.SeedSequence(spec.seed, spawn_key=(r, 0))``;
    ``model`` is ``crack_networks.kachanov_model(...)``, ``load`` its ``load_cycle``.
    """
    import crack_networks as cn

    ss = np.random.SeedSequence(spec.seed, spawn_key=(r, 0))
    kw = {k: getattr(spec, k) for k in _SAMPLER_FIELDS if getattr(spec, k) is not None}
    if kw.get("orientation") == "uniform":
        kw["orientation"] = None  # sample_crack_set: None = uniform in [0, pi)
    cracks = cn.sample_crack_set(spec.n_cracks, rng=np.random.default_rng(ss), **kw)
    model = cn.kachanov_model(cracks, shear_modulus=spec.shear_modulus,
                              poisson_ratio=spec.poisson_ratio, friction=spec.friction)
    load = model.load_cycle(static=spec.static, cyclic=spec.cyclic)
    return cracks, model, load


def _realisation_task(spec: SweepSpec, r: int) -> dict:
    from ..bounds.engine import shakedown_bounds

    t0 = time.perf_counter()
    cracks, model, load = realisation_model(spec, r)
    t1 = time.perf_counter()
    b = shakedown_bounds(model.system, load, adjacency=True)  # lam_adj is opt-in
    a = np.asarray(cracks.half_lengths, float)
    return dict(realisation=r, n_cracks=int(a.size), abar=float(a.mean()),
                lam1=float(b.lam1), lam2=float(b.lam2), lam_adj=float(b.lam_adj),
                bounds_status=str(b.status), build_seconds=t1 - t0,
                bounds_seconds=time.perf_counter() - t1)


def _run_task(spec: SweepSpec, r: int, lam_index: int, lam: float, state: int) -> dict:
    _, model, load = realisation_model(spec, r)
    system = model.system
    v0 = initial_slip(system, load, state, (spec.seed, r, 1), scale=spec.state_scale)
    row = dict(realisation=r, lam_index=lam_index, lam=float(lam), state=state)
    row.update(run_row(system, load, lam, v0, spec.solver_options()))
    row["W_star"] = float(model.normalised_dissipation(row["W"], p0=spec.p0))
    return row


def lam_grid(spec: SweepSpec, realisations: pd.DataFrame) -> np.ndarray:
    """The load factors of the study (explicit, or ``"auto"`` from the realisations' bounds)."""
    if spec.lams != "auto":
        return np.array(spec.lams, float)
    l1 = realisations["lam1"].to_numpy(float)
    l2 = realisations["lam2"].to_numpy(float)
    l1, l2 = l1[np.isfinite(l1)], l2[np.isfinite(l2)]
    if not l2.size:
        raise InputError("lams='auto' needs a finite lam2 in at least one realisation; "
                         "give explicit lams")
    lo = spec.lam_span[0] * (l1.min() if l1.size else l2.min())
    return np.linspace(lo, spec.lam_span[1] * l2.max(), spec.n_lams)


def _bands(summary: pd.DataFrame, confidence: float) -> pd.DataFrame:
    from scipy import stats

    out = []
    for i, g in summary.groupby("lam_index", sort=True):
        row = dict(lam_index=int(i), lam=float(g["lam"].iloc[0]), n_realisations=len(g))
        for col in ("W_star_min", "W_star_max"):
            x = g[col].to_numpy(float)
            x = x[np.isfinite(x)]
            m = x.mean() if x.size else np.nan
            half = (stats.t.ppf(0.5 + confidence / 2, x.size - 1) * x.std(ddof=1)
                    / np.sqrt(x.size)) if x.size > 1 else np.nan
            # W* >= 0: the lower end of the interval is clipped at 0
            row[f"{col}_mean"], row[f"{col}_lo"], row[f"{col}_hi"] = m, max(m - half, 0.0), m + half
        out.append(row)
    return pd.DataFrame(out)


@dataclass(frozen=True)
class SweepResult:
    """Outcome of :func:`run_sweep`.

    Attributes
    ----------
    spec : SweepSpec
    realisations : pandas.DataFrame
        One row per realisation: ``realisation, n_cracks, abar, lam1, lam2, lam_adj,
        bounds_status`` and timings.
    runs : pandas.DataFrame
        One row per (realisation, lam, initial state): ``realisation, lam_index, lam, state, W,
        W_star, cycles_to_steady, n_cycles, period, shook_down, frac_slip, frac_open, status``.
    summary : pandas.DataFrame
        One row per (realisation, lam): ``W_star_min``, ``W_star_max`` over the initial states
        that reached a steady cycle (``n_steady`` of ``n_states``), the ranges of ``frac_slip``
        and ``frac_open``, and the realisation's ``lam1``, ``lam2``.
    bands : pandas.DataFrame
        Per lam: mean of ``W_star_min`` / ``W_star_max`` over realisations and its
        ``confidence`` interval (Student t, lower end clipped at 0; nan with one realisation).
    lams : ndarray
    store : pathlib.Path
    n_resumed, n_run : int
        Tasks found done in the store / run in this call.
    wall_seconds : float
    task_seconds : pandas.Series
        Wall time of every task, by key.
    """

    spec: SweepSpec
    realisations: pd.DataFrame
    runs: pd.DataFrame
    summary: pd.DataFrame
    bands: pd.DataFrame
    lams: np.ndarray
    store: Path
    n_resumed: int
    n_run: int
    wall_seconds: float
    task_seconds: pd.Series

    def plot(self, ax=None, **kwargs):
        """``W*`` against ``lam``: min and max over initial states, ``lam1``, ``lam2``, bands."""
        from ..plotting.sweep import plot_sweep

        return plot_sweep(self, ax=ax, **kwargs)

    def to_dict(self) -> dict:
        """A JSON-serialisable digest (spec, bounds, the summary table)."""
        def clean(df):
            return json.loads(df.to_json(orient="records"))

        return dict(spec=self.spec.to_dict(), lams=[float(x) for x in self.lams],
                    realisations=clean(self.realisations), summary=clean(self.summary),
                    n_runs=int(len(self.runs)), n_resumed=self.n_resumed, n_run=self.n_run,
                    wall_seconds=self.wall_seconds)


def _summarise(runs: pd.DataFrame, realisations: pd.DataFrame) -> pd.DataFrame:
    g = runs.groupby(["realisation", "lam_index"], sort=True)
    summary = g.agg(
        lam=("lam", "first"),
        W_star_min=("W_star", "min"),
        W_star_max=("W_star", "max"),
        n_states=("state", "size"),
        n_steady=("W_star", "count"),
        n_shook_down=("shook_down", "sum"),
        frac_slip_min=("frac_slip", "min"),
        frac_slip_max=("frac_slip", "max"),
        frac_open_min=("frac_open", "min"),
        frac_open_max=("frac_open", "max"),
    ).reset_index()
    summary = summary.merge(realisations[["realisation", "lam1", "lam2"]], on="realisation")
    summary["n_shook_down"] = summary["n_shook_down"].astype(int)
    return summary


def study_tasks(spec: SweepSpec, realisations: pd.DataFrame | None = None):
    """The study's tasks: realisation tasks (``real-r``) or, given their rows, run tasks
    (``r{r}-l{i}-s{j}``), ordered realisation-major so each worker reuses its cached model."""
    if realisations is None:
        return [Task(f"real-{r}", _realisation_task, (spec, r)) for r in range(spec.n_realisations)]
    lams = lam_grid(spec, realisations)
    return [Task(f"r{r}-l{i}-s{j}", _run_task, (spec, r, i, float(lam), j))
            for r in range(spec.n_realisations) for i, lam in enumerate(lams)
            for j in range(spec.n_states)]


def run_sweep(spec: SweepSpec, store, *, n_workers: int | None = None, scheduler=None,
              progress: bool = True, format: str | None = None,
              confidence: float = 0.95) -> SweepResult:
    """Run (or resume) the crack-network study, results appended to ``store`` as they arrive.

    Parameters
    ----------
    spec : SweepSpec
    store : path
        A folder: ``spec.json``, ``realisations/`` and ``runs/`` (Parquet parts or CSV files).
        A folder made by another spec is refused; rerunning with the same spec resumes.
    n_workers : int, optional
        Local processes; default ``os.cpu_count()``.  Ignored with ``scheduler``.
    scheduler : str or distributed.Client, optional
        Dask scheduler address: run the tasks on that cluster.
    progress : bool
        Progress with time left on stderr.
    format : {"parquet", "csv"}, optional
        Store format (default Parquet when pyarrow is installed).
    confidence : float
        Level of the bands over realisations.

    Returns
    -------
    SweepResult
        Equal, bit for bit, for any ``n_workers``/``scheduler`` and any interruptions.
    """
    import os

    if not isinstance(spec, SweepSpec):
        raise InputError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    t0 = time.perf_counter()
    store = Path(store)
    store.mkdir(parents=True, exist_ok=True)
    _check_spec_file(store / "spec.json", spec)
    n_workers = int(n_workers or os.cpu_count() or 1)
    fmt = format
    sub = (lambda name: store / f"{name}.csv") if fmt == "csv" else (lambda name: store / name)
    with Workers(n_workers, scheduler) as workers:  # one pool for both phases
        a = run_tasks(study_tasks(spec), open_store(sub("realisations"), fmt),
                      desc="realisations", workers=workers, progress=progress)
        realisations = a.rows.drop(columns=[KEY])
        b = run_tasks(study_tasks(spec, realisations), open_store(sub("runs"), fmt),
                      desc="runs", workers=workers, progress=progress)
    runs = b.rows.drop(columns=[KEY])
    summary = _summarise(runs, realisations)
    return SweepResult(spec=spec, realisations=realisations, runs=runs, summary=summary,
                       bands=_bands(summary, confidence), lams=lam_grid(spec, realisations),
                       store=store, n_resumed=a.n_resumed + b.n_resumed, n_run=a.n_run + b.n_run,
                       wall_seconds=time.perf_counter() - t0,
                       task_seconds=pd.concat([a.seconds, b.seconds]))


def _check_spec_file(path: Path, spec: SweepSpec) -> None:
    new = spec.to_dict()
    if path.exists():
        old = json.loads(path.read_text())
        diff = {k: (old.get(k), v) for k, v in new.items() if old.get(k) != v}
        if diff:
            k, (o, n) = next(iter(diff.items()))
            raise InputError(
                f"store {path.parent} holds a sweep with another spec ({k}: {o!r} there, "
                f"{n!r} now; {len(diff)} field(s) differ); use another store folder to run "
                "this spec, or the same spec to resume")
        return
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(new, indent=2))
    tmp.replace(path)
