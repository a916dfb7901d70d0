"""Assembly of an :class:`~shakedown.fe.condense.FEModel` and its static condensation onto the
contact DOFs: constraint maps, the factorised interior block, welded reactions, the Guyan
mass and field recovery (frame and signs: :mod:`shakedown.fe.condense`).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ...model.errors import InputError
from .condensed import CondensedModel, factorize

__all__ = ["Assembled"]


#: Memory budget [bytes] of the dense right-hand-side blocks ``K_ii^-1 K_ic[:, chunk]``.
RHS_BLOCK_BYTES = 64 * 2**20

#: Largest ``K_ii^-1 K_ic`` [bytes] kept in memory at once for the Guyan mass.
GUYAN_FULL_BYTES = 256 * 2**20



def _sort_along(coords: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Order of boundary nodes: along their mean tangent (counter-clockwise run) in 2-D; in
    3-D row by row of the mean tangent frame (``t_y`` first, then ``t_x``, coordinates
    rounded to ``1e-9`` of the patch size so that rows of a grid stay rows)."""
    if coords.shape[1] == 3:
        tx, ty, _ = tangent_frames(normals.mean(axis=0)[None])
        size = max(float(np.ptp(coords, axis=0).max()), np.finfo(float).tiny)
        r = np.round(coords / (1e-9 * size))
        return np.lexsort((r @ tx[0], r @ ty[0]))
    tangents = np.c_[-normals[:, 1], normals[:, 0]]
    t = tangents.mean(axis=0)
    if np.linalg.norm(t) < 1e-12:
        t = tangents[0]
    return np.lexsort((coords @ np.array([-t[1], t[0]]), coords @ t))


def tangent_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthonormal frames ``(t_x, t_y, n)`` of 3-D contact nodes from their outward normals.

    ``n = -normal`` points from the obstacle into the body; ``t_x`` is the global ``x`` axis
    projected on the tangent plane (the ``y`` axis where the normal is within ~25 degrees of
    ``x``), ``t_y = n x t_x`` so that ``t_x x t_y = n`` (right-handed).  On a bottom face
    (outward normal ``-z``): ``t_x = +x``, ``t_y = +y``, ``n = +z``.

    Parameters
    ----------
    normals : ndarray, shape (N, 3)
        Outward unit normals of the body.

    Returns
    -------
    t_x, t_y, n : ndarray, each shape (N, 3)
    """
    n = -np.asarray(normals, dtype=float)
    n = n / np.linalg.norm(n, axis=1)[:, None]
    ref = np.where((np.abs(n[:, 0]) > 0.9)[:, None], [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    tx = ref - np.sum(ref * n, axis=1)[:, None] * n
    tx /= np.linalg.norm(tx, axis=1)[:, None]
    ty = np.cross(n, tx)
    return tx, ty, n


def _match(xa: np.ndarray, xb: np.ndarray, tol: float, what: str) -> np.ndarray:
    """Index ``m`` with ``xb[m[k]] == xa[k]`` (within tol); clear error otherwise."""
    from scipy.spatial import cKDTree

    if len(xa) != len(xb):
        raise InputError(
            f"{what}: the two sides have {len(xa)} and {len(xb)} nodes; they must match "
            "one to one (conforming meshes)"
        )
    d, m = cKDTree(xb).query(xa)
    if np.any(d > tol) or np.unique(m).size != m.size:
        k = int(np.argmax(d))
        raise InputError(
            f"{what}: node at {xa[k]} has no partner within {tol:.2g} (nearest {d[k]:.3g}); "
            "the meshes of the two sides must match node to node"
        )
    return m


class Assembled:
    """Assembly, constraint map and factorization of an :class:`FEModel` (internal)."""

    def __init__(self, model, mass: bool):
        t0 = time.perf_counter()
        self.model, self.with_mass = model, mass
        bodies = model.bodies
        self.dim = dim = bodies[0].dim
        for k, b in enumerate(bodies):
            if b.dim != dim:
                raise InputError(f"bodies[{k}] is {b.dim}-D but bodies[0] is {dim}-D: every body "
                                 "of a model has the same dimension")
        self.offsets = np.cumsum([0] + [b.n_dofs for b in bodies])
        n_full = int(self.offsets[-1])
        diam = max(b.mesh.diameter for b in bodies)
        tol = 1e-8 * diam
        held = {}
        for k, b in enumerate(bodies):
            for d, tag in b.held_dofs().items():
                held[int(self.offsets[k] + d)] = (k, *tag)
        node_gdofs = [b.node_dofs + self.offsets[k] for k, b in enumerate(bodies)]

        # periodic: slave global dof -> master global dof
        alias = {}
        for k, m_, s_ in model.periodic:
            b = bodies[k]
            nm, ns = b.boundary_nodes(m_), b.boundary_nodes(s_)
            xm, xs = b.node_coordinates[nm], b.node_coordinates[ns]
            shift = xs.mean(axis=0) - xm.mean(axis=0)
            idx = _match(xs - shift, xm, tol, f"periodic sides {m_!r} -> {s_!r} of body {k}")
            for s, m in zip(ns, nm[idx], strict=True):
                for c in range(dim):
                    gs, gm = int(node_gdofs[k][s, c]), int(node_gdofs[k][m, c])
                    if gs not in held:
                        alias[gs] = gm
        # contact nodes (rigid obstacle), then interface nodes
        nodes = []  # (kind, body, node, normal, partner_body, partner_node)
        taken = set()
        for k, name in model.contact:
            b = bodies[k]
            nn, nrm = b.node_normals(name)
            order = _sort_along(b.node_coordinates[nn], nrm)
            for j in order:
                g = node_gdofs[k][nn[j]]
                if (k, nn[j]) in taken or any(int(x) in held or int(x) in alias for x in g):
                    continue
                taken.add((k, int(nn[j])))
                nodes.append(("contact", k, int(nn[j]), nrm[j], -1, -1))
        for a, na, bb, nb_ in model.interfaces:
            A, B = bodies[a], bodies[bb]
            nn, nrm = A.node_normals(na)
            mb = B.boundary_nodes(nb_)
            idx = _match(A.node_coordinates[nn], B.node_coordinates[mb], tol,
                         f"interface {na!r} (body {a}) / {nb_!r} (body {bb})")
            order = _sort_along(A.node_coordinates[nn], nrm)
            for j in order:
                g = node_gdofs[a][nn[j]]
                if (a, nn[j]) in taken or any(int(x) in held or int(x) in alias for x in g):
                    continue
                taken.add((a, int(nn[j])))
                nodes.append(("interface", a, int(nn[j]), nrm[j], bb, int(mb[idx[j]])))
        N = len(nodes)
        if N == 0:
            raise InputError(
                "no contact node is left: every node of the contact boundaries is held "
                "(Dirichlet) or a periodic copy"
            )
        self.nodes = nodes
        self.N = N
        self.nc = nc = dim * N  # contact unknowns: (dim - 1) N slips, then N gaps
        normals = np.array([nd[3] for nd in nodes])
        self.normals = normals
        if dim == 2:
            tangents = np.c_[-normals[:, 1], normals[:, 0]]
            # z columns of node j: its slip j, its gap N + j; coefficients t and -n
            frame = [((j, N + j), np.stack([tangents[j], -normals[j]])) for j in range(N)]
        else:
            tx, ty, n_in = tangent_frames(normals)
            tangents = np.stack([tx, ty], axis=1)  # (N, 2, 3)
            frame = [((2 * j, 2 * j + 1, 2 * N + j), np.stack([tx[j], ty[j], n_in[j]]))
                     for j in range(N)]
        self.tangents = tangents
        self.coords = np.array([bodies[nd[1]].node_coordinates[nd[2]] for nd in nodes])

        # rows of the map u = P z + P_D u_D, as dicts {column: coef}; columns: z then held
        rows: dict[int, dict] = {}
        frame_of = {}  # dof -> {z column: coefficient} (u_c = sum of frame vectors' c-th parts)
        for j, (_kind, k, node, _nrm, _pb, _pn) in enumerate(nodes):
            cols, vecs = frame[j]
            for c in range(dim):
                frame_of[int(node_gdofs[k][node, c])] = {col: vecs[a, c] for a, col in
                                                        enumerate(cols)}
        iface = {}
        for kind, k, node, _nrm, pb, pn in nodes:
            if kind == "interface":
                for c in range(dim):
                    iface[int(node_gdofs[k][node, c])] = int(node_gdofs[pb][pn, c])
        held_list = sorted(held)
        self.held_list = held_list
        held_col = {d: nc + n_full + i for i, d in enumerate(held_list)}  # provisional
        n_int = 0
        int_col = {}
        for d in range(n_full):
            if d in held or d in alias or d in frame_of:
                continue
            int_col[d] = nc + n_int
            n_int += 1
        for d, fr in frame_of.items():
            if d not in iface:
                rows[d] = dict(fr)
        for d in held_list:
            rows[d] = {held_col[d]: 1.0}
        for d, col in int_col.items():
            rows[d] = {col: 1.0}

        def resolve(d, depth=0):
            if d in rows:
                return rows[d]
            if depth > 50:
                raise InputError("periodic / interface constraints form a cycle")
            if d in alias:
                r = dict(resolve(alias[d], depth + 1))
            elif d in iface:
                r = dict(resolve(iface[d], depth + 1))
                for col, coef in frame_of[d].items():
                    r[col] = r.get(col, 0.0) + coef
            else:  # pragma: no cover - every dof is classified above
                raise AssertionError(d)
            rows[d] = r
            return r

        for d in range(n_full):
            resolve(d)
        nz = nc + n_int
        I, J, V = [], [], []
        for d, r in rows.items():
            for col, val in r.items():
                I.append(d)
                J.append(col)
                V.append(val)
        I, J, V = np.array(I), np.array(J), np.array(V, dtype=float)
        # compact the held columns to nz .. nz + n_held - 1
        is_h = J >= nz
        J[is_h] = nz + (J[is_h] - (nc + n_full))
        P_all = sp.csr_matrix((V, (I, J)), shape=(n_full, nz + len(held_list)))
        self.P, self.P_D = P_all[:, :nz].tocsc(), P_all[:, nz:].tocsc()
        self.nz, self.n_int, self.n_full = nz, n_int, n_full
        self._check_support(held, alias)

        # assembly
        self.K_full = sp.block_diag([b.stiffness() for b in bodies], format="csr")
        self.M_full = (sp.block_diag([b.mass() for b in bodies], format="csr")
                       if mass else None)
        self.t_assembly = time.perf_counter() - t0
        Kz = (self.P.T @ self.K_full @ self.P).tocsc()
        c, i = slice(0, nc), slice(nc, nz)
        self.Kz = Kz  # contact unknowns first, then the interior DOFs
        self.Kci, self.Kii = Kz[c, i].tocsc(), Kz[i, i].tocsc()
        if mass:
            Mz = (self.P.T @ self.M_full @ self.P).tocsc()
            self.Mcc, self.Mci, self.Mii = Mz[c, c].toarray(), Mz[c, i].tocsc(), Mz[i, i].tocsc()
        coupled = self.Kci if not mass else (abs(self.Kci) + abs(self.Mci))
        self.boundary_layer = np.unique(coupled.nonzero()[1])
        self._lu, self.t_factor = None, 0.0

    @property
    def Kcc(self) -> np.ndarray:
        """The contact block of ``K_z`` (dense)."""
        return self.Kz[: self.nc, : self.nc].toarray()

    @property
    def lu(self):
        """Factor of ``K_ii`` with the boundary layer last (for the condensation; once)."""
        if self._lu is None:
            t1 = time.perf_counter()
            self._lu = factorize(self.Kii, "K_ii", self.boundary_layer)
            self.t_factor = time.perf_counter() - t1
        return self._lu

    def _check_support(self, held, alias):
        """Each connected part of every body must be held, in contact or joined to one."""
        from scipy.sparse.csgraph import connected_components

        supported_parts = []
        parts = []
        support_dofs = set(held)
        for nd in self.nodes:
            for k, node in ((nd[1], nd[2]), (nd[4], nd[5])):
                if k >= 0:  # the node and, at an interface, its partner
                    support_dofs.add(int(self.model.bodies[k].node_dofs[node, 0]
                                         + self.offsets[k]))
        for k, b in enumerate(self.model.bodies):
            m = b.mesh.mesh
            nv = m.p.shape[1]
            rows = np.repeat(np.arange(m.t.shape[1]), m.t.shape[0])
            inc = sp.csr_matrix((np.ones(rows.size), (rows, m.t.T.ravel())),
                                shape=(m.t.shape[1], nv))
            n_comp, lab = connected_components(inc.T @ inc, directed=False)
            verts_dofs = b.node_dofs[:nv] + self.offsets[k]
            for comp in range(n_comp):
                dofs = verts_dofs[lab == comp].ravel()
                parts.append((k, comp))
                supported_parts.append(any(int(d) in support_dofs for d in dofs))
        if not all(supported_parts):
            k, comp = parts[supported_parts.index(False)]
            raise InputError(
                f"body {k} (connected part {comp}) has rigid-body modes: it has no Dirichlet "
                "part, no contact node and no interface; hold a boundary (dirichlet=[...]) or "
                "add it to contact"
            )

    # ------------------------------------------------------------------ products
    def guyan_mass(self):
        """``T^T M T`` with ``T = [I; -X]``, ``X = K_ii^-1 K_ic`` (blocked by memory budget)."""
        N2 = self.nc
        Mg = np.array(self.Mcc, copy=True)
        if self.n_int == 0:  # every node is a contact or held node: nothing to condense
            return 0.5 * (Mg + Mg.T)
        Kic, Mic = self.Kci.T.tocsc(), self.Mci.T.tocsc()
        n_i = max(self.n_int, 1)
        if 8 * n_i * N2 <= GUYAN_FULL_BYTES:  # one pass: X in memory
            X = self.lu.solve(Kic.toarray())
            MX = self.Mci @ X
            Mg += -MX - MX.T + X.T @ (self.Mii @ X)
            return 0.5 * (Mg + Mg.T)
        chunk = max(1, int(RHS_BLOCK_BYTES // (3 * 8 * n_i)))
        for s in range(0, N2, chunk):
            cols = slice(s, min(s + chunk, N2))
            X = self.lu.solve(Kic[:, cols].toarray())
            Y1 = self.lu.solve(Mic[:, cols].toarray())
            Y2 = self.lu.solve(self.Mii @ X)
            Mg[:, cols] += -(self.Mci @ X) - self.Kci @ Y1 + self.Kci @ Y2
        return 0.5 * (Mg + Mg.T)

    def load_rhs(self, case: str):
        """``g = P^T (f - K P_D u_D)`` and the held values ``u_D`` of one load case."""
        f = np.zeros(self.n_full)
        uD = np.zeros(len(self.held_list))
        pos = {d: i for i, d in enumerate(self.held_list)}
        for k, b in enumerate(self.model.bodies):
            if case in b.loads:
                fk, pres = b.load_vector(b.loads[case])
                f[self.offsets[k]:self.offsets[k + 1]] += fk
                for d, val in pres.items():
                    uD[pos[int(self.offsets[k] + d)]] = val
        g = self.P.T @ (f - self.K_full @ (self.P_D @ uD))
        return g, uD

    def welded(self, case: str, solve=None):
        """Welded reactions ``(q_w, p_w)`` of a load case (``solve``: ``K_ii^-1``, default the
        condensation's factor)."""
        g, _ = self.load_rhs(case)
        gc, gi = g[: self.nc], g[self.nc:]
        solve = self.lu.solve if solve is None and self.n_int else solve
        r = -(gc - self.Kci @ solve(gi)) if self.n_int else -gc
        nt = self.nc - self.N
        q = r[:nt] if self.dim == 2 else r[:nt].reshape(self.N, 2)
        return q, r[nt:]

    def condensed(self) -> CondensedModel:
        _ = self.lu  # factorized (timed) before the condensation
        t0 = time.perf_counter()
        S = self.Kcc - self.lu.schur_correction(self.Kci.T)
        S = 0.5 * (S + S.T)
        Mg = self.guyan_mass() if self.with_mass else None
        welded = {case: self.welded(case) for case in self.model.load_cases}
        t_cond = time.perf_counter() - t0
        cm = CondensedModel(
            model=self.model, K=S, M=Mg, node_coordinates=self.coords, normals=self.normals,
            tangents=self.tangents,
            node_body=np.array([nd[1] for nd in self.nodes]),
            node_index=np.array([nd[2] for nd in self.nodes]),
            node_kind=tuple(nd[0] for nd in self.nodes), welded=welded, from_cache=False,
            dim=self.dim,
            timings={"assembly": self.t_assembly, "factorization": self.t_factor,
                     "condensation": t_cond},
            counts={"n_full_dofs": self.n_full, "n_interior_dofs": self.n_int,
                    "n_contact_nodes": self.N, "nnz_K_ii": int(self.Kii.nnz)},
        )
        cm._lazy["assembled"] = self
        return cm

    # ------------------------------------------------------------------ recovery
    def displacements(self, zc: np.ndarray, case: str | None, solve=None):
        g, uD = self.load_rhs(case) if case is not None else (np.zeros(self.nz), None)
        gi = g[self.nc:]
        solve = self.lu.solve if solve is None and self.n_int else solve
        zi = solve(gi - self.Kci.T @ zc) if self.n_int else np.zeros(0)
        u = self.P @ np.concatenate([zc, zi])
        if uD is not None:
            u += self.P_D @ uD
        return [u[self.offsets[k]:self.offsets[k + 1]] for k in range(len(self.model.bodies))]
