"""The Monte Carlo crack-network study (issues 4 and 13; seed 002 section 4.1, Fig. 11).

:class:`~.spec.SweepSpec`, :func:`run_sweep` -> :class:`SweepResult`: realisations x load factors
x initial states.  Per realisation ``lam1``, ``lam2``, ``lam_adj`` and a safe state; per run the
steady ``W* = W mu / (4 (1 - nu) p0^2 abar^2)`` (MODEL.md s.7), cycles to steady state, the
fractions of cracks that slip and open in the steady cycle; per (realisation, lam) min and max
over the initial states; ``lam_u``, bands over realisations, a table per band of load factors
and the verdict (:mod:`.summary`).  Load factors and states: :mod:`.design`.

Work per run
------------
One task per (realisation, load factor) runs *all* initial states with one step solver, so the
factorisations of the active sets that the states share are computed once (the solver caches
them); the system (Kachanov
matrices, critical friction) is built once per realisation and process (:func:`realisation_model`,
cached); the bounds skip the separation LP the study does not use.

Determinism: every random draw comes from ``numpy.random.SeedSequence(seed, spawn_key=...)``
named by the task, never from a stream shared between tasks: realisation ``r`` draws its
cracks from ``spawn_key=(r, 0)`` and its initial state ``j`` from ``spawn_key=(r, 1, j)``.  A
task is self-contained (its own step solver, its states in a fixed order), so its rows do not
depend on the number of workers or on the order in which tasks finish.  The refinement points
are chosen from the rows of the first phase, which are themselves deterministic.
"""

from __future__ import annotations

import json
import os
import threading
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from ..model.errors import DamagedFileError, InputError
from ..model.results import VerdictText, short_repr
from . import summary as _summary
from .design import initial_states, lam_points, refine_points, state_kind
from .engine import Task, run_tasks
from .runs import run_row
from .safe_files import make_folder, refuse_link, write_atomic
from .spec import _SAMPLER_FIELDS, SweepSpec
from .tables import KEY, open_store
from .workers import Workers, start_method

__all__ = ["SweepResult", "lam_grid", "run_sweep", "realisation_model", "study_tasks"]


@lru_cache(maxsize=2)
def realisation_model(spec: SweepSpec, r: int):
    """``(cracks, model, load)`` of realisation ``r`` of a study (cached per process).

    The cracks are drawn with ``numpy.random.SeedSequence(spec.seed, spawn_key=(r, 0))``;
    ``model`` is ``crack_networks.kachanov_model(...)``, ``load`` its ``load_cycle``.  A spec
    with a ``source`` (a given system) returns ``(None, source, source.load)``: the source has
    the model's ``system`` and ``normalised_dissipation``.
    """
    if spec.source is not None:
        return None, spec.source, spec.source.load
    import crack_networks as cn

    ss = np.random.SeedSequence(spec.seed, spawn_key=(r, 0))
    kw = {k: getattr(spec, k) for k in _SAMPLER_FIELDS if getattr(spec, k) is not None}
    if kw.get("orientation") == "uniform":
        kw["orientation"] = None  # sample_crack_set: None = uniform in [0, pi)
    cracks = cn.sample_crack_set(spec.n_cracks, rng=np.random.default_rng(ss), **kw)
    model = cn.kachanov_model(cracks, shear_modulus=spec.shear_modulus,
                              poisson_ratio=spec.poisson_ratio, friction=spec.friction,
                              interaction_radius=spec.interaction_radius)
    load = model.load_cycle(static=spec.static, cyclic=spec.cyclic)
    return cracks, model, load


def _realisation_task(spec: SweepSpec, r: int) -> dict:
    from ..bounds.engine import shakedown_bounds

    t0 = time.perf_counter()
    cracks, model, load = realisation_model(spec, r)
    t1 = time.perf_counter()
    b = shakedown_bounds(model.system, load, separation=False, adjacency=True)  # lam_adj: opt-in
    if cracks is None:  # a given system: no crack sizes
        size = dict(n_nodes=int(model.system.n_nodes), abar=float("nan"))
    else:
        a = np.asarray(cracks.half_lengths, float)
        size = dict(n_cracks=int(a.size), abar=float(a.mean()))
    safe = np.asarray(b.state_at_lam2, float)
    return dict(realisation=r, **size,
                lam1=float(b.lam1), lam2=float(b.lam2), lam_adj=float(b.lam_adj),
                bounds_status=str(b.status),
                safe_state=json.dumps([float(x) for x in safe]) if safe.size else "",
                build_seconds=t1 - t0, bounds_seconds=time.perf_counter() - t1)


@lru_cache(maxsize=2)
def _states(spec: SweepSpec, r: int, safe_state: str) -> np.ndarray:
    """The initial states of realisation ``r`` (the same at every load factor; a pure
    function of its arguments, so caching it per process keeps results bit-identical)."""
    _, model, load = realisation_model(spec, r)
    safe = np.array(json.loads(safe_state), float) if safe_state else None
    out = initial_states(model.system, load, spec.n_states, (spec.seed, r, 1), safe_state=safe,
                         scale=spec.state_scale)
    out.setflags(write=False)
    return out


def _point_task(spec: SweepSpec, r: int, point: str, lam: float, lam2: float,
                safe_state: str) -> list[dict]:
    """Every initial state at one (realisation, load factor), with one step solver."""
    from ..evolution.complementarity import StepSolver

    _, model, load = realisation_model(spec, r)
    system = model.system
    states = _states(spec, r, safe_state)
    # one step solver for the states of this task only, states in a fixed order:
    # deterministic.  The states run one after the other: solve_cycles' batched path (2-D
    # initial_slip) was measured 2x slower per run on the default network (0.9 s against
    # 0.4 s per run, benchmarks/RESULTS_study.md), so it is not used here.
    solver = StepSolver(system)
    rows = []
    for j, v0 in enumerate(states):
        row = dict(realisation=r, point=point, lam=float(lam),
                   x=float(lam / lam2) if lam2 > 0 else np.nan, state=j,
                   state_kind=state_kind(j))
        row.update(run_row(system, load, lam, v0, spec.solver_options(), step_solver=solver))
        row["W_star"] = float(model.normalised_dissipation(row["W"], p0=spec.p0))
        rows.append(row)
    return rows


def _points(spec: SweepSpec, rel: pd.Series) -> list[tuple[str, float]]:
    if spec.lams != "auto":
        return [(f"l{i}", float(x)) for i, x in enumerate(spec.lams)]
    return lam_points(rel.lam1, rel.lam2, rel.lam_adj, n_lams=spec.n_lams,
                      lam_span=spec.lam_span, n_band=spec.n_band, n_adj=spec.n_adj)


def lam_grid(spec: SweepSpec, realisations: pd.DataFrame) -> np.ndarray:
    """The first-phase load factors of the study over all realisations, sorted (before the
    refinement, which depends on the runs)."""
    lams = [lam for _, rel in realisations.iterrows() for _, lam in _points(spec, rel)]
    return np.unique(np.asarray(lams, float))


def study_tasks(spec: SweepSpec, realisations: pd.DataFrame | None = None,
                runs: pd.DataFrame | None = None) -> list[Task]:
    """The study's tasks, phase by phase: realisations (``real-r``); given their rows, the
    first load factors (``r{r}-{point}``); given those runs too, the refinement points."""
    if realisations is None:
        return [Task(f"real-{r}", _realisation_task, (spec, r)) for r in range(spec.n_realisations)]
    tasks = []
    for _, rel in realisations.iterrows():
        r = int(rel.realisation)
        if runs is None:
            pts = _points(spec, rel)
        elif spec.lams != "auto":
            pts = []
        else:
            s = _summary.summarise(runs[runs["realisation"] == r], realisations)
            pts = refine_points(s, spec.n_refine)
        tasks += [Task(f"r{r}-{p}", _point_task, (spec, r, p, lam, float(rel.lam2),
                                                  str(rel.safe_state)))
                  for p, lam in pts]
    return tasks


@dataclass(frozen=True)
class SweepResult:
    """Outcome of :func:`run_sweep`.

    Attributes
    ----------
    spec : SweepSpec
    realisations : pandas.DataFrame
        One row per realisation: ``realisation, n_cracks, abar, lam1, lam2, lam_adj,
        bounds_status, safe_state`` (JSON), timings, and ``lam_u, lam_u_low, lam_same``.
    runs : pandas.DataFrame
        One row per (realisation, point, initial state): ``realisation, point, lam, x``
        (``lam / lam2``), ``state, state_kind, W, W_star, cycles_to_steady, n_cycles, period,
        shook_down, frac_slip, frac_open, frac_active, max_residual, status``.
    summary : pandas.DataFrame
        One row per (realisation, point) (:func:`.summary.summarise`).
    regions : pandas.DataFrame
        Per realisation and band of load factors: runs and runs in cyclic slip.
    bands : pandas.DataFrame
        Per point over realisations: mean, std and Student-t ``confidence`` interval.
    verdict : str
        The study's answer (:func:`.summary.verdict`); also callable, ``res.verdict()``, like
        the ``verdict()`` of every other result.
    lams : ndarray
        Every load factor of the study (all realisations), sorted.
    store : pathlib.Path
    n_resumed, n_run : int
        Tasks found done in the store / run in this call.
    wall_seconds : float
    task_seconds : pandas.Series
    confidence : float
    """

    spec: SweepSpec
    realisations: pd.DataFrame
    runs: pd.DataFrame
    summary: pd.DataFrame
    regions: pd.DataFrame
    bands: pd.DataFrame
    verdict: str
    lams: np.ndarray
    store: Path
    n_resumed: int
    n_run: int
    wall_seconds: float
    task_seconds: pd.Series
    confidence: float = 0.95

    def __post_init__(self):
        object.__setattr__(self, "verdict", VerdictText(self.verdict))  # res.verdict() too

    def __repr__(self) -> str:
        return short_repr(self, ("n_run", "n_resumed", "wall_seconds"),
                          {"model": self.spec.describe(), "n_runs": int(len(self.runs)),
                           "n_load_factors": int(np.size(self.lams)),
                           "n_states": self.spec.n_states})

    def plot(self, ax=None, **kwargs):
        """``W*`` against ``lam`` (or ``lam / lam2``): see :func:`shakedown.plotting.sweep`."""
        from ..plotting.sweep import plot_sweep

        return plot_sweep(self, ax=ax, **kwargs)

    def to_dict(self) -> dict:
        """A JSON-serialisable digest (spec, bounds, the summary tables, the verdict)."""
        def clean(df):
            return json.loads(df.to_json(orient="records"))

        return dict(spec=self.spec.to_dict(), verdict=self.verdict,
                    lams=[float(x) for x in self.lams],
                    realisations=clean(self.realisations.drop(columns=["safe_state"])),
                    summary=clean(self.summary), regions=clean(self.regions),
                    n_runs=int(len(self.runs)), n_resumed=self.n_resumed, n_run=self.n_run,
                    wall_seconds=self.wall_seconds)


#: Estimated work (runs x nodes^2) below which a study runs in this process by default, when
#: worker processes are spawned: the built-in default study (144 runs of 100 cracks: 1.44e6)
#: costs about 3 s of CPU in its runs with the compiled kernel (14 s with steps in Python),
#: while each spawned worker costs about 2.5 s of CPU to start (its imports), so for studies up
#: to a few times that size such a pool costs more than it saves
#: (``benchmarks/RESULTS_first_run.md``, issue 25).
SMALL_STUDY = 4.0e6
#: The same threshold when the workers are forked (:func:`~.workers.start_method`): a forked
#: worker starts in milliseconds with this process's imports, so a study of about a second of
#: CPU already gains from every core (the default study on an idle 2-core machine with a cold
#: numba cache: 10.6 s wall, against 17.2 s in one process).
SMALL_STUDY_FORK = 2.0e5


def auto_workers(spec: SweepSpec) -> int:
    """The default number of local worker processes of ``spec``'s study: 1 (this process) when
    its estimated work (runs x nodes^2) is below :data:`SMALL_STUDY` (:data:`SMALL_STUDY_FORK`
    when the workers would be forked), else every core."""
    n = spec.source.n_nodes if spec.source is not None else spec.n_cracks
    n_lams = len(spec.lams) if spec.lams != "auto" else (
        spec.n_lams + spec.n_band + spec.n_adj + spec.n_refine)
    work = float(spec.n_realisations) * n_lams * spec.n_states * float(n) ** 2
    small = SMALL_STUDY_FORK if start_method() == "fork" else SMALL_STUDY
    return 1 if work < small else int(os.cpu_count() or 1)


def run_sweep(spec: SweepSpec, store, *, n_workers: int | None = None, scheduler=None,
              progress: bool = True, format: str | None = None,
              confidence: float = 0.95, meanwhile=None) -> SweepResult:
    """Run (or resume) the crack-network study, results appended to ``store`` as they arrive.

    Parameters
    ----------
    spec : SweepSpec
    store : path
        A folder (not a symbolic link): ``spec.json``, ``realisations/``, ``runs/`` and
        ``refined/`` (Parquet parts or CSV files).  A folder made by another spec is refused;
        rerunning with the same spec resumes.
    n_workers : int, optional
        Local processes (one BLAS thread each); default :func:`auto_workers` (this process
        for a small study, else ``os.cpu_count()``).  Ignored with ``scheduler``.
    scheduler : str or distributed.Client, optional
        Dask scheduler address: run the tasks on that cluster (trusted like code).
    progress : bool
        Progress with time left on stderr.
    format : {"parquet", "csv"}, optional
        Store format (default Parquet when pyarrow is installed).
    confidence : float
        Level of the bands over realisations.
    meanwhile : callable, optional
        Called without arguments in a thread of this process once the worker processes have
        started, while they run the tasks (e.g. the imports that the plots will need: this
        process only waits then); not called when the tasks run in this process.  What it
        raises is ignored.

    Returns
    -------
    SweepResult
        Equal, bit for bit, for any ``n_workers``/``scheduler`` and any interruptions.
    """
    if not isinstance(spec, SweepSpec):
        raise InputError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    t0 = time.perf_counter()
    store = make_folder(store, "store")
    _check_spec_file(store / "spec.json", spec)
    n_workers = int(n_workers or auto_workers(spec))
    sub = (lambda name: store / f"{name}.csv") if format == "csv" else (lambda name: store / name)
    done = []
    with Workers(n_workers, scheduler) as workers:  # one pool for every phase
        if meanwhile is not None and workers.kind != "inline":
            threading.Thread(target=_quietly, args=(meanwhile,), daemon=True,
                             name="shakedown-meanwhile").start()
        def phase(tasks, name):
            out = run_tasks(tasks, open_store(sub(name), format), desc=name, workers=workers,
                            progress=progress)
            done.append(out)
            return out.rows.drop(columns=[KEY])

        realisations = phase(study_tasks(spec), "realisations")
        runs = phase(study_tasks(spec, realisations), "runs")
        more = study_tasks(spec, realisations, runs)
        if more:
            runs = pd.concat([runs, phase(more, "refined")], ignore_index=True)
    runs = runs.sort_values(["realisation", "lam", "point", "state"], kind="stable")
    runs = runs.reset_index(drop=True)
    summ = _summary.summarise(runs, realisations)
    lamu = _summary.lam_u(summ)
    regs = _summary.regions(summ, lamu)
    realisations = realisations.merge(lamu, on="realisation", how="left")
    return SweepResult(
        spec=spec, realisations=realisations, runs=runs, summary=summ, regions=regs,
        bands=_summary.bands(summ, confidence),
        verdict=_summary.verdict(spec, realisations, summ, lamu, regs),
        lams=np.unique(runs["lam"].to_numpy(float)), store=store,
        n_resumed=sum(d.n_resumed for d in done), n_run=sum(d.n_run for d in done),
        wall_seconds=time.perf_counter() - t0,
        task_seconds=pd.concat([d.seconds for d in done]), confidence=confidence)


def _quietly(func) -> None:
    try:
        func()
    except Exception:  # noqa: BLE001 - a convenience (e.g. early imports): the caller redoes it
        pass


def _check_spec_file(path: Path, spec: SweepSpec) -> None:
    new = spec.to_dict()
    if refuse_link(path, "store file").exists():
        try:
            old = json.loads(path.read_bytes().decode("utf-8"))
            if not isinstance(old, dict):
                raise ValueError(f"a JSON {type(old).__name__}, not an object")
        except (ValueError, RecursionError, OSError) as exc:
            raise DamagedFileError(
                f"store file {path} is not a readable spec ({type(exc).__name__}: {exc}); the "
                "store's spec cannot be checked: use another store folder, or remove the store "
                "(--set fresh=true) to start over") from None
        diff = {k: (old.get(k), v) for k, v in new.items() if old.get(k) != v}
        if diff:
            k, (o, n) = next(iter(diff.items()))
            raise InputError(
                f"store {path.parent} holds a sweep with another spec ({k}: {o!r} there, "
                f"{n!r} now; {len(diff)} field(s) differ); use another store folder to run "
                "this spec, or the same spec to resume")
        return
    write_atomic(path, json.dumps(new, indent=2).encode(), "store file")
