"""Certificates of the 3-D ``lam2``, checked from scratch (MODEL.md s.8.3).

* :func:`check_safe_state`: a slip state ``v`` and a load factor ``lam`` are safe when every node
  stays inside its friction cone over the *continuous* cycle; the reactions are recomputed from
  ``A``, ``B`` and the load (not from the engine's reduced data) and the worst time of every
  node found exactly (:mod:`.separation`).  A safe state proves ``lam2 >= lam``.
* :func:`check_dual_bound`: multipliers of a finite set of cuts prove ``lam2 <= bound`` by weak
  duality (:func:`.socp.dual_bound`); the check recomputes the bound -- valid whatever the
  multipliers: they are moved into their cones and their stationarity residual is charged
  against an a-priori bound on the state (:mod:`.dual`) -- and objects to a claimed bound
  below the proven one.

Both are unit-free: violations are relative to the force scale of the problem, residuals to the
multipliers' size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .data import cone_data
from .separation import worst_times_of
from .socp import dual_bound

#: A safe state may exceed a cone by this much (relative to the force scale ``F``).
SAFE_TOL = 1e-9
#: Relative slack of the comparison of a proven bound with a claimed one.
DUAL_RTOL = 1e-9


@dataclass(frozen=True)
class ConeCertificate:
    """Dual certificate of ``lam2 <= lam2_upper``: cut multipliers in the engine's units.

    Attributes
    ----------
    nodes : ndarray of int, shape (M,)
        Node (0-based) of each cut.
    times : ndarray, shape (M,)
        Time (cycles) of each cut.
    multipliers : ndarray, shape (M, 3)
        ``z_m`` in ``SOC_3`` (normal, then the two tangential components) [-], for the cone
        ``(b_i(t), a_i(t))`` in units of the force scale.
    y_cap : float
        Multiplier of the load-factor cap (0 unless ``lam2`` is unbounded).
    """

    nodes: np.ndarray
    times: np.ndarray
    multipliers: np.ndarray
    y_cap: float = 0.0


def check_safe_state(system, load, v, lam, *, tol=SAFE_TOL, data=None):
    """Whether ``v`` (2N,) [length] is safe at load factor ``lam`` over the whole cycle.

    Returns
    -------
    ok : bool
    worst : float
        ``max_i max_t (|W_i q_i(t)| - p_i(t)) / F`` (``<= 0``: inside every cone) [-].
    t_worst : ndarray, shape (N,)
        Worst time of every node (cycles).
    """
    data = cone_data(system, load) if data is None else data
    n = data.n_nodes
    v = np.asarray(v, float).reshape(-1)
    if v.shape != (2 * n,):
        from ...model.errors import ShapeError
        raise ShapeError(f"v must have shape ({2 * n},) (v_1x, v_1y, v_2x, ...); got {v.shape}")
    s = np.asarray(system.A @ v).reshape(n, 2)
    bv = np.asarray(system.B.T @ v).reshape(n)
    a_base = data.a0 + s * data.weights / data.force
    b_base = data.b0 + bv / data.force
    g, tw = worst_times_of(data, a_base, b_base, float(lam) / data.load_factor)
    worst = float(g.max())
    return bool(worst <= tol), worst, tw


def check_dual_bound(system, load, certificate: ConeCertificate, claimed_upper, *,
                     rtol=DUAL_RTOL, data=None):
    """Whether ``certificate`` proves ``lam2 <= claimed_upper``.

    Returns
    -------
    ok : bool
        The bound the multipliers prove is ``<= claimed_upper (1 + rtol)``.  The proof holds
        for any multipliers (:mod:`.dual`); wrong ones prove a larger bound or none (``inf``).
    bound : float
        The bound the multipliers prove [-] (load factor).
    residuals : dict
        ``"cone"``, ``"stationarity"``, ``"sign"`` (relative): the multipliers' quality.
    """
    data = cone_data(system, load) if data is None else data
    bound, res = dual_bound(data, np.asarray(certificate.nodes), np.asarray(certificate.times),
                            certificate.multipliers, certificate.y_cap)
    bound *= data.load_factor
    ok = bound <= float(claimed_upper) * (1 + rtol) + 1e-300
    return bool(ok), float(bound), res
