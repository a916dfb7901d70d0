"""Condense out the nodes that stay open: the system of the closed nodes alone.

The bounds of :mod:`shakedown.bounds` assume every node in contact (MODEL.md s.3, s.8.3).  When
the static load opens part of an interface (the rim of a bolted lap joint, the cells outside a
Hertzian contact), the open nodes carry no reaction (``q = 0``, ``p = 0``) as long as they stay
open, so their unknowns ``u_o`` (slips and gap) follow from those of the closed nodes ``u_c``:

    0 = r_o(t) + K_oc u_c + K_oo u_o   ->   u_o = -K_oo^-1 (r_o(t) + K_oc u_c),

and the closed nodes see the Schur complement ``K_cc - K_co K_oo^-1 K_oc`` and the welded
reactions ``r_c - K_co K_oo^-1 r_o`` (for every harmonic or sample of the load).  This is exact
while every open node keeps a gap ``w_o(t) >= 0``; :meth:`ClosedSubsystem.open_gaps` gives those
gaps for a state of the closed nodes, to check it.  Works for 2-D and 3-D systems (dense ``K``;
a sparse ``K`` is densified).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .loading import LoadCycle
from .system import DiscreteSystem


def _unknowns(nodes, n, dim):
    """Indices of the unknowns of ``nodes`` in ``u = (v, w)``: slips (both components in 3-D,
    node by node), then gaps."""
    nodes = np.asarray(nodes, int)
    if dim == 3:
        return np.concatenate([np.stack([2 * nodes, 2 * nodes + 1], -1).ravel(), 2 * n + nodes])
    return np.concatenate([nodes, n + nodes])


def _flat(q, p):
    """``(q (..., N[, 2]), p (..., N)) -> r (..., dim-1 N + N)``."""
    q = np.asarray(q, float)
    lead = p.shape[:-1]
    return np.concatenate([q.reshape(lead + (-1,)), p], axis=-1)


@dataclass(frozen=True)
class ClosedSubsystem:
    """The system and load of the closed nodes, the open ones condensed out as free.

    Attributes
    ----------
    system : DiscreteSystem
        Of the closed nodes (their order: ``closed``), same ``dim`` as the full system.
    load : LoadCycle
        Welded reactions of the closed nodes with the open ones free [force].
    closed, open : ndarray of int
        Node indices (0-based) into the full system.
    """

    system: DiscreteSystem
    load: LoadCycle
    closed: np.ndarray
    open: np.ndarray
    _X: np.ndarray          # K_oo^-1 K_oc, shape (n_o unknowns, n_c unknowns)
    _Koo_inv_ro: object     # callable r_o -> K_oo^-1 r_o
    _full_load: LoadCycle
    _dim: int

    def open_displacements(self, slip, gap, t, lam: float):
        """Slips and gaps of the open nodes at times ``t`` (cycles, shape (T,)) for the closed
        nodes' state ``(slip, gap)`` (shapes (Nc[, 2]), (Nc,)) at load factor ``lam``.

        Returns ``(slip_o (T, No[, 2]), gap_o (T, No))`` [length].
        """
        no = self.open.size
        n = self.closed.size + no
        v = np.asarray(slip, float).reshape(-1)
        w = np.asarray(gap, float).reshape(-1)
        if v.size != (self._dim - 1) * self.closed.size or w.size != self.closed.size:
            raise InputError(f"open_displacements: slip and gap of the {self.closed.size} closed "
                             f"nodes expected; got sizes {v.size} and {w.size}")
        uc = np.concatenate([v, w])
        t = np.atleast_1d(np.asarray(t, float))
        qw, pw = self._full_load.evaluate(t, lam)
        r = _flat(qw, pw)
        ro = r[:, _unknowns(self.open, n, self._dim)]
        uo = -(self._Koo_inv_ro(ro.T).T + self._X @ uc)
        k = (self._dim - 1) * no
        slips = uo[:, :k].reshape((t.size, no, 2) if self._dim == 3 else (t.size, no))
        return slips, uo[:, k:]

    def open_gaps(self, slip, gap, lam: float, n_times: int = 64):
        """Smallest gap [length] of each open node over ``n_times`` instants of the cycle
        (shape (No,)): ``>= 0`` everywhere means the condensation is exact for this state."""
        t = np.arange(n_times) / n_times
        return self.open_displacements(slip, gap, t, lam)[1].min(axis=0)


def condense_open(system: DiscreteSystem, load: LoadCycle, closed) -> ClosedSubsystem:
    """The system of the nodes ``closed`` with every other node free (zero reactions).

    Parameters
    ----------
    system : DiscreteSystem
        ``N`` nodes, 2-D or 3-D.
    load : LoadCycle
        Of the same ``N`` nodes and dimension.
    closed : array_like of int
        Node indices (0-based, distinct, at least one) kept; the others are condensed out.

    Returns
    -------
    ClosedSubsystem
    """
    n, dim = system.n_nodes, system.dim
    try:
        c = np.unique(np.asarray(closed, dtype=int))
    except (TypeError, ValueError) as exc:
        raise InputError(f"closed must be a list of node indices; got {closed!r}") from exc
    if c.size == 0 or c[0] < 0 or c[-1] >= n:
        raise InputError(f"closed must name at least one node in 0..{n - 1}; got {closed!r}")
    if load.n_nodes != n or load.dim != dim:
        raise InputError(f"the load has {load.n_nodes} nodes (dim {load.dim}) but the system "
                         f"{n} (dim {dim}): build them from the same model")
    o = np.setdiff1d(np.arange(n), c)
    K = system.K.toarray() if hasattr(system.K, "toarray") else np.asarray(system.K, float)
    ic, io = _unknowns(c, n, dim), _unknowns(o, n, dim)
    if o.size:
        import scipy.linalg as sla

        fac = sla.cho_factor(K[np.ix_(io, io)])
        X = sla.cho_solve(fac, K[np.ix_(io, ic)])
        Kc = K[np.ix_(ic, ic)] - K[np.ix_(ic, io)] @ X

        def solve_oo(r):
            return sla.cho_solve(fac, r)
    else:
        X = np.zeros((0, ic.size))
        Kc = K[np.ix_(ic, ic)]

        def solve_oo(r):
            return r
    Kc = 0.5 * (Kc + Kc.T)
    m = c.size
    k = (dim - 1) * m
    sub = DiscreteSystem(Kc[:k, :k], Kc[:k, k:], Kc[k:, k:], system.friction[c], dim=dim)

    def cond(q, p):
        r = _flat(q, p)
        rc = r[..., ic] - r[..., io] @ X
        qc = rc[..., :k].reshape(p.shape[:-1] + ((m, 2) if dim == 3 else (m,)))
        return qc, rc[..., k:]

    q0, p0 = cond(load.q0, load.p0)
    if load.kind == "samples":
        q1, p1 = cond(load.q1, load.p1)
        sub_load = LoadCycle.from_samples(q0, p0, q1, p1)
    else:
        (qc, pc), (qs, ps) = cond(load.q_cos, load.p_cos), cond(load.q_sin, load.p_sin)
        sub_load = LoadCycle.from_harmonics(q0, p0, q_cos=qc, p_cos=pc, q_sin=qs, p_sin=ps)
    return ClosedSubsystem(sub, sub_load, c, o, X, solve_oo, load, dim)
