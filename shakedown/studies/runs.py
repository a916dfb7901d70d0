"""One run of a sweep: initial slips and the row of a run's steady outcome (any system)."""

from __future__ import annotations

import numpy as np

__all__ = ["initial_slips", "initial_slip", "run_row", "row_of_run"]


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


def run_row(system, load, lam: float, slip, solver: dict, *, step_solver=None) -> dict:
    """Solve one (system, load, lam, initial slip) cycle run; the row of its steady outcome.

    Columns: ``W`` (steady dissipation per period, nan when no steady orbit was reached),
    ``cycles_to_steady`` (-1 if none), ``n_cycles``, ``period`` (0, 1 or 2), ``shook_down``,
    ``frac_slip`` / ``frac_open`` / ``frac_active`` (fractions of nodes that slip / separate /
    do either at some step of the steady orbit, nan if none), ``max_residual`` and
    ``status`` (``CycleRun.status``: ``"periodic"``, ``"not_converged"``, ``"step_failed"``).
    An exception (bad input, a bug) propagates: it is not a result, so it is not stored and
    the task runs again when the sweep is resumed.

    ``slip`` of shape (n_states, N) runs the states together (``solve_cycles``'s batched path:
    one solver, shared factorisations) and returns a list of rows, one per state.

    ``step_solver``: a :class:`~shakedown.StepSolver` of ``system`` to reuse (its factor cache);
    by default a fresh one.  Reuse changes results only in the last bits (the cache chooses
    between an LU solve and a low-rank update), so a task that reuses one must run its states
    in a fixed order to stay bit-reproducible.
    """
    from ..evolution.complementarity import StepSolver
    from ..evolution.cycles import solve_cycles

    # Never the process-wide solver: it keeps LU factors and low-rank updates from earlier
    # runs, and answers would then depend (in the last bits) on which runs the same process
    # did before -- i.e. on the number of workers.
    runs = solve_cycles(system, load, float(lam), initial_slip=np.asarray(slip, float),
                        solver=step_solver if step_solver is not None else StepSolver(system),
                        **solver)
    if isinstance(runs, list):
        return [row_of_run(system, run) for run in runs]
    return row_of_run(system, runs)


def row_of_run(system, run) -> dict:
    """The row of :func:`run_row` for a finished :class:`~shakedown.CycleRun`."""
    from ..evolution.complementarity import FEAS_TOL, SEPARATED

    row = dict(W=float(run.steady_dissipation), cycles_to_steady=int(run.cycles_to_steady),
               n_cycles=int(run.n_cycles), period=int(run.period),
               shook_down=bool(run.shook_down), frac_slip=np.nan, frac_open=np.nan,
               frac_active=np.nan, max_residual=float(run.max_residual), status=str(run.status))
    if run.period > 0:
        # slip: the node's slip moves over the orbit by more than the solver's own zero
        # (FEAS_TOL * force_scale / A_jj, as in CycleRun.shook_down); open: a separated step
        from ..evolution.cycle_results import orbit_arrays

        v, _, states = orbit_arrays(run.steady_orbit)
        travel = np.abs(np.diff(v, axis=0)).sum(axis=0)
        zero = FEAS_TOL * float(run.force_scale) / system.A.diagonal()
        slips = travel > zero
        opens = np.any(states == SEPARATED, axis=0)
        row.update(frac_slip=slips.mean(), frac_open=opens.mean(),
                   frac_active=(slips | opens).mean())
    return row
