"""A 3-D shakedown problem in cone units, nondimensional (MODEL.md s.8.3).

Node ``i`` is safe at time ``t`` when ``|W_i (q_w,i(t) + (A v)_i)| <= p_w,i(t) + (B^T v)_i``
with ``W_i = diag(1 / f_x,i, 1 / f_y,i)`` (isotropic: ``|q| <= f p``; elliptic cones alike).
With the slip state written through ``s = A v`` (``A`` is positive definite, so ``s`` is free)
and ``u = W s / F`` the constraint of node ``i`` reads, in units of the force scale ``F``,

    | a0_i + u_i + lam a1_i(t) |  <=  b0_i + (E u)_i + lam b1_i(t),   E = B^T A^-1 diag(f) ,

where ``a0 = W q0 / F``, ``b0 = p0 / F`` and ``a1``, ``b1`` the periodic parts scaled by the
load-factor scale ``L`` (``lam = L lam_hat``).  Only ``E`` couples the nodes (``E = 0`` when
``B = 0``: every node is then its own problem).  Everything the cone engine solves is in these
units, so its tolerances are relative to the problem's own scales and its answers do not depend
on the unit system.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...model.errors import InputError, ShapeError


@dataclass(frozen=True)
class ConeData:
    """Nondimensional data of the 3-D safe region (module docstring).

    Attributes
    ----------
    a0 : ndarray, shape (N, 2)
        ``W q0 / F`` [-].
    b0 : ndarray, shape (N,)
        ``p0 / F`` [-].
    kind : {"harmonic", "samples"}
    ac, as_ : ndarray, shape (H, N, 2)
        Cosine / sine coefficients of ``a1`` (harmonic ``k`` has frequency ``k + 1``).
    bc, bs : ndarray, shape (H, N)
        Same for ``b1``.
    a1s, b1s : ndarray, shape (S, N, 2), (S, N)
        Samples of ``a1``, ``b1`` at ``t = k / S`` (``kind == "samples"``).
    E : ndarray, shape (N, 2N), or None
        ``B^T A^-1 diag(f)`` (``None`` for an uncoupled system).
    weights : ndarray, shape (N, 2)
        ``W = 1 / friction_xy`` [-].
    force : float
        ``F`` [force].
    load_factor : float
        ``L`` [-].
    """

    a0: np.ndarray
    b0: np.ndarray
    kind: str
    ac: np.ndarray
    as_: np.ndarray
    bc: np.ndarray
    bs: np.ndarray
    a1s: np.ndarray
    b1s: np.ndarray
    E: np.ndarray | None
    weights: np.ndarray
    force: float
    load_factor: float

    @property
    def n_nodes(self) -> int:
        return self.a0.shape[0]

    @property
    def coupled(self) -> bool:
        return self.E is not None

    def periodic(self, t, nodes=None):
        """``(a1, b1)`` at times ``t`` (cycles) for ``nodes`` (all by default).

        ``t`` has shape ``(M,)`` with ``nodes`` of shape ``(M,)`` (one time per entry), or any
        shape without ``nodes`` (every node at every time: ``t.shape + (N, 2)``, ``+ (N,)``).
        """
        t = np.asarray(t, float)
        if self.kind == "samples":
            S = self.b1s.shape[0]
            x = np.mod(t, 1.0) * S
            i0 = np.floor(x).astype(int) % S
            fr = x - np.floor(x)
            i1 = (i0 + 1) % S
            if nodes is None:
                fa = fr[..., None, None]
                return ((1 - fa) * self.a1s[i0] + fa * self.a1s[i1],
                        (1 - fr[..., None]) * self.b1s[i0] + fr[..., None] * self.b1s[i1])
            return ((1 - fr[:, None]) * self.a1s[i0, nodes] + fr[:, None] * self.a1s[i1, nodes],
                    (1 - fr) * self.b1s[i0, nodes] + fr * self.b1s[i1, nodes])
        k = np.arange(1, self.ac.shape[0] + 1)
        ang = 2 * np.pi * t[..., None] * k
        c, s = np.cos(ang), np.sin(ang)
        if nodes is None:
            a = np.einsum("...h,hnc->...nc", c, self.ac) + np.einsum("...h,hnc->...nc", s, self.as_)
            return a, c @ self.bc + s @ self.bs
        a = np.einsum("mh,hmc->mc", c, self.ac[:, nodes]) + np.einsum("mh,hmc->mc", s,
                                                                       self.as_[:, nodes])
        b = np.einsum("mh,hm->m", c, self.bc[:, nodes]) + np.einsum("mh,hm->m", s,
                                                                     self.bs[:, nodes])
        return a, b

    @cached_property
    def coupling_bound(self) -> float:
        """A proven upper bound of ``||E||_2`` (0 when uncoupled; computed once): the a-priori
        bound on the state in :mod:`.dual`."""
        from .dual import coupling_norm

        return coupling_norm(self.E)

    def coupling(self, u) -> np.ndarray:
        """``E u``, shape (N,) (zeros for an uncoupled system)."""
        if self.E is None:
            return np.zeros(self.n_nodes)
        return self.E @ np.asarray(u, float).reshape(-1)

    def slip(self, u, system) -> np.ndarray:
        """The slip state ``v = A^-1 s``, ``s = F u / W``, shape (2N,) [length]."""
        s = (self.force * np.asarray(u, float).reshape(-1, 2) / self.weights).reshape(-1)
        return _solve_A(system.A, s[:, None])[:, 0]

    def reduced(self, system, v) -> np.ndarray:
        """``u = W (A v) / F`` of a slip state ``v`` (2N,), shape (N, 2)."""
        s = np.asarray(system.A @ np.asarray(v, float)).reshape(-1, 2)
        return s * self.weights / self.force


def _solve_A(A, rhs):
    if sp.issparse(A):
        return spla.splu(sp.csc_matrix(A)).solve(np.asarray(rhs, float))
    return sla.cho_solve(sla.cho_factor(np.asarray(A, float)), np.asarray(rhs, float))


def check_pair_3d(system, load):
    """The system and load of a 3-D analysis: shapes, dimensions, friction (``ShapeError`` /
    ``InputError`` naming the field and the fix)."""
    if getattr(system, "dim", 2) != 3:
        raise InputError(f"system.dim must be 3 for the cone engine; got {getattr(system, 'dim', 2)}")
    if getattr(load, "dim", 2) != 3:
        raise InputError(
            "load is two-dimensional (q0 of shape (N,)) but the system is three-dimensional: build "
            "the LoadCycle with q0 of shape (N, 2) (one tangential vector per node)")
    if load.n_nodes != system.n_nodes:
        raise ShapeError(f"load has {load.n_nodes} nodes but system has {system.n_nodes}; build "
                         "the LoadCycle with one entry per contact node")
    fxy = np.asarray(system.friction_xy, float)
    if np.any(fxy <= 0):
        j = int(np.argwhere(fxy <= 0)[0][0])
        raise InputError(
            f"friction_xy[{j}] = {fxy[j].tolist()}: the 3-D bounds need f > 0 at every node "
            "(a frictionless node carries no tangential reaction; remove it from the system "
            "by condensation or give it a positive friction coefficient)")


def cone_data(system, load) -> ConeData:
    """The nondimensional cone data of ``system`` (dim 3) under ``load`` (module docstring)."""
    check_pair_3d(system, load)
    n = system.n_nodes
    W = 1.0 / np.asarray(system.friction_xy, float)  # (N, 2)
    q0 = np.asarray(load.q0, float).reshape(n, 2)
    p0 = np.asarray(load.p0, float).reshape(n)
    if load.kind == "samples":
        q1 = np.asarray(load.q1, float) * W
        p1 = np.asarray(load.p1, float)
        periodic = [q1, p1]
    else:
        qc = np.asarray(load.q_cos, float) * W
        qs = np.asarray(load.q_sin, float) * W
        periodic = [qc, qs, np.asarray(load.p_cos, float), np.asarray(load.p_sin, float)]
    a0 = q0 * W
    F = max(float(np.abs(a0).max(initial=0.0)), float(np.abs(p0).max(initial=0.0)))
    amp = max(float(np.abs(x).max(initial=0.0)) for x in periodic)
    if F == 0.0:
        F = amp if amp > 0 else 1.0
    L = F / amp if amp > 0 else 1.0
    periodic = [x * (L / F) for x in periodic]
    B = system.B
    coupled = bool(system.is_coupled)
    E = None
    if coupled:
        Bd = B.toarray() if sp.issparse(B) else np.asarray(B, float)
        X = _solve_A(system.A, Bd)  # A^-1 B, (2N, N)
        E = np.ascontiguousarray(X.T * (1.0 / W).reshape(-1)[None, :])
    h = 1
    empty3, empty2 = np.zeros((0, n, 2)), np.zeros((0, n))
    if load.kind == "samples":
        return ConeData(a0 / F, p0 / F, "samples", np.zeros((h, n, 2)), np.zeros((h, n, 2)),
                        np.zeros((h, n)), np.zeros((h, n)), periodic[0], periodic[1], E, W,
                        float(F), float(L))
    return ConeData(a0 / F, p0 / F, "harmonic", *periodic, empty3, empty2, E, W, float(F),
                    float(L))
