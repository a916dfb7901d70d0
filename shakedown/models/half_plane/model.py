"""Half-plane contact under force control as a :class:`shakedown.DiscreteSystem`.

Two elastic bodies (plane strain, each approximated as a half-plane near the contact; seed
``002`` s.4.2, MODEL.md s.6) are pressed together by ``P(t)`` and sheared by ``Q(t)``.  The
cell compliance ``F`` of :mod:`.influence` gives the mean slips and gaps of ``N`` cells::

    u = (v, w) = g~ + E z + F r,    E^T r = R = (Q, P)                          (3)

with ``r = (q, p)`` the cell forces (reactions on body 1, MODEL.md s.1), ``g~ = (0, g)`` the cell
means of the initial gap ``g(x)``, ``z = (s, -d)`` the rigid shift and approach and ``E`` the two
rigid-body modes (uniform slip, uniform gap).  ``Q = sum q_j`` is the tangential resultant of the
contact tractions *on body 1* (the load applied at body 1's distant boundary is ``-Q``);
``P = sum p_j`` is the normal resultant, compression positive.

Exact condensation of the rigid-body modes
------------------------------------------
Under force control ``z`` is unknown and the stiffness of all ``N`` cells is only positive
*semi*-definite (null space ``E``), which :class:`~shakedown.DiscreteSystem` refuses.  We take
one *reference cell* ``m`` (the cell at the minimum of ``g``, ``x = 0`` for the built-in
profiles) and measure every displacement from it: ``u'_j = u_j - u_m`` (``T^T u`` below).
``z`` drops out, and eliminating ``r_m = R - sum_{j != m} r_j`` (``r = T r' + e_m R``) gives, for the
other ``N - 1`` cells::

    u' = T^T g~ + T^T F e_m R + F' r',    F' = T^T F T   (symmetric positive definite)   (4)
    r' = r_w + K u',  K = F'^-1,  r_w = -K T^T (g~ + F e_m R(t))                       (5)

which is MODEL.md s.1 with ``u' = (v, w)`` and welded reactions linear in ``(Q(t), P(t))``.
(5) is exact, with no spring, *provided the reference cell sticks and stays closed*
(``u_m = 0`` then makes ``u'`` the true slips and gaps).  Its reactions follow from the
resultants, ``q_m = Q - sum q'_j``, ``p_m = P - sum p'_j`` (:meth:`HalfPlaneModel.reference_reactions`),
and :meth:`HalfPlaneModel.check_reference` verifies ``p_m > 0`` and ``|q_m| <= f p_m`` along a run.
For ``beta = 0``, ``|Q| < f P`` and a symmetric convex profile the Cattaneo-Mindlin /
Ciavarella-Jager stick zone is always a central interval, so the centre cell never slips;
for ``beta != 0`` the check is what guarantees exactness, and ``reference_x`` (or
:func:`shakedown.studies.half_plane.choose_reference`, which moves the reference to the cell
with the largest stick margin) keeps it satisfied up to ``beta ~ 0.1-0.2`` at ``f = 0.5``.  Why not a soft
spring: under force control the only stiffness against a rigid tangential shift is friction
itself, so any spring changes the resultant ``sum q = Q`` by ``k s``; the reference cell changes
nothing while it sticks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...model import DiscreteSystem, InputError, LoadCycle
from .influence import compliance

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)
PROFILES = ("hertz", "flat_rounded", "power", "samples")


def _positive(name, value):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number > 0, got {value!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise InputError(f"{name} must be > 0, got {value!r}")
    return v


def _modulus(name, value):
    """A Young's modulus ``> 0``; ``inf`` marks a rigid body."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number > 0 (inf: rigid), got {value!r}") from None
    if np.isnan(v) or v <= 0:
        raise InputError(f"{name} must be > 0 (inf: rigid), got {value!r}")
    return v


def rigid_indenter_materials(beta: float, youngs_modulus: float = 1.0):
    """``((E, nu), (inf, 0))``: an elastic body 1 on a rigid body 2 with Dundurs' ``beta``.

    ``beta = (1 - 2 nu) / (2 (1 - nu))`` for a rigid body 2, so ``nu = (1 - 2 beta)/(2 (1 - beta))``;
    ``0 <= beta < 0.5`` (``beta = 0``: incompressible body 1).
    """
    b = float(beta)
    if not 0.0 <= b < 0.5:
        raise InputError(f"beta must be in [0, 0.5) for a rigid body 2, got {beta!r}")
    return ((float(youngs_modulus), (1 - 2 * b) / (2 * (1 - b))), (np.inf, 0.0))


def _materials(materials):
    try:
        (E1, nu1), (E2, nu2) = materials
    except (TypeError, ValueError):
        raise InputError(
            f"materials must be ((E1, nu1), (E2, nu2)), got {materials!r}") from None
    E1 = _modulus("materials[0] Young's modulus E1", E1)
    E2 = _modulus("materials[1] Young's modulus E2", E2)
    if np.isinf(E1) and np.isinf(E2):
        raise InputError("materials: at most one body may be rigid (E = inf)")
    for name, nu in (("materials[0] Poisson ratio nu1", nu1), ("materials[1] Poisson ratio nu2", nu2)):
        if not (isinstance(nu, (int, float, np.floating)) and -1.0 < nu <= 0.5):
            raise InputError(f"{name} must be in (-1, 0.5], got {nu!r}")
    inv = (1 - nu1**2) / E1 + (1 - nu2**2) / E2
    k1 = (1 - 2 * nu1) * (1 + nu1) / (2 * E1)
    k2 = (1 - 2 * nu2) * (1 + nu2) / (2 * E2)
    return 1.0 / inv, (k1 - k2) / inv


def profile_function(profile: str, *, radius=None, flat_half_width=None, exponent=None,
                     gap_samples=None):
    """The initial gap ``g(x)`` [length] as a vectorised function, validated.

    ``"hertz"``: ``x^2 / (2 R)``; ``"flat_rounded"``: 0 for ``|x| <= b``, ``(|x| - b)^2 / (2 R)``
    beyond (``b = flat_half_width``); ``"power"``: ``|x|^n / (n R^(n-1))`` (``n = exponent``,
    ``= x^2/2R`` for ``n = 2``); ``"samples"``: ``gap_samples = (x, g)`` interpolated linearly.
    """
    if profile not in PROFILES:
        raise InputError(f"profile must be one of {PROFILES}, got {profile!r}")
    if profile == "samples":
        try:
            xs, gs = (np.asarray(a, float) for a in gap_samples)
        except (TypeError, ValueError):
            raise InputError(
                f"gap_samples must be (x, g), two 1-D arrays, got {gap_samples!r}") from None
        if xs.ndim != 1 or xs.shape != gs.shape or xs.size < 2 or np.any(np.diff(xs) <= 0):
            raise InputError("gap_samples must be (x, g) with x strictly increasing, same length >= 2")
        if not (np.all(np.isfinite(gs)) and np.all(np.isfinite(xs))):
            raise InputError("gap_samples must be finite")
        return lambda x: np.interp(x, xs, gs)
    R = _positive("radius", radius)
    if profile == "hertz":
        return lambda x: np.asarray(x) ** 2 / (2 * R)
    if profile == "flat_rounded":
        b = _positive("flat_half_width", flat_half_width)
        return lambda x: np.maximum(np.abs(x) - b, 0.0) ** 2 / (2 * R)
    n = _positive("exponent", exponent)
    if n < 1:
        raise InputError(f"exponent must be >= 1 (a convex profile), got {exponent!r}")
    return lambda x: np.abs(x) ** n / (n * R ** (n - 1))


@dataclass(frozen=True, eq=False)
class HalfPlaneModel:
    """A discretised half-plane contact; build with :func:`half_plane_model`.

    Attributes
    ----------
    system : DiscreteSystem
        The ``N - 1`` non-reference cells, left to right, eq. (5) of the module docstring.
    x : ndarray, shape (N - 1,)
        Centres of the system's nodes [length].
    x_cells : ndarray, shape (N,)
        Centres of all cells; ``reference`` is the index of the reference cell in it.
    h : float
        Cell width [length].
    e_star, beta : float
        Plane-strain contact modulus ``E*`` [force/length^2] and Dundurs' ``beta``.
    gap : ndarray, shape (N,)
        Cell means of the initial gap ``g`` [length].
    profile, radius : str, float or None
    """

    system: DiscreteSystem
    x: np.ndarray
    x_cells: np.ndarray
    reference: int
    h: float
    e_star: float
    beta: float
    gap: np.ndarray
    profile: str
    radius: float | None
    gap_function: object = field(repr=False)
    r_gap: np.ndarray = field(repr=False)       # welded reactions of g~, shape (2(N-1),)
    r_unit: np.ndarray = field(repr=False)      # welded reactions per unit (Q, P), (2(N-1), 2)

    @property
    def n_cells(self) -> int:
        return self.x_cells.size

    @property
    def friction(self) -> float:
        return float(self.system.friction[0])

    def welded(self, Q, P):
        """Welded reactions ``(q_w, p_w)`` for resultants ``Q``, ``P`` (scalars or shape (T,))."""
        Q = np.asarray(Q, float)[..., None]
        P = np.asarray(P, float)[..., None]
        r = self.r_gap + Q * self.r_unit[:, 0] + P * self.r_unit[:, 1]
        n = self.system.n_nodes
        return r[..., :n], r[..., n:]

    def load_cycle(self, P0, P1=0.0, Q1=0.0, phase=0.0) -> LoadCycle:
        """``P(t) = P0 + lam P1 cos(2 pi t + phase)``, ``Q(t) = lam Q1 cos(2 pi t)``.

        Parameters
        ----------
        P0 : float
            Mean normal load, ``> 0`` [force per unit thickness].
        P1, Q1 : float
            Amplitudes of the normal and tangential loads [force per unit thickness].
        phase : float
            Phase of ``P`` ahead of ``Q`` [rad].
        """
        P0 = _positive("P0", P0)
        vals = {}
        for name, v in (("P1", P1), ("Q1", Q1), ("phase", phase)):
            try:
                vals[name] = float(v)
            except (TypeError, ValueError):
                raise InputError(f"{name} must be a number, got {v!r}") from None
            if not np.isfinite(vals[name]):
                raise InputError(f"{name} must be finite, got {v!r}")
        P1, Q1, ph = vals["P1"], vals["Q1"], vals["phase"]
        q0, p0 = self.welded(0.0, P0)
        uq, up = self.welded(1.0, 0.0)
        uq, up = uq - self.welded(0.0, 0.0)[0], up - self.welded(0.0, 0.0)[1]
        vq, vp = self.welded(0.0, 1.0)
        vq, vp = vq - self.welded(0.0, 0.0)[0], vp - self.welded(0.0, 0.0)[1]
        return LoadCycle.from_harmonics(
            q0, p0,
            q_cos=Q1 * uq + P1 * np.cos(ph) * vq, q_sin=-P1 * np.sin(ph) * vq,
            p_cos=Q1 * up + P1 * np.cos(ph) * vp, p_sin=-P1 * np.sin(ph) * vp)

    def load_from_samples(self, P0, P1_samples, Q1_samples) -> LoadCycle:
        """``P = P0 + lam P1(t)``, ``Q = lam Q1(t)`` from samples at ``t = k / S`` (linear between)."""
        P0 = _positive("P0", P0)
        P1 = np.asarray(P1_samples, float)
        Q1 = np.asarray(Q1_samples, float)
        if P1.ndim != 1 or P1.shape != Q1.shape or P1.size < 2:
            raise InputError("P1_samples and Q1_samples must be 1-D, same length >= 2")
        q0, p0 = self.welded(0.0, P0)
        qa, pa = self.welded(Q1, P1)
        qz, pz = self.welded(0.0, 0.0)
        return LoadCycle.from_samples(q0, p0, qa - qz, pa - pz)

    def reference_reactions(self, q, p, Q, P):
        """Reactions of the reference cell, ``(Q - sum q, P - sum p)`` (shapes (..., N-1) -> (...))."""
        return np.asarray(Q) - np.sum(q, axis=-1), np.asarray(P) - np.sum(p, axis=-1)

    def full(self, values, ref_value=0.0):
        """Insert ``ref_value`` at the reference cell: shape (..., N-1) -> (..., N)."""
        return np.insert(np.asarray(values, float), self.reference, ref_value, axis=-1)

    def check_reference(self, table, P_of_t, Q_of_t, rtol: float = 1e-9):
        """Is the reference cell stuck and closed along a run (eq. (5) exact)?

        ``table`` is a ``steady_table`` / ``history`` of :func:`shakedown.solve_cycles`;
        ``P_of_t``, ``Q_of_t`` give the resultants at its times.  Returns ``(ok, worst)`` with
        ``worst = max_t (|q_m| - f p_m) / P_scale`` (``<= rtol`` means inside the cone).
        """
        g = table.groupby("t")
        t = np.array(sorted(g.groups))
        qs = g["q"].sum().loc[t].to_numpy()
        ps = g["p"].sum().loc[t].to_numpy()
        Q, P = np.asarray(Q_of_t(t), float), np.asarray(P_of_t(t), float)
        qm, pm = Q - qs, P - ps
        scale = max(np.max(np.abs(P)), np.finfo(float).tiny)
        worst = float(np.max((np.abs(qm) - self.friction * pm) / scale))
        ok = bool(worst <= rtol and np.all(pm > -rtol * scale))
        return ok, worst


def half_plane_model(profile: str = "hertz", *, radius=None, n_nodes: int = 101, width=None,
                     friction=0.5, materials=((1.0, 0.3), (1.0, 0.3)), flat_half_width=None,
                     exponent=None, gap_samples=None, reference_x=None) -> HalfPlaneModel:
    """Discretise a 2-D half-plane contact into a :class:`shakedown.DiscreteSystem`.

    Parameters
    ----------
    profile : {"hertz", "flat_rounded", "power", "samples"}
        Initial gap ``g(x)``, see :func:`profile_function`.
    radius : float
        Relative radius of curvature ``R`` [length] (``1/R = 1/R1 + 1/R2``).
    n_nodes : int
        Number of cells ``N`` (odd, >= 3); the system has ``N - 1`` nodes (one is the reference).
    width : float
        Width of the window ``[-width/2, width/2]`` [length]; must contain the largest contact.
    friction : float
        Coulomb coefficient ``f >= 0``.
    materials : ((E1, nu1), (E2, nu2))
        Young's moduli [force/length^2] and Poisson ratios; body 1 (``y > 0``) carries ``q``.
    flat_half_width, exponent, gap_samples
        Profile parameters (see :func:`profile_function`).
    reference_x : float, optional
        Put the reference cell (stuck and closed by construction) at the cell nearest this
        position [length]; default: the minimum of ``g`` nearest ``x = 0``.

    Examples
    --------
    >>> import shakedown as sd
    >>> m = sd.half_plane_model(radius=1.0, n_nodes=21, width=0.2, friction=0.5)
    >>> m.system.n_nodes, m.system.is_coupled
    (20, False)
    """
    gfun = profile_function(profile, radius=radius, flat_half_width=flat_half_width,
                            exponent=exponent, gap_samples=gap_samples)
    if isinstance(n_nodes, bool) or not isinstance(n_nodes, (int, np.integer)) or n_nodes < 3 \
            or n_nodes % 2 == 0:
        raise InputError(f"n_nodes must be an odd integer >= 3, got {n_nodes!r}")
    width = _positive("width", width)
    try:
        f = float(friction)
    except (TypeError, ValueError):
        raise InputError(f"friction must be a number >= 0, got {friction!r}") from None
    if not np.isfinite(f) or f < 0:
        raise InputError(f"friction must be >= 0, got {friction!r}")
    e_star, beta = _materials(materials)
    N = int(n_nodes)
    h = width / N
    xc = -width / 2 + h * (np.arange(N) + 0.5)
    gap = 0.5 * (gfun(xc[:, None] + 0.5 * h * _GAUSS_X[None, :]) @ _GAUSS_W)  # cell means
    if not np.all(np.isfinite(gap)):
        raise InputError("the gap profile must be finite on the window")
    best = np.flatnonzero(gap <= gap.min() + 1e-12 * max(abs(gap).max(), 1e-300))
    m = int(best[np.argmin(np.abs(xc[best]))])
    if reference_x is not None:
        try:
            m = int(np.argmin(np.abs(xc - float(reference_x))))
        except (TypeError, ValueError):
            raise InputError(f"reference_x must be a number, got {reference_x!r}") from None
    F = compliance(N, h, e_star, beta)
    keep = np.delete(np.arange(N), m)
    T1 = np.zeros((N, N - 1))
    T1[keep, np.arange(N - 1)] = 1.0
    T1[m, :] = -1.0
    T = np.block([[T1, np.zeros_like(T1)], [np.zeros_like(T1), T1]])  # r = T r' + e_m R
    Fp = T.T @ F @ T
    Fp = 0.5 * (Fp + Fp.T)
    K = np.linalg.inv(Fp)
    K = 0.5 * (K + K.T)
    n = N - 1
    gt = np.concatenate([np.zeros(N), gap])
    em = np.zeros((2 * N, 2))
    em[m, 0] = em[N + m, 1] = 1.0
    r_gap = -K @ (T.T @ gt)
    r_unit = -K @ (T.T @ (F @ em))
    system = DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], f)
    return HalfPlaneModel(system=system, x=xc[keep], x_cells=xc, reference=m, h=h,
                          e_star=e_star, beta=beta, gap=gap, profile=profile,
                          radius=None if radius is None else float(radius), gap_function=gfun,
                          r_gap=r_gap, r_unit=r_unit)
