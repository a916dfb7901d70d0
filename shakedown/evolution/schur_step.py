"""The step's assignment systems on an uncondensed stiffness (``K`` the Schur complement of a
sparse ``K_z``, :mod:`shakedown.model.schur`).

An assignment ``s`` leaves ``k`` contact unknowns ``z_F`` (slips of non-stick nodes, gaps of
separated ones) with the equations ``G_s z = h_s`` (rows of ``K``, see
:mod:`.factors`).  With ``K`` the Schur complement of ``K_z`` the same ``z_F`` solve the
sparse system

    [ G_s^z[:, F]   G_s^z[:, I] ] [z_F]   [h_s]
    [ K_iF          K_ii        ] [ u ] = [ 0 ]

where ``G_s^z`` are the same combinations of the contact rows of ``K_z`` and ``u`` the
interior DOFs (eliminating ``u`` gives back ``G_s z = h_s``).  It is factorized by SuperLU
(COLAMD, partial pivoting) at ``O(nnz)`` memory instead of the dense ``O(N^2)``; one solve
gives ``z_F`` and ``u`` and so the reactions ``K z = K_cc z + K_ci u`` by one sparse product,
without a second solve with ``K_ii``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: Pivot threshold of the singularity test of a sparse assignment factor (relative to the
#: largest pivot), here and in the sparse path of :mod:`.factors`.
PIVOT_RTOL = 1e-14


class AugmentedLU:
    """SuperLU factor of an assignment's augmented system; solves give ``z_F`` and ``K z``."""

    def __init__(self, lu, k: int, contact_rows: sp.csr_matrix):
        self.lu, self.k = lu, k
        self.contact_rows = contact_rows  # K_z[:2N, F + I]: reactions of (z_F, u)
        self.m = lu.shape[0] - k

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``z_F`` for right-hand sides ``h_s`` (shape (k,) or (k, g))."""
        return self.solve_with_reactions(rhs)[0]

    def solve_with_reactions(self, rhs: np.ndarray):
        """``(z_F, K z)`` for right-hand sides ``h_s`` (shape (k,) or (k, g))."""
        rhs = np.asarray(rhs, float)
        full = np.zeros((self.k + self.m,) + rhs.shape[1:])
        full[:self.k] = rhs
        x = self.lu.solve(full)
        return x[:self.k], self.contact_rows @ x

    @property
    def nbytes(self) -> int:
        return (12 * (self.lu.L.nnz + self.lu.U.nnz) + 8 * self.lu.shape[0]
                + 12 * self.contact_rows.nnz)


def assignment_rows(M, n, coef, jv, jw, cols=None):
    """The assignment's equation rows of a sparse ``M`` whose first ``2N`` rows are those of
    ``(q, p)``: ``q_j + c_j p_j`` for the slipping or open nodes ``jv``, then ``p_j`` for the
    open ones ``jw`` (CSR; at ``cols`` when given)."""
    out = M[np.concatenate([jv, n + jw])]
    low = M[n + jv]
    if cols is not None:
        out, low = out[:, cols], low[:, cols]
    if jv.size:
        out = sp.vstack([out[:jv.size] + sp.diags(coef) @ low, out[jv.size:]], format="csr")
    return out


def pivoted_lu(M):
    """SuperLU of a sparse square ``M``; ``None`` when it is exactly singular or a pivot is
    below :data:`PIVOT_RTOL` of the largest (a cheap proxy for a reciprocal condition number;
    every answer is verified afterwards)."""
    try:
        lu = spla.splu(sp.csc_matrix(M))
    except RuntimeError:  # exactly singular
        return None
    piv = np.abs(lu.U.diagonal())
    if not np.all(np.isfinite(piv)) or piv.min() < PIVOT_RTOL * piv.max():
        return None
    return lu


def factor(K, free, coef, jv, jw):
    """The :class:`AugmentedLU` of an assignment (``free``, ``coef``, ``jv``, ``jw`` as in
    :meth:`.factors.FactorCache._layout`) of the :class:`~shakedown.model.schur.SchurStiffness`
    ``K``; ``None`` if (nearly) singular."""
    n = K.n
    Kz = K.Kz
    rows = assignment_rows(Kz, n, coef, jv, jw)
    cols = np.concatenate([free, np.arange(2 * n, Kz.shape[0])])
    lu = pivoted_lu(sp.vstack([rows, K.interior_rows], format="csc")[:, cols])
    if lu is None:
        return None
    return AugmentedLU(lu, free.size, Kz[:2 * n][:, cols].tocsr())
