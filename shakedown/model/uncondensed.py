"""A frictional system whose reduced stiffness is kept uncondensed (sparse ``K_z``).

:class:`UncondensedSystem` is a :class:`~shakedown.DiscreteSystem` whose ``K`` is a
:class:`~shakedown.model.schur.SchurStiffness`: the Schur complement of a sparse stiffness in
the contact unknowns and the interior DOFs, never formed.  It is what
:meth:`shakedown.fe.FEModel.uncondensed` returns for an FE interface with many contact nodes.

* The cyclic solver (:func:`~shakedown.solve_cycles`, :func:`~shakedown.solve_step`,
  :func:`~shakedown.steady_cycle`) factorizes each node-state assignment together with the
  interior block (one sparse LU of ``O(nnz)`` memory) and never forms ``K``.
* ``A``, ``B``, ``C`` are :class:`~shakedown.model.schur.SchurBlock` views (products,
  diagonals).  The shakedown bounds form their dense constraint rows ``A -/+ F B^T`` from
  ``K[:, :N]`` (``N`` sparse solves); the uniqueness certificate uses the dense ``C`` kept with
  the diagonal (within :data:`~shakedown.model.schur.DENSE_C_BYTES`); the stability checks
  densify ``K``, and :meth:`UncondensedSystem.to_dense` condenses once (``2N`` sparse solves
  in blocks).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from . import sparse as _sparse
from .errors import InputError, NotPositiveDefiniteError
from .schur import SchurBlock, SchurStiffness
from .system import COUPLING_RTOL, SYMMETRY_RTOL, DiscreteSystem, _as_friction
from .validation import MAX_CONDITION


class UncondensedSystem(DiscreteSystem):
    """``N`` frictional contact nodes with ``K = K_cc - K_ci K_ii^-1 K_ic`` kept as sparse ``K_z``.

    Parameters
    ----------
    Kz : scipy.sparse matrix, shape (dim N + m, dim N + m)
        Symmetric positive definite stiffness [force / length]: first the slips ``v`` of the
        ``N`` contact nodes (in 3-D node by node, ``(v_1x, v_1y, ..., v_Nx, v_Ny)``), then their
        gaps ``w``, then ``m`` interior DOFs (the reactions on the interior DOFs are zero: their
        loads are in the welded reactions).
    n_nodes : int
        ``N``.
    friction : float or array_like, shape (N,)
        Coulomb friction coefficient of each node (``>= 0``).
    symmetry_rtol : float, optional
        Relative tolerance of the symmetry check of ``K_z``.
    dim : {2, 3}
        Space dimension of the contact (``dim - 1`` slip components per node).

    Raises
    ------
    ShapeError, InputError, NotSymmetricError, NotPositiveDefiniteError
        ``K_z`` not square, not finite, not symmetric, not positive definite or numerically
        singular (``cond_1(K_z) > 1e12``; the condensed ``K`` is then no worse conditioned:
        its spectrum lies within ``K_z``'s).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> from shakedown.model.uncondensed import UncondensedSystem
    >>> Kz = sp.csr_matrix(np.array([[2.0, 0.5, -1.0], [0.5, 3.0, 0.0], [-1.0, 0.0, 4.0]]))
    >>> s = UncondensedSystem(Kz, 1, friction=0.4)
    >>> float(s.to_dense().A[0, 0])  # 2 - 1 * 1 / 4
    1.75
    """

    def __init__(self, Kz, n_nodes: int, friction, *, symmetry_rtol: float = SYMMETRY_RTOL,
                 dim: int = 2, _stiffness: SchurStiffness | None = None):
        rtol = symmetry_rtol
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating)) \
                or not 0 <= rtol < 1:
            raise InputError(f"symmetry_rtol must be a number in [0, 1); got {rtol!r}")
        if _stiffness is None:
            Kz = _sparse.sparse_matrix("Kz", Kz)
            _sparse.check_symmetric("Kz", Kz, rtol, max(_sparse.abs_max(Kz),
                                                        np.finfo(float).tiny))
            Kz = (0.5 * (Kz + Kz.T)).tocsr()
            lu = _sparse.check_sparse_conditioning("Kz (uncondensed stiffness)", Kz,
                                                   max_condition=np.inf)  # SPD
            _stiffness = SchurStiffness(Kz, n_nodes, dim)
            _check_condition(_stiffness, lu)
        K = _stiffness
        set_ = object.__setattr__
        set_(self, "symmetry_rtol", float(rtol))
        if K.dim == 3:
            set_(self, "dim", 3)
        self.__dict__["K"] = K
        set_(self, "A", SchurBlock(K, 0, 0))
        set_(self, "B", SchurBlock(K, 0, 1))
        set_(self, "C", SchurBlock(K, 1, 1))
        set_(self, "friction", _as_friction(friction, K.n, K.dim))

    @property
    def is_sparse(self) -> bool:
        """``True``: ``K`` is never dense (its assignment systems are sparse)."""
        return True

    @property
    def Kz(self) -> sp.csr_matrix:
        """The uncondensed stiffness ``K_z`` (CSR)."""
        return self.K.Kz

    @property
    def nnz(self) -> int:
        """Stored entries of ``K_z``."""
        return self.K.nnz

    @property
    def n_nodes(self) -> int:
        return self.K.n

    def diagonal(self) -> np.ndarray:
        """``diag(K)`` (``2N`` solves with ``K_ii``, once), shape (2N,) [force / length]."""
        return self.K.diagonal()

    def to_dense(self) -> DiscreteSystem:
        """The condensed system with dense ``K`` (``2N`` solves with ``K_ii`` in blocks; kept)."""
        dense = self.__dict__.get("_dense")
        if dense is None:
            K = self.K.toarray()
            n = self.K.nt
            extra = {"dim": 3} if self.K.dim == 3 else {}
            dense = DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], self.friction,
                                   symmetry_rtol=self.symmetry_rtol, **extra)
            self.__dict__["_dense"] = dense
        return dense

    def to_sparse(self) -> UncondensedSystem:
        """Itself (its ``K`` is already never densified)."""
        return self

    @property
    def is_coupled(self) -> bool:
        """``True`` unless ``B`` is zero to ``COUPLING_RTOL`` (tested on two random slips)."""
        n, m = self.K.nt, self.K.m
        x = np.random.default_rng(0).standard_normal((m, 2))
        x[n:] = 0.0
        r = self.K @ x  # (A x, B^T x)
        y = np.zeros_like(x)
        y[n:] = x[:m - n]
        rc = self.K @ y
        scale = max(np.abs(r[:n]).max(), np.abs(rc[n:]).max())
        return bool(np.abs(r[n:]).max() > COUPLING_RTOL * scale)

    @property
    def condition_number(self) -> float:
        """2-norm condition number of ``K`` (Lanczos: ``K`` by products, ``K^-1`` as the
        leading block of ``K_z^-1``)."""
        cache = self.__dict__
        if "_cond" not in cache:
            m = self.K.m
            big = spla.LinearOperator((m, m), matvec=lambda x: self.K @ x, dtype=float)
            lmax = _sparse.extreme_eigenvalue(big, "LA", 1e-8) if m > 2 else float(
                np.linalg.eigvalsh(self.K.toarray())[-1])
            lmin = _sparse.smallest_schur_eigenvalue(self.Kz, m)
            cache["_cond"] = lmax / lmin
        return cache["_cond"]

    def with_friction(self, friction) -> UncondensedSystem:
        """A copy with another friction; ``K_z`` and its factor are shared."""
        return UncondensedSystem(None, self.n_nodes, friction,
                                 symmetry_rtol=self.symmetry_rtol, dim=self.K.dim,
                                 _stiffness=self.K)

    def subsystem(self, nodes) -> DiscreteSystem:
        """The (dense) system restricted to ``nodes``, the others held welded."""
        idx = np.asarray(nodes, dtype=int)
        t = self.K.dim - 1
        tang = (t * idx[:, None] + np.arange(t)).ravel()
        both = np.concatenate([tang, self.K.nt + idx])
        Ks = self.K[np.ix_(both, both)]
        k = tang.size
        extra = {"dim": 3} if t == 2 else {}
        return DiscreteSystem(Ks[:k, :k], Ks[:k, k:], Ks[k:, k:], self.friction[idx], **extra)

    def __repr__(self) -> str:
        f = self.friction
        fr = f"{f[0]:g}" if np.all(f == f[0]) else f"[{f.min():g}..{f.max():g}]"
        return (f"UncondensedSystem(n_nodes={self.n_nodes}, interior_dofs={self.K.n_interior}, "
                f"friction={fr}, nnz={self.nnz})")

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_dense", None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)


def _check_condition(K: SchurStiffness, lu) -> None:
    """``cond_1(K) <= MAX_CONDITION`` for the condensed ``K`` (Higham's 1-norm estimates of ``K``
    by products and of ``K^-1``, the leading block of ``K_z^-1``, by solves with ``lu``)."""
    m = K.m
    if m <= 2:
        cond = np.linalg.cond(K.toarray(), 1)
    else:
        op = spla.LinearOperator((m, m), matvec=lambda x: K @ np.ravel(x),
                                 rmatvec=lambda x: K @ np.ravel(x), dtype=float)
        iop = _sparse.leading_block_inverse(lu, m)
        cond = float(spla.onenormest(op)) * float(spla.onenormest(iop))
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise NotPositiveDefiniteError(
            f"K (the Schur complement of Kz onto the {K.n} contact nodes) is numerically "
            f"singular: condition number ~{cond:.3g} > {MAX_CONDITION:.0e}; remove the "
            "rigid-body or zero-stiffness modes, or rescale the degrees of freedom")
