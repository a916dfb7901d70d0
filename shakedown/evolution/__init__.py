"""The cyclic quasi-static solver: step LCP, implicit and event-driven cycles, steady cycles,
uniqueness studies (MODEL.md s.4).

Modules, bottom up: :mod:`.lemke` (pivoting), :mod:`.step_types`, :mod:`.factors`,
:mod:`.active_set`, :mod:`.fallbacks` and :mod:`.complementarity` (the step solver),
:mod:`.kernel_jit`, :mod:`.kernel_cache`, :mod:`.kernel` and :mod:`.fast_period` (the compiled
period loop, numba), :mod:`.events` (exact events), :mod:`.cycle_results` and :mod:`.multistate`
(the period loop, several initial states together), :mod:`.cycles` (:func:`solve_cycles`), :mod:`.steady_maps`
and :mod:`.steady` (:func:`steady_cycle`), :mod:`.uniqueness` (:func:`uniqueness_study`).
May import :mod:`shakedown.model` only.
"""

from .complementarity import STATE_NAMES, StepResult, StepSolver, solve_step
from .cycles import CycleRun, EnergyIdentity, solve_cycles
from .steady import SteadyCycle, natural_slip_scale, sample_initial_slips, steady_cycle
from .uniqueness import UniquenessStudy, uniqueness_study

__all__ = [
    "STATE_NAMES",
    "StepResult",
    "StepSolver",
    "solve_step",
    "CycleRun",
    "EnergyIdentity",
    "solve_cycles",
    "SteadyCycle",
    "natural_slip_scale",
    "sample_initial_slips",
    "steady_cycle",
    "UniquenessStudy",
    "uniqueness_study",
]
