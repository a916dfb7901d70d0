"""Helpers of :mod:`.assembly` for 3-D bodies: the stiffness assembled with each local
function's strains computed once per element block, and the outward normals and areas of
boundary facets (triangles and quadrilaterals)."""

from __future__ import annotations

import numpy as np

#: Memory budget [bytes] of the strain arrays of one block of elements in :func:`_voigt_stiffness`.
STRAIN_BLOCK_BYTES = 32 * 2**20


def _voigt_stiffness(basis, D: np.ndarray, pairs):
    """``K_ij = int eps(phi_i) . D eps(phi_j) dx`` (sparse CSR) over the basis' quadrature.

    The same integrals as scikit-fem's ``asm`` of the form ``eps(u) . D eps(v)``, with the
    engineering (Voigt) strains of every local basis function computed once per element block
    instead of once per pair of local functions (a 3-D element has 24-30 local functions:
    576-900 pairs), then ``K_e = sum_q E^T D E dx`` by ``einsum``.
    """
    import scipy.sparse as sp

    nloc = basis.Nbfun
    grads = np.stack([basis.basis[i][0].grad for i in range(nloc)])  # (nloc, d, d, nel, nqp)
    dx = basis.dx
    nel, nqp = dx.shape
    step = max(1, int(STRAIN_BLOCK_BYTES // (8 * len(pairs) * nloc * nqp)))
    data = np.empty((nloc, nloc, nel))
    for s0 in range(0, nel, step):
        e = slice(s0, min(s0 + step, nel))
        g = grads[..., e, :]
        E = np.stack([g[:, p, p] if p == q else g[:, p, q] + g[:, q, p] for p, q in pairs])
        DE = np.einsum("ab,bjeq->ajeq", D, E, optimize=True)
        data[:, :, e] = np.einsum("aieq,ajeq,eq->ije", E, DE, dx[e], optimize=True)
    dofs = basis.element_dofs  # (nloc, nel)
    rows = np.broadcast_to(dofs[:, None, :], data.shape).ravel()
    cols = np.broadcast_to(dofs[None, :, :], data.shape).ravel()
    return sp.coo_matrix((data.ravel(), (rows, cols)), shape=(basis.N, basis.N)).tocsr()


def _facet_normals_3d(m, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals (n_f, 3) and areas (n_f,) of boundary facets of a 3-D mesh
    (triangles: exact; quadrilaterals: the normal of the diagonals' cross product, the area
    of the two triangles split along a diagonal)."""
    P = m.p[:, m.facets[:, facets]]  # (3, n_vertices, n_f)
    if P.shape[1] == 3:
        c = np.cross((P[:, 1] - P[:, 0]).T, (P[:, 2] - P[:, 0]).T)
        area = 0.5 * np.linalg.norm(c, axis=1)
    else:
        # scikit-fem's quadrilateral facets of a hexahedron: vertices in cyclic order
        c = np.cross((P[:, 2] - P[:, 0]).T, (P[:, 3] - P[:, 1]).T)
        t1 = np.cross((P[:, 1] - P[:, 0]).T, (P[:, 2] - P[:, 0]).T)
        t2 = np.cross((P[:, 2] - P[:, 0]).T, (P[:, 3] - P[:, 0]).T)
        area = 0.5 * (np.linalg.norm(t1, axis=1) + np.linalg.norm(t2, axis=1))
    n = c / np.linalg.norm(c, axis=1)[:, None]
    centre = m.p[:, m.t[:, m.f2t[0, facets]]].mean(axis=1).T
    flip = np.sum(n * (P.mean(axis=1).T - centre), axis=1) < 0
    n[flip] *= -1
    return n, area
