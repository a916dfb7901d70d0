"""The condensed FE model (:class:`CondensedModel`) and the sparse factorization helper.

See :mod:`shakedown.fe.condense` for the frame and sign conventions.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...model.errors import InputError

#: Relative size of the smallest pivot below which a matrix counts as singular.
SINGULAR_RTOL = 1e-12

#: Memory budget [bytes] of dense right-hand-side blocks in the fallback solves.
RHS_BLOCK_BYTES = 64 * 2**20


class SchurFactor:
    """Sparse LU of a symmetric matrix ``A`` ordered so that its *boundary layer* comes last.

    The fill-reducing ordering is SuperLU's minimum degree on ``A + A^T`` (taken from a cheap
    incomplete factorization); the rows ``boundary`` (the DOFs coupled to the contact DOFs) are
    then moved to the end and ``A`` is factorized with that fixed order (``P A P^T = L U``).
    When the factorization is symmetric (no pivoting, ``U = D L^T``) the Schur correction
    ``B^T A^-1 B`` of a block ``B`` whose non-zero rows lie in the boundary layer is
    ``Y^T D_b^-1 Y`` with ``Y = L_bb^-1 B_b`` (dense, ``n_b x n_b``): no solve with the
    ``n - n_b`` leading rows at all.  Otherwise it falls back to full solves.
    """

    def __init__(self, A: sp.csc_matrix, boundary: np.ndarray, name: str):
        A = A.tocsc()
        n = A.shape[0]
        self.n = n
        if n == 0:
            self.lu, self.order, self.nb, self.symmetric = None, np.zeros(0, int), 0, False
            return
        try:
            ilu = spla.spilu(A, drop_tol=0.5, fill_factor=1, permc_spec="MMD_AT_PLUS_A",
                             options={"SymmetricMode": True})
            order = np.argsort(ilu.perm_c)
        except RuntimeError:
            order = np.arange(n)
        isb = np.zeros(n, dtype=bool)
        isb[np.asarray(boundary, dtype=int)] = True
        order = np.concatenate([order[~isb[order]], order[isb[order]]])
        self.order, self.inv, self.nb = order, np.argsort(order), int(isb.sum())
        Ap = A[order][:, order].tocsc()
        try:
            lu = spla.splu(Ap, permc_spec="NATURAL", options={"SymmetricMode": True})
        except RuntimeError as exc:
            raise InputError(
                f"{name} is singular ({exc}): part of the model can move freely while the "
                "contact nodes are held; hold a boundary (dirichlet=[...]) or add contact or "
                "interfaces"
            ) from None
        d = np.abs(lu.U.diagonal())
        if d.min() <= SINGULAR_RTOL * d.max():
            raise InputError(
                f"{name} is numerically singular (pivot ratio {d.min() / d.max():.2g}): part "
                "of the model has a zero-energy mode while the contact nodes are held; check "
                "the Dirichlet parts, interfaces and periodic sides"
            )
        self.lu = lu
        self.symmetric = False
        ident = np.arange(n)
        if self.nb and np.array_equal(lu.perm_r, ident) and np.array_equal(lu.perm_c, ident):
            k = n - self.nb
            Lb = _trailing(lu.L.tocsc(), k)
            Ub = _trailing(lu.U.tocsc(), k)
            db = lu.U.diagonal()[k:]
            Lb[np.diag_indices_from(Lb)] = 1.0
            if np.abs(Ub - db[:, None] * Lb.T).max() <= 1e-10 * np.abs(Ub).max():
                self.symmetric, self.Lb, self.db = True, Lb, db

    def solve(self, b):
        """``A^-1 b`` for ``b`` of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        return self.lu.solve(np.ascontiguousarray(b[self.order]))[self.inv]

    def schur_correction(self, B: sp.spmatrix) -> np.ndarray:
        """``B^T A^-1 B`` (dense (m, m)) for a sparse ``B`` of shape (n, m)."""
        B = sp.csr_matrix(B)
        m = B.shape[1]
        if self.n == 0:
            return np.zeros((m, m))
        rows = np.unique(B.nonzero()[0])
        if self.symmetric and np.all(self.inv[rows] >= self.n - self.nb):
            Bb = B[self.order[self.n - self.nb:]].toarray()
            Y = sla.solve_triangular(self.Lb, Bb, lower=True, unit_diagonal=True)
            return Y.T @ (Y / self.db[:, None])
        out = np.zeros((m, m))
        chunk = max(1, int(RHS_BLOCK_BYTES // (8 * self.n)))
        Bc = B.tocsc()
        for s in range(0, m, chunk):
            cols = slice(s, min(s + chunk, m))
            out[:, cols] = B.T @ self.solve(Bc[:, cols].toarray())
        return out


def _trailing(M: sp.csc_matrix, k: int) -> np.ndarray:
    """Dense ``M[k:, k:]`` of a sparse CSC matrix (cheap when ``M`` is triangular)."""
    sub = M[:, k:].tocoo()
    keep = sub.row >= k
    n = M.shape[0] - k
    out = np.zeros((n, n))
    out[sub.row[keep] - k, sub.col[keep]] = sub.data[keep]
    return out


def factorize(A: sp.csc_matrix, name: str, boundary=None) -> SchurFactor:
    """:class:`SchurFactor` of ``A`` (``boundary``: rows to order last; default none)."""
    return SchurFactor(A, np.zeros(0, int) if boundary is None else boundary, name)


@dataclass(frozen=True, eq=False)
class CondensedModel:
    """An FE model condensed onto its ``N`` contact nodes.

    Attributes
    ----------
    model : FEModel
    K : ndarray, shape (2N, 2N) (2-D) or (3N, 3N) (3-D)
        Condensed stiffness in the order ``(v_1..v_N, w_1..w_N)`` (2-D) or
        ``(v_1x, v_1y, ..., v_Nx, v_Ny, w_1, ..., w_N)`` (3-D) [force / length]:
        ``K = [[A, B], [B^T, C]]`` of MODEL.md s.1 / s.8 (``== system.K``).
    M : ndarray, same shape as ``K``, or None
        Guyan-condensed consistent mass (only with ``condense(mass=True)``) [mass].
    node_coordinates, normals : ndarray, shape (N, dim)
        Contact node positions and outward unit normals of the body.
    tangents : ndarray, shape (N, 2) (2-D) or (N, 2, 3) (3-D)
        2-D: the tangent ``t = (-n_y, n_x)``; 3-D: the rows ``t_x``, ``t_y`` of the node's
        frame ``(t_x, t_y, -normal)`` (:func:`~shakedown.fe.assembled.tangent_frames`).
    node_body, node_index : ndarray, shape (N,)
        Body and node number (in :attr:`Body.node_coordinates`) of each contact node.
    node_kind : tuple of str
        ``"contact"`` (rigid obstacle) or ``"interface"`` per node.
    welded : dict
        Load case -> ``(q_w, p_w)``: welded reactions [force], ``q_w`` shape (N,) (2-D) or
        (N, 2) (3-D, components along ``t_x``, ``t_y``), ``p_w`` shape (N,).
    from_cache : bool
        ``True`` when read from the on-disk cache (no assembly, no factorization).
    timings : dict
        Seconds spent in ``assembly``, ``factorization``, ``condensation`` (0 from cache).
    counts : dict
        ``n_full_dofs``, ``n_interior_dofs``, ``n_contact_nodes``, ``nnz_K_ii``.
    dim : int
        2 or 3.
    """

    model: object  # FEModel
    K: np.ndarray
    M: np.ndarray | None
    node_coordinates: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    node_body: np.ndarray
    node_index: np.ndarray
    node_kind: tuple
    welded: dict
    from_cache: bool
    timings: dict
    counts: dict
    dim: int = 2
    _lazy: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        for a in (self.K, self.M, self.node_coordinates, self.normals, self.tangents):
            if a is not None:
                a.setflags(write=False)

    @property
    def n_nodes(self) -> int:
        return self.K.shape[0] // self.dim

    @property
    def _nt(self) -> int:
        """Number of tangential unknowns, ``(dim - 1) N``."""
        return (self.dim - 1) * self.n_nodes

    @property
    def A(self) -> np.ndarray:
        return self.K[: self._nt, : self._nt]

    @property
    def B(self) -> np.ndarray:
        return self.K[: self._nt, self._nt:]

    @property
    def C(self) -> np.ndarray:
        return self.K[self._nt:, self._nt:]

    @property
    def system(self):
        """:class:`shakedown.DiscreteSystem` with the model's friction (default 0); ``dim = 3``
        for a 3-D model."""
        if "system" not in self._lazy:
            from ...model.system import DiscreteSystem

            extra = {"dim": 3} if self.dim == 3 else {}
            self._lazy["system"] = DiscreteSystem(self.A, self.B, self.C, self.model.friction,
                                                  **extra)
        return self._lazy["system"]

    def with_friction(self, friction):
        """The :class:`DiscreteSystem` with another friction (scalar or (N,))."""
        return self.system.with_friction(friction)

    def _assembled(self):
        if "assembled" not in self._lazy:
            self._lazy["assembled"] = self.model.assemble(self.M is not None)
        return self._lazy["assembled"]

    # ------------------------------------------------------------------ loads
    def _combine(self, combo, what) -> tuple[np.ndarray, np.ndarray]:
        N = self.n_nodes
        q, p = np.zeros(N if self.dim == 2 else (N, 2)), np.zeros(N)
        if combo is None:
            return q, p
        if isinstance(combo, str):
            combo = {combo: 1.0}
        if not isinstance(combo, dict):
            raise InputError(f"{what} must be a load case name or a dict name -> factor; "
                             f"got {combo!r}")
        for name, fac in combo.items():
            if name not in self.welded:
                raise InputError(f"{what}: unknown load case {name!r}; the model has "
                                 f"{sorted(self.welded)}")
            qw, pw = self.welded[name]
            q, p = q + float(fac) * qw, p + float(fac) * pw
        return q, p

    def welded_reactions(self, combo) -> tuple[np.ndarray, np.ndarray]:
        """``(q_w, p_w)`` of a load case or a combination ``{case: factor}`` [force]; ``q_w`` of
        shape (N,) in 2-D, (N, 2) in 3-D."""
        return self._combine(combo, "combo")

    def load_cycle(self, static=None, cyclic=None, cyclic_sin=None, samples=None):
        """Welded reactions of static + periodic loads as a :class:`~shakedown.LoadCycle`.

        Parameters
        ----------
        static : str or dict, optional
            Load case (or ``{case: factor}``) of the constant part ``r_0``.
        cyclic, cyclic_sin : str or dict, optional
            Cases of the ``cos(2 pi t)`` and ``sin(2 pi t)`` amplitudes of ``r_1`` (harmonic).
        samples : list of (str or dict), optional
            Instead of harmonics: ``r_1`` sampled at ``t = k / len(samples)`` (piecewise
            linear), each sample a load combination.

        Returns
        -------
        LoadCycle
            2-D: ``q0`` shape (N,); 3-D: ``q0`` shape (N, 2) (``load.dim == 3``).
        """
        from ...model.loading import LoadCycle

        q0, p0 = self._combine(static, "static")
        if samples is not None:
            qs, ps = zip(*(self._combine(s, "samples") for s in samples), strict=True)
            return LoadCycle.from_samples(q0, p0, np.array(qs), np.array(ps))
        if cyclic is None and cyclic_sin is None:
            return LoadCycle.static(q0, p0)
        qc, pc = self._combine(cyclic, "cyclic")
        qs, ps = self._combine(cyclic_sin, "cyclic_sin")
        return LoadCycle.from_harmonics(q0, p0, q_cos=qc, q_sin=qs, p_cos=pc, p_sin=ps)

    # ------------------------------------------------------------------ dynamics
    def dynamic_stiffness(self, s: float) -> np.ndarray:
        """Exact condensed ``K(s) = S(K + s M)`` (``s = lam^2``), shape (2N, 2N).

        ``K(s) = K_cc + s M_cc - (K_ci + s M_ci)(K_ii + s M_ii)^-1 (K_ic + s M_ic)``, in the
        order ``(v, w)``; ``K(0) = K``.  Needs ``condense(mass=True)``.  Each call factorizes
        ``K_ii + s M_ii`` once (sparse LU).
        """
        if self.M is None:
            raise InputError("dynamic_stiffness needs the mass: use model.condense(mass=True)")
        s = float(s)
        if s == 0.0:
            return np.array(self.K)
        a = self._assembled()
        if a.n_int == 0:
            return a.Kcc + s * a.Mcc
        lu = factorize((a.Kii + s * a.Mii).tocsc(), "K_ii + s M_ii", a.boundary_layer)
        S = a.Kcc + s * a.Mcc - lu.schur_correction((a.Kci + s * a.Mci).T)
        return 0.5 * (S + S.T)

    # ------------------------------------------------------------------ recovery
    def displacements(self, slip=None, gap=None, load=None):
        """Full displacement field(s) for contact values and a load case.

        Parameters
        ----------
        slip : array_like, shape (N,) (2-D) or (N, 2) (3-D), optional (default 0)
        gap : array_like, shape (N,), optional (default 0)
        load : str, optional
            Load case (external loads and prescribed displacements); None = unloaded.

        Returns
        -------
        list of ndarray
            One DOF vector per body (scikit-fem numbering of ``body.basis``).
        """
        N = self.n_nodes
        nt = self._nt
        v = np.zeros(nt) if slip is None else np.asarray(slip, float).reshape(nt)
        w = np.zeros(N) if gap is None else np.asarray(gap, float).reshape(N)
        if load is not None and load not in self.welded:
            raise InputError(f"unknown load case {load!r}; the model has {sorted(self.welded)}")
        return self._assembled().displacements(np.concatenate([v, w]), load,
                                               solve=self._interior_solve())

    def _interior_solve(self):
        """``K_ii^-1`` for the recovery (``None``: the condensation's factor)."""
        return None

    # ------------------------------------------------------------------ checks / cache
    def _check_rigid(self, allow: bool):
        """Raise unless ``K`` is positive definite (Cholesky pivots above round-off)."""
        scale = max(float(np.abs(np.diag(self.K)).max()), np.finfo(float).tiny)
        try:
            piv = np.diag(np.linalg.cholesky(self.K)) ** 2
            singular = piv.min() <= 1e-10 * scale
        except np.linalg.LinAlgError:
            singular = True
        if singular and not allow:
            ev = np.linalg.eigvalsh(self.K)
            raise InputError(
                f"the condensed K is singular (smallest eigenvalue {ev[0]:.3g}, largest "
                f"{ev[-1]:.3g}): the model is held only by its contact nodes, so a rigid-body "
                "motion moves them all (no Dirichlet part). Hold a boundary (dirichlet=[...]) "
                "or pass allow_rigid_body_modes=True to get the semi-definite K"
            )

    def _to_arrays(self) -> dict:
        cases = sorted(self.welded)
        out = {
            "K": self.K, "coords": self.node_coordinates, "normals": self.normals,
            "tangents": self.tangents, "node_body": self.node_body,
            "node_index": self.node_index, "node_kind": np.array(self.node_kind, dtype="U16"),
            "cases": np.array(cases, dtype="U200"),
            "q_w": np.array([self.welded[c][0] for c in cases]).reshape(
                (len(cases), self.n_nodes) + (() if self.dim == 2 else (2,))),
            "p_w": np.array([self.welded[c][1] for c in cases]).reshape(len(cases), self.n_nodes),
            "counts": np.array([self.counts[k] for k in _COUNT_KEYS]),
        }
        if self.M is not None:
            out["M"] = self.M
        return out

    @classmethod
    def _from_arrays(cls, model, a: dict) -> CondensedModel:
        cases = [str(c) for c in a["cases"]]
        return cls(
            model=model, K=a["K"], M=a.get("M"), node_coordinates=a["coords"],
            normals=a["normals"], tangents=a["tangents"], node_body=a["node_body"],
            node_index=a["node_index"], node_kind=tuple(str(k) for k in a["node_kind"]),
            welded={c: (a["q_w"][i], a["p_w"][i]) for i, c in enumerate(cases)},
            from_cache=True, timings={"assembly": 0.0, "factorization": 0.0,
                                      "condensation": 0.0},
            counts=dict(zip(_COUNT_KEYS, (int(x) for x in a["counts"]), strict=True)),
            dim=int(a["coords"].shape[1]),
        )

    def __repr__(self) -> str:
        return (f"CondensedModel(N={self.n_nodes}, mass={self.M is not None}, "
                f"cases={sorted(self.welded)}, from_cache={self.from_cache})")


_COUNT_KEYS = ("n_full_dofs", "n_interior_dofs", "n_contact_nodes", "nnz_K_ii")
