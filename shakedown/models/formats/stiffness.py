r"""A full stiffness matrix with named contact DOFs, condensed onto the contact nodes.

For a user who exports the stiffness ``K`` (``n x n``, e.g. from Abaqus ``*MATRIX GENERATE``,
ANSYS ``HBMAT`` converted to Matrix Market, or Code_Aster ``IMPR_MATR_ASSE``) and knows, for
each of the ``N`` contact nodes, the index of its tangential and of its normal displacement
DOF.

Conventions
-----------
MODEL.md s.1, in the frame of :mod:`shakedown.fe.condense`.

For contact node ``j`` let ``u_t`` be its displacement along the tangential DOF and ``u_n``
along the normal DOF, and ``R_t``, ``R_n`` the obstacle's reaction force on the body along the
same DOFs.  With ``s_t = tangential_sign[j]`` and ``s_n = normal_sign[j]``:

* ``normal_sign = +1`` (default) when the normal DOF's positive direction is the body's
  *outward* normal (pointing into the obstacle); ``-1`` when it points into the body (e.g. the
  ``+y`` DOF of a node on the bottom face of a body resting on a floor is ``-1``).
* ``tangential_sign = +1`` (default) when the tangential DOF's positive direction is the slip
  direction ``t`` of MODEL.md (for a 2-D body, ``t = (-n_y, n_x)``: the boundary run
  counter-clockwise); ``-1`` to reverse it.

Then slip ``v_j = s_t u_t``, gap ``w_j = -s_n u_n`` (opening: moving away from the obstacle),
``q_j = s_t R_t``, ``p_j = -s_n R_n`` (compression positive).  With ``T = diag(s_t, -s_n)``
over the ordered contact DOFs ``c = (t_1..t_N, n_1..n_N)``, the remaining free DOFs ``i`` and
the Schur complement ``S = K_cc - K_ci K_ii^-1 K_ic``, the equilibrium ``K u = f + R`` gives

    (q, p) = T S T (v, w) - T g_c,      g_c = f_c - K_ci K_ii^-1 f_i,

so the reduced stiffness is ``T S T`` and the welded reactions of an external force vector
``f`` are ``-T g_c``.  ``fixed_dofs`` (held at zero: supports) are removed before condensing.
:func:`uncondensed_stiffness` keeps ``K_z = D K[o, o] D`` (``o = (c, i)``, ``D = diag(T, I)``)
instead, whose Schur complement onto its first ``2N`` rows is the same ``T S T``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...model.errors import InputError

#: Smallest pivot of ``K_ii``'s LU, relative to the largest, below which the body counts as
#: not held (a rigid-body mode): far above round-off (~1e-16) and far below the pivot ratio
#: of any usable FE mesh (~1/(mesh size)^2 ~ 1e-8 for a million DOFs).
SINGULAR_RTOL = 1e-12


@dataclass(frozen=True)
class CondensedStiffness:
    """A full stiffness condensed onto ``N`` contact nodes.

    Attributes
    ----------
    K : ndarray, shape (2N, 2N)
        Reduced stiffness in the order ``(v_1..v_N, w_1..w_N)`` [the file's force / length].
    contact_dofs : ndarray of int, shape (2N,)
        The full-matrix (0-based) DOFs ``(t_1..t_N, n_1..n_N)``.
    signs : ndarray, shape (2N,)
        Diagonal of ``T``: ``s_t`` then ``-s_n``.
    interior_dofs : ndarray of int
        The condensed-out (free, not fixed) DOFs.
    """

    K: np.ndarray
    contact_dofs: np.ndarray
    signs: np.ndarray
    interior_dofs: np.ndarray
    _factor: object = None
    _Kci: object = None

    @property
    def n_nodes(self) -> int:
        return self.K.shape[0] // 2

    @property
    def blocks(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C)`` of MODEL.md s.1."""
        n = self.n_nodes
        return self.K[:n, :n], self.K[:n, n:], self.K[n:, n:]

    def welded(self, force) -> tuple[np.ndarray, np.ndarray]:
        """Welded reactions ``(q_w, p_w)`` [force] of a full external force vector ``f``.

        Parameters
        ----------
        force : array_like, shape (n,)
            Nodal forces on every DOF of the full matrix (entries at fixed DOFs are ignored:
            the supports take them).
        """
        f = np.asarray(force, dtype=float)
        n_full = len(self.contact_dofs) + len(self.interior_dofs)
        if f.ndim != 1:
            raise InputError(f"force must be a vector of the full matrix's DOFs; got shape {f.shape}")
        if not np.all(np.isfinite(f)):
            raise InputError("force has non-finite entries (nan or inf)")
        if f.shape[0] < n_full:
            raise InputError(f"force has {f.shape[0]} entries; the stiffness has at least "
                             f"{n_full} DOFs")
        g = f[self.contact_dofs].copy()
        if len(self.interior_dofs):
            g -= self._Kci @ self._factor.solve(f[self.interior_dofs])
        r = -self.signs * g
        n = self.n_nodes
        return r[:n], r[n:]


@dataclass(frozen=True)
class UncondensedStiffness(CondensedStiffness):
    """A full stiffness kept uncondensed (:func:`uncondensed_stiffness`): ``K`` is ``None``;
    ``Kz`` the sparse ``K_z`` in the order (slips, gaps, interior DOFs) with the signs of
    ``T``; :meth:`system` gives the frictional system, :meth:`welded` the welded reactions."""

    _system: object = None

    @property
    def n_nodes(self) -> int:
        return self.contact_dofs.size // 2

    @property
    def Kz(self) -> sp.csr_matrix:
        return self._system.Kz

    @property
    def blocks(self):
        """``(A, B, C)`` (dense: the condensation, ``2N`` sparse solves)."""
        d = self._system.to_dense()
        return d.A, d.B, d.C

    def system(self, friction):
        """The :class:`~shakedown.model.uncondensed.UncondensedSystem` with ``friction``."""
        return self._system.with_friction(friction)


def _dofs(name, value, n_full, base):
    try:
        arr = np.array(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a list of integer DOF indices; got {value!r}") from None
    if not np.all(arr == np.round(arr)):
        raise InputError(f"{name} must hold integers; got {value!r}")
    idx = arr.astype(int) - base
    bad = (idx < 0) | (idx >= n_full)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise InputError(f"{name}[{k + base}] = {int(arr[k])} is outside the stiffness's DOFs "
                         f"{base}..{n_full - 1 + base} (dof_base = {base})")
    return idx


def _signs(name, value, n):
    s = np.broadcast_to(np.array(value, dtype=float), (n,)) if np.ndim(value) == 0 else \
        np.array(value, dtype=float)
    if s.shape != (n,) or not np.all(np.isin(s, (-1.0, 1.0))):
        raise InputError(f"{name} must be +1 or -1 (or a list of {n} of them); got {value!r}")
    return s


class _SuperLU:
    """Plain SuperLU of ``K_ii`` (when :mod:`shakedown.fe`'s factorization is not installed)."""

    def __init__(self, A):
        self.lu = spla.splu(A)
        pivots = np.abs(self.lu.U.diagonal())
        if pivots.min() <= SINGULAR_RTOL * pivots.max():
            raise RuntimeError("near singular")

    def solve(self, b):
        return self.lu.solve(np.asarray(b, dtype=float))

    def schur_correction(self, B):
        return (B.T @ self.solve(B.toarray())).astype(float)


def _factorize(Kii, Kci, n_interior):
    """The factor of ``K_ii``: shakedown.fe's boundary-layer-ordered LU (its Schur correction
    needs only the factor's trailing block) when installed, else a plain SuperLU."""
    try:
        from ..fe.condensed import factorize
    except ImportError:  # scikit-fem (the 'fe' extra) not installed
        factorize = None
    try:
        if factorize is None:
            return _SuperLU(Kii)
        return factorize(Kii, "K_ii", np.unique(Kci.nonzero()[1]))
    except (RuntimeError, InputError):
        raise InputError(
            f"the stiffness restricted to the {n_interior} interior DOFs is singular: the "
            "body is not held when its contact DOFs are fixed; list its supports in "
            "fixed_dofs") from None


def condense_stiffness(K, tangential_dofs, normal_dofs, *, fixed_dofs=(), tangential_sign=1,
                       normal_sign=1, dof_base: int = 0, symmetry_rtol: float = 1e-8
                       ) -> CondensedStiffness:
    """Condense a full stiffness onto its contact nodes (see the module's conventions).

    Parameters
    ----------
    K : array_like or scipy.sparse matrix, shape (n, n)
        Symmetric stiffness of every DOF [force / length].
    tangential_dofs, normal_dofs : sequence of int, length N
        DOF of each contact node's tangential and normal displacement (node ``j`` is the
        ``j``-th entry of both).
    fixed_dofs : sequence of int
        DOFs held at zero (supports); removed from ``K``.
    tangential_sign, normal_sign : {+1, -1} or sequence of them
        Orientation of the DOFs against MODEL.md's ``t`` and outward ``n`` (module docstring).
    dof_base : {0, 1}
        ``1`` when the indices count from 1 (as in the FE codes' exports and scene files).
    symmetry_rtol : float
        ``max|K - K^T| <= symmetry_rtol * max|K|`` is required (scale-free).

    Returns
    -------
    CondensedStiffness

    Raises
    ------
    InputError
        Non-square or non-symmetric ``K``, DOF lists out of range, repeated or overlapping,
        or a singular interior block (the body is not held without its contact nodes: list
        its supports in ``fixed_dofs``).
    """
    Ks, c, signs, interior = _contact_layout(K, tangential_dofs, normal_dofs, fixed_dofs,
                                             tangential_sign, normal_sign, dof_base,
                                             symmetry_rtol)
    Kcc = Ks[c][:, c].toarray()
    factor = Kci = None
    if interior.size:
        Kci = Ks[c][:, interior].tocsr()
        factor = _factorize(Ks[interior][:, interior].tocsc(), Kci, interior.size)
        Kcc = Kcc - factor.schur_correction(Kci.T)
    S = 0.5 * (Kcc + Kcc.T)
    Kred = signs[:, None] * S * signs[None, :]
    return CondensedStiffness(K=Kred, contact_dofs=c, signs=signs, interior_dofs=interior,
                              _factor=factor, _Kci=Kci)


def uncondensed_stiffness(K, tangential_dofs, normal_dofs, *, fixed_dofs=(), tangential_sign=1,
                          normal_sign=1, dof_base: int = 0, symmetry_rtol: float = 1e-8
                          ) -> UncondensedStiffness:
    """The same as :func:`condense_stiffness` without condensing: ``K`` reordered and signed
    into ``K_z`` (contact slips, gaps, then the interior DOFs) for many contact nodes; its
    :meth:`UncondensedStiffness.system` never forms the dense reduced stiffness
    (:class:`~shakedown.model.uncondensed.UncondensedSystem`).  Arguments and errors as
    :func:`condense_stiffness` (a body that is not held: ``NotPositiveDefiniteError``).
    """
    from ...model.uncondensed import UncondensedSystem

    Ks, c, signs, interior = _contact_layout(K, tangential_dofs, normal_dofs, fixed_dofs,
                                             tangential_sign, normal_sign, dof_base,
                                             symmetry_rtol)
    order = np.concatenate([c, interior])
    D = sp.diags(np.concatenate([signs, np.ones(interior.size)]))
    Kz = (D @ Ks[order][:, order] @ D).tocsr()
    system = UncondensedSystem(Kz, c.size // 2, 0.0, symmetry_rtol=symmetry_rtol)
    return UncondensedStiffness(K=None, contact_dofs=c, signs=signs, interior_dofs=interior,
                                _factor=_InteriorSolve(system.K),
                                _Kci=Ks[c][:, interior].tocsr() if interior.size else None,
                                _system=system)


class _InteriorSolve:
    """``K_ii^-1`` of an uncondensed stiffness (for :meth:`CondensedStiffness.welded`)."""

    def __init__(self, schur):
        self.schur = schur

    def solve(self, b):
        return self.schur.solve_interior(b)


def _contact_layout(K, tangential_dofs, normal_dofs, fixed_dofs, tangential_sign, normal_sign,
                    dof_base, symmetry_rtol):
    """Checked ``(K as CSR, contact DOFs (t then n), signs (s_t, -s_n), interior DOFs)``."""
    if dof_base not in (0, 1):
        raise InputError(f"dof_base must be 0 or 1; got {dof_base!r}")
    Ks = sp.csr_matrix(K, dtype=float) if not sp.issparse(K) else K.tocsr().astype(float)
    n_full = Ks.shape[0]
    if Ks.shape != (n_full, n_full) or n_full == 0:
        raise InputError(f"the stiffness must be a non-empty square matrix; got shape {Ks.shape}")
    if not np.all(np.isfinite(Ks.data)):
        raise InputError("the stiffness has non-finite entries (nan or inf)")
    scale = abs(Ks).max()
    asym = abs(Ks - Ks.T).max() if Ks.nnz else 0.0
    if asym > symmetry_rtol * scale:
        raise InputError(f"the stiffness is not symmetric: max|K - K^T| = {asym:.3g} > "
                         f"{symmetry_rtol:g} max|K| = {symmetry_rtol * scale:.3g}")
    t = _dofs("tangential_dofs", tangential_dofs, n_full, dof_base)
    nn = _dofs("normal_dofs", normal_dofs, n_full, dof_base)
    fixed = _dofs("fixed_dofs", fixed_dofs, n_full, dof_base) if len(fixed_dofs) else \
        np.zeros(0, int)
    if t.shape != nn.shape or t.size == 0:
        raise InputError(f"tangential_dofs and normal_dofs must list one DOF per contact node "
                         f"(same length, at least 1); got {t.size} and {nn.size}")
    c = np.concatenate([t, nn])
    if len(np.unique(c)) != c.size:
        raise InputError("a DOF appears twice in tangential_dofs / normal_dofs")
    if np.intersect1d(c, fixed).size:
        raise InputError(f"DOF {int(np.intersect1d(c, fixed)[0]) + dof_base} is both a contact "
                         "DOF and a fixed DOF")
    n = t.size
    signs = np.concatenate([_signs("tangential_sign", tangential_sign, n),
                            -_signs("normal_sign", normal_sign, n)])
    interior = np.setdiff1d(np.arange(n_full), np.concatenate([c, fixed]))
    return Ks, c, signs, interior
