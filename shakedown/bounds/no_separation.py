"""The no-separation limit by the dual simplex in the coordinates of the ``lam2`` basis.

``max lam`` with the no-separation rows added (MODEL.md s.3, ``docs/conventions.md``): the
``lam2`` vertex is dual feasible for it, so :class:`~.basis_lp.BasisLP` solves it from there
with the extra rows (some of them violated at the start).
"""

from __future__ import annotations

import numpy as np

from .basis_lp import BasisLP


def separation_lp(frame, cs):
    """``max lam`` with the no-separation rows ``sep_G v <= sep_c + lam sep_m`` added (MODEL.md
    s.3), by the dual simplex from the ``lam2`` vertex (where some of them are violated).

    Returns ``(answer, tab)``: the :class:`~.certificates.DenseAnswer` (multipliers on the rows
    of ``tab``: ``[G, -m]``, the separation rows, ``-lam <= 0``, unit norm; the caller checks
    its residuals) -- or ``(None, None)`` if the separation rows are sparse.
    """
    import scipy.sparse as sp

    if sp.issparse(cs.sep_G):
        return None, None
    n, R = cs.n_nodes, len(cs.c)
    A = np.vstack([np.hstack([cs.G, -cs.m[:, None]]), np.hstack([cs.sep_G, -cs.sep_m[:, None]]),
                   np.r_[np.zeros(n), -1.0][None, :]])
    b = np.r_[cs.c, cs.sep_c, 0.0]
    nrm = np.linalg.norm(A, axis=1)
    nrm[nrm == 0] = 1.0
    tab = _Rows(A / nrm[:, None], b / nrm, np.r_[np.zeros(n), 1.0])
    gx = np.linalg.norm(cs.sep_G, axis=1)
    gx[gx == 0] = 1.0
    Gx = np.vstack([cs.sep_G / gx[:, None], np.zeros((1, n))])
    cx = np.r_[cs.sep_c / gx, 0.0]
    mx = np.r_[cs.sep_m / gx, 1.0]  # last: lam >= 0
    lp = BasisLP(frame, tab, extra=(Gx, cx, mx, np.r_[R + np.arange(n), R + n]))
    return lp.solve(None), tab


class _Rows:
    """The rows of an LP in ``v`` (unit norm) as :class:`BasisLP` reads them."""

    def __init__(self, A, b, e):
        self.A, self.b, self.e = A, b, e
        self.R, self.n = A.shape
