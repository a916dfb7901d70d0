"""The extreme constraints ``G v <= c + lam m`` of the safe shakedown region (MODEL.md s.3).

With every node closed, the state is the slip vector ``v``.  Node ``j`` is safe at time ``t``
when (seed 002 eq. 4, per-node friction ``F = diag(f)``)

    I_j :  ((A - F B^T) v)_j <=  f_j p_w_j(t) - q_w_j(t)
    II_j:  ((A + F B^T) v)_j >= -f_j p_w_j(t) - q_w_j(t)

With ``r_w = r_0 + lam r_1(t)`` the extreme (tightest) position over a cycle of every
constraint is affine in ``lam``; stacking the ``2N`` extreme constraints as

    G v <= c + lam m,   G = [A - F B^T; -(A + F B^T)],
                        c = [f p0 - q0; f p0 + q0],
                        m = [min_t (f p1 - q1); min_t (f p1 + q1)]

the safe shakedown region is ``H(lam) = {v : G v <= c + lam m}``.

:class:`Scales` nondimensionalises a constraint set at the boundary of every LP solver
(stiffness by ``max |G|``, forces by ``max |c|``, load factors by ``max |c| / max |m|``), so
that every solver tolerance is relative to the problem's own scales and the answers do not
depend on the unit system (issue 10).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..model import citations
from ..model.errors import InputError, ShapeError
from ..model.loading import LoadCycle
from ..model.sparse import abs_max
from ..model.system import DiscreteSystem
from ..model.validation import check_same_dimension, require_two_dimensional


@dataclass(frozen=True)
class ConstraintSet:
    """The ``2N`` extreme constraints ``G v <= c + lam m`` (rows ``0..N-1``: I, ``N..2N-1``: II).

    Attributes
    ----------
    G : ndarray or scipy.sparse.csr_matrix, shape (2N, N)
        Constraint normals [force / length] (sparse for a sparse system).
    c : ndarray, shape (2N,)
        Offsets at ``lam = 0`` [force].
    m : ndarray, shape (2N,)
        Rate of change of the offsets with ``lam`` [force] (``<= 0`` for loads with zero mean).
    t_extreme : ndarray, shape (2N,)
        Time (cycles) at which each constraint reaches its extreme position.
    sep_G, sep_c, sep_m : ndarray
        No-separation rows ``-(B^T v)_j <= p0_j + lam min_t p1_j`` (``p_w + B^T v >= 0``).
    row_labels : tuple of str, optional
        Names of the rows when they are not the 2-D ``I_j`` / ``II_j`` (3-D facets).
    pairs : ndarray of int, shape (P, 2), optional
        Rows whose meeting in ``H`` defines ``lam_adj`` (default ``(j, N + j)``: ``I_j``,
        ``II_j``; 3-D: opposite facets of one node).
    """

    G: np.ndarray
    c: np.ndarray
    m: np.ndarray
    t_extreme: np.ndarray
    sep_G: np.ndarray
    sep_c: np.ndarray
    sep_m: np.ndarray
    row_labels: tuple | None = None
    pairs: np.ndarray | None = None

    @property
    def n_nodes(self) -> int:
        """Columns of ``G`` (the unknowns: ``N`` in 2-D, ``2N`` slip components in 3-D)."""
        return self.G.shape[1]

    @property
    def n_rows(self) -> int:
        """Rows of ``G`` (``2N`` in 2-D)."""
        return self.G.shape[0]

    def adjacency_pairs(self) -> np.ndarray:
        """Row pairs of ``lam_adj``, shape (P, 2) (2-D: ``(j, N + j)``)."""
        if self.pairs is not None:
            return np.asarray(self.pairs)
        n = self.n_nodes
        return np.column_stack([np.arange(n), np.arange(n, 2 * n)])

    def labels(self) -> list[str]:
        """``"I_1" .. "I_N", "II_1" .. "II_N"`` (nodes numbered from 1 for people), or
        ``row_labels`` when given."""
        if self.row_labels is not None:
            return list(self.row_labels)
        n = self.n_nodes
        return [f"I_{j + 1}" for j in range(n)] + [f"II_{j + 1}" for j in range(n)]

    def offsets(self, lam: float) -> np.ndarray:
        return self.c + lam * self.m

    def instantaneous(self, system: DiscreteSystem, load: LoadCycle, t, lam: float):
        """Offsets ``b(t)`` of the 2N constraints at time(s) ``t``: ``G v <= b(t)``."""
        q, p = load.evaluate(t, lam)
        f = system.friction
        return np.concatenate([f * p - q, f * p + q], axis=-1)


@dataclass(frozen=True)
class Scales:
    """Units of a constraint set: ``v = slip * v_hat``, ``lam = load_factor * lam_hat``.

    Attributes
    ----------
    stiffness : float
        ``max |G|`` [force / length].
    force : float
        ``max |c|`` (``max |m|`` when ``c = 0``) [force].
    load_factor : float
        ``max |c| / max |m|`` (1 when either is 0) [-].
    """

    stiffness: float
    force: float
    load_factor: float

    @property
    def slip(self) -> float:
        """``force / stiffness`` [length]."""
        return self.force / self.stiffness

    @classmethod
    def of(cls, cs: ConstraintSet) -> Scales:
        k = abs_max(cs.G)
        fc = float(np.abs(cs.c).max(initial=0.0))
        fm = float(np.abs(cs.m).max(initial=0.0))
        force = fc if fc > 0 else (fm if fm > 0 else 1.0)
        lf = fc / fm if fc > 0 and fm > 0 else 1.0
        return cls(stiffness=k if k > 0 else 1.0, force=force, load_factor=lf)

    def nondimensional(self, cs: ConstraintSet) -> ConstraintSet:
        """``cs`` in these units: ``G / k``, ``c / F``, ``m * Lambda / F`` (and the separation
        rows alike); the LPs of :mod:`shakedown.bounds` are solved in these units only."""
        k, f, lf = self.stiffness, self.force, self.load_factor
        return replace(
            cs, G=cs.G / k, c=cs.c / f, m=cs.m * (lf / f),
            sep_G=cs.sep_G / k, sep_c=cs.sep_c / f, sep_m=cs.sep_m * (lf / f),
        )


def extreme_constraints(system: DiscreteSystem, load: LoadCycle) -> ConstraintSet:
    """Assemble the extreme constraints of ``system`` under ``load`` (module docstring)."""
    _check_pair(system, load)
    A, B, f = system.A, system.B, system.friction
    if hasattr(system.K, "columns"):  # uncondensed (K = Schur complement of K_z): its rows
        # A - f B^T are dense; [A; B^T] = K[:, :N] by N sparse solves, never all of K
        n = system.n_nodes
        AB = system.K.columns(np.arange(n))
        FBt = f[:, None] * AB[n:]
        G = np.vstack([AB[:n] - FBt, -(AB[:n] + FBt)])
        sep_G = -AB[n:]
    elif system.is_sparse:  # rows scaled by f: diag(f) B^T, all sparse
        FBt = sp.diags(f) @ B.T
        G = sp.vstack([A - FBt, -(A + FBt)], format="csr")
        sep_G = sp.csr_matrix(-B.T)
    else:
        return family_constraints(system, load, [(1.0, f), (-1.0, f)])
    c = np.concatenate([f * load.p0 - load.q0, f * load.p0 + load.q0])
    mI, tI = load.periodic_min(-1.0, f)
    mII, tII = load.periodic_min(1.0, f)
    mp, _ = load.periodic_min(0.0, 1.0)
    return ConstraintSet(
        G=G, c=c, m=np.concatenate([mI, mII]), t_extreme=np.concatenate([tI, tII]),
        sep_G=sep_G, sep_c=load.p0.copy(), sep_m=mp,
    )


def family_constraints(system, load, families, *, row_labels=None, pairs=None) -> ConstraintSet:
    """Extreme constraints of families of friction hyperplanes, one row per node and family.

    Family ``(w, phi)`` asks ``w_j . q_j(t) <= phi_j p_j(t)`` at every node ``j`` and time
    ``t``; with ``q = q_w + A v``, ``p = p_w + B^T v`` its extreme row is

        (w_j . (A v)_j - phi_j (B^T v)_j)  <=  phi_j p0_j - w_j . q0_j
                                               + lam min_t (phi_j p1_j(t) - w_j . q1_j(t)).

    2-D: ``w = +1`` / ``-1`` and ``phi = f`` are the families ``I`` / ``II`` (section 3).  3-D:
    ``w_j`` is a 2-vector (a facet normal of node ``j``'s polygon, divided by the friction
    coefficients for elliptic cones) and ``(A v)_j`` the node's two rows of ``A``.  Rows are
    stacked family by family (dense ``A``, ``B``).

    Parameters
    ----------
    families : list of (w, phi)
        ``w``: scalar or (N,) in 2-D, (N, 2) in 3-D; ``phi``: scalar or (N,).
    row_labels, pairs : optional
        Stored on the :class:`ConstraintSet` (default: the 2-D ``I_j`` / ``II_j``).
    """
    n = system.n_nodes
    dim = getattr(system, "dim", 2)
    A = system.A.toarray() if sp.issparse(system.A) else system.A
    Bt = (system.B.toarray() if sp.issparse(system.B) else system.B).T
    q0 = np.asarray(load.q0, float)
    rows, cs, ms, ts = [], [], [], []
    for w, phi in families:
        phi = np.broadcast_to(np.asarray(phi, float), (n,))
        FBt = phi[:, None] * Bt
        if dim == 2:
            w = np.asarray(w, float)
            rows.append((A if w.ndim == 0 and w == 1.0 else -A if w.ndim == 0 and w == -1.0
                         else np.broadcast_to(w, (n,))[:, None] * A) - FBt)
            wq0 = w * q0
        else:
            w = np.broadcast_to(np.asarray(w, float), (n, 2))
            A3 = A.reshape(n, 2, 2 * n)
            rows.append(w[:, 0, None] * A3[:, 0] + w[:, 1, None] * A3[:, 1] - FBt)
            wq0 = np.einsum("jc,jc->j", w, q0)
        cs.append(phi * load.p0 - wq0)
        m, t = load.periodic_min(-w, phi)
        ms.append(m)
        ts.append(t)
    mp, _ = load.periodic_min(np.zeros_like(q0), 1.0)
    return ConstraintSet(
        G=np.vstack(rows), c=np.concatenate(cs), m=np.concatenate(ms),
        t_extreme=np.concatenate(ts), sep_G=-Bt.copy(), sep_c=np.asarray(load.p0, float).copy(),
        sep_m=mp, row_labels=row_labels, pairs=pairs,
    )


def _check_pair(system, load):
    if not isinstance(system, DiscreteSystem):
        raise InputError(
            f"system must be a shakedown.DiscreteSystem; got {type(system).__name__}"
        )
    if not isinstance(load, LoadCycle):
        raise InputError(f"load must be a shakedown.LoadCycle; got {type(load).__name__}")
    if load.n_nodes != system.n_nodes:
        raise ShapeError(
            f"load has {load.n_nodes} nodes but system has {system.n_nodes}; "
            "build the LoadCycle with one entry per contact node"
        )
    check_same_dimension(system, load)
    require_two_dimensional(system, "the hyperplane bounds engine (2-D)")


def _check_lam(lam) -> float:
    try:
        lam = float(lam)
    except (TypeError, ValueError) as exc:
        raise InputError(f"lam must be a number >= 0; got {lam!r}") from exc
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam must be finite and >= 0; got {lam}")
    return lam


@dataclass(frozen=True)
class SafeRegion:
    """The safe shakedown region ``H(lam) = {v : normals @ v <= offsets}`` (a polyhedron).

    Attributes
    ----------
    lam : float
    normals : ndarray, shape (2N, N)
        [force / length]
    offsets : ndarray, shape (2N,)
        [force]
    labels : list of str
        ``"I_j"`` / ``"II_j"`` (``j`` from 1).
    separation_normals, separation_offsets : ndarray, shape (N, N), (N,)
        Rows of ``p_w(t) + B^T v >= 0`` at every ``t`` (not part of ``H``; see MODEL.md s.3).
    """

    lam: float
    normals: np.ndarray
    offsets: np.ndarray
    labels: list
    separation_normals: np.ndarray
    separation_offsets: np.ndarray

    def contains(self, v, tol: float = 1e-9) -> bool:
        """``True`` when ``v`` satisfies every extreme constraint to ``tol`` times the row's
        force scale ``|normals| |v| + |offsets|`` (unit-free)."""
        v = np.asarray(v, float)
        scale = _row_scale(self.normals, self.offsets, v)
        return bool(np.all(self.normals @ v - self.offsets <= tol * scale))

    def slack(self, v) -> np.ndarray:
        return self.offsets - self.normals @ np.asarray(v, float)

    def vertices_2d(self):
        """Vertices (counter-clockwise) of a bounded two-node region; empty array if empty."""
        if self.normals.shape[1] != 2:
            raise InputError("vertices_2d is for two-node systems")
        G = self.normals.toarray() if sp.issparse(self.normals) else self.normals
        return _polygon_2d(G, self.offsets)

    def area(self) -> float:
        """Area of a bounded two-node region (0 when empty) [length^2]."""
        P = self.vertices_2d()
        if len(P) < 3:
            return 0.0
        x, y = P[:, 0], P[:, 1]
        return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _row_scale(G, b, x):
    """Force scale of each row of ``G x <= b`` at ``x``: ``max|G| max|x| + |b|`` (> 0)."""
    s = abs_max(G) * np.abs(x).max(initial=0.0) + np.abs(b)
    return np.maximum(s, np.finfo(float).tiny)


def _polygon_2d(G, b, tol=1e-12):
    """Vertices of ``{x in R^2 : G x <= b}`` by pairwise intersection (bounded case).

    Feasibility and duplicate tests are relative to the rows' own scales (unit-free).
    """
    pts = []
    n = len(b)
    for i in range(n):
        for j in range(i + 1, n):
            M = G[[i, j]]
            det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
            if abs(det) <= 1e-14 * np.abs(M).max() ** 2:
                continue
            x = np.linalg.solve(M, b[[i, j]])
            if np.all(G @ x - b <= tol * _row_scale(G, b, x)):
                pts.append(x)
    if not pts:
        return np.zeros((0, 2))
    P = np.array(pts)
    span = max(np.abs(P).max(), np.finfo(float).tiny)
    _, keep = np.unique(np.round(P / span, 12), axis=0, return_index=True)
    P = P[np.sort(keep)]
    c = P.mean(axis=0)
    order = np.argsort(np.arctan2(P[:, 1] - c[1], P[:, 0] - c[0]))
    return P[order]


def safe_region(system: DiscreteSystem, load: LoadCycle, lam: float) -> SafeRegion:
    """The safe shakedown region ``H(lam)`` as a polyhedron ``normals @ v <= offsets``."""
    citations.register("melan1936", "klarbring2007")
    lam = _check_lam(lam)
    cs = extreme_constraints(system, load)
    return SafeRegion(
        lam=lam,
        normals=cs.G,
        offsets=cs.offsets(lam),
        labels=cs.labels(),
        separation_normals=cs.sep_G,
        separation_offsets=cs.sep_c + lam * cs.sep_m,
    )
