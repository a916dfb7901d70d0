"""Higher-fidelity model: a displacement-discontinuity boundary-element method (Galerkin).

Kachanov's model gives every crack the elliptical discontinuity of a uniformly loaded isolated
crack and equates only line *averages* of the interaction stresses.  This model refines both:

* Discretisation.  On crack ``i`` each discontinuity component (opening, slip) is expanded in
  ``n_modes`` square-root-weighted Chebyshev modes, ``sum_k x_ik D_k(s)`` with
  ``D_k(s) = 2 (1 - nu) a / (mu (k + 1)) sqrt(1 - s^2/a^2) U_k(s/a)`` (:mod:`.fields`): a
  displacement-discontinuity (DD) boundary element with the exact square-root tip behaviour
  and spectral (rather than constant-element) resolution along the crack.  Mode ``k`` loads its
  own faces with exactly ``-U_k``, so the isolated crack is diagonal in this basis, and its
  field everywhere is closed form.
* Equations.  Galerkin: the traction condition on each crack is tested with the modes'
  weights ``sqrt(1 - s^2/a^2) U_l(s/a)``, ``l < n_modes``.  Integrals along the other cracks
  use Gauss-Chebyshev (second kind) quadrature with ``n_q`` points per (target, source) pair,
  ``n_q`` growing like ``10 a_i / d_ij`` for close pairs (``d_ij`` the segment distance), so
  nearly touching cracks keep the quadrature error ~``exp(-2 n_q d / a) < 1e-8``.  The
  continuous Galerkin matrix is symmetric (reciprocity); ``n_modes = 1`` gives the
  elliptic-weighted Kachanov model.
* Condensation to one node per crack.  The crack faces carry *uniform* reactions
  ``(p_i, q_i)`` (what the discrete system models: the seed's single-crack argument); the
  higher modes of each crack are free.  The mean discontinuity is the mode-0 coefficient times
  ``c_i``, so with ``H`` the normalised Galerkin matrix (``-I`` on the self blocks) and
  ``P`` the selection of the mode-0 rows,

      b = -C P H^-1 P^T (Delta R / 2a),    K = -diag(2a) (P H^-1 P^T)^-1 diag(1/c)

  (``Delta R`` = reactions minus welded reactions, ``C = diag(c)``).  This ``K`` is the Schur
  complement of the Galerkin matrix onto the mean-discontinuity unknowns: the exact (as
  ``n_modes -> inf``) stiffness of the one-node-per-crack system that Kachanov approximates.
  For ``n_modes = 1`` it reduces to :func:`crack_networks.kachanov.stiffness_from_factors`.

Convergence is spectral in ``n_modes`` for separated cracks and slower (rate ``~ (1 +
sqrt(2 d / a))^-n``) for nearly touching ones; ``tests/test_bem.py`` checks it against the
exact two-collinear-crack solution (:func:`collinear_exact_amplification`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import ellipe, ellipk

from shakedown.model.errors import InputError

from .cracks import CrackSet
from .fields import mode_stress_local
from .model import CrackNetworkModel, _check_cracks, _check_material

__all__ = [
    "BEMModel",
    "bem_model",
    "collinear_exact_amplification",
    "elliptic_transmission_factors",
    "galerkin_matrix",
]

#: Quadrature points per unit of ``a_i / d_ij`` (segment distance) for close pairs.
QUAD_PER_RATIO = 10.0
#: Largest number of quadrature points per pair.
QUAD_MAX = 2048


def collinear_exact_amplification(gap_over_a):
    """Exact mean-opening amplification of two equal collinear cracks under remote tension.

    Cracks ``b < |x| < c`` (half-length ``a = (c - b)/2``, tip gap ``g = 2b``).  With the
    Westergaard function ``Z = s (z^2 - d^2) / sqrt((z^2 - b^2)(z^2 - c^2))`` and
    ``d^2 = c^2 E(k) / K(k)``, ``k^2 = 1 - b^2/c^2`` (single-valued displacements), the mean
    opening is ``(2 (1 - nu) s / mu) (pi / 2) ((b^2 + c^2)/2 - d^2) / (c - b)`` and, divided by
    the isolated crack's ``pi a (1 - nu) s / (2 mu)``,

        amplification = 4 ((b^2 + c^2)/2 - c^2 E(k)/K(k)) / (c - b)^2.

    (Equal by symmetry for the mean slip under remote shear.)  Tends to 1 as ``g -> inf`` and
    to 2 as ``g -> 0`` (one crack of twice the length).  Cancellation limits the accuracy to
    ~``1e-16 g^2`` (use gaps below ``1e4``).
    """
    g = np.asarray(gap_over_a, dtype=float)
    b = g / 2.0
    c = b + 2.0
    m = 1.0 - (b / c) ** 2  # parameter k^2 (scipy convention)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(m < 1.0, ellipe(m) / ellipk(m), 0.0)
    return 4.0 * ((b**2 + c**2) / 2.0 - c**2 * ratio) / (c - b) ** 2


def _chebyshev_u(s, n):
    """``U_0 .. U_{n-1}`` at ``s`` (shape S) -> shape S + (n,)."""
    out = np.empty(np.shape(s) + (n,))
    out[..., 0] = 1.0
    if n > 1:
        out[..., 1] = 2.0 * s
    for k in range(2, n):
        out[..., k] = 2.0 * s * out[..., k - 1] - out[..., k - 2]
    return out


def _quad_points(pairs_ratio, n_modes, quad_factor):
    """Quadrature size per pair: a power of two >= n_modes + 4 and >= factor * a_i / d_ij."""
    need = np.maximum(n_modes + 4, quad_factor * QUAD_PER_RATIO * pairs_ratio)
    need = np.minimum(need, QUAD_MAX)
    return (2 ** np.ceil(np.log2(need))).astype(int)


def galerkin_matrix(cracks: CrackSet, n_modes: int, *, quad_factor: float = 1.0,
                    chunk_points: int = 400_000):
    """Normalised Galerkin matrix ``H`` of the DD model, shape (2 m N, 2 m N).

    Row ``(i, l, r)`` / column ``(j, k, d)`` (index ``(i m + l) 2 + r``): the ``U_l``-weighted
    average, ``(2/pi) int sqrt(1-s^2) U_l(s) sigma_r ds``, over crack ``i``'s line of the
    normal (``r = 0``) or shear (``r = 1``) stress caused by unit mode ``k`` of component ``d``
    on crack ``j``.  Self blocks are ``-I`` (exact).
    """
    n = cracks.n_cracks
    m = int(n_modes)
    H = np.zeros((n, m, 2, n, m, 2))
    idx = np.arange(n)
    for r in range(2):
        H[idx, :, r, idx, :, r] = -np.eye(m)
    if n == 1:
        return H.reshape(2 * m * n, 2 * m * n)
    c, a, al = cracks.centres, cracks.half_lengths, cracks.angles
    D = cracks.distances()
    I, J = np.nonzero(~np.eye(n, dtype=bool))
    with np.errstate(divide="ignore"):
        ratio = a[I] / D[I, J]
    ratio = np.maximum(ratio, 2.0 * m * a[I] / a[J] / QUAD_PER_RATIO)
    nq = _quad_points(ratio, m, quad_factor)
    for q in np.unique(nq):
        sel = np.flatnonzero(nq == q)
        theta = np.arange(1, q + 1) * np.pi / (q + 1)
        s = np.cos(theta)
        wq = (2.0 / (q + 1)) * np.sin(theta) ** 2  # (2/pi) * Gauss-Chebyshev-2 weights
        WU = wq[:, None] * _chebyshev_u(s, m)  # (q, m_l)
        step = max(1, chunk_points // (q * m))
        for p0 in range(0, sel.size, step):
            ps = sel[p0 : p0 + step]
            i, j = I[ps], J[ps]
            beta = al[i] - al[j]  # target line angle in the source frame
            zc = (c[i, 0] - c[j, 0]) + 1j * (c[i, 1] - c[j, 1])
            zc = zc * np.exp(-1j * al[j])
            zeta = (zc[:, None] + a[i, None] * s[None, :] * np.exp(1j * beta)[:, None]) / a[
                j, None
            ]
            with np.errstate(all="ignore"):
                st = mode_stress_local(zeta, m)  # (P, q, m_k, 2_d, 3) source frame
            cb, sb = np.cos(beta)[:, None, None, None], np.sin(beta)[:, None, None, None]
            xx, xy, yy = st[..., 0], st[..., 1], st[..., 2]
            # n_i = (-sin b, cos b), t_i = (cos b, sin b) in the source frame
            snx, sny = -sb * xx + cb * xy, -sb * xy + cb * yy  # sigma . n_i
            trac = np.stack([-sb * snx + cb * sny, cb * snx + sb * sny], axis=-1)  # (P,q,k,d,r)
            # (P, k, d, r, q) @ (q, l) -> (P, k, d, r, l) -> (P, l, r, k, d)
            prod = np.moveaxis(trac, 1, -1) @ WU
            H[i, :, :, j, :, :] = prod.transpose(0, 4, 3, 1, 2)
    return H.reshape(2 * m * n, 2 * m * n)


def elliptic_transmission_factors(cracks: CrackSet, *, quad_factor: float = 1.0) -> np.ndarray:
    """Transmission factors averaged with the elliptical weight ``sqrt(1 - s^2/a^2)``.

    Same layout as :func:`crack_networks.transmission_factors`; reciprocal:
    ``a_i^2 Lam_ij = a_j^2 Lam_ji^T`` up to the quadrature error.
    """
    cracks = _check_cracks(cracks)
    n = cracks.n_cracks
    H = galerkin_matrix(cracks, 1, quad_factor=quad_factor).reshape(n, 2, n, 2)
    Lam = H.transpose(0, 2, 1, 3).copy()
    idx = np.arange(n)
    Lam[idx, idx] = 0.0
    return Lam


@dataclass(frozen=True, eq=False)
class BEMModel(CrackNetworkModel):
    """Galerkin DD model condensed to one node per crack (see the module docstring).

    Attributes (in addition to :class:`~crack_networks.kachanov.CrackNetworkModel`)
    ----------------------------------------------------------------------------------
    n_modes : int
        Chebyshev modes per crack and component.
    quad_factor : float
        Multiplier of the quadrature sizes.
    n_unknowns : int
        ``2 n_modes N``.
    """

    n_modes: int = 16
    quad_factor: float = 1.0
    n_unknowns: int = field(default=0)


def bem_model(
    cracks: CrackSet,
    shear_modulus: float = 1.0,
    poisson_ratio: float = 0.25,
    friction=0.6,
    *,
    n_modes: int = 16,
    quad_factor: float = 1.0,
    symmetric: bool = True,
    validate: bool = True,
) -> BEMModel:
    """The higher-fidelity discrete model of a crack network.

    Parameters
    ----------
    cracks, shear_modulus, poisson_ratio, friction, symmetric, validate
        As in :func:`crack_networks.kachanov_model`.
    n_modes : int
        Chebyshev modes per crack and component (``>= 1``; 1 = elliptic Kachanov).
    quad_factor : float
        Multiplies every pair's quadrature size (``> 0``; use 2 to check convergence).

    Returns
    -------
    BEMModel
        Same interface as :class:`~crack_networks.KachanovModel` (``.system``,
        ``.load_cycle``, ``.stiffness_raw``, ``.asymmetry``, ...).

    Examples
    --------
    >>> import crack_networks as cn
    >>> cs = cn.CrackSet([[0.0, 0.0], [2.5, 0.0]], [1.0, 1.0], [0.0, 0.0])
    >>> m = cn.bem_model(cs, n_modes=8)
    >>> m.stiffness_raw.shape
    (4, 4)
    """
    cracks = _check_cracks(cracks)
    mu, nu = _check_material(shear_modulus, poisson_ratio)
    if isinstance(n_modes, bool) or int(n_modes) != n_modes or n_modes < 1:
        raise InputError(f"n_modes must be an integer >= 1; got {n_modes!r}")
    if not (np.isfinite(quad_factor) and quad_factor > 0):
        raise InputError(f"quad_factor must be a finite number > 0; got {quad_factor!r}")
    n, m = cracks.n_cracks, int(n_modes)
    H = galerkin_matrix(cracks, m, quad_factor=quad_factor)
    # mode-0 rows/columns: index (i m + 0) 2 + r
    sel = ((np.arange(n)[:, None] * m) * 2 + np.arange(2)[None, :]).reshape(-1)
    E = np.zeros((H.shape[0], 2 * n))
    E[sel, np.arange(2 * n)] = 1.0
    X = np.linalg.solve(H, E)[sel]  # P H^-1 P^T, (2N, 2N)
    a = np.repeat(cracks.half_lengths, 2)
    c = np.pi * a * (1.0 - nu) / (2.0 * mu)
    K = -(2.0 * a)[:, None] * np.linalg.inv(X) / c[None, :]
    K.setflags(write=False)
    model = BEMModel(
        cracks=cracks, shear_modulus=mu, poisson_ratio=nu, friction=friction,
        symmetric=bool(symmetric), stiffness_raw=K, n_modes=m, quad_factor=float(quad_factor),
        n_unknowns=H.shape[0],
    )
    if validate:
        model.system  # noqa: B018
    return model
