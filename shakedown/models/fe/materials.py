"""Linear elastic materials for 2-D (plane strain / plane stress) and 3-D FE models.

The in-plane stiffness ``D`` maps the engineering strain ``(eps_xx, eps_yy, gamma_xy)``
(``gamma_xy = 2 eps_xy``) to the stress ``(sig_xx, sig_yy, sig_xy)``, i.e. Voigt order
``(xx, yy, xy)``.  A 3-D material (``plane="3d"``) has the full ``6 x 6`` stiffness in Voigt
order ``(xx, yy, zz, yz, xz, xy)`` with engineering shear strains.  In the notation of seed
``001`` (Agwa & Pinto da Costa 2007), ``D44 = C_xyxy = D[2, 2]`` and ``D24 = C_yyxy = D[1, 2]``
(y = contact normal; ``D[5, 5]`` and ``D[1, 5]`` of a 3-D material).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...model.errors import InputError

_PLANES = ("strain", "stress", "3d")
_VOIGT = {(0, 0): 0, (1, 1): 1, (0, 1): 2, (1, 0): 2}
_VOIGT3 = {(0, 0): 0, (1, 1): 1, (2, 2): 2, (1, 2): 3, (2, 1): 3, (0, 2): 4, (2, 0): 4,
           (0, 1): 5, (1, 0): 5}


@dataclass(frozen=True, eq=False)
class Material:
    """A homogeneous linear elastic material in 2-D or 3-D.

    Attributes
    ----------
    D : ndarray, shape (3, 3) or (6, 6)
        In-plane stiffness in Voigt order ``(xx, yy, xy)`` with engineering shear strain
        [stress] (2-D), or the 3-D stiffness in Voigt order ``(xx, yy, zz, yz, xz, xy)``
        (``plane="3d"``).  Symmetric positive definite.
    density : float
        Mass density [mass / volume]; used for the consistent mass matrix.
    plane : {"strain", "stress", "3d"}
    name : str
        ``"isotropic"`` or ``"transversely_isotropic"``.
    parameters : dict
        The constructor's arguments (used for the cache key and for reports).
    """

    D: np.ndarray
    density: float
    plane: str
    name: str
    parameters: dict = field(default_factory=dict)

    def __post_init__(self):
        D = np.array(self.D, dtype=float)
        size = 6 if self.plane == "3d" else 3
        if D.shape != (size, size) or not np.all(np.isfinite(D)):
            raise InputError(f"D must be a finite ({size}, {size}) array for plane = "
                             f"{self.plane!r}; got shape {D.shape}")
        if np.abs(D - D.T).max() > 1e-12 * np.abs(D).max():
            raise InputError("D must be symmetric")
        scale = np.abs(D).max()
        Dn = 0.5 * (D / scale + D.T / scale) if scale > 0 else D  # no overflow near 1e308
        if scale == 0 or np.linalg.eigvalsh(Dn)[0] <= 0:
            raise InputError(
                f"the in-plane stiffness D of the {self.name} material is not positive "
                f"definite (eigenvalues {scale * np.linalg.eigvalsh(Dn)}); check the elastic "
                "constants"
            )
        if not (np.isfinite(self.density) and self.density > 0):
            raise InputError(f"density must be > 0; got {self.density!r}")
        D = 0.5 * D + 0.5 * D.T
        D.setflags(write=False)
        object.__setattr__(self, "D", D)

    @property
    def dim(self) -> int:
        """Space dimension of the material: 3 for ``plane="3d"``, else 2."""
        return 3 if self.plane == "3d" else 2

    @property
    def D44(self) -> float:
        """``C_xyxy`` (shear stiffness in the x-y frame), seed 001 notation."""
        return float(self.D[5, 5] if self.dim == 3 else self.D[2, 2])

    @property
    def D24(self) -> float:
        """``C_yyxy`` (normal stress on y-faces per unit shear strain), seed 001 notation."""
        return float(self.D[1, 5] if self.dim == 3 else self.D[1, 2])

    def layer_critical_friction(self) -> float:
        """``D44 / |D24|``: critical friction of the infinite layer (seed 001, s.3).

        ``inf`` when ``D24 = 0`` (e.g. isotropic: never directionally unstable).
        """
        d24 = abs(self.D24)
        if d24 <= 1e-14 * np.abs(self.D).max():
            return float("inf")
        return self.D44 / d24

    def key(self) -> dict:
        """JSON-able description (cache key)."""
        return {
            "name": self.name,
            "plane": self.plane,
            "density": float(self.density),
            "D": [float(x) for x in self.D.ravel()],
        }

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v:g}" for k, v in self.parameters.items() if k != "plane")
        return f"Material({self.name}, plane {self.plane}, {args})"


def _check_plane(plane: str) -> str:
    if plane not in _PLANES:
        raise InputError(f"plane must be 'strain' or 'stress' (2-D) or '3d' (3-D bodies); got "
                         f"{plane!r}")
    return plane


def _positive(name: str, value) -> float:
    if isinstance(value, (str, bytes, bool, np.bool_)):  # "210e9" and True: not numbers
        raise InputError(f"{name} must be a number; got {type(value).__name__} {value!r} "
                         "(write it without quotes)")
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{name} must be a number; got {value!r}") from exc
    if not (np.isfinite(x) and x > 0):
        raise InputError(f"{name} must be > 0; got {value!r}")
    return x


def _in_plane(C6: np.ndarray, plane: str) -> np.ndarray:
    """3x3 in-plane stiffness (11, 22, 12) from the 6x6 Voigt stiffness (11,22,33,23,13,12);
    the 6x6 itself for ``plane="3d"``."""
    if plane == "3d":
        return C6
    idx = [0, 1, 5]
    if plane == "strain":
        return C6[np.ix_(idx, idx)]
    S6 = np.linalg.inv(C6)
    return np.linalg.inv(S6[np.ix_(idx, idx)])


def rotate_voigt(D: np.ndarray, theta: float) -> np.ndarray:
    """Stiffness of a material whose axes are turned by ``theta`` [rad] about z from x, y.

    ``D`` is given in the material axes ``(p1, p2[, e3])``; ``p1 = (cos theta, sin theta)``:
    in-plane ``(3, 3)`` (Voigt ``(xx, yy, xy)``) or 3-D ``(6, 6)`` (Voigt ``(xx, yy, zz, yz,
    xz, xy)``).  The fourth-order tensor is rotated, ``C'_ijkl = R_ia R_jb R_kc R_ld C_abcd``.
    """
    D = np.asarray(D, dtype=float)
    voigt, d = (_VOIGT, 2) if D.shape == (3, 3) else (_VOIGT3, 3)
    T = np.zeros((d,) * 4)
    for (i, j), a in voigt.items():
        for (k, l), b in voigt.items():
            T[i, j, k, l] = D[a, b]
    c, s = np.cos(theta), np.sin(theta)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])[:d, :d]
    T = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, T)
    pairs = [(0, 0), (1, 1), (0, 1)] if d == 2 else [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2),
                                                      (0, 1)]
    return np.array([[T[i, j, k, l] for (k, l) in pairs] for (i, j) in pairs])


def isotropic(E: float, nu: float, plane: str = "strain", density: float = 1.0) -> Material:
    """Isotropic material.

    Parameters
    ----------
    E : float
        Young's modulus [stress], ``> 0``.
    nu : float
        Poisson ratio, ``-1 < nu < 0.5``.
    plane : {"strain", "stress", "3d"}
        Plane strain or plane stress (2-D bodies), or ``"3d"`` for 3-D bodies (``6 x 6``).
    density : float
        Mass density [mass / volume].

    Examples
    --------
    >>> from shakedown import fe
    >>> mat = fe.isotropic(1.0, 0.3)
    >>> round(mat.D44, 6)   # shear modulus E / (2 (1 + nu))
    0.384615
    """
    E = _positive("E", E)
    plane = _check_plane(plane)
    try:
        if isinstance(nu, (str, bytes, bool, np.bool_)):
            raise TypeError(f"{type(nu).__name__}")
        nu = float(nu)
    except (TypeError, ValueError) as exc:
        raise InputError(f"nu must be a number; got {nu!r}") from exc
    if not (-1.0 < nu < 0.5):
        raise InputError(
            f"nu must satisfy -1 < nu < 0.5 (positive definite elasticity); got nu = {nu}"
        )
    if plane == "3d":
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        D = np.diag([2 * mu] * 3 + [mu] * 3)
        D[:3, :3] += lam
    elif plane == "strain":
        f = E / ((1 + nu) * (1 - 2 * nu))
        D = f * np.array([[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 * nu) / 2]])
    else:
        f = E / (1 - nu**2)
        D = f * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    return Material(
        D, _positive("density", density), plane, "isotropic",
        {"E": E, "nu": nu, "plane": plane, "density": float(density)},
    )


def transversely_isotropic(
    E1: float,
    E2: float,
    nu12: float,
    nu23: float,
    G12: float,
    theta: float,
    plane: str = "strain",
    density: float = 1.0,
) -> Material:
    """Transversely isotropic material with the stiff axis ``p1`` in the x-y plane (seed 001).

    The plane of isotropy is ``p2``-``e3`` (``E3 = E2``, ``nu13 = nu12``, ``G13 = G12``,
    ``G23 = E2 / (2 (1 + nu23))``); ``p1 = (cos theta, sin theta)``.

    Parameters
    ----------
    E1, E2 : float
        Young's moduli along ``p1`` and in the plane of isotropy [stress].
    nu12, nu23 : float
        Poisson ratios (``nu12``: contraction along ``p2`` for a pull along ``p1``).
    G12 : float
        Shear modulus in the ``p1``-``p2`` plane [stress].
    theta : float
        Angle of ``p1`` from the x axis [rad] (a rotation about z).
    plane : {"strain", "stress", "3d"}
    density : float

    Raises
    ------
    InputError
        If the 3-D compliance is not positive definite (inconsistent constants).

    Examples
    --------
    >>> import numpy as np
    >>> from shakedown import fe
    >>> m = fe.transversely_isotropic(8, 1, 0.4, 0.3, 0.1, np.deg2rad(80))
    >>> round(m.layer_critical_friction(), 7)   # seed 001: 0.2629238
    0.2629238
    """
    E1, E2, G12 = _positive("E1", E1), _positive("E2", E2), _positive("G12", G12)
    plane = _check_plane(plane)
    nu12, nu23, theta = float(nu12), float(nu23), float(theta)
    if not np.isfinite(theta):
        raise InputError(f"theta must be finite (radians); got {theta}")
    if not (-1.0 < nu23 < 1.0):
        raise InputError(f"nu23 must satisfy -1 < nu23 < 1 (G23 > 0); got {nu23}")
    S = np.zeros((6, 6))
    S[0, 0] = 1 / E1
    S[1, 1] = S[2, 2] = 1 / E2
    S[0, 1] = S[1, 0] = S[0, 2] = S[2, 0] = -nu12 / E1
    S[1, 2] = S[2, 1] = -nu23 / E2
    S[3, 3] = 2 * (1 + nu23) / E2
    S[4, 4] = S[5, 5] = 1 / G12
    ev = np.linalg.eigvalsh(S)
    if ev[0] <= 0:
        raise InputError(
            "the compliance of the transversely isotropic material is not positive definite "
            f"(smallest eigenvalue {ev[0]:.3g}) for E1={E1}, E2={E2}, nu12={nu12}, "
            f"nu23={nu23}: need |nu23| < 1 and nu12^2 < E1 (1 - nu23) / (2 E2)"
        )
    D = rotate_voigt(_in_plane(np.linalg.inv(S), plane), theta)
    params = {"E1": E1, "E2": E2, "nu12": nu12, "nu23": nu23, "G12": G12, "theta": theta,
              "plane": plane, "density": float(density)}
    return Material(D, _positive("density", density), plane, "transversely_isotropic", params)
