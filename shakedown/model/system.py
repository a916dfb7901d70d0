"""Discrete frictional systems: ``q = q_w + A v + B w``, ``p = p_w + B^T v + C w`` (MODEL.md s.1).

``K = [[A, B], [B^T, C]]`` is the reduced (condensed) stiffness in work-conjugate units:
force (per unit thickness) over displacement.  ``v`` is the slip and ``w >= 0`` the gap of
each of the ``N`` contact nodes; ``q``, ``p`` the tangential and normal reactions
(compression positive).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from . import citations
from . import sparse as _sparse
from .critical import CriticalFriction as CriticalFriction
from .critical import critical_friction_2d
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


def _as_matrix(name: str, value, n: int | None = None, shape: tuple | None = None,
               dim: int = 2) -> np.ndarray:
    """``value`` as a finite real 2-D array: square, or of the given ``shape`` (then the
    message says which shape ``dim`` asks for)."""
    arr = real_array(name, value, what="a real 2-D array", copy=False)  # only read: K is new
    if arr.ndim == 0 and n is None:
        arr = arr.reshape(1, 1)
    if shape is None and (arr.ndim != 2 or arr.shape[0] != arr.shape[1]):
        want = "(2N, 2N)" if dim == 3 else "(N, N)"
        raise ShapeError(f"{name} must be a square 2-D array {want}; got shape {arr.shape}")
    if arr.ndim == 2 and 0 in arr.shape:
        raise ShapeError(
            f"{name} has shape {arr.shape}: a system needs at least one contact node (N >= 1)"
        )
    if shape is None and n is not None:
        shape = (n, n)
    if shape is not None and arr.shape != shape:
        sym = (" = (2N, N)" if name == "B" else " = (N, N)") if dim == 3 else ""
        raise ShapeError(f"{name} must have shape {shape}{sym} to match A"
                         f"{' (dim = 3: A is (2N, 2N))' if dim == 3 else ''}; "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InputError(
            f"{name} must be finite; {name} {position(tuple(bad))} is {arr[tuple(bad)]}"
        )
    return arr


def _as_friction(value, n: int, dim: int = 2) -> np.ndarray:
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
    aniso = dim == 3 and f.shape == (n, 2)
    if f.shape != (n,) and not aniso:
        extra = f" or ({n}, 2) (anisotropic f_x, f_y)" if dim == 3 else ""
        raise ShapeError(f"friction must be a scalar or have shape ({n},){extra}; "
                         f"got shape {f.shape}")
    if not np.all(np.isfinite(f)):
        raise InputError(f"friction must be finite; got {f[~np.isfinite(f)][0]}")
    if np.any(f < 0):
        j = int(np.argmax(np.any(f < 0, axis=-1) if aniso else f < 0))
        raise InputError(f"friction must be >= 0; node {j + 1} has friction {f[j]}")
    if aniso and np.array_equal(f[:, 0], f[:, 1]):
        f = np.ascontiguousarray(f[:, 0])  # isotropic after all: one coefficient per node
    f.setflags(write=False)
    return f


def _all_numbers(value) -> bool:
    """Every leaf of ``value`` is a real number (not a bool or a string)."""
    flat = np.asarray(value, dtype=object).ravel()
    return all(isinstance(x, (int, float, np.integer, np.floating))
               and not isinstance(x, (bool, np.bool_)) for x in flat)


def _tangential_size(rows: int, dim: int) -> tuple[int, int]:
    """``(rows of A, N)``: ``A`` is (N, N) in 2-D and (2N, 2N) in 3-D."""
    if dim == 3 and rows % 2:
        raise ShapeError(f"A must have shape (2N, 2N) for dim = 3 (two tangential slips per "
                         f"node, ordered v_1x, v_1y, v_2x, ...); got {rows} rows, an odd number")
    return rows, (rows // 2 if dim == 3 else rows)


@dataclass(frozen=True, eq=False)
class DiscreteSystem:
    """A linear elastic system with ``N`` frictional contact nodes (MODEL.md s.1).

    Parameters
    ----------
    A, B, C : array_like, shape (N, N)
        Blocks of the reduced stiffness ``K = [[A, B], [B^T, C]]`` [force / length].
        ``A`` maps slip to tangential reaction, ``C`` gap to normal reaction, ``B`` couples
        gap to tangential reaction (and, transposed, slip to normal reaction).
        With ``dim = 3`` (MODEL.md s.8): ``A`` has shape (2N, 2N) over the tangential slips
        ordered node by node ``(v_1x, v_1y, v_2x, v_2y, ...)``, ``B`` (2N, N), ``C`` (N, N).
    friction : float or array_like, shape (N,)
        Coulomb friction coefficient of each node (dimensionless, ``>= 0``).  With
        ``dim = 3`` also shape (N, 2): anisotropic (elliptic) friction ``(f_x, f_y)`` per node,
        the cone ``|diag(1/f_x, 1/f_y) q| <= p``.
    symmetry_rtol : float, optional
        Relative tolerance of the symmetry check of ``A`` and ``C``.
    dim : {2, 3}, optional
        Dimension of the contact problem: 2 (one tangential slip per node, the default) or 3
        (two tangential slips per node and circular, or elliptic, friction cones).

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
    >>> s3 = sd.DiscreteSystem(np.eye(2), [[0.1], [0.0]], [[2.0]], friction=0.4, dim=3)
    >>> s3.n_nodes, s3.K.shape
    (1, (3, 3))
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    friction: np.ndarray
    symmetry_rtol: float = field(default=SYMMETRY_RTOL, repr=False)
    dim: int = 2

    def __post_init__(self):
        rtol = self.symmetry_rtol
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating)) \
                or not 0 <= rtol < 1:
            raise InputError(f"symmetry_rtol must be a number in [0, 1); got {rtol!r}")
        dim = self.dim
        if isinstance(dim, (bool, np.bool_)) or dim not in (2, 3):
            raise InputError(f"dim must be 2 or 3 (the dimension of the contact problem); "
                             f"got {dim!r}")
        object.__setattr__(self, "dim", int(dim))
        if any(sp.issparse(M) for M in (self.A, self.B, self.C)):
            self._init_sparse()
            return
        A = _as_matrix("A", self.A, dim=dim)
        nt, n = _tangential_size(A.shape[0], dim)
        B = _as_matrix("B", self.B, shape=(nt, n), dim=dim)
        C = _as_matrix("C", self.C, n, dim=dim)
        f = _as_friction(self.friction, n, dim)
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
        K = np.empty((nt + n, nt + n))
        np.add(A, A.T, out=K[:nt, :nt])
        np.add(C, C.T, out=K[nt:, nt:])
        K[:nt, :nt] *= 0.5
        K[nt:, nt:] *= 0.5
        K[:nt, nt:] = B
        K[nt:, :nt] = B.T
        del A, B, C
        # positive definite and not numerically singular (cond <= MAX_CONDITION)
        check_conditioning("K = [[A, B], [B^T, C]]", K)
        K.setflags(write=False)
        self.__dict__["K"] = K  # the cached_property's value
        object.__setattr__(self, "A", K[:nt, :nt])
        object.__setattr__(self, "B", K[:nt, nt:])
        object.__setattr__(self, "C", K[nt:, nt:])
        object.__setattr__(self, "friction", f)

    def _init_sparse(self):
        """Sparse blocks: one symmetric CSR ``K``, checked without densifying
        (:mod:`.sparse`); ``A``, ``B``, ``C`` are CSR copies of its blocks."""
        A = _sparse.sparse_matrix("A", self.A)
        nt, n = _tangential_size(A.shape[0], self.dim)
        if self.dim == 3:
            B = _sparse.sparse_matrix("B", self.B, shape=(nt, n))
        else:
            B = _sparse.sparse_matrix("B", self.B, n)
        C = _sparse.sparse_matrix("C", self.C, n)
        f = _as_friction(self.friction, n, self.dim)
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
        object.__setattr__(self, "A", K[:nt, :nt].tocsr())
        object.__setattr__(self, "B", K[:nt, nt:].tocsr())
        object.__setattr__(self, "C", K[nt:, nt:].tocsr())
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
                              self.friction, symmetry_rtol=self.symmetry_rtol, dim=self.dim)

    def to_sparse(self) -> DiscreteSystem:
        """The same system with ``K`` as a ``scipy.sparse`` CSR matrix (exact zeros dropped;
        itself when already sparse)."""
        if self.is_sparse:
            return self
        return DiscreteSystem(sp.csr_matrix(self.A), sp.csr_matrix(self.B),
                              sp.csr_matrix(self.C), self.friction,
                              symmetry_rtol=self.symmetry_rtol, dim=self.dim)

    @property
    def n_nodes(self) -> int:
        """Number of contact nodes ``N``."""
        return self.C.shape[0]

    @property
    def n_tangential(self) -> int:
        """Number of tangential unknowns: ``N`` in 2-D, ``2N`` in 3-D (the rows of ``A``)."""
        return self.A.shape[0]

    @property
    def is_anisotropic(self) -> bool:
        """``True`` for elliptic friction cones (``friction`` of shape (N, 2), 3-D only)."""
        return np.ndim(self.friction) == 2

    @property
    def friction_xy(self) -> np.ndarray:
        """Friction coefficients ``(f_x, f_y)`` per node, shape (N, 2) (3-D systems only; both
        columns equal for isotropic friction)."""
        if self.dim != 3:
            raise InputError("friction_xy is defined for dim = 3 systems only; a 2-D system has "
                             "one friction coefficient per node (system.friction)")
        f = self.friction
        out = f if f.ndim == 2 else np.repeat(f[:, None], 2, axis=1)
        out = np.array(out, float)
        out.setflags(write=False)
        return out

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
        """A copy with another friction (scalar or shape (N,); (N, 2) in 3-D); the matrices are
        shared."""
        return DiscreteSystem(self.A, self.B, self.C, friction, symmetry_rtol=self.symmetry_rtol,
                              dim=self.dim)

    def subsystem(self, nodes) -> DiscreteSystem:
        """The system restricted to ``nodes`` (the others held welded: ``v = w = 0``)."""
        idx = np.asarray(nodes, dtype=int)
        ix = np.ix_(idx, idx)
        if self.dim == 3:
            t = np.stack([2 * idx, 2 * idx + 1], axis=-1).ravel()  # both slips of each node
            return DiscreteSystem(self.A[np.ix_(t, t)], self.B[np.ix_(t, idx)], self.C[ix],
                                  self.friction[idx], dim=3)
        return DiscreteSystem(self.A[ix], self.B[ix], self.C[ix], self.friction[idx])

    def reactions(self, slip, gap, q_w, p_w):
        """Reactions ``(q, p)`` for slips and gaps and welded reactions.

        2-D: ``slip``, ``gap``, ``q_w``, ``p_w`` of shape (..., N).  3-D: ``slip`` and ``q_w`` of
        shape (..., N, 2), ``gap`` and ``p_w`` (..., N); ``q`` is returned with shape (..., N, 2).
        """
        v = np.asarray(slip, float)
        w = np.asarray(gap, float)
        n = self.n_nodes
        if self.dim == 3:
            if v.shape[-2:] != (n, 2) or w.shape[-1:] != (n,):
                raise ShapeError(f"3-D reactions need slip of shape (..., {n}, 2) and gap of "
                                 f"shape (..., {n}); got {v.shape} and {w.shape}")
            lead = np.broadcast_shapes(v.shape[:-2], w.shape[:-1])
            u = np.concatenate([np.broadcast_to(v, lead + (n, 2)).reshape(lead + (2 * n,)),
                                np.broadcast_to(w, lead + (n,))], axis=-1).reshape(-1, 3 * n)
            r = (self.K @ u.T).T.reshape(lead + (3 * n,))
            return (np.asarray(q_w, float) + r[..., :2 * n].reshape(lead + (n, 2)),
                    np.asarray(p_w, float) + r[..., 2 * n:])
        u = np.concatenate(np.broadcast_arrays(v, w), axis=-1).reshape(-1, 2 * n)
        r = (self.K @ u.T).T.reshape(np.broadcast_shapes(v.shape, w.shape)[:-1] + (2 * n,))
        return np.asarray(q_w, float) + r[..., :n], np.asarray(p_w, float) + r[..., n:]

    def __repr__(self) -> str:
        f = self.friction
        if self.is_anisotropic:
            fr = f"[{f.min():g}..{f.max():g}] (anisotropic)"
        else:
            fr = f"{f[0]:g}" if np.all(f == f[0]) else f"[{f.min():g}..{f.max():g}]"
        sparse = f", sparse (nnz={self.nnz})" if self.is_sparse else ""
        dim = ", dim=3" if self.dim == 3 else ""
        return (
            f"DiscreteSystem(n_nodes={self.n_nodes}{dim}, coupled={self.is_coupled}, "
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

        For ``dim = 3`` a sufficient bound ``lambda_max(F C F) < 4 lambda_min(A - B C^-1 B^T)``
        with its proof (:mod:`shakedown.model.critical3d`).

        Returns
        -------
        CriticalFriction
        """
        if self.dim == 3:  # a sufficient bound with its proof: shakedown/model/critical3d.py
            from .critical3d import critical_friction_3d

            cache = self.__dict__.setdefault("_critical_cache", {})
            if "3d" not in cache:
                cache["3d"] = critical_friction_3d(self)
            return cache["3d"]
        citations.register("klarbring1990")
        cache = self.__dict__.setdefault("_critical_cache", {})
        key = int(max_exact_nodes)
        if key not in cache:
            cache[key] = critical_friction_2d(self, key)
        return cache[key]
