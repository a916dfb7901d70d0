"""Discrete frictional systems: ``q = q_w + A v + B w``, ``p = p_w + B^T v + C w`` (MODEL.md s.1).

``K = [[A, B], [B^T, C]]`` is the reduced (condensed) stiffness in work-conjugate units:
force (per unit thickness) over displacement.  ``v`` is the slip and ``w >= 0`` the gap of
each of the ``N`` contact nodes; ``q``, ``p`` the tangential and normal reactions
(compression positive).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from . import citations
from . import sparse as _sparse
from .errors import InputError, NotSymmetricError, ShapeError
from .numbers import position
from .validation import MAX_CONDITION, check_conditioning, real_array

#: Relative tolerance of the symmetry check ``max|K - K^T| <= SYMMETRY_RTOL * max|K|``.
#: FE condensation in double precision reaches ~1e-13; 1e-8 leaves room for matrices read
#: from text files with 10 significant digits.
SYMMETRY_RTOL = 1e-8

#: Relative tolerance of ``is_coupled``: ``B`` counts as zero when
#: ``max|B| <= COUPLING_RTOL * max(|A|, |C|)``.
COUPLING_RTOL = 1e-12

#: Largest ``N`` for which ``critical_friction`` enumerates every principal minor.
EXACT_CRITICAL_FRICTION_MAX_NODES = 4


def _as_matrix(name: str, value, n: int | None = None) -> np.ndarray:
    arr = real_array(name, value, what="a real 2-D array", copy=False)  # only read: K is new
    if arr.ndim == 0 and n is None:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise ShapeError(f"{name} must be a square 2-D array (N, N); got shape {arr.shape}")
    if arr.shape[0] == 0:
        raise ShapeError(
            f"{name} has shape {arr.shape}: a system needs at least one contact node (N >= 1)"
        )
    if n is not None and arr.shape != (n, n):
        raise ShapeError(f"{name} must have shape ({n}, {n}) to match A; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InputError(
            f"{name} must be finite; {name} {position(tuple(bad))} is {arr[tuple(bad)]}"
        )
    return arr


def _as_friction(value, n: int) -> np.ndarray:
    kind = np.asarray(value).dtype.kind if not isinstance(value, (str, bytes)) else "U"
    if kind in "bUS" or ((kind == "O" or isinstance(value, (list, tuple)))
                         and not _all_numbers(value)):
        # "0.7" and True would convert silently to 0.7 and 1.0 (issue 9)
        raise InputError(
            f"friction must be a number >= 0 or one number per node (shape ({n},)); got "
            f"{value!r} ({type(value).__name__}): write it as a plain number, e.g. friction=0.7"
        )
    f = real_array("friction", value, what=f"a number or an array of shape ({n},)")
    if f.ndim == 0:
        f = np.full(n, float(f))
    if f.shape != (n,):
        raise ShapeError(f"friction must be a scalar or have shape ({n},); got shape {f.shape}")
    if not np.all(np.isfinite(f)):
        raise InputError(f"friction must be finite; got {f[~np.isfinite(f)][0]}")
    if np.any(f < 0):
        j = int(np.argmax(f < 0))
        raise InputError(f"friction must be >= 0; node {j + 1} has friction {f[j]}")
    f.setflags(write=False)
    return f


def _all_numbers(value) -> bool:
    """Every leaf of ``value`` is a real number (not a bool or a string)."""
    flat = np.asarray(value, dtype=object).ravel()
    return all(isinstance(x, (int, float, np.integer, np.floating))
               and not isinstance(x, (bool, np.bool_)) for x in flat)


@dataclass(frozen=True)
class CriticalFriction:
    """Critical friction of the incremental problem (Klarbring's P-matrix criterion).

    Attributes
    ----------
    factor : float
        Critical multiplier ``alpha_c`` of the friction *profile*: the incremental problem has a
        unique solution for every load increment when the friction is ``alpha * friction`` with
        ``alpha < alpha_c``.  For a uniform friction this is ``f_c / f``.  ``inf`` when no
        friction level can make the problem ill-posed (e.g. ``B = 0``).
    value : float
        ``alpha_c * max(friction)``: the critical value expressed as a friction coefficient
        (exact for uniform friction).
    exact : bool
        ``True`` when ``factor`` is the exact critical multiplier (single node, uncoupled
        system, or full enumeration of principal minors); ``False`` when it is only a
        *sufficient* bound (below it uniqueness is guaranteed; the true value may be larger).
    upper_bound : float
        A necessary bound on ``factor`` from the 2 x 2 single-node minors (the true critical
        factor is at most this).
    method : str
        ``"uncoupled"``, ``"enumeration"``, ``"single-node"`` or ``"sufficient-bound"``.
    well_posed : bool
        ``factor > 1``: the system's actual friction is below critical.
    """

    factor: float
    value: float
    exact: bool
    upper_bound: float
    method: str
    well_posed: bool

    def __str__(self) -> str:
        kind = "exact" if self.exact else "sufficient bound"
        return (
            f"critical friction factor {self.factor:.6g} ({kind}, {self.method}); "
            f"necessary upper bound {self.upper_bound:.6g}; "
            f"{'well-posed' if self.well_posed else 'NOT well-posed'} at the given friction"
        )


@dataclass(frozen=True, eq=False)
class DiscreteSystem:
    """A linear elastic system with ``N`` frictional contact nodes (MODEL.md s.1).

    Parameters
    ----------
    A, B, C : array_like, shape (N, N)
        Blocks of the reduced stiffness ``K = [[A, B], [B^T, C]]`` [force / length].
        ``A`` maps slip to tangential reaction, ``C`` gap to normal reaction, ``B`` couples
        gap to tangential reaction (and, transposed, slip to normal reaction).
    friction : float or array_like, shape (N,)
        Coulomb friction coefficient of each node (dimensionless, ``>= 0``).
    symmetry_rtol : float, optional
        Relative tolerance of the symmetry check of ``A`` and ``C``.

    Raises
    ------
    ShapeError, InputError, NotSymmetricError, NotPositiveDefiniteError
        With a message naming the field, the offending value and the fix.

    Examples
    --------
    >>> import shakedown as sd
    >>> s = sd.DiscreteSystem([[2.0]], [[0.5]], [[3.0]], friction=0.4)
    >>> s.n_nodes, s.is_coupled
    (1, True)
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    friction: np.ndarray
    symmetry_rtol: float = field(default=SYMMETRY_RTOL, repr=False)

    def __post_init__(self):
        rtol = self.symmetry_rtol
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating)) \
                or not 0 <= rtol < 1:
            raise InputError(f"symmetry_rtol must be a number in [0, 1); got {rtol!r}")
        if any(sp.issparse(M) for M in (self.A, self.B, self.C)):
            self._init_sparse()
            return
        A = _as_matrix("A", self.A)
        n = A.shape[0]
        B = _as_matrix("B", self.B, n)
        C = _as_matrix("C", self.C, n)
        f = _as_friction(self.friction, n)
        scale = max(np.abs(A).max(), np.abs(C).max(), np.abs(B).max(), np.finfo(float).tiny)
        for name, M in (("A", A), ("C", C)):
            asym = np.abs(M - M.T).max()
            if asym > self.symmetry_rtol * scale:
                i, j = np.unravel_index(np.argmax(np.abs(M - M.T)), M.shape)
                raise NotSymmetricError(
                    f"K must be symmetric: {name} {position((i, j))} is {M[i, j]:.6g} but "
                    f"{name} {position((j, i))} is {M[j, i]:.6g} (max asymmetry {asym:.3g} > "
                    f"{self.symmetry_rtol:g} * max|K| = {self.symmetry_rtol * scale:.3g}); "
                    "symmetrise it, e.g. (M + M.T) / 2, or pass a larger symmetry_rtol"
                )
        # one exactly symmetric K (downstream factorizations see symmetric data); A, B, C are
        # views of its blocks, so the system holds 4 N^2 numbers, not 7 N^2
        K = np.empty((2 * n, 2 * n))
        np.add(A, A.T, out=K[:n, :n])
        np.add(C, C.T, out=K[n:, n:])
        K[:n, :n] *= 0.5
        K[n:, n:] *= 0.5
        K[:n, n:] = B
        K[n:, :n] = B.T
        del A, B, C
        # positive definite and not numerically singular (cond <= MAX_CONDITION)
        check_conditioning("K = [[A, B], [B^T, C]]", K)
        K.setflags(write=False)
        self.__dict__["K"] = K  # the cached_property's value
        object.__setattr__(self, "A", K[:n, :n])
        object.__setattr__(self, "B", K[:n, n:])
        object.__setattr__(self, "C", K[n:, n:])
        object.__setattr__(self, "friction", f)

    def _init_sparse(self):
        """Sparse blocks: one symmetric CSR ``K``, checked without densifying
        (:mod:`.sparse`); ``A``, ``B``, ``C`` are CSR copies of its blocks."""
        A = _sparse.sparse_matrix("A", self.A)
        n = A.shape[0]
        B = _sparse.sparse_matrix("B", self.B, n)
        C = _sparse.sparse_matrix("C", self.C, n)
        f = _as_friction(self.friction, n)
        scale = max(_sparse.abs_max(A), _sparse.abs_max(B), _sparse.abs_max(C),
                    np.finfo(float).tiny)
        for name, M in (("A", A), ("C", C)):
            _sparse.check_symmetric(name, M, self.symmetry_rtol, scale)
        K = sp.bmat([[0.5 * (A + A.T), B], [B.T, 0.5 * (C + C.T)]], format="csr")
        K.eliminate_zeros()
        K.sort_indices()
        del A, B, C
        _sparse.check_sparse_conditioning("K = [[A, B], [B^T, C]]", K,
                                          max_condition=MAX_CONDITION)
        self.__dict__["K"] = K  # (no factor kept: a system is pickled to worker processes)
        object.__setattr__(self, "A", K[:n, :n].tocsr())
        object.__setattr__(self, "B", K[:n, n:].tocsr())
        object.__setattr__(self, "C", K[n:, n:].tocsr())
        object.__setattr__(self, "friction", f)

    # ------------------------------------------------------------------ properties
    @property
    def is_sparse(self) -> bool:
        """``True`` when ``K`` (and ``A``, ``B``, ``C``) are ``scipy.sparse`` CSR matrices."""
        return sp.issparse(self.__dict__.get("K", self.A))

    @property
    def nnz(self) -> int:
        """Stored entries of ``K`` (``(2N)^2`` for a dense system)."""
        K = self.K
        return int(K.nnz) if sp.issparse(K) else int(K.size)

    def diagonal(self) -> np.ndarray:
        """The diagonal of ``K`` (``diag(A)``, then ``diag(C)``), shape (2N,) [force / length]."""
        return np.asarray(self.K.diagonal(), float)

    def to_dense(self) -> DiscreteSystem:
        """The same system with dense ``K`` (itself when already dense)."""
        if not self.is_sparse:
            return self
        return DiscreteSystem(self.A.toarray(), self.B.toarray(), self.C.toarray(),
                              self.friction, symmetry_rtol=self.symmetry_rtol)

    def to_sparse(self) -> DiscreteSystem:
        """The same system with ``K`` as a ``scipy.sparse`` CSR matrix (exact zeros dropped;
        itself when already sparse)."""
        if self.is_sparse:
            return self
        return DiscreteSystem(sp.csr_matrix(self.A), sp.csr_matrix(self.B),
                              sp.csr_matrix(self.C), self.friction,
                              symmetry_rtol=self.symmetry_rtol)

    @property
    def n_nodes(self) -> int:
        """Number of contact nodes ``N``."""
        return self.A.shape[0]

    @cached_property
    def K(self) -> np.ndarray:
        """The full reduced stiffness ``[[A, B], [B^T, C]]``, shape (2N, 2N) (read-only; ``A``,
        ``B``, ``C`` are views of its blocks)."""
        K = np.block([[self.A, self.B], [self.B.T, self.C]])  # only for unpickled old objects
        K.setflags(write=False)
        return K

    @property
    def is_coupled(self) -> bool:
        """``True`` unless ``max|B| <= COUPLING_RTOL * max(|A|, |C|)``."""
        amax = _sparse.abs_max
        scale = max(amax(self.A), amax(self.C))
        return bool(amax(self.B) > COUPLING_RTOL * scale)

    @cached_property
    def condition_number(self) -> float:
        """2-norm condition number of ``K`` (Lanczos estimate for a sparse ``K``)."""
        if self.is_sparse:
            return _sparse.largest_eigenvalue(self.K) / _sparse.smallest_eigenvalue(self.K)
        ev = np.linalg.eigvalsh(self.K)
        return float(ev[-1] / ev[0])

    def with_friction(self, friction) -> DiscreteSystem:
        """A copy with another friction (scalar or shape (N,)); the matrices are shared."""
        return DiscreteSystem(self.A, self.B, self.C, friction, symmetry_rtol=self.symmetry_rtol)

    def subsystem(self, nodes) -> DiscreteSystem:
        """The system restricted to ``nodes`` (the others held welded: ``v = w = 0``)."""
        idx = np.asarray(nodes, dtype=int)
        ix = np.ix_(idx, idx)
        return DiscreteSystem(self.A[ix], self.B[ix], self.C[ix], self.friction[idx])

    def reactions(self, slip, gap, q_w, p_w):
        """Reactions ``(q, p)`` for slips and gaps (shape (..., N)) and welded reactions."""
        v = np.asarray(slip, float)
        w = np.asarray(gap, float)
        n = self.n_nodes
        u = np.concatenate(np.broadcast_arrays(v, w), axis=-1).reshape(-1, 2 * n)
        r = (self.K @ u.T).T.reshape(np.broadcast_shapes(v.shape, w.shape)[:-1] + (2 * n,))
        return np.asarray(q_w, float) + r[..., :n], np.asarray(p_w, float) + r[..., n:]

    def __repr__(self) -> str:
        f = self.friction
        fr = f"{f[0]:g}" if np.all(f == f[0]) else f"[{f.min():g}..{f.max():g}]"
        sparse = f", sparse (nnz={self.nnz})" if self.is_sparse else ""
        return (
            f"DiscreteSystem(n_nodes={self.n_nodes}, coupled={self.is_coupled}, "
            f"friction={fr}{sparse})"
        )

    # ------------------------------------------------------------------ critical friction
    def critical_friction(self, max_exact_nodes: int = EXACT_CRITICAL_FRICTION_MAX_NODES):
        """Critical friction of the incremental problem (MODEL.md s.4), computed once.

        The answer depends only on the (frozen) system, so it is cached per
        ``max_exact_nodes`` on the instance: every step solver, cycle run and study row of the
        same system shares one computation (``with_friction`` returns a new system with its
        own cache).

        The step LCP has a unique solution for every data iff, for every slip-direction sign
        matrix ``S = diag(s)``, ``s in {-1, 1}^N``, the matrix

            M_S(alpha) = [[C, B^T S], [alpha F C + S B, alpha F B^T S + S A S]]

        (unknowns: gaps ``w`` and slip magnitudes ``x = S dv``) is a P-matrix (Klarbring 1990).
        At ``alpha = 0`` it is ``D K D`` with ``D = diag(I, S)``, hence P; the critical factor is
        the smallest ``alpha > 0`` at which a principal minor of some ``M_S`` vanishes.

        For ``N <= max_exact_nodes`` every minor is enumerated (``2^N 3^N`` generalized
        eigenproblems).  For larger systems a *sufficient* bound is returned:
        ``alpha_s = sqrt(lambda_min(A - B C^-1 B^T) / lambda_max(F C F))`` (positive definiteness of
        ``M_S`` for every ``S``), with the necessary single-node bound ``min_j A_jj / |B_jj| / f_j``.

        Returns
        -------
        CriticalFriction
        """
        citations.register("klarbring1990")
        cache = self.__dict__.setdefault("_critical_cache", {})
        key = int(max_exact_nodes)
        if key not in cache:
            cache[key] = self._critical_friction(key)
        return cache[key]

    def _critical_friction(self, max_exact_nodes: int):
        n = self.n_nodes
        f = self.friction
        fmax = float(f.max()) if n else 0.0
        diagB = np.abs(self.B.diagonal())
        with np.errstate(divide="ignore", invalid="ignore"):
            node_bounds = np.where((diagB > 0) & (f > 0), self.A.diagonal() / (diagB * f), np.inf)
        upper = float(node_bounds.min())

        def result(factor, exact, method):
            return CriticalFriction(
                factor=float(factor),
                value=float(factor * fmax) if fmax > 0 else float("inf"),
                exact=exact,
                upper_bound=upper,
                method=method,
                well_posed=bool(factor > 1.0),
            )

        if not self.is_coupled or fmax == 0.0:
            # block-triangular M_S with SPD diagonal blocks: P for every alpha
            return result(np.inf, True, "uncoupled" if not self.is_coupled else "frictionless")
        if n == 1:
            return result(upper, True, "single-node")
        if n <= max_exact_nodes:
            if self.is_sparse:
                return self.to_dense()._critical_friction(max_exact_nodes)
            return result(self._critical_factor_by_enumeration(), True, "enumeration")
        if self.is_sparse:
            # (A - B C^-1 B^T)^-1 is the leading block of K^-1: Lanczos with solves, no dense Schur
            lmin, lmax = _sparse.critical_eigenvalues(self, f)
            return result(min(np.sqrt(max(lmin, 0.0) / lmax), upper), False, "sufficient-bound")
        schur = self.A - self.B @ np.linalg.solve(self.C, self.B.T)
        lmin = float(np.linalg.eigvalsh(0.5 * (schur + schur.T))[0])
        lmax = float(np.linalg.eigvalsh(f[:, None] * self.C * f[None, :])[-1])
        return result(min(np.sqrt(max(lmin, 0.0) / lmax), upper), False, "sufficient-bound")

    def _critical_factor_by_enumeration(self) -> float:
        n = self.n_nodes
        A, B, C, F = self.A, self.B, self.C, np.diag(self.friction)
        best = np.inf
        zero = np.zeros((n, n))
        for s in itertools.product((-1.0, 1.0), repeat=n):
            S = np.diag(s)
            M0 = np.block([[C, B.T @ S], [S @ B, S @ A @ S]])
            M1 = np.block([[zero, zero], [F @ C, F @ B.T @ S]])
            for size in range(1, 2 * n + 1):
                for J in itertools.combinations(range(2 * n), size):
                    # the sign of an x-node that is not in J is irrelevant: count each once
                    x_nodes = [j - n for j in J if j >= n]
                    if any(s[k] < 0 for k in range(n) if k not in x_nodes):
                        continue
                    M1J = M1[np.ix_(J, J)]
                    if not np.any(M1J):
                        continue
                    # det(M0 + a M1) = 0  <=>  M1 x = mu (-M0) x with a = 1 / mu
                    ev = sla.eigvals(M1J, -M0[np.ix_(J, J)])
                    with np.errstate(divide="ignore", invalid="ignore"):
                        alphas = 1.0 / ev
                    real = np.abs(alphas.imag) <= 1e-9 * np.maximum(1.0, np.abs(alphas.real))
                    cand = alphas.real[real & np.isfinite(alphas.real) & (alphas.real > 0)]
                    if cand.size:
                        best = min(best, float(cand.min()))
        return best
