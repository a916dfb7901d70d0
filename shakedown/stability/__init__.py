"""Nonlinear (complementarity) eigenvalue check of frictional equilibria (MODEL.md s.5).

MCEIP, the *mixed complementarity eigenvalue problem*: with some contact nodes slipping, find
the smallest friction ``mu*`` at which a non-zero perturbation of the slips can grow while every
slipping node stays on its friction cone and the others unload from it (MCEIP-mu, quasi-static
divergence; the equilibrium is stable for friction below ``mu*``), and, with a mass, the growth
rates of perturbations ``~ e^(s t)`` at a given friction (MCEIP-lam).  The Python API calls the
growth rate ``lam`` (the seeds' notation); everything the ``shakedown`` command prints or writes
calls it ``s`` / ``growth_rate``, since ``lam`` is the load factor there.

Pipeline: classify the nodes of an equilibrium or snapshot (:func:`classify_nodes`), condense
the stiffness onto the slip nodes (:func:`slip_pencil`), solve MCEIP-mu for the critical
friction (:func:`mceip_mu`) or MCEIP-lam for the growth rates at a given friction
(:func:`growth_rates`, :func:`lam_mu_curves`).  Every answer is verified (equation residual,
sign conditions, complementarity) and carries its residuals.  Along a cyclic evolution,
:func:`stability_along_cycle` reports the margin ``mu* / f`` at each node-state change.
Seed 000 (Hassani, Ionescu & Sakki 2007) and seed 001 (Agwa & Pinto da Costa 2007).
"""

from .classify import (
    CLASSIFY_RTOL,
    FREE,
    FRICTIONLESS,
    SLIP,
    STICK,
    NodePartition,
    classify_nodes,
    classify_state,
)
from .cycle import CycleStability, stability_along_cycle
from .enumerate import enumerate_solutions
from .growth import GrowthRates, LamMuCurves, growth_rates, lam_mu_curves
from .layer import (
    layer_critical_friction,
    layer_dynamic_stiffness,
    layer_growth_rates,
    layer_mu,
)
from .linear import active_set, linear_arpack, linear_dense, restricted_eigenpairs
from .mceip import METHODS, mceip_mu, mceip_mu_all
from .pencil import SlipPencil, as_dynamic_stiffness, slip_pencil
from .power import power_iteration
from .result import VERIFY_TOL, MCEIPResult, residuals

__all__ = [
    "CLASSIFY_RTOL", "FREE", "FRICTIONLESS", "SLIP", "STICK", "NodePartition",
    "classify_nodes", "classify_state", "SlipPencil", "slip_pencil", "as_dynamic_stiffness",
    "MCEIPResult", "residuals", "VERIFY_TOL", "METHODS", "mceip_mu", "mceip_mu_all",
    "enumerate_solutions", "linear_dense", "linear_arpack", "active_set",
    "restricted_eigenpairs", "power_iteration", "GrowthRates", "LamMuCurves", "growth_rates",
    "lam_mu_curves", "CycleStability", "stability_along_cycle", "layer_critical_friction",
    "layer_dynamic_stiffness", "layer_growth_rates", "layer_mu",
]
