"""Named reference systems for the cyclic solver, each citing its source.

Seed 002 (Barber, frictional systems under oscillating loads) draws its two-node scenarios as
schematic constraint diagrams without numbers.  The matrices and loads here were *designed for
this package* to reproduce the behaviour each figure describes; the behaviour (not the
numbers) is what the source supports, and the tests check it.

>>> import shakedown as sd
>>> len(sd.gallery.names()), sd.gallery.names()[0]
(5, 'fig4_triangle')
>>> p = sd.gallery.get("fig8_coupled_one_at_a_time")
>>> p.system.n_nodes, p.system.is_coupled
(2, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model.errors import InputError
from .model.loading import LoadCycle
from .model.system import DiscreteSystem

__all__ = [
    "ReferenceProblem",
    "names",
    "get",
    "fig4_triangle",
    "fig5_uncoupled_stuck",
    "fig6_uncoupled_both_slip",
    "fig8_coupled_one_at_a_time",
    "three_node_below_lam1",
]


@dataclass(frozen=True)
class ReferenceProblem:
    """A system, a load cycle and a load factor with the behaviour they are known for.

    Attributes
    ----------
    name : str
    system : DiscreteSystem
    load : LoadCycle
    lam : float
        The load factor of the scenario.
    steps_per_cycle : int
        Implicit steps per cycle that resolve the load (a multiple of the number of samples
        for sampled loads, so that the extremes are hit exactly).
    source : str
        The figure / section the scenario reproduces.
    behaviour : str
        What happens (and what the tests check).
    designed : bool
        ``True``: the numbers were designed here (the source gives none).
    """

    name: str
    system: DiscreteSystem
    load: LoadCycle
    lam: float
    steps_per_cycle: int
    source: str
    behaviour: str
    designed: bool = True


def fig5_uncoupled_stuck() -> ReferenceProblem:
    """Uncoupled two-node system: node 0 slips every cycle, node 1 is permanently stuck.

    ``A = [[1, 0.5], [0.5, 1]]``, ``B = 0``, ``C = I``, ``f = 0.3``, ``p_w = 1``; node 0 has a
    tangential load ``lam cos(2 pi t)`` (its extreme constraints overlap for ``lam > 0.3``),
    node 1 only ``0.1 lam sin(2 pi t)`` (a safe band remains between its extreme lines).
    Different initial slips of node 1 stay locked in; the dissipation is the same from every
    initial state, ``W = 4 f p (lam Q - f p) / A_00 = 0.24`` at ``lam = 0.5`` (node 1 held).
    """
    system = DiscreteSystem([[1.0, 0.5], [0.5, 1.0]], np.zeros((2, 2)), np.eye(2), 0.3)
    load = LoadCycle.from_harmonics([0.0, 0.0], [1.0, 1.0], q_cos=[1.0, 0.0], q_sin=[0.0, 0.1])
    return ReferenceProblem(
        "fig5_uncoupled_stuck", system, load, 0.5, 64,
        "seed 002 section 3, Fig. 5 (and Fig. 7 in tau = A v space)",
        "node 1 permanently stuck with initial-state dependent locked-in slip; W unique (0.24)",
    )


def fig6_uncoupled_both_slip() -> ReferenceProblem:
    """Uncoupled two-node system in which both nodes slip: a unique steady state.

    As :func:`fig5_uncoupled_stuck` with node 1's load raised to ``0.8 lam sin(2 pi t)``, which
    closes its safe band: both nodes slip, simultaneously at times, and the steady state is
    reached after finitely many cycles and is the same from every initial state.
    """
    system = DiscreteSystem([[1.0, 0.5], [0.5, 1.0]], np.zeros((2, 2)), np.eye(2), 0.3)
    load = LoadCycle.from_harmonics([0.0, 0.0], [1.0, 1.0], q_cos=[1.0, 0.0], q_sin=[0.0, 0.8])
    return ReferenceProblem(
        "fig6_uncoupled_both_slip", system, load, 0.5, 64,
        "seed 002 section 3, Fig. 6",
        "both nodes slip; unique steady state (slips, reactions and W) from every initial state",
    )


def fig8_coupled_one_at_a_time() -> ReferenceProblem:
    """Coupled two-node system whose constraints advance one at a time (seed 002 Fig. 8).

    ``A = [[1, 0.9], [0.9, 1]]``, ``B = 0.3 I``, ``C = I``, ``f = 0.3``, ``p_w = 1``.  The load
    is sampled (8 samples): tangential pulses ``+1`` on node 0, ``+1`` on node 1, ``-1`` on node
    0, ``-1`` on node 1, each returning to 0 before the next starts, so the extreme positions
    are reached in the sequence ``I^E, III^E, II^E, IV^E`` and only one node slips at a time.
    At ``lam = 0.4`` both nodes slip every cycle (``S0`` empty) and the memory of the initial
    state fades geometrically (about 0.6 per cycle): the steady state is unique but reached only
    asymptotically (~50 cycles to 1e-10 with 8 steps per cycle).
    """
    system = DiscreteSystem([[1.0, 0.9], [0.9, 1.0]], 0.3 * np.eye(2), np.eye(2), 0.3)
    q1 = np.array(
        [[0, 0], [1, 0], [0, 0], [0, 1], [0, 0], [-1, 0], [0, 0], [0, -1]], dtype=float
    )
    load = LoadCycle.from_samples([0.0, 0.0], [1.0, 1.0], q1, np.zeros_like(q1))
    return ReferenceProblem(
        "fig8_coupled_one_at_a_time", system, load, 0.4, 8,
        "seed 002 section 3.2, Fig. 8",
        "one node slips at a time; geometric convergence to a unique steady state",
    )


def fig4_triangle() -> ReferenceProblem:
    """Coupled two-node system between ``lam1`` and ``lam2``: the initial state decides.

    Found by a random search over SPD ``K`` (rounded to two decimals) for a system whose safe
    region loses an extreme constraint well before it vanishes (``lam1 ~ 0.36``,
    ``lam2 ~ 0.85``, computed by :func:`shakedown.shakedown_bounds`).  At ``lam = 0.6`` some
    initial states shake down and others settle into cyclic slip between the constraints
    that no longer abut ``H`` (seed 002 Fig. 4; Ahn, Bertocchi & Barber 2008).
    """
    A = [[3.26, -0.72], [-0.72, 2.24]]
    B = [[0.52, -2.12], [1.46, -0.55]]
    C = [[2.95, -1.52], [-1.52, 3.92]]
    system = DiscreteSystem(A, B, C, 0.39)
    load = LoadCycle.from_harmonics(
        [0.49, 0.18], [3.27, 3.53], q_cos=[0.90, -0.35], q_sin=[-1.48, -0.11],
        p_cos=[-0.09, 0.16],
    )
    return ReferenceProblem(
        "fig4_triangle", system, load, 0.6, 64,
        "seed 002 section 2.3, Fig. 4 (Ahn et al. 2008)",
        "lam1 < lam < lam2: shakedown or cyclic slip depending on the initial state",
    )


def three_node_below_lam1() -> ReferenceProblem:
    """Coupled three-node system with cyclic slip from some initial states *below* ``lam1``.

    Drawn by the random search of ``notebooks/02_cycles.ipynb`` (SPD ``K`` = ``L L^T + 0.5 I``
    with normal ``L``, ``numpy.random.default_rng(11)``, third system with
    ``lam_adj < 0.8 lam1``) and rounded to two decimals.  ``lam_adj = 0`` (the extreme facets
    ``I_2``, ``II_2`` of node 2 already meet in ``H`` at ``lam = 0``), ``lam1 ~ 0.702``,
    ``lam2 ~ 1.230``.  At ``lam = lam1 / 2`` most sampled initial states shake down, but some
    settle into steady cyclic slip of node 2 (``W ~ 0.008-0.04``, no separation; the same with
    the exact event-driven method and with 8x finer implicit steps).  It is a numerical
    counterexample to the N-node form of the ``lam1`` criterion stated without proof in seed
    002 section 2.3 (MODEL.md s.3 asks to test it); ``lam_adj`` is not contradicted.
    """
    A = [[3.34, -0.73, -3.02], [-0.73, 1.65, 1.32], [-3.02, 1.32, 5.33]]
    B = [[-0.88, -3.79, -0.01], [-0.31, 0.34, 0.84], [1.04, 3.64, 1.05]]
    C = [[3.44, 0.95, 0.24], [0.95, 9.48, -3.4], [0.24, -3.4, 3.82]]
    system = DiscreteSystem(A, B, C, 0.52)
    load = LoadCycle.from_harmonics(
        [-0.86, -0.06, -0.09], [5.27, 8.21, 1.94], q_cos=[0.75, -0.04, -0.53],
        q_sin=[1.46, 0.99, 1.27], p_cos=[0.12, -0.02, -0.08],
    )
    return ReferenceProblem(
        "three_node_below_lam1", system, load, 0.351, 64,
        "this package's uniqueness experiments (notebooks/02_cycles.ipynb); claim tested: "
        "seed 002 section 2.3, MODEL.md s.3",
        "lam_adj = 0 < lam = lam1 / 2: some initial states end in cyclic slip of node 2",
    )


_REGISTRY = {
    f.__name__: f
    for f in (fig4_triangle, fig5_uncoupled_stuck, fig6_uncoupled_both_slip,
              fig8_coupled_one_at_a_time, three_node_below_lam1)
}


def names() -> list[str]:
    """Names of the reference problems."""
    return sorted(_REGISTRY)


def get(name: str) -> ReferenceProblem:
    """The reference problem called ``name`` (see :func:`names`)."""
    try:
        return _REGISTRY[name]()
    except KeyError:
        raise InputError(
            f"unknown reference problem {name!r}; choose one of {', '.join(names())}"
        ) from None
