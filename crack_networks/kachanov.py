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

import numpy as np

from shakedown.model import citations
from shakedown.model.errors import InputError

from .bem import elliptic_transmission_factors
from .cracks import CrackSet
from .fields import segment_average_traction
from .model import (
    Asymmetry,
    CrackNetworkModel,
    _check_cracks,
    _check_material,
    far_field_tractions,
)

__all__ = [
    "Asymmetry",
    "CrackNetworkModel",
    "KachanovModel",
    "far_field_tractions",
    "kachanov_model",
    "kachanov_stiffness",
    "transmission_factors",
]

_WEIGHTINGS = ("uniform", "elliptic")
#: Crack pairs per vectorised block of the closed-form averages.  A pair needs about 1 kB of
#: complex temporaries in :func:`.fields.segment_average_traction`, so a block's working memory
#: is about 32 MB whatever the number of cracks (the previous 2e5 pairs took ~200 MB).
BLOCK_PAIRS = 32_768


def _rows_per_block(n: int, chunk_size: int | None) -> int:
    return int(chunk_size) if chunk_size else max(1, BLOCK_PAIRS // max(n, 1))


def transmission_factors(cracks: CrackSet, *, chunk_size: int | None = None) -> np.ndarray:
    """Kachanov's transmission factors (uniform line averages), in closed form.

    Parameters
    ----------
    cracks : CrackSet
    chunk_size : int, optional
        Rows per vectorised block (default: :data:`BLOCK_PAIRS` pairs per block, so that the
        working memory beyond the (N, N, 2, 2) result is bounded for any N).

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
    rows = _rows_per_block(n, chunk_size)
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


def stiffness_from_factors(Lam, half_lengths, shear_modulus, poisson_ratio, *,
                           chunk_size: int | None = None) -> np.ndarray:
    """``K`` (2N, 2N) from transmission factors: ``K_ii = k0 I``, ``K_ij = -k0 a_i/a_j Lam_ij``.

    Written into the result block of rows by block of rows, with no (N, N, 2, 2) temporary.
    """
    n = Lam.shape[0]
    a = np.asarray(half_lengths, float)
    k0 = 4.0 * shear_modulus / (np.pi * (1.0 - poisson_ratio))
    K = np.empty((2 * n, 2 * n))
    K4 = K.reshape(n, 2, n, 2)  # a view: (i, r, j, d)
    rows = _rows_per_block(n, chunk_size)
    for i0 in range(0, n, rows):
        i1 = min(n, i0 + rows)
        blk = Lam[i0:i1].transpose(0, 2, 1, 3)  # (i, r, j, d)
        np.multiply(blk, (-k0 * (a[i0:i1, None] / a[None, :]))[:, None, :, None],
                    out=K4[i0:i1])  # the same products as before: bit-identical K
    idx = np.arange(n)
    K4[idx, :, idx, :] = k0 * np.eye(2)
    return K


def _near_pairs(cracks: CrackSet, radius: float):
    """Ordered pairs ``(i, j)``, ``i != j``, whose centres are closer than ``radius`` times
    ``a_i + a_j`` (a k-d tree: O(N log N + pairs))."""
    from scipy.spatial import cKDTree

    c, a = cracks.centres, cracks.half_lengths
    tree = cKDTree(c)
    pairs = tree.query_pairs(float(radius) * 2.0 * float(a.max()), output_type="ndarray")
    if pairs.size:
        d = np.linalg.norm(c[pairs[:, 0]] - c[pairs[:, 1]], axis=1)
        pairs = pairs[d < radius * (a[pairs[:, 0]] + a[pairs[:, 1]])]
    return np.concatenate([pairs, pairs[:, ::-1]]) if pairs.size else np.zeros((0, 2), int)


def kachanov_stiffness(cracks: CrackSet, shear_modulus: float = 1.0,
                       poisson_ratio: float = 0.25, *, interaction_radius: float | None = None,
                       chunk_size: int | None = None):
    """Kachanov's raw stiffness ``K`` (2N, 2N), full or truncated.

    Parameters
    ----------
    cracks : CrackSet
    shear_modulus : float
        ``mu`` [stress].
    poisson_ratio : float
    interaction_radius : float, optional
        Keep only the interactions of pairs whose centre distance is below
        ``interaction_radius * (a_i + a_j)`` (dimensionless; the transmission factors decay
        as ``(a / distance)^2``); the result is then a ``scipy.sparse.csr_matrix`` assembled
        pair by pair, in O(N + pairs) time and memory, never densified.  The error against
        the full matrix is measured in ``benchmarks/RESULTS_kachanov_assembly.md``.  Default:
        the full dense matrix, assembled in blocks of rows.
    chunk_size : int, optional
        Rows (dense) per block.

    Returns
    -------
    ndarray or scipy.sparse.csr_matrix, shape (2N, 2N)
        Rows and columns ordered ``(w_1, v_1, w_2, v_2, ...)`` as :func:`stiffness_from_factors`.
    """
    cracks = _check_cracks(cracks)
    mu, nu = _check_material(shear_modulus, poisson_ratio)
    if interaction_radius is None:
        return stiffness_from_factors(transmission_factors(cracks, chunk_size=chunk_size),
                                      cracks.half_lengths, mu, nu, chunk_size=chunk_size)
    r = float(interaction_radius)
    if not (np.isfinite(r) and r > 0):
        raise InputError(f"interaction_radius must be a positive number of crack lengths "
                         f"(e.g. 5); got {interaction_radius!r}")
    import scipy.sparse as sp

    n = cracks.n_cracks
    c, a, al = cracks.centres, cracks.half_lengths, cracks.angles
    k0 = 4.0 * mu / (np.pi * (1.0 - nu))
    pairs = _near_pairs(cracks, r)
    vals = np.empty((len(pairs), 2, 2))
    with np.errstate(all="ignore"):
        for p0 in range(0, len(pairs), BLOCK_PAIRS):
            i, j = pairs[p0:p0 + BLOCK_PAIRS, 0], pairs[p0:p0 + BLOCK_PAIRS, 1]
            vals[p0:p0 + BLOCK_PAIRS] = segment_average_traction(c[j], a[j], al[j], c[i], a[i],
                                                                 al[i])
    i, j = pairs[:, 0], pairs[:, 1]
    vals *= (-k0 * (a[i] / a[j]))[:, None, None]
    r_, d_ = np.meshgrid([0, 1], [0, 1], indexing="ij")
    rows = np.concatenate([(2 * i[:, None, None] + r_).ravel(), np.arange(2 * n)])
    cols = np.concatenate([(2 * j[:, None, None] + d_).ravel(), np.arange(2 * n)])
    data = np.concatenate([vals.ravel(), np.full(2 * n, k0)])
    return sp.csr_matrix((data, (rows, cols)), shape=(2 * n, 2 * n))


def kachanov_model(
    cracks: CrackSet,
    shear_modulus: float = 1.0,
    poisson_ratio: float = 0.25,
    friction=0.6,
    *,
    symmetric: bool = True,
    weighting: str = "uniform",
    validate: bool = True,
    interaction_radius: float | None = None,
    sparse: bool | None = None,
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
    interaction_radius : float, optional
        Truncate the interactions to pairs closer than ``interaction_radius * (a_i + a_j)``
        (:func:`kachanov_stiffness`; uniform weighting only).
        :attr:`KachanovModel.transmission_factors` is then None.
    sparse : bool, optional
        Keep the truncated ``K`` sparse (CSR): the model's :attr:`~CrackNetworkModel.system`
        is then a sparse :class:`shakedown.DiscreteSystem`, which the cyclic solver and the
        bounds use without densifying.  Default: ``True`` with ``interaction_radius``;
        ``False`` makes the truncated matrix dense (the full interaction is always dense).

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
    citations.register("kachanov1987")
    cracks = _check_cracks(cracks)
    mu, nu = _check_material(shear_modulus, poisson_ratio)
    if weighting not in _WEIGHTINGS:
        raise InputError(f"weighting must be one of {_WEIGHTINGS}; got {weighting!r}")
    if interaction_radius is not None:
        if weighting != "uniform":
            raise InputError("interaction_radius works with weighting='uniform' only; remove "
                             "one of them")
        Lam = None
        K = kachanov_stiffness(cracks, mu, nu, interaction_radius=interaction_radius)
        if sparse is False:
            K = K.toarray()
    else:
        if sparse:
            raise InputError("sparse=True needs interaction_radius (the full Kachanov "
                             "interaction is dense); pass e.g. interaction_radius=12")
        if weighting == "uniform":
            Lam = transmission_factors(cracks)
        else:
            Lam = elliptic_transmission_factors(cracks)
        K = stiffness_from_factors(Lam, cracks.half_lengths, mu, nu)
        Lam.setflags(write=False)
    if isinstance(K, np.ndarray):
        K.setflags(write=False)
    model = KachanovModel(
        cracks=cracks, shear_modulus=mu, poisson_ratio=nu, friction=friction,
        symmetric=bool(symmetric), stiffness_raw=K, transmission_factors=Lam,
        weighting=weighting,
    )
    if validate:
        model.system  # noqa: B018  (raises on indefinite K or bad friction)
    cracks.warn_if_close(stacklevel=3)  # Kachanov's error is large for close pairs
    return model
