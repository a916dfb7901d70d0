"""Melan's ``lam2`` of a fretting load on similar materials, matrix-free (MODEL.md s.8.3).

Scope: similar materials (``beta = 0``, uncoupled), a constant normal force ``P0`` and the
harmonic tangential load ``Q(t) = lam (Q_x cos 2 pi t, Q_y sin 2 pi t)`` of
:meth:`.model.HalfSpaceModel.load_cycle` (``P1 = 0``).  The normal problem is then independent of
the tangential one: the contact set ``C`` and the cell forces ``p`` are those of frictionless
contact (:func:`.normal.normal_contact`) at every instant, and the cells outside ``C`` stay open
and carry nothing.  The shakedown problem lives on the cells of ``C`` (the system of
:attr:`.model.HalfSpaceModel.system` restricted to them: with every cell of the window as a node,
the welded pressure of the open cells is a tension and no state is safe).  On ``C`` the welded
(bonded) reactions are ``p`` and ``lam (Q_x U + Q_y V)``-type shears, with ``U``, ``V`` (|C|, 2)
the bonded tractions of a unit ``Q_x`` and ``Q_y``::

    F_tt,CC U + ds = 0  (a rigid shift: no slip),   sum_C U = (1, 0)                     (1)

solved by conjugate gradients on the zero-sum subspace with FFT products of ``F_tt``
(:func:`bonded_tractions`).  With ``B = 0`` the safe region of the cone engine decouples by node
(:mod:`shakedown.bounds.cones.data`: ``E = 0``, the residual shear of every non-reference node is
free), so node ``i`` admits a safe state at ``lam`` iff the path ``lam M_i (cos, sin)``,
``M_i = [Q_x U_i, Q_y V_i]`` (2 x 2), fits in a disc of radius ``f p_i`` around some centre; the path
is an ellipse centred at the origin, whose smallest enclosing circle is centred there too with
radius ``sigma_max(M_i)``.  Hence, per node and without any matrix::

    lam2 = min over non-reference cells i of C of  f p_i / sigma_max(M_i)                     (2)

(the reference cell carries the resultant's balance and is not a node of the system, as in the
dense model).  The construction is cross-checked against the dense cone engine on the same
contact-cell system in ``tests/models/test_half_space_bounds.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import LinearOperator, cg

from ...model import DiscreteSystem, InputError, SolverError
from .normal import normal_contact
from .tangential import SurfaceCompliance


@dataclass(frozen=True)
class FrettingLam2:
    """Answer of :func:`fretting_lam2`.

    Attributes
    ----------
    lam2 : float
        Melan's limit (2) [-] (multiplies ``Q_x``, ``Q_y``).
    node_lam : ndarray, shape (n^2,)
        ``f p_i / sigma_max(M_i)`` per cell (``inf`` outside the contact, at the reference cell
        and where the bonded traction vanishes).
    critical_cell : int
        The cell attaining ``lam2``.
    contact : ndarray of bool, shape (n^2,)
    p : ndarray, shape (n^2,)
        Cell forces under ``P0`` [force].
    U, V : ndarray, shape (n^2, 2)
        Bonded tractions of a unit ``Q_x`` and ``Q_y`` [-] (zero outside the contact).
    cg_iterations : int
    residual : float
        Relative residual of (1) (no slip in ``C`` up to a rigid shift; resultant) [-].
    """

    lam2: float
    node_lam: np.ndarray
    critical_cell: int
    contact: np.ndarray
    p: np.ndarray
    U: np.ndarray
    V: np.ndarray
    cg_iterations: int
    residual: float

    def __repr__(self) -> str:
        from ...model.results import short_repr

        return short_repr(self, ("lam2", "critical_cell", "cg_iterations", "residual"),
                          {"n_contact_cells": int(np.count_nonzero(self.contact))})

    def verdict(self) -> str:
        """Melan's limit of the fretting load in one or two sentences (cells numbered from 1)."""
        from ...model.numbers import sig

        n = int(np.count_nonzero(self.contact))
        if not np.isfinite(self.lam2):
            return (f"No contact cell limits the tangential load ({n} cells in contact): "
                    "lam2 = inf, a safe state exists at every load factor.")
        return (f"No safe state above lam2 = {sig(self.lam2)} (the tangential amplitudes "
                f"Q_x, Q_y times lam2, Melan's limit on the friction cones of the {n} contact "
                f"cells; set by cell {int(self.critical_cell) + 1}, bonded tractions to a "
                f"relative residual {sig(self.residual)}): cyclic slip from every initial state "
                "there.")


def bonded_tractions(model, contact, ops=None, rtol: float = 1e-12, maxiter: int = 5000):
    """Bonded tractions of a unit ``Q_x`` and ``Q_y`` on the cells ``contact`` (1), by CG.

    Returns ``U, V`` (n^2, 2) [-], the CG iterations and the relative residual of (1): the
    largest deviation of the slip from a rigid shift over the contact, relative to the slip.
    """
    ops = SurfaceCompliance(model) if ops is None else ops
    C = np.flatnonzero(np.asarray(contact, bool))
    if C.size < 2:
        raise InputError(f"contact has {C.size} cells: at least 2 are needed for bonded tractions")
    N = model.n_cells
    m = C.size

    def embed(x):
        q = np.zeros((N, 2))
        q[C] = x.reshape(m, 2)
        return q

    def proj(y):  # zero-sum subspace of the contact cells, per component
        y = y.reshape(m, 2)
        return (y - y.mean(axis=0)).ravel()

    op = LinearOperator((2 * m, 2 * m), matvec=lambda x: proj(ops.tt(embed(proj(x)))[C].ravel()),
                        dtype=float)
    out, its, worst = [], 0, 0.0
    for e in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
        q0 = np.tile(e / m, (m, 1)).ravel()
        rhs = -proj(ops.tt(embed(q0))[C].ravel())
        count = [0]
        z, info = cg(op, rhs, rtol=rtol, atol=0.0, maxiter=maxiter,
                     callback=lambda _x, c=count: c.__setitem__(0, c[0] + 1))
        if info != 0:
            raise SolverError(f"bonded tractions: CG did not reach rtol = {rtol:g} in {maxiter} "
                              f"iterations", partial=z)
        its += count[0]
        q = embed(q0 + proj(z))
        v = ops.tt(q)[C]
        worst = max(worst, float(np.abs(v - v.mean(axis=0)).max() / np.abs(v).max()),
                    float(np.abs(q.sum(axis=0) - e).max()))
        out.append(q)
    return out[0], out[1], its, worst


def fretting_lam2(model, P0, Qx, Qy=0.0) -> FrettingLam2:
    """Melan's ``lam2`` (2) of ``P = P0``, ``Q = lam (Qx cos 2 pi t, Qy sin 2 pi t)``, matrix-free.

    Parameters
    ----------
    model : HalfSpaceModel
        Similar materials (``model.beta == 0``).
    P0 : float
        Normal force ``> 0`` [force].
    Qx, Qy : float
        Tangential amplitudes [force] (not both zero).

    Returns
    -------
    FrettingLam2
    """
    if model.beta != 0:
        raise InputError(f"fretting_lam2 needs similar materials (beta = 0), got beta = "
                         f"{model.beta:g}: use sd.shakedown_bounds on model.system (dense)")
    Qx, Qy = float(Qx), float(Qy)
    if not (np.isfinite(Qx) and np.isfinite(Qy)) or (Qx == 0 and Qy == 0):
        raise InputError(f"Qx, Qy must be finite and not both zero, got {Qx!r}, {Qy!r}")
    ops = SurfaceCompliance(model)
    normal = normal_contact(model, P0, rtol=1e-13, apply=ops.zz)
    contact = normal.p > 0
    U, V, its, res = bonded_tractions(model, contact, ops)
    M = np.stack([Qx * U, Qy * V], axis=-1)  # (N, 2, 2): columns cos, sin
    smax = np.linalg.norm(M, ord=2, axis=(1, 2))
    node = np.full(model.n_cells, np.inf)
    ok = contact & (smax > 0)
    ok[model.reference] = False
    node[ok] = model.friction * normal.p[ok] / smax[ok]
    k = int(np.argmin(node))
    return FrettingLam2(lam2=float(node[k]), node_lam=node, critical_cell=k, contact=contact,
                        p=normal.p, U=U, V=V, cg_iterations=its, residual=res)


def contact_system_dense(m, contact):
    """The dense counterpart: the 3-D system of the cells ``contact`` (reference cell condensed out).

    Returns ``(system, welded, nodes)``: a :class:`~shakedown.DiscreteSystem` (``B = 0``), a
    function ``welded(Qx, Qy, P) -> (q (M, 2), p (M,))`` of the welded reactions and the cell index
    of each of the ``M`` nodes.  Dense: ``O(|C|^2)`` memory (small grids, cross-checks).
    """
    if m.beta != 0:
        raise InputError(f"contact_system_dense needs similar materials (beta = 0), got {m.beta:g}")
    Fd = m.dense_compliance()
    N, ref = m.n_cells, m.reference
    nodes = np.array([j for j in np.flatnonzero(contact) if j != ref])
    t_rows = np.stack([2 * nodes, 2 * nodes + 1], axis=1).ravel()
    t_ref = np.tile([2 * ref, 2 * ref + 1], nodes.size)
    n_rows, n_ref = 2 * N + nodes, np.full(nodes.size, 2 * N + ref)

    def red(r, rr, c, cr):
        return Fd[np.ix_(r, c)] - Fd[np.ix_(r, cr)] - Fd[np.ix_(rr, c)] + Fd[np.ix_(rr, cr)]

    At = np.linalg.inv(red(t_rows, t_ref, t_rows, t_ref))
    Cn = np.linalg.inv(red(n_rows, n_ref, n_rows, n_ref))
    At, Cn = 0.5 * (At + At.T), 0.5 * (Cn + Cn.T)
    system = DiscreteSystem(At, np.zeros((At.shape[0], Cn.shape[0])), Cn, m.friction, dim=3)

    def welded(Qx, Qy, Pn):
        u = Fd[:, [2 * ref, 2 * ref + 1, 2 * N + ref]] @ np.array([Qx, Qy, Pn])
        u[2 * N:] += m.gap
        q = -At @ (u[t_rows] - u[t_ref])
        p = -Cn @ (u[n_rows] - u[n_ref])
        return q.reshape(-1, 2), p

    return system, welded, nodes
