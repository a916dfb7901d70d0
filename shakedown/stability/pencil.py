"""Condensation onto the slip nodes: the pencil ``K0 + mu K1`` (MODEL.md s.5).

A perturbation ``(v', w')`` with reactions ``(q', p')`` keeps stick nodes fixed
(``v' = w' = 0``), keeps slip nodes closed (``w' = 0``), leaves free nodes unloaded
(``q' = p' = 0``; frictionless closed nodes: ``q' = 0``, ``w' = 0``).  Eliminating the unloaded
DOFs ``e`` by a Schur complement (``c``: the slip nodes' tangential and normal DOFs,
``s``: their tangential DOFs),

    r_c = S v'_s,   S = K_cs - K_ce K_ee^-1 K_es,

gives on the slip nodes ``q'_s = S_tt v'_s``, ``p'_s = S_nt v'_s``.  With ``X = diag(chi)``,
``x = X v'_s`` and ``y = X q'_s + mu F p'_s`` (``F = diag(friction profile)``, ones for a
uniform friction ``mu``):

    y = (K0 + mu K1) x,   K0 = X S_tt X  (SPD),   K1 = F S_nt X.

Sign check (MODEL.md s.1): a slip node with ``chi = +1`` has ``q = -f p``; it stays on the cone
while slipping iff ``-(q + q') = f (p + p')``, i.e. ``y = chi q' + f p' = 0``, and it may
unload into stick iff ``y >= 0``.  With mass, ``K`` is replaced by the dynamic stiffness
``K(s)``, ``s = lam^2`` (growth ``e^(lam t)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..model.errors import InputError, ShapeError
from ..model.system import SYMMETRY_RTOL
from ..model.validation import (
    check_node_vector,
    check_stiffness,
    real_array,
    require_two_dimensional,
)
from .classify import FREE, FRICTIONLESS, SLIP, NodePartition


@dataclass(frozen=True, eq=False)
class SlipPencil:
    """The matrices of MCEIP ``y = (K0 + mu K1) x`` on the slip nodes.

    Attributes
    ----------
    K0 : ndarray, shape (n, n)
        ``X S_tt X``, symmetric positive definite [force / length].
    K1 : ndarray, shape (n, n)
        ``F S_nt X`` [force / length], not symmetric.
    nodes : ndarray of int, shape (n,)
        Global indices of the slip nodes.
    chi : ndarray, shape (n,)
        Their slip directions.
    profile : ndarray, shape (n,)
        Friction profile ``F`` (the friction of node ``j`` is ``mu * profile[j]``).
    lam : float
        Growth rate at which the (dynamic) stiffness was taken (0: quasi-static).
    """

    K0: np.ndarray
    K1: np.ndarray
    nodes: np.ndarray
    chi: np.ndarray
    profile: np.ndarray
    lam: float = 0.0

    def __post_init__(self):
        # a pencil a user builds by hand is checked like one from slip_pencil: the eigen-solvers
        # downstream call LAPACK on K0 and K1 without further checks
        K0 = check_stiffness("K0", self.K0, symmetry_rtol=SYMMETRY_RTOL)
        m = K0.shape[0]
        K1 = real_array("K1", self.K1)
        if K1.shape != (m, m):
            raise ShapeError(f"K1 must have the shape of K0 ({m}, {m}); got {K1.shape}")
        if not np.all(np.isfinite(K1)):
            raise InputError("K1 must be finite; got a NaN or inf entry")
        prof = check_node_vector("profile", self.profile, m, nonneg=True, what="friction ratio")
        chi = check_node_vector("chi", self.chi, m, what="slip direction")
        if not np.all(np.abs(chi) == 1):
            raise InputError(f"chi must be +1 or -1 per slip node; got {chi}")
        for a in (K0, K1, prof, chi):
            a.setflags(write=False)
        object.__setattr__(self, "K0", K0)
        object.__setattr__(self, "K1", K1)
        object.__setattr__(self, "profile", prof)
        object.__setattr__(self, "chi", chi)

    @property
    def size(self) -> int:
        return self.K0.shape[0]

    def matrix(self, mu: float) -> np.ndarray:
        """``K0 + mu K1``."""
        return self.K0 + mu * self.K1

    def restricted(self, support) -> SlipPencil:
        """The pencil on a subset of the slip nodes (the others held stuck)."""
        J = np.asarray(support, dtype=int)
        ix = np.ix_(J, J)
        return SlipPencil(
            self.K0[ix], self.K1[ix], self.nodes[J], self.chi[J], self.profile[J], self.lam
        )

    @property
    def scale(self) -> float:
        """``max(|K0|, |K1|)`` (used to make residuals relative)."""
        return float(max(np.abs(self.K0).max(initial=0), np.abs(self.K1).max(initial=0), 1e-300))


def as_dynamic_stiffness(source, mass=None):
    """A callable ``s -> K(s)`` (shape (2N, 2N)) from one of several sources.

    Parameters
    ----------
    source
        A :class:`~shakedown.DiscreteSystem` or an array ``K`` (shape (2N, 2N), order:
        tangential DOFs of all nodes, then normal DOFs); a callable ``s -> K(s)``; or an object
        with a ``dynamic_stiffness(s)`` method (a condensed FE model: exact condensation of
        ``K + s M``).
    mass : array_like, shape (2N, 2N), optional
        Mass on the contact DOFs for array / system sources: ``K(s) = K + s M`` (a Guyan-type
        lumping onto the contact nodes; documented approximation).  Without it, only ``s = 0``
        is allowed.
    """
    if hasattr(source, "dynamic_stiffness"):
        return source.dynamic_stiffness
    if callable(source) and not isinstance(source, np.ndarray):
        return source
    require_two_dimensional(source, "the stability eigen-check (MCEIP)")
    K = source.K if hasattr(source, "K") else source
    if hasattr(K, "toarray"):  # the eigenproblems are dense: a sparse or uncondensed K
        K = K.toarray()  # (2N x 2N) is densified here
    K = real_array("K", K)
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] % 2:
        raise ShapeError(f"K must have shape (2N, 2N); got {K.shape}")
    K = check_stiffness("K", K, symmetry_rtol=SYMMETRY_RTOL)
    if mass is None:

        def static_only(s):
            if s != 0:
                raise InputError(
                    f"a growth rate lam > 0 (s = lam^2 = {s:g}) needs a mass: pass mass= "
                    "(2N, 2N) or a condensed FE model with dynamic_stiffness(s)"
                )
            return K

        return static_only
    M = real_array("mass", mass)
    if M.shape != K.shape:
        raise ShapeError(f"mass must have shape {K.shape} like K; got {M.shape}")
    if not np.all(np.isfinite(M)) or np.abs(M - M.T).max() > SYMMETRY_RTOL * np.abs(M).max():
        raise InputError("mass must be a finite symmetric matrix (2N, 2N)")
    return lambda s: K + s * M


def slip_pencil(
    stiffness,
    partition: NodePartition,
    *,
    friction_profile=None,
    lam: float = 0.0,
    mass=None,
) -> SlipPencil:
    """Condense ``K`` (or ``K(lam^2)``) onto the slip nodes of ``partition``.

    Parameters
    ----------
    stiffness
        Anything accepted by :func:`as_dynamic_stiffness` (DiscreteSystem, array (2N, 2N),
        callable, condensed FE model).
    partition : NodePartition
        Node states and slip directions; ``partition.n_nodes`` must be ``N``.
    friction_profile : array_like, shape (N,), optional
        Relative friction per node (default ones: uniform friction ``mu``).
    lam : float
        Growth rate (``>= 0``); ``K(s)`` is evaluated at ``s = lam^2``.
    mass : array_like, optional
        See :func:`as_dynamic_stiffness`.

    Returns
    -------
    SlipPencil
    """
    if not isinstance(partition, NodePartition):
        raise InputError(
            f"partition must be a NodePartition; got {type(partition).__name__} "
            "(use classify_nodes or NodePartition.from_states)"
        )
    try:
        lam = float(lam)
    except (TypeError, ValueError):
        raise InputError(f"lam must be a number >= 0; got {lam!r}") from None
    if not (np.isfinite(lam) and lam >= 0):
        raise InputError(f"lam must be finite and >= 0; got {lam}")
    if not np.isfinite(lam * lam):
        raise InputError(f"lam = {lam:g} is too large: lam^2 overflows")
    K = real_array("K(s)", as_dynamic_stiffness(stiffness, mass)(lam * lam))
    n = partition.n_nodes
    if K.shape != (2 * n, 2 * n):
        raise ShapeError(
            f"K must have shape (2N, 2N) = ({2 * n}, {2 * n}) for a partition of {n} nodes; "
            f"got {K.shape}"
        )
    # every source (array, system, callable, FE model) is checked at the s it is used at
    K = check_stiffness(f"K(s = {lam**2:g})", K, symmetry_rtol=SYMMETRY_RTOL)
    states = partition.states
    s = np.flatnonzero(states == SLIP)
    if s.size == 0:
        raise InputError("the partition has no slip node: nothing to condense (no MCEIP)")
    e = np.concatenate(
        [np.flatnonzero(states == FREE), np.flatnonzero(states == FREE) + n,
         np.flatnonzero(states == FRICTIONLESS)]
    )
    rows = np.concatenate([s, s + n])
    Kcs = K[np.ix_(rows, s)]
    if e.size:
        Kee = K[np.ix_(e, e)]
        try:
            cho = sla.cho_factor(Kee)
        except np.linalg.LinAlgError:
            raise InputError(
                "the free nodes' block of K is not positive definite: the partition leaves a "
                "rigid-body motion (e.g. every node free); check the node states"
            ) from None
        Kcs = Kcs - K[np.ix_(rows, e)] @ sla.cho_solve(cho, K[np.ix_(e, s)])
    m = s.size
    S_tt = 0.5 * (Kcs[:m] + Kcs[:m].T)
    S_nt = Kcs[m:]
    chi = partition.chi[s]
    if friction_profile is None:
        prof = np.ones(m)
    else:
        prof = real_array("friction_profile", friction_profile)
        if prof.ndim == 0:
            prof = np.full(n, float(prof))
        prof = check_node_vector("friction_profile", prof, n, nonneg=True,
                                 what="friction ratio")[s]
    K0 = chi[:, None] * S_tt * chi[None, :]
    K1 = prof[:, None] * S_nt * chi[None, :]
    for a in (K0, K1):
        a.setflags(write=False)
    return SlipPencil(K0, K1, s, chi, prof, float(lam))
