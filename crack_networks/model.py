"""The model object shared by the Kachanov and BEM crack-network models: the
:class:`CrackNetworkModel` (stiffness, friction -> :class:`shakedown.DiscreteSystem`, far-field
loads -> :class:`shakedown.LoadCycle`), far-field tractions, and the input checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from shakedown.model.errors import InputError, NotPositiveDefiniteError
from shakedown.model.loading import LoadCycle
from shakedown.model.system import DiscreteSystem

from .cracks import CrackSet
from .fields import isolated_compliance

__all__ = ["Asymmetry", "CrackNetworkModel", "far_field_tractions"]

#: Default loads of seed 002 s.4.1 (MODEL.md s.7): ``S0 = p0 {-1, 0, -1}``, ``S1 = p0 {0, 1, 0}``
#: as ``(sxx, sxy, syy)`` with ``p0 = 1``.
SEED_STATIC = (-1.0, 0.0, -1.0)
SEED_CYCLIC = (0.0, 1.0, 0.0)

def _check_material(shear_modulus, poisson_ratio):
    mu = float(shear_modulus)
    nu = float(poisson_ratio)
    if not (np.isfinite(mu) and mu > 0):
        raise InputError(f"shear_modulus must be a finite number > 0; got {shear_modulus!r}")
    if not (np.isfinite(nu) and -1.0 < nu < 0.5):
        raise InputError(f"poisson_ratio must lie in (-1, 0.5); got {poisson_ratio!r}")
    return mu, nu


def _check_cracks(cracks):
    if not isinstance(cracks, CrackSet):
        raise InputError(
            f"cracks must be a crack_networks.CrackSet; got {type(cracks).__name__} "
            "(build one with CrackSet(centres, half_lengths, angles))"
        )
    return cracks


def far_field_tractions(cracks: CrackSet, stress) -> np.ndarray:
    """Resolved far-field stress ``(n.S.n, t.S.n)`` on every crack line.

    Parameters
    ----------
    stress : array_like, shape (..., 3)
        ``(sxx, sxy, syy)``, tension positive [stress].

    Returns
    -------
    ndarray, shape (..., N, 2)
    """
    S = np.asarray(stress, dtype=float)
    if S.shape[-1:] != (3,):
        raise InputError(f"stress must be (sxx, sxy, syy) with a last axis of 3; got {S.shape}")
    if not np.all(np.isfinite(S)):
        raise InputError(f"stress must be finite; got {S}")
    n, t = cracks.normals, cracks.tangents
    sxx, sxy, syy = (S[..., k, None] for k in range(3))
    Sn_x = sxx * n[:, 0] + sxy * n[:, 1]
    Sn_y = sxy * n[:, 0] + syy * n[:, 1]
    return np.stack([Sn_x * n[:, 0] + Sn_y * n[:, 1], Sn_x * t[:, 0] + Sn_y * t[:, 1]], axis=-1)


@dataclass(frozen=True)
class Asymmetry:
    """How far a crack-network ``K`` is from symmetric (before symmetrisation).

    Attributes
    ----------
    relative_norm : float
        ``||K - K^T||_F / ||K||_F``.
    max_pair : float
        ``max_{i != j} max|K_ij - K_ji^T| / k0`` (``k0`` the isolated-crack stiffness).
    worst_pair : tuple[int, int]
        The pair ``(i, j)`` attaining ``max_pair``.
    pair : ndarray, shape (N, N)
        Per pair, ``max|K_ij - K_ji^T| / max(max|K_ij|, max|K_ji|)`` (0 on the diagonal).
    """

    relative_norm: float
    max_pair: float
    worst_pair: tuple
    pair: np.ndarray = field(repr=False)


@dataclass(frozen=True, eq=False)
class CrackNetworkModel:
    """One node per crack: stiffness, welded reactions and the :class:`DiscreteSystem`.

    Attributes
    ----------
    cracks : CrackSet
    shear_modulus, poisson_ratio : float
        ``mu`` [stress], ``nu`` (plane strain).
    friction : float or ndarray, shape (N,)
    symmetric : bool
        Whether :attr:`system` uses ``(K + K^T) / 2`` (``True``) or requires ``K`` symmetric.
    stiffness_raw : ndarray or scipy.sparse.csr_matrix, shape (2N, 2N)
        ``K`` before symmetrisation, interleaved per crack as ``(opening, slip)`` columns and
        ``(P, Q)`` rows [force per unit thickness / length].  Sparse for a truncated
        interaction (``kachanov_model(..., interaction_radius=r)``): then :attr:`system` is a
        sparse :class:`~shakedown.DiscreteSystem` and nothing here densifies it.
    """

    cracks: CrackSet
    shear_modulus: float
    poisson_ratio: float
    friction: object
    symmetric: bool
    stiffness_raw: np.ndarray = field(repr=False)

    # ---------------------------------------------------------------- scalars
    @property
    def n_cracks(self) -> int:
        return self.cracks.n_cracks

    @property
    def self_stiffness(self) -> float:
        """``k0 = 4 mu / (pi (1 - nu))``, the isolated crack's stiffness [stress]."""
        return 4.0 * self.shear_modulus / (np.pi * (1.0 - self.poisson_ratio))

    @property
    def compliance(self) -> np.ndarray:
        """``c = pi a (1 - nu) / (2 mu)`` per crack, shape (N,)."""
        return isolated_compliance(self.cracks.half_lengths, self.shear_modulus, self.poisson_ratio)

    # ---------------------------------------------------------------- matrices
    @cached_property
    def stiffness(self) -> np.ndarray:
        """``K`` used by :attr:`system` (symmetrised when ``symmetric``), shape (2N, 2N)."""
        K = self.stiffness_raw
        K = 0.5 * (K + K.T) if self.symmetric else K.copy()
        if not sp.issparse(K):
            K.setflags(write=False)
        return K

    @property
    def is_sparse(self) -> bool:
        """``True`` when the stiffness is a ``scipy.sparse`` matrix (truncated interaction)."""
        return sp.issparse(self.stiffness_raw)

    def _sparse_blocks(self, K):
        """``(A, B, Bt, C)`` of a sparse interleaved ``K`` (CSR)."""
        n = self.n_cracks
        o, t = 2 * np.arange(n), 2 * np.arange(n) + 1  # opening / P, slip / Q
        K = sp.csr_matrix(K)
        Kt, Ko = K[t], K[o]
        return (Kt[:, t].tocsr(), Kt[:, o].tocsr(), Ko[:, t].tocsr(), Ko[:, o].tocsr())

    def blocks(self, symmetric: bool | None = None):
        """``(A, B, Bt, C)`` of ``K``: ``q = A v + B w``, ``p = Bt v + C w`` (+ welded).

        ``symmetric=None`` uses the model's choice; ``False`` returns the raw blocks (then
        ``Bt`` need not equal ``B.T``).
        """
        sym = self.symmetric if symmetric is None else symmetric
        K = self.stiffness_raw
        K = 0.5 * (K + K.T) if sym else K
        if sp.issparse(K):
            return self._sparse_blocks(K)
        n = self.n_cracks
        K4 = K.reshape(n, 2, n, 2)
        return (
            K4[:, 1, :, 1].copy(), K4[:, 1, :, 0].copy(), K4[:, 0, :, 1].copy(),
            K4[:, 0, :, 0].copy(),
        )

    @cached_property
    def asymmetry(self) -> Asymmetry:
        """:class:`Asymmetry` of :attr:`stiffness_raw`."""
        n = self.n_cracks
        K = self.stiffness_raw
        if sp.issparse(K):
            return self._sparse_asymmetry(K)
        D = K - K.T
        rel = float(np.linalg.norm(D) / np.linalg.norm(K))
        D4 = np.abs(D.reshape(n, 2, n, 2)).max(axis=(1, 3))
        M4 = np.abs(K.reshape(n, 2, n, 2)).max(axis=(1, 3))
        np.fill_diagonal(D4, 0.0)
        scale = np.maximum(M4, M4.T)
        with np.errstate(divide="ignore", invalid="ignore"):
            pair = np.where(scale > 0, D4 / scale, 0.0)
        np.fill_diagonal(pair, 0.0)
        k = int(np.argmax(D4))
        i, j = divmod(k, n)
        return Asymmetry(rel, float(D4[i, j] / self.self_stiffness), (i, j), pair)

    def _sparse_asymmetry(self, K) -> Asymmetry:
        """:class:`Asymmetry` of a sparse ``K`` (``pair`` is then a sparse (N, N) matrix)."""
        n = self.n_cracks
        D = (K - K.T).tocoo()
        rel = float(spla.norm(D) / spla.norm(K)) if D.nnz else 0.0

        def per_pair(M):  # max |entry| per crack pair, sparse (N, N)
            M = sp.coo_matrix(M)
            if not M.nnz:
                return sp.csr_matrix((n, n))
            keys = (M.row // 2).astype(np.int64) * n + M.col // 2
            order = np.argsort(keys, kind="stable")
            k, start = np.unique(keys[order], return_index=True)
            mx = np.maximum.reduceat(np.abs(M.data[order]), start)
            return sp.csr_matrix((mx, (k // n, k % n)), shape=(n, n))

        D4 = per_pair(D)
        D4.setdiag(0.0)
        D4.eliminate_zeros()
        if not D4.nnz:
            return Asymmetry(rel, 0.0, (0, 0), D4)
        M4 = per_pair(K)
        scale = M4.maximum(M4.T).tocsr()
        Dc = D4.tocoo()
        pair = sp.csr_matrix((Dc.data / np.asarray(scale[Dc.row, Dc.col]).ravel(),
                              (Dc.row, Dc.col)), shape=(n, n))
        k = int(np.argmax(Dc.data))
        i, j = int(Dc.row[k]), int(Dc.col[k])
        return Asymmetry(rel, float(Dc.data[k] / self.self_stiffness), (i, j), pair)

    @cached_property
    def min_eigenvalue(self) -> float:
        """Smallest eigenvalue of ``(K + K^T) / 2`` [stress]."""
        K = self.stiffness_raw
        if sp.issparse(K):
            Ks = sp.csr_matrix(0.5 * (K + K.T))
            if Ks.shape[0] <= 4:
                return float(np.linalg.eigvalsh(Ks.toarray())[0])
            return float(spla.eigsh(Ks, k=1, which="SA", return_eigenvectors=False)[0])
        return float(np.linalg.eigvalsh(0.5 * (K + K.T))[0])

    @cached_property
    def system(self) -> DiscreteSystem:
        """The :class:`shakedown.DiscreteSystem`, one node per crack in input order."""
        if not self.symmetric:
            asym = self.asymmetry.relative_norm
            if asym > 1e-8:
                raise InputError(
                    f"symmetric=False but K is not symmetric (relative asymmetry {asym:.3g}); "
                    "a DiscreteSystem needs a symmetric K. Use symmetric=True (the default), or "
                    "read the raw matrices from .stiffness_raw / .blocks(symmetric=False)"
                )
        # the blocks of blocks(symmetric=True), the same numbers, built one at a time from
        # the raw K (no symmetrised copy of all of K; DiscreteSystem copies them into its K)
        n = self.n_cracks

        def sym(P, Q):
            out = P + Q.T
            out *= 0.5
            return out

        try:
            if self.is_sparse:  # a sparse system: K is never densified
                A, B, _, C = self.blocks(symmetric=True)
                return DiscreteSystem(A, B, C, self.friction)
            K4 = self.stiffness_raw.reshape(n, 2, n, 2)
            return DiscreteSystem(sym(K4[:, 1, :, 1], K4[:, 1, :, 1]),
                                  sym(K4[:, 1, :, 0], K4[:, 0, :, 1]),
                                  sym(K4[:, 0, :, 0], K4[:, 0, :, 0]), self.friction)
        except NotPositiveDefiniteError:
            raise NotPositiveDefiniteError(
                f"the crack-network stiffness K is not positive definite (smallest eigenvalue "
                f"{self.min_eigenvalue:.4g}, isolated-crack stiffness {self.self_stiffness:.4g}): "
                f"the {self.n_cracks} cracks (closest pair {self.cracks.min_distance():.3g} "
                "apart) are too dense or too close for this interaction model. Increase "
                "min_spacing or lower the density, or use crack_networks.bem_model"
            ) from None

    # ---------------------------------------------------------------- loads
    def welded_reactions(self, stress):
        """Welded reactions ``(q_w, p_w)`` [force per unit thickness] for far-field stresses.

        Parameters
        ----------
        stress : array_like, shape (..., 3)
            ``(sxx, sxy, syy)``, tension positive.

        Returns
        -------
        q_w, p_w : ndarray, shape (..., N)
            ``q_w = -2a t.S.n``, ``p_w = -2a n.S.n`` (MODEL.md s.6, work-conjugate forces).
        """
        tr = far_field_tractions(self.cracks, stress)
        two_a = 2.0 * self.cracks.half_lengths
        return -two_a * tr[..., 1], -two_a * tr[..., 0]

    def load_cycle(self, static=SEED_STATIC, cyclic=SEED_CYCLIC) -> LoadCycle:
        """The :class:`shakedown.LoadCycle` of ``S(t) = static + lam * cyclic * cos(2 pi t)``.

        ``static``, ``cyclic``: far-field stresses ``(sxx, sxy, syy)`` (defaults: seed 002
        s.4.1 with ``p0 = 1``).
        """
        q0, p0 = self.welded_reactions(static)
        q1, p1 = self.welded_reactions(cyclic)
        return LoadCycle.from_harmonics(q0, p0, q_cos=q1, p_cos=p1)

    def load_from_samples(self, static, samples) -> LoadCycle:
        """A sampled far-field history: ``S(t_k) = static + lam * samples[k]``, ``t_k = k / S``."""
        q0, p0 = self.welded_reactions(static)
        q1, p1 = self.welded_reactions(np.asarray(samples, float))
        return LoadCycle.from_samples(q0, p0, q1, p1)

    def normalised_dissipation(self, W, p0: float = 1.0):
        """``W* = W mu / (4 (1 - nu) p0^2 abar^2)`` (MODEL.md s.7)."""
        abar = self.cracks.mean_half_length
        return np.asarray(W) * self.shear_modulus / (
            4.0 * (1.0 - self.poisson_ratio) * p0**2 * abar**2
        )

    def mean_discontinuities(self, stress) -> np.ndarray:
        """Mean (opening, slip) of traction-free cracks under a far-field stress, shape (N, 2).

        Solves ``K b = -r_w`` with the raw ``K`` (every crack open and frictionless).
        """
        q, p = self.welded_reactions(stress)
        r = np.stack([p, q], axis=-1).reshape(-1)
        K = self.stiffness_raw
        if sp.issparse(K):
            return spla.spsolve(sp.csc_matrix(K), -r).reshape(-1, 2)
        return np.linalg.solve(K, -r).reshape(-1, 2)
