"""Argument checks shared by the analyses (messages name the field, the value and the fix)."""

from __future__ import annotations

import numpy as np

from .errors import InputError, ShapeError
from .numbers import position


def check_same_nodes(system, load) -> None:
    """``load`` must have one entry per node of ``system``, in the same dimension."""
    if load.n_nodes != system.n_nodes:
        raise ShapeError(
            f"load has {load.n_nodes} nodes but the system has {system.n_nodes}; build the "
            "LoadCycle with arrays of shape (N,)"
        )
    check_same_dimension(system, load)


def check_same_dimension(system, load) -> None:
    """A 3-D system needs a 3-D load (``q0`` of shape (N, 2)) and a 2-D system a 2-D one."""
    sdim, ldim = getattr(system, "dim", 2), getattr(load, "dim", 2)
    if sdim != ldim:
        want = "(N, 2) (q_x, q_y per node)" if sdim == 3 else "(N,)"
        raise ShapeError(
            f"the system has dim = {sdim} but the load has dim = {ldim}: build the LoadCycle "
            f"with tangential arrays (q0, q_cos, ...) of shape {want}"
        )


def require_two_dimensional(system, what: str) -> None:
    """Refuse a 3-D system in an analysis that has no 3-D counterpart (yet)."""
    if getattr(system, "dim", 2) != 2:
        raise InputError(
            f"{what} is not available for dim = 3 systems (two tangential slips per node); "
            "it works on 2-D systems (dim = 2)"
        )


def check_load_factor(lam, load=None) -> float:
    """A finite load factor ``lam >= 0`` as a float.

    With ``load`` (a LoadCycle), the welded reactions ``r_0 + lam r_1`` must be representable:
    their bound ``max|r_0| + lam * max|r_1|`` must be finite (else the solvers would compute
    with inf and NaN).
    """
    if isinstance(lam, (bool, np.bool_, str, bytes)) or (
            isinstance(lam, np.ndarray) and lam.dtype.kind not in "iuf"):
        raise InputError(f"lam must be a number >= 0; got {type(lam).__name__} {lam!r} "
                         "(write it as a plain number, e.g. lam=0.5)")
    try:
        lam = float(lam)
    except OverflowError:
        raise InputError(f"lam must be a finite number >= 0; got an integer too large for a "
                         f"float ({str(lam)[:20]}...)") from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"lam must be a number >= 0; got {lam!r}") from exc
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam must be a finite number >= 0; got {lam}")
    if load is not None:
        parts = ([load.q_cos, load.q_sin, load.p_cos, load.p_sin] if load.kind == "harmonic"
                 else [load.q1, load.p1])
        r1 = sum(float(np.abs(a).max(initial=0.0)) for a in parts)
        r0 = max(float(np.abs(load.q0).max()), float(np.abs(load.p0).max()))
        with np.errstate(over="ignore"):
            if not np.isfinite(r0 + lam * r1):
                raise InputError(
                    f"lam = {lam:g} makes the welded reactions overflow (periodic part up to "
                    f"{r1:.3g} per unit lam); use a smaller lam or express forces in larger units"
                )
    return lam


def check_positive(name: str, value, *, unit: str = "") -> float:
    """``value`` as a finite float ``> 0`` (a length, a modulus, a density)."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise InputError(f"{name} must be a finite number > 0{unit}; got "
                         f"{type(value).__name__} {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{name} must be a finite number > 0{unit}; got {value!r}") from exc
    if not (np.isfinite(x) and x > 0):
        raise InputError(f"{name} must be a finite number > 0{unit}; got {x}")
    return x


#: Largest count (samples, steps per period, ...) accepted: 1e7 samples of one node already
#: take 80 MB; more is a typo (e.g. 1e300), not a resolution anyone needs.
MAX_COUNT = 10**7


def check_count(name: str, value, minimum: int, maximum: int = MAX_COUNT) -> int:
    """``value`` as an integer in ``[minimum, maximum]``; bools, NaN, fractions, text refused."""
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not ok and isinstance(value, (float, np.floating)) and np.isfinite(value):
        ok = float(value).is_integer() and abs(value) < 2.0**63
    if not ok or int(value) < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}; got {value!r}")
    if int(value) > maximum:
        raise InputError(f"{name} must be an integer <= {maximum:.0e}; got {value!r}")
    return int(value)


def check_node_vector(name: str, value, n: int, *, nonneg: bool = False,
                      what: str = "value") -> np.ndarray:
    """A finite array of shape ``(n,)`` (one ``what`` per node); ``nonneg`` forbids negatives."""
    try:
        x = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a real array of shape ({n},); got {value!r}") from exc
    if x.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},) (one {what} per node); got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be finite; got {x[~np.isfinite(x)][0]}")
    if nonneg and np.any(x < 0):
        j = int(np.argmax(x < 0))
        raise InputError(f"{name} must be >= 0 (nodes cannot penetrate); node {j + 1} has {x[j]}")
    return x


#: Largest accepted condition number of a stiffness ``K`` (LAPACK's 1-norm estimate from the
#: Cholesky factor).  A solve with ``K`` loses ``log10(cond)`` digits: at ``cond = 1e12`` about
#: ``cond * eps = 2e-4`` relative error is left, the size of the solvers' verification
#: tolerances relative to the load, so beyond it no answer could be certified.
MAX_CONDITION = 1e12


def real_array(name: str, value, *, what: str = "a real array", copy: bool = True) -> np.ndarray:
    """``value`` as a float array; complex, boolean-free object or text input is an error.

    ``copy=False``: a float ndarray is returned as it is (a view, for callers that only read).

    Complex input is refused rather than cast (numpy would drop the imaginary part with only
    a warning).
    """
    if isinstance(value, np.ndarray) and value.dtype.kind == "c" or (
        not isinstance(value, np.ndarray) and np.iscomplexobj(_peek(value))
    ):
        raise InputError(
            f"{name} must be {what}; got complex values (pass the real part explicitly, "
            "e.g. np.real(...), if the imaginary part is round-off)"
        )
    kind = _peek(value).dtype.kind if not isinstance(value, np.ndarray) else value.dtype.kind
    if kind in "bUSO" or isinstance(value, (str, bytes)):
        # True -> 1.0 and "0.5" -> 0.5 would convert silently; objects may be huge integers
        bad = _first_non_number(value)
        if bad is not None or kind in "bUS" or isinstance(value, (str, bytes)):
            shown = bad if bad is not None else value
            raise InputError(
                f"{name} must be {what} of numbers; got {type(shown).__name__} {_short(shown)} "
                "(booleans and text are not numbers: write the values as plain numbers)")
    try:
        return np.array(value, dtype=float) if copy else np.asarray(value, dtype=float)
    except OverflowError:
        raise InputError(f"{name} must be {what}; it holds an integer too large for a float "
                         "(more than 1.8e308): express it in larger units") from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be {what}; got {type(value).__name__}") from exc


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _first_non_number(value, depth: int = 0):
    """The first entry of nested lists/arrays that is not a real number (bools and text are
    not), or None."""
    if depth > 64:
        return value
    if isinstance(value, (bool, np.bool_, str, bytes)):
        return value
    if isinstance(value, (int, float, np.integer, np.floating)):
        return None
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        return None
    if isinstance(value, np.ndarray):
        value = [value.item()] if value.ndim == 0 else value.ravel()
    if isinstance(value, (list, tuple, np.ndarray)):
        for v in value:
            bad = _first_non_number(v, depth + 1)
            if bad is not None:
                return bad
        return None
    return value


def _peek(value):
    try:
        return np.asarray(value)
    except Exception:  # ragged lists etc.: the float conversion reports them
        return np.zeros(0)


def check_stiffness(name: str, K, *, symmetry_rtol: float = 1e-8,
                    max_condition: float = MAX_CONDITION) -> np.ndarray:
    """A finite, symmetric, positive definite, not numerically singular square matrix.

    Parameters
    ----------
    name : str
        How the message calls the matrix (e.g. ``"K"``).
    K : array_like, shape (m, m)
        Stiffness [force / length].
    symmetry_rtol : float
        ``max|K - K^T| <= symmetry_rtol * max|K|`` is accepted (then symmetrised).
    max_condition : float
        Largest accepted (estimated 1-norm) condition number.

    Returns
    -------
    ndarray
        The exactly symmetric matrix ``(K + K^T) / 2``.
    """
    from .errors import NotSymmetricError

    K = real_array(name, K)
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] == 0:
        raise ShapeError(f"{name} must be a non-empty square matrix; got shape {K.shape}")
    if not np.all(np.isfinite(K)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(K))[0])
        raise InputError(f"{name} must be finite; {name} {position(bad)} is {K[bad]}")
    scale = float(np.abs(K).max())
    asym = float(np.abs(K - K.T).max())
    if asym > symmetry_rtol * scale:
        i, j = np.unravel_index(np.argmax(np.abs(K - K.T)), K.shape)
        raise NotSymmetricError(
            f"{name} must be symmetric: {name} {position((i, j))} is {K[i, j]:.6g} but {name} "
            f"{position((j, i))} is {K[j, i]:.6g} (max asymmetry {asym:.3g} > {symmetry_rtol:g} * "
            f"max|{name}|); "
            "symmetrise it, e.g. (K + K.T) / 2"
        )
    K = 0.5 * (K + K.T)
    check_conditioning(name, K, max_condition=max_condition)
    return K


def check_conditioning(name: str, K: np.ndarray, *, max_condition: float = MAX_CONDITION):
    """Cholesky of the symmetric finite ``K``; positive definite and ``cond(K) <= max_condition``.

    The condition number is LAPACK's ``dpocon`` estimate (1-norm, O(m^2) from the factor).
    """
    import scipy.linalg as sla
    from scipy.linalg import lapack

    from .errors import NotPositiveDefiniteError

    try:
        R = sla.cholesky(K, lower=False, check_finite=False)  # K is checked finite above
    except np.linalg.LinAlgError:
        lam_min = float(np.linalg.eigvalsh(K)[0])
        raise NotPositiveDefiniteError(
            f"{name} must be positive definite; Cholesky failed (smallest eigenvalue "
            f"{lam_min:.6g}). A reduced stiffness of a body held against rigid-body motion is "
            "always SPD: check the signs and the condensation"
        ) from None
    anorm = float(np.abs(K).sum(axis=0).max())
    rcond, info = lapack.dpocon(R, anorm)
    if info != 0 or not rcond > 1.0 / max_condition:
        cond = 1.0 / rcond if rcond > 0 else float("inf")
        raise NotPositiveDefiniteError(
            f"{name} is numerically singular: condition number ~{cond:.3g} > {max_condition:.0e} "
            "(its smallest stiffness is below round-off of its largest); remove the "
            "rigid-body or zero-stiffness modes, or rescale the degrees of freedom"
        )
    return R
