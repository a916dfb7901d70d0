"""Sparse reduced stiffness: validation and the checks a dense ``K`` gets, without densifying.

A :class:`~shakedown.DiscreteSystem` built from ``scipy.sparse`` blocks keeps ``K`` as a
``scipy.sparse.csr_matrix`` (a truncated Kachanov interaction, a user's sparse stiffness).
Its symmetry, finiteness, positive definiteness and conditioning are checked here with
sparse operations only: a symmetric-mode sparse LU with diagonal pivots (SuperLU) gives the
inertia (``K`` is positive definite iff every pivot is positive, Sylvester), and the 1-norm
condition number is estimated from solves with that factor (Higham's ``onenormest``).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import InputError, NotPositiveDefiniteError, NotSymmetricError, ShapeError
from .numbers import position

#: Lanczos basis size: contact stiffnesses have clustered extreme eigenvalues (a long interface's
#: high-frequency modes differ by ~1e-5 relative), where ARPACK's default 20 vectors restart
#: thousands of times; 64 cuts the products ~5x at equal accuracy (1000-node FE strip:
#: 6661 -> 1400 products).
LANCZOS_NCV = 64


def extreme_eigenvalue(op, which: str, tol: float = 1e-10) -> float:
    """One extreme eigenvalue (``which``: ``"LA"``, ``"SA"``, ``"LM"``) of a symmetric matrix or
    operator by Lanczos with a :data:`LANCZOS_NCV`-vector basis."""
    n = op.shape[0]
    return float(spla.eigsh(op, k=1, which=which, return_eigenvectors=False, tol=tol,
                            ncv=min(n - 1, LANCZOS_NCV))[0])


def is_sparse(value) -> bool:
    """``True`` for a ``scipy.sparse`` matrix or array."""
    return sp.issparse(value)


def sparse_matrix(name: str, value, n: int | None = None,
                  shape: tuple | None = None) -> sp.csr_matrix:
    """``value`` as a finite, real CSR matrix (explicit zeros dropped): square, of shape
    ``(n, n)`` when ``n`` is given, or of the given ``shape`` (3-D ``B``: (2N, N))."""
    if sp.issparse(value):
        if value.dtype.kind == "c":
            raise InputError(f"{name} must be a real sparse matrix; got complex values")
        M = sp.csr_matrix(value, dtype=float)
    else:
        from .validation import real_array
        arr = real_array(name, value, what="a real 2-D array", copy=False)
        if arr.ndim == 0 and n is None and shape is None:
            arr = arr.reshape(1, 1)
        if arr.ndim != 2:
            raise ShapeError(f"{name} must be a 2-D array; got shape {arr.shape}")
        M = sp.csr_matrix(arr)
    if shape is None and M.shape[0] != M.shape[1]:
        raise ShapeError(f"{name} must be a square 2-D array (N, N); got shape {M.shape}")
    if 0 in M.shape:
        raise ShapeError(
            f"{name} has shape {M.shape}: a system needs at least one contact node (N >= 1)")
    if shape is None and n is not None:
        shape = (n, n)
    if shape is not None and M.shape != tuple(shape):
        raise ShapeError(f"{name} must have shape {tuple(shape)} to match A; got shape {M.shape}")
    if not np.all(np.isfinite(M.data)):
        coo = M.tocoo()
        k = int(np.flatnonzero(~np.isfinite(coo.data))[0])
        raise InputError(f"{name} must be finite; {name} "
                         f"{position((coo.row[k], coo.col[k]))} is {coo.data[k]}")
    M.eliminate_zeros()
    M.sort_indices()
    return M


def abs_max(M) -> float:
    """``max |M|`` of a dense or sparse matrix (0 for an empty sparse matrix)."""
    if sp.issparse(M):
        return float(np.abs(M.data).max()) if M.nnz else 0.0
    return float(np.abs(M).max()) if M.size else 0.0


def check_symmetric(name: str, M: sp.csr_matrix, rtol: float, scale: float) -> None:
    """``max |M - M^T| <= rtol * scale`` for a sparse ``M`` (the error names the entry)."""
    D = (M - M.T).tocoo()
    if not D.nnz:
        return
    k = int(np.argmax(np.abs(D.data)))
    asym = float(abs(D.data[k]))
    if asym > rtol * scale:
        i, j = int(D.row[k]), int(D.col[k])
        raise NotSymmetricError(
            f"K must be symmetric: {name} {position((i, j))} is {M[i, j]:.6g} but {name} "
            f"{position((j, i))} is {M[j, i]:.6g} (max asymmetry {asym:.3g} > {rtol:g} * max|K| = "
            f"{rtol * scale:.3g}); "
            "symmetrise it, e.g. (M + M.T) / 2, or pass a larger symmetry_rtol")


def symmetric_lu(K: sp.spmatrix):
    """SuperLU factor of the symmetric ``K`` with a symmetric ordering and diagonal pivots
    (``P K P^T = L U``): ``diag(U)`` are the pivots of ``L D L^T``.  ``None`` when SuperLU finds
    ``K`` exactly singular."""
    try:
        return spla.splu(sp.csc_matrix(K), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options=dict(SymmetricMode=True))
    except RuntimeError:  # "Factor is exactly singular"
        return None


def check_sparse_conditioning(name: str, K: sp.spmatrix, *, max_condition: float):
    """Positive definite and ``cond_1(K) <= max_condition`` for a symmetric sparse ``K``.

    Returns the symmetric LU factor (reused for the condition estimate).
    """
    lu = symmetric_lu(K)
    if lu is None:
        raise NotPositiveDefiniteError(
            f"{name} must be positive definite; it is exactly singular (a zero pivot in its "
            "sparse LU factorisation). A reduced stiffness of a body held against rigid-body "
            "motion is always SPD: check the signs and the condensation")
    piv = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c):  # SuperLU left the diagonal: no inertia
        lmin = float(spla.eigsh(sp.csr_matrix(K), k=1, which="SA",
                                return_eigenvectors=False)[0]) if K.shape[0] > 2 \
            else float(np.linalg.eigvalsh(K.toarray())[0])
        piv = np.array([lmin])
    if np.any(~(piv > 0)):
        neg = int(np.count_nonzero(~(piv > 0)))
        raise NotPositiveDefiniteError(
            f"{name} must be positive definite; its sparse LDL^T factorisation has {neg} "
            "non-positive pivot(s). A reduced stiffness of a body held against rigid-body "
            "motion is always SPD: check the signs and the condensation")
    n = K.shape[0]
    anorm = float(abs(K).sum(axis=0).max())
    inv = spla.LinearOperator((n, n), matvec=lu.solve, rmatvec=lambda x: lu.solve(x, trans="T"),
                              dtype=float)
    ainv = float(spla.onenormest(inv)) if n > 1 else float(1.0 / abs(piv[0]))
    cond = anorm * ainv
    if not np.isfinite(cond) or cond > max_condition:
        raise NotPositiveDefiniteError(
            f"{name} is numerically singular: condition number ~{cond:.3g} > {max_condition:.0e} "
            "(its smallest stiffness is below round-off of its largest); remove the "
            "rigid-body or zero-stiffness modes, or rescale the degrees of freedom")
    return lu


def smallest_eigenvalue(K: sp.spmatrix, lu=None) -> float:
    """Smallest eigenvalue of a symmetric positive definite sparse ``K`` (Lanczos on ``K^-1``
    with ``lu``, the factor of :func:`symmetric_lu`)."""
    n = K.shape[0]
    if n <= 2:
        return float(np.linalg.eigvalsh(K.toarray())[0])
    lu = symmetric_lu(K) if lu is None else lu
    inv = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
    return float(1.0 / extreme_eigenvalue(inv, "LM", 1e-10))


def smallest_schur_eigenvalue(K: sp.spmatrix, n: int, lu=None) -> float:
    """Smallest eigenvalue of the Schur complement ``A - B C^-1 B^T`` of ``K = [[A, B], [B^T, C]]``
    (``A``: the leading ``n x n`` block) without forming it: its inverse is the leading block of
    ``K^-1``, applied by solves with ``lu`` (Lanczos)."""
    if n <= 2:
        Kd = K.toarray()
        S = Kd[:n, :n] - Kd[:n, n:] @ np.linalg.solve(Kd[n:, n:], Kd[n:, :n])
        return float(np.linalg.eigvalsh(0.5 * (S + S.T))[0])
    lu = symmetric_lu(K) if lu is None else lu
    return float(1.0 / extreme_eigenvalue(leading_block_inverse(lu, n), "LM", 1e-10))


def leading_block_inverse(lu, n: int) -> spla.LinearOperator:
    """The leading ``n x n`` block of ``K^-1`` (the inverse of the Schur complement of ``K``
    onto its first ``n`` unknowns) as a symmetric operator of solves with ``lu``."""
    m = lu.shape[0]

    def apply(x):
        y = np.zeros(m)
        y[:n] = np.ravel(x)
        return lu.solve(y)[:n]

    return spla.LinearOperator((n, n), matvec=apply, rmatvec=apply, dtype=float)


def largest_eigenvalue(K: sp.spmatrix) -> float:
    """Largest eigenvalue of a symmetric sparse ``K`` (Lanczos)."""
    n = K.shape[0]
    if n <= 2:
        return float(np.linalg.eigvalsh(K.toarray())[-1])
    return float(extreme_eigenvalue(sp.csr_matrix(K), "LA", 1e-10))


def critical_eigenvalues(system, f: np.ndarray) -> tuple[float, float]:
    """``lambda_min(A - B C^-1 B^T)`` and ``lambda_max(F C F)`` of a sparse system without forming
    either matrix (Lanczos); for an uncondensed system (``K`` a Schur complement of ``K_z``) the
    first is the Schur complement of ``K_z`` onto the slips, the second uses the dense ``C``
    kept with the diagonal (:meth:`~shakedown.model.schur.SchurStiffness.dense_C`; beyond its
    memory budget, Lanczos with products by ``C``)."""
    n = system.n_nodes
    K = system.K
    lmin = smallest_schur_eigenvalue(getattr(K, "Kz", K), n)
    if sp.issparse(system.C):
        Fs = sp.diags(f)
        return lmin, largest_eigenvalue(sp.csr_matrix(Fs @ system.C @ Fs))
    Cd = K.dense_C() if hasattr(K, "dense_C") else None
    if Cd is not None:  # kept from the diagonal's columns (schur.DENSE_C_BYTES)
        M = f[:, None] * Cd * f[None, :]
        return lmin, float(sla.eigh(M, eigvals_only=True, subset_by_index=[n - 1, n - 1],
                                    check_finite=False)[0])
    C = system.C
    op = spla.LinearOperator((n, n), matvec=lambda x: f * (C @ (f * np.ravel(x))), dtype=float)
    return lmin, float(extreme_eigenvalue(op, "LA", 1e-10))
