"""Kachanov's interaction model of a crack network as a :class:`shakedown.DiscreteSystem`.

Derivation (MODEL.md s.1 and s.6; M. Kachanov 1987, Int. J. Solids Struct. 23, 23-43)
-------------------------------------------------------------------------------------
Crack ``i`` (half-length ``a_i``, tangent ``t_i``, normal ``n_i``) is one node with gap
``w_i`` = mean opening ``n.[u]`` and slip ``v_i`` = mean ``t.[u]`` (``[u] = u(+) - u(-)``, the
``+`` face on the ``n`` side).  The reactions on the ``+`` face, per unit thickness, are
``P_i = 2 a_i p_i`` and ``Q_i = 2 a_i q_i`` with the face tractions ``p = -n.sigma.n``
(compression positive) and ``q = -t.sigma.n``; these forces and the mean discontinuities are
work-conjugate (a uniform traction ``p`` works ``p * 2a * mean(n.[u])``).

1. Superposition.  The stress is the far field ``S`` (cracks welded) plus the perturbation of
   every crack's displacement discontinuity.  Kachanov's approximation: each crack opens and
   slips with the *elliptical* profile of a uniformly loaded isolated crack, so crack ``j`` is
   described by its uniform "load" ``s_j = (s_n, s_t)``, the remote stress that would produce
   its discontinuity; its mean discontinuity is ``b_j = (w_j, v_j) = c_j s_j`` with
   ``c_j = pi a_j (1 - nu) / (2 mu)`` (plane strain).
2. Its perturbation field is, on its own faces, the uniform stress ``-s_j``; on the line of
   crack ``i`` it averages to ``Lambda_ij s_j`` (the transmission factors, :mod:`.fields`, in
   closed form).  Averaged over the line of crack ``i`` the normal and shear stress are

       (sigma_nn, sigma_tn)_i = S_i - s_i + sum_{j != i} Lambda_ij s_j,
       S_i = (n_i.S.n_i, t_i.S.n_i).

3. The face tractions are the reactions with the opposite sign, ``(p, q)_i = -(sigma_nn,
   sigma_tn)_i``; with ``(p_w, q_w)_i = -S_i`` (the welded reactions, MODEL.md s.6) and
   ``s_j = b_j / c_j``:

       (p, q)_i = (p_w, q_w)_i + b_i / c_i - sum_{j != i} Lambda_ij b_j / c_j.

4. Multiplying by ``2 a_i`` gives forces.  With the 2 x 2 block ``K_ij`` mapping
   ``(w_j, v_j)`` to ``(P_i, Q_i)``:

       K_ii = k0 I,     K_ij = -k0 (a_i / a_j) Lambda_ij,     k0 = 2 a / c = 4 mu / (pi (1 - nu)),

   and, in MODEL.md's blocks, ``A = K[Q, v]``, ``B = K[Q, w]``, ``B^T = K[P, v]``,
   ``C = K[P, w]``.  The self stiffness ``k0`` does not depend on the length (force per unit
   thickness over mean discontinuity).  Signs: opening a crack (``w_j > 0``) pushes its
   neighbours' faces together where its perturbation field is compressive (``Lambda < 0``) and
   so raises their ``p``; e.g. two collinear cracks have ``Lambda^nn > 0`` (tension ahead of the
   tips) and ``C_12 < 0``.  The BEM model (:mod:`.bem`) checks every sign independently.

Why symmetrise by default
-------------------------
Elasticity is reciprocal: weighting the line averages with the elliptical profile gives
``a_i^2 Lambda_ij = a_j^2 Lambda_ji^T`` exactly and a symmetric ``K`` (the ``"elliptic"``
weighting below, the one-mode Galerkin method).  Kachanov's *uniform* averages break this
slightly (:attr:`KachanovModel.asymmetry` reports by how much).  A :class:`shakedown.DiscreteSystem`
needs a symmetric positive definite ``K`` (energies, the LCP's well-posedness, the hyperplane
theory), so the default system uses ``(K + K^T) / 2``, the energy-consistent part; the raw
matrices stay available (:attr:`KachanovModel.stiffness_raw`, :meth:`KachanovModel.blocks`).
Very dense or nearly touching sets can make the symmetrised ``K`` indefinite (Kachanov's
approximation then fails); :attr:`KachanovModel.system` raises
:class:`shakedown.NotPositiveDefiniteError` saying so.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from shakedown.errors import InputError, NotPositiveDefiniteError
from shakedown.loading import LoadCycle
from shakedown.system import DiscreteSystem

from .cracks import CrackSet
from .fields import isolated_compliance, segment_average_traction

__all__ = [
    "Asymmetry",
    "CrackNetworkModel",
    "KachanovModel",
    "far_field_tractions",
    "kachanov_model",
    "transmission_factors",
]

#: Default loads of seed 002 s.4.1 (MODEL.md s.7): ``S0 = p0 {-1, 0, -1}``, ``S1 = p0 {0, 1, 0}``
#: as ``(sxx, sxy, syy)`` with ``p0 = 1``.
SEED_STATIC = (-1.0, 0.0, -1.0)
SEED_CYCLIC = (0.0, 1.0, 0.0)

_WEIGHTINGS = ("uniform", "elliptic")


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


def transmission_factors(cracks: CrackSet, *, chunk_size: int | None = None) -> np.ndarray:
    """Kachanov's transmission factors (uniform line averages), in closed form.

    Parameters
    ----------
    cracks : CrackSet
    chunk_size : int, optional
        Target rows per vectorised block (default keeps blocks near 2e5 pairs).

    Returns
    -------
    ndarray, shape (N, N, 2, 2)
        ``[i, j, r, d]``: average over crack ``i``'s line of its normal (``r = 0``,
        ``n_i.S.n_i``) or shear (``r = 1``, ``t_i.S.n_i``) stress caused by a unit uniform face
        traction of component ``d`` (0 normal, 1 shear; Kachanov's sense, see :mod:`.fields`)
        on crack ``j``; zero for ``i == j``.  Dimensionless.
    """
    cracks = _check_cracks(cracks)
    n = cracks.n_cracks
    c, a, al = cracks.centres, cracks.half_lengths, cracks.angles
    rows = chunk_size or max(1, 200_000 // n)
    out = np.zeros((n, n, 2, 2))
    with np.errstate(all="ignore"):
        for i0 in range(0, n, rows):
            sl = slice(i0, min(n, i0 + rows))
            out[sl] = segment_average_traction(
                c[None, :], a[None, :], al[None, :], c[sl, None], a[sl, None], al[sl, None]
            )
    idx = np.arange(n)
    out[idx, idx] = 0.0
    return out


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
    stiffness_raw : ndarray, shape (2N, 2N)
        ``K`` before symmetrisation, interleaved per crack as ``(opening, slip)`` columns and
        ``(P, Q)`` rows [force per unit thickness / length].
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
        K.setflags(write=False)
        return K

    def blocks(self, symmetric: bool | None = None):
        """``(A, B, Bt, C)`` of ``K``: ``q = A v + B w``, ``p = Bt v + C w`` (+ welded).

        ``symmetric=None`` uses the model's choice; ``False`` returns the raw blocks (then
        ``Bt`` need not equal ``B.T``).
        """
        sym = self.symmetric if symmetric is None else symmetric
        K = self.stiffness_raw
        K = 0.5 * (K + K.T) if sym else K
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

    @cached_property
    def min_eigenvalue(self) -> float:
        """Smallest eigenvalue of ``(K + K^T) / 2`` [stress]."""
        K = self.stiffness_raw
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
        A, B, _, C = self.blocks(symmetric=True)
        try:
            return DiscreteSystem(A, B, C, self.friction)
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
        return np.linalg.solve(self.stiffness_raw, -r).reshape(-1, 2)


@dataclass(frozen=True, eq=False)
class KachanovModel(CrackNetworkModel):
    """Kachanov's one-node-per-crack model (see the module docstring for the derivation).

    Attributes (in addition to :class:`CrackNetworkModel`)
    -------------------------------------------------------
    transmission_factors : ndarray, shape (N, N, 2, 2)
        As returned by :func:`transmission_factors` (or the elliptic-weighted averages).
    weighting : str
        ``"uniform"`` (Kachanov) or ``"elliptic"`` (reciprocal, one-mode Galerkin).
    """

    transmission_factors: np.ndarray = field(default=None, repr=False)
    weighting: str = "uniform"


def stiffness_from_factors(Lam, half_lengths, shear_modulus, poisson_ratio) -> np.ndarray:
    """``K`` (2N, 2N) from transmission factors: ``K_ii = k0 I``, ``K_ij = -k0 a_i/a_j Lam_ij``."""
    n = Lam.shape[0]
    a = np.asarray(half_lengths, float)
    k0 = 4.0 * shear_modulus / (np.pi * (1.0 - poisson_ratio))
    K4 = -k0 * (a[:, None] / a[None, :])[:, :, None, None] * Lam  # (i, j, r, d)
    idx = np.arange(n)
    K4[idx, idx] = k0 * np.eye(2)
    return np.ascontiguousarray(K4.transpose(0, 2, 1, 3)).reshape(2 * n, 2 * n)


def kachanov_model(
    cracks: CrackSet,
    shear_modulus: float = 1.0,
    poisson_ratio: float = 0.25,
    friction=0.6,
    *,
    symmetric: bool = True,
    weighting: str = "uniform",
    validate: bool = True,
) -> KachanovModel:
    """Build Kachanov's discrete model of a crack network.

    Parameters
    ----------
    cracks : CrackSet
    shear_modulus : float
        ``mu`` [stress].
    poisson_ratio : float
        ``nu`` (plane strain), in ``(-1, 0.5)``.
    friction : float or array_like, shape (N,)
        Coulomb coefficient per crack.
    symmetric : bool
        Use ``(K + K^T) / 2`` in :attr:`~CrackNetworkModel.system` (default, see the module
        docstring).  With ``False`` the system is only available when ``K`` is symmetric.
    weighting : {"uniform", "elliptic"}
        Line averages of Kachanov (1987) (closed form) or weighted by the elliptical opening
        profile (reciprocal: ``K`` symmetric up to quadrature error; Gauss-Chebyshev quadrature,
        see :mod:`.bem`).
    validate : bool
        Build :attr:`~CrackNetworkModel.system` now, so that an indefinite ``K`` or bad
        friction raises here.

    Returns
    -------
    KachanovModel

    Examples
    --------
    >>> import crack_networks as cn
    >>> cs = cn.CrackSet([[0.0, 0.0], [3.0, 0.0]], [1.0, 1.0], [0.0, 0.0])
    >>> m = cn.kachanov_model(cs)
    >>> m.transmission_factors.shape
    (2, 2, 2, 2)
    """
    cracks = _check_cracks(cracks)
    mu, nu = _check_material(shear_modulus, poisson_ratio)
    if weighting not in _WEIGHTINGS:
        raise InputError(f"weighting must be one of {_WEIGHTINGS}; got {weighting!r}")
    if weighting == "uniform":
        Lam = transmission_factors(cracks)
    else:
        from .bem import elliptic_transmission_factors

        Lam = elliptic_transmission_factors(cracks)
    K = stiffness_from_factors(Lam, cracks.half_lengths, mu, nu)
    K.setflags(write=False)
    Lam.setflags(write=False)
    model = KachanovModel(
        cracks=cracks, shear_modulus=mu, poisson_ratio=nu, friction=friction,
        symmetric=bool(symmetric), stiffness_raw=K, transmission_factors=Lam,
        weighting=weighting,
    )
    if validate:
        model.system  # noqa: B018  (raises on indefinite K or bad friction)
    return model
