"""A dense primal-dual interior point for the cut SOCPs of a coupled system (MODEL.md s.8.3).

The relaxation on cuts ``(i_m, t_m)`` (:mod:`.socp`) in the variables ``x = (u (2N), lam)``:

    max lam   s.t.   s_m = ( b0_i + (E u)_i + lam b1_m,  a0_i + u_i + lam a1_m )  in  SOC_3,
                     lam <= cap ,

has few, densely coupled variables (the residual state ``u``) and many small cones (``N`` nodes
times the cuts of each).  Clarabel factorises its sparse KKT matrix, whose ``E`` block makes a
dense ``3N x 3N`` part, at every iteration.  Here the Newton systems are reduced to the normal
equations ``G^T W^-2 G dx = r`` of size ``2N + 1``: with Nesterov-Todd scalings ``W_m`` (3 x 3
per cone) the cones of a node sum to one 4 x 4 block over ``(ph_i, u_i, lam)`` (``ph = E u``),
and the coupling enters through one BLAS-3 product ``E^T diag(p) E`` (``p_i > 0`` the summed
``(0, 0)`` entries), so an iteration costs ``~ 2 N^3 + (2N)^3 / 3`` flops and ``O(M)`` for the
cones.  Mehrotra's predictor-corrector (Vandenberghe, *The CVXOPT linear and quadratic cone
program solvers*, 2010, sections 2-4; Nesterov & Todd 1997) from an infeasible start, with one
step of iterative refinement on the reduced system.

Accuracy: the normal equations of a second-order cone program become ill-conditioned as the
gap closes (``cond ~ mu^-2``), and the directions lose their accuracy at a per-cone gap
``mu ~ 1e-9`` (measured); the iteration then stops at its best iterate, whose value agrees with
Clarabel's to ``~ 1e-8`` relative.  With ``split=True`` the late iterations solve the Newton
systems in the split augmented form of :mod:`.ipm_split` instead, which reaches relative gaps
of ``~ 1e-12`` (used where the bracket must be closed tighter than the normal equations
allow).  The answer carries no trust of its own:
:func:`.rounds.solve_round` checks the state on the cuts, the multipliers by
:func:`.socp.dual_bound` (cone membership, stationarity) and the gap between the two, and
re-solves with Clarabel when they do not pass.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.linalg.blas import dsyrk

from .socp import LAM_CAP, CutAnswer

#: Stop when the primal / dual residuals and the relative gap are below this.
IPM_TOL = 1e-11
#: Most interior-point iterations.
IPM_MAX_ITER = 80
#: Steps of iterative refinement per Newton solve.
REFINE = 3
#: Best merit (largest of the relative residuals and gap) accepted from a stalled run.
STALL_TOL = 1e-6
#: Best merit of a stalled run still returned as ``"inaccurate"`` (the state is usable).
USABLE_TOL = 1e-3
#: Regularisation of the equilibrated normal matrix (unit diagonal).
REG = 1e-10
#: Neighbourhood of the central path kept by the steps (:func:`_central_step`).
CENTRAL = 1e-3
_J = np.array([1.0, -1.0, -1.0])


def _jdet(x):
    """``x0^2 - |x1|^2`` per cone, shape (M,)."""
    return x[:, 0] ** 2 - x[:, 1] ** 2 - x[:, 2] ** 2


def _jprod(x, y):
    """Jordan product ``x o y = (x . y, x0 y1 + y0 x1)`` per cone."""
    out = np.empty_like(x)
    out[:, 0] = np.einsum("mc,mc->m", x, y)
    out[:, 1:] = x[:, :1] * y[:, 1:] + y[:, :1] * x[:, 1:]
    return out


def _jdiv(lam, r):
    """``w`` with ``lam o w = r`` per cone (``lam`` in the interior)."""
    det = _jdet(lam)
    w = np.empty_like(r)
    w[:, 0] = (lam[:, 0] * r[:, 0] - np.einsum("mc,mc->m", lam[:, 1:], r[:, 1:])) / det
    w[:, 1:] = (r[:, 1:] - w[:, :1] * lam[:, 1:]) / lam[:, :1]
    return w


def _max_step(x, d):
    """Largest ``alpha`` with ``x + alpha d`` in ``SOC_3`` for every cone (``inf`` if none):
    the smallest positive root of ``det(x + alpha d) = 0``."""
    a, c = _jdet(d), _jdet(x)
    b = 2 * (x[:, 0] * d[:, 0] - x[:, 1] * d[:, 1] - x[:, 2] * d[:, 2])
    disc = b * b - 4 * a * c
    ok = disc >= 0
    sq = np.sqrt(np.where(ok, disc, 0.0))
    q = -0.5 * (b + np.where(b >= 0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(q != 0, c / q, np.inf)
        r2 = np.where(a != 0, q / a, np.inf)
    r1 = np.where(ok & (r1 > 0), r1, np.inf)
    r2 = np.where(ok & (r2 > 0), r2, np.inf)
    return float(min(r1.min(initial=np.inf), r2.min(initial=np.inf)))


class _Cuts:
    """The linear map ``G`` of the cuts and of the cap row (``s = h - G x``)."""

    def __init__(self, E, nodes, a1, b1, a0, b0, cap):
        self.E, self.nodes, self.cap = E, nodes, float(cap)
        self.n, self.m = a0.shape[0], nodes.size
        self.col = np.column_stack([b1, a1])  # (M, 3): the lam column of each cut
        self.h = np.column_stack([b0[nodes], a0[nodes]])
        self.rep = np.repeat(np.arange(self.n), 2)
        self.ET_rep = np.ascontiguousarray(E.T[:, self.rep])  # (2N, 2N): E^T R by a product

    def apply(self, u, lam):
        """``G x``: (M, 3) for the cuts and a float for the cap row."""
        gx = np.empty((self.m, 3))
        gx[:, 0] = -(self.E @ u.reshape(-1))[self.nodes]
        gx[:, 1:] = -u[self.nodes]
        gx -= lam * self.col
        return gx, lam

    def adjoint(self, v, vc):
        """``G^T (v, vc)``: ``(du (N, 2), dlam)``."""
        y = np.bincount(self.nodes, weights=v[:, 0], minlength=self.n)
        du = np.column_stack([np.bincount(self.nodes, weights=v[:, c], minlength=self.n)
                              for c in (1, 2)])
        du = -(du + (self.E.T @ y).reshape(self.n, 2))
        return du, vc - float(np.einsum("mc,mc->", self.col, v))

    def normal_matrix(self, Hm, hc, *, signed=False):
        """``G^T diag(Hm, hc) G`` (2N + 1, upper triangle valid) for 3 x 3 blocks ``Hm``;
        ``signed``: ``Hm`` symmetric, possibly indefinite (the ``E^T diag(p) E`` part by two
        rank-k updates, for ``p >= 0`` and ``p < 0``), the matrix full (:mod:`.ipm_split`)."""
        n, nodes = self.n, self.nodes

        def per_node(w):
            return np.bincount(nodes, weights=w, minlength=n)

        Hcol = np.einsum("mab,mb->ma", Hm, self.col)
        p = per_node(Hm[:, 0, 0])
        r = np.column_stack([per_node(Hm[:, 0, 1]), per_node(Hm[:, 0, 2])])
        U = np.stack([per_node(Hm[:, 1, 1]), per_node(Hm[:, 1, 2]), per_node(Hm[:, 2, 2])], 1)
        g = per_node(Hcol[:, 0])
        k = np.column_stack([per_node(Hcol[:, 1]), per_node(Hcol[:, 2])])
        ll = float(np.einsum("ma,ma->", Hcol, self.col)) + hc
        Nm = np.zeros((2 * n + 1, 2 * n + 1), order="F")
        if signed:
            B = Nm[: 2 * n, : 2 * n]
            B[:] = dsyrk(1.0, np.sqrt(np.maximum(p, 0))[:, None] * self.E, trans=1, lower=0)
            B -= dsyrk(1.0, np.sqrt(np.maximum(-p, 0))[:, None] * self.E, trans=1, lower=0)
            B[:] = np.triu(B) + np.triu(B, 1).T
        else:
            Nm[: 2 * n, : 2 * n] = dsyrk(1.0, np.sqrt(p)[:, None] * self.E, trans=1, lower=0)
        ER = self.ET_rep * r.reshape(-1)[None, :]
        Nm[: 2 * n, : 2 * n] += ER + ER.T
        i = np.arange(n)
        Nm[2 * i, 2 * i] += U[:, 0]
        Nm[2 * i, 2 * i + 1] += U[:, 1]
        Nm[2 * i + 1, 2 * i] += U[:, 1]
        Nm[2 * i + 1, 2 * i + 1] += U[:, 2]
        Nm[: 2 * n, 2 * n] = self.E.T @ g + k.reshape(-1)
        if signed:
            Nm[2 * n, : 2 * n] = Nm[: 2 * n, 2 * n]
        Nm[2 * n, 2 * n] = ll
        return Nm


def _nt_scaling(s, z):
    """Nesterov-Todd scaling of every cone: ``W = eta [[w0, w1^T], [w1, I + w1 w1^T / (1 + w0)]]``
    (``w^T J w = 1``), symmetric, with ``W z = W^-1 s``.

    Returns ``(W, Winv, lam)``: (M, 3, 3), (M, 3, 3) and the scaled point ``lam = W z``."""
    ss, zz = np.sqrt(_jdet(s)), np.sqrt(_jdet(z))
    sb, zb = s / ss[:, None], z / zz[:, None]
    gam = np.sqrt(0.5 * (1 + np.einsum("mc,mc->m", sb, zb)))
    w = (sb + zb * _J) / (2 * gam[:, None])
    eta = np.sqrt(ss / zz)
    Wb = np.empty((s.shape[0], 3, 3))
    Wb[:, 0, 0] = w[:, 0]
    Wb[:, 0, 1:] = Wb[:, 1:, 0] = w[:, 1:]
    Wb[:, 1:, 1:] = np.eye(2) + w[:, 1:, None] * w[:, None, 1:] / (1 + w[:, 0])[:, None, None]
    W = eta[:, None, None] * Wb
    Winv = (Wb * np.outer(_J, _J)) / eta[:, None, None]
    return W, Winv, np.einsum("mab,mb->ma", W, z)


def solve_dense(E, nodes, a1, b1, a0, b0, *, u0, lam0=0.0, cap=LAM_CAP, tol=IPM_TOL,
                max_iter=IPM_MAX_ITER, split=False) -> CutAnswer:
    """``max lam`` over the cuts (module docstring) by the dense interior point.

    Parameters
    ----------
    E : ndarray, shape (N, 2N)
        The coupling ``B^T A^-1 diag(f)`` in cone units (:mod:`.data`).
    nodes : ndarray of int, shape (M,)
    a1 : ndarray, shape (M, 2)
    b1 : ndarray, shape (M,)
        Periodic parts of the cuts at their times (load-factor scaled).
    a0 : ndarray, shape (N, 2)
    b0 : ndarray, shape (N,)
    u0 : ndarray, shape (N, 2)
        Starting state (best strictly inside every cone at ``lam0``; any state works).
    lam0 : float
    cap : float
        Upper bound on ``lam`` (reaching it: status ``"unbounded"``).
    split : bool
        Solve the Newton systems in the split augmented form of :mod:`.ipm_split` (accurate
        to a relative gap of ~1e-12 instead of ~1e-8, dearer per iteration) once some cone
        is ill-conditioned (``w0^2 >`` :data:`.ipm_split.SPLIT_LATE`); before that, and
        always with ``split=False``, by the normal equations.

    Returns
    -------
    CutAnswer
        Status ``"optimal"`` (converged, or stalled at a merit below :data:`STALL_TOL`),
        ``"inaccurate"`` (stalled below :data:`USABLE_TOL`), ``"unbounded"`` or ``"failed"``;
        the caller checks it.
    """
    nodes = np.asarray(nodes, int)
    G = _Cuts(E, nodes, np.asarray(a1, float), np.asarray(b1, float), a0, b0, cap)
    n = G.n
    u, lam = np.array(u0, float).reshape(n, 2), float(lam0)
    gx, gc = G.apply(u, lam)
    s, sc = G.h - gx, cap - gc
    shift = max(0.0, -float(np.min(s[:, 0] - np.linalg.norm(s[:, 1:], axis=1))))
    s[:, 0] += shift + 1e-3 * (1 + shift)
    sc = max(sc, 1.0)
    z, zc = np.zeros_like(s), 1.0 / sc
    z[:, 0] = 1.0
    nu = G.m + 1
    hscale = 1.0 + float(np.abs(G.h).max(initial=0.0))
    it, status = 0, "failed"
    W = Winv = lm = None
    best, stalls = (np.inf, u, lam, z, zc, s), 0
    while it < max_iter:
        it += 1
        gx, gc = G.apply(u, lam)
        rz, rzc = gx + s - G.h, gc + sc - cap
        rx_u, rx_l = G.adjoint(z, zc)
        rx_l -= 1.0
        gap = float(np.einsum("mc,mc->", s, z)) + sc * zc
        pres = max(float(np.abs(rz).max(initial=0.0)), abs(rzc) / cap) / hscale
        zmax = max(float(np.abs(z).max(initial=0.0)), zc, 1.0)
        dres = max(float(np.abs(rx_u).max(initial=0.0)), abs(rx_l)) / zmax
        merit = max(pres, dres, gap / max(1.0, abs(lam)))
        if merit < best[0]:
            best = (merit, u.copy(), lam, z.copy(), zc, s.copy())
        if pres <= tol and dres <= tol and gap <= tol * max(1.0, abs(lam)):
            status = "optimal"
            break
        if merit > 1e3 * best[0] or stalls >= 3:  # the normal equations have lost accuracy
            break
        if W is None:
            W, Winv, lm = _nt_scaling(s, z)
        try:
            nt = _Newton(G, W, Winv, lm, sc, zc, split=split)
        except (np.linalg.LinAlgError, ValueError):
            break
        mu = gap / nu
        ll = _jprod(lm, lm)
        aff = nt.solve(-rx_u, -rx_l, -rz, -rzc, -ll, -sc * zc)
        a_aff = min(1.0, nt.max_step(aff))
        gap_aff = float(np.einsum("mc,mc->", s + a_aff * aff[4], z + a_aff * aff[2])) \
            + (sc + a_aff * aff[5]) * (zc + a_aff * aff[3])
        sigma = min(1.0, max(0.0, gap_aff / gap)) ** 3
        # Mehrotra's second-order term (W^-T ds_a) o (W dz_a), in the scaled space
        ds_s, dz_s = nt.scaled(aff)
        bs = -ll - _jprod(ds_s, dz_s)
        bs[:, 0] += sigma * mu
        bsc = -sc * zc - aff[5] * aff[3] + sigma * mu
        d = nt.solve(-rx_u, -rx_l, -rz, -rzc, bs, bsc)
        alpha = nt.central_step(d, nu)
        stalls = stalls + 1 if alpha < 1e-2 else 0
        u, lam = u + alpha * d[0], lam + alpha * d[1]
        z, zc = z + alpha * d[2], zc + alpha * d[3]
        s, sc = s + alpha * d[4], sc + alpha * d[5]
        if not (np.isfinite(lam) and np.all(np.isfinite(z)) and sc > 0 and zc > 0):
            break
        # the scaling updated in the scaled space (CVXOPT's update_scaling): W <- W~ W with W~
        # the NT scaling of the scaled iterates, which are well centred (no cancellation)
        ds_s, dz_s = nt.scaled(d)
        Wt_, Wti, lm = _nt_scaling(lm + alpha * ds_s, lm + alpha * dz_s)
        W, Winv = np.einsum("mab,mbc->mac", Wt_, W), np.einsum("mab,mbc->mac", Winv, Wti)
    merit, u, lam, z, zc, s = best
    if status != "optimal" and merit <= STALL_TOL:
        status = "optimal"  # as accurate as the normal equations allow; the caller certifies
    elif status != "optimal" and merit <= USABLE_TOL:
        status = "inaccurate"  # usable for the cuts and the lower bound; the caller decides
    if status == "optimal" and lam >= 0.999 * cap:
        status = "unbounded"
    return CutAnswer(status, float(lam), u, z, float(zc), it)


class _Newton:
    """The Newton systems of one iteration (scaling ``s = W^T lam``, ``z = W^-1 lam``):

        G^T dz = bx,   G dx + ds = bz,   lam o (W dz + W^-T ds) = bs ,

    reduced to ``G^T W^-1 W^-T G dx = r`` (equilibrated, regularised Cholesky) with
    :data:`REFINE` steps of iterative refinement on the whole system.  The cap row is a
    one-dimensional cone (``W = sqrt(sc / zc)``)."""

    def __init__(self, G, W, Winv, lm, sc, zc, split=False):
        self.G, self.W, self.lm = G, W, lm
        self.WT, self.WinvT = W.transpose(0, 2, 1), Winv.transpose(0, 2, 1)
        self.lmc, self.Wc, self.hc = np.sqrt(sc * zc), np.sqrt(sc / zc), zc / sc
        self.Hm = np.einsum("mab,mcb->mac", Winv, Winv)  # W^-1 W^-T
        if split and _needs_split(W):  # rank-one parts of the active cones kept out of N
            from .ipm_split import SplitSolver

            self.cf = SplitSolver(G, W, self.Hm, self.hc)
            self.split = True
            return
        self.split = False
        Nm = G.normal_matrix(self.Hm, self.hc)
        dg = np.sqrt(np.diag(Nm).copy())
        if not (np.all(dg > 0) and np.all(np.isfinite(dg))):
            raise ValueError("normal matrix with a zero or non-finite diagonal")
        Nm /= dg[:, None]
        Nm /= dg[None, :]  # equilibrated: unit diagonal
        Nm[np.diag_indices_from(Nm)] += REG  # regularised; the refinement removes it
        self.cf = _Scaled(sla.cho_factor(Nm, lower=False, overwrite_a=True,
                                         check_finite=False), dg)

    def _once(self, bx_u, bx_l, bz, bzc, bs, bsc):
        G, n = self.G, self.G.n
        Wt = np.einsum("mab,mb->ma", self.WT, _jdiv(self.lm, bs))
        tc = bsc / self.lmc
        if self.split:
            return self._once_split(bx_u, bx_l, bz, bzc, bz - Wt, bzc - self.Wc * tc)
        au, al = G.adjoint(np.einsum("mab,mb->ma", self.Hm, bz - Wt),
                           self.hc * (bzc - self.Wc * tc))
        dx = self.cf.solve(np.concatenate([(bx_u + au).reshape(-1), [bx_l + al]]))
        ddu, ddl = dx[:-1].reshape(n, 2), dx[-1]
        gdx, gdc = G.apply(ddu, ddl)
        dz = np.einsum("mab,mb->ma", self.Hm, gdx - bz + Wt)
        dzc = self.hc * (gdc - bzc + self.Wc * tc)
        return [ddu, ddl, dz, dzc, bz - gdx, bzc - gdc]

    def _once_split(self, bx_u, bx_l, bz, bzc, c, cc):
        """:meth:`_once` through :class:`.ipm_split.SplitSolver` (``c = bz - W^T (lam \\ bs)``)."""
        G, n, sp_ = self.G, self.G.n, self.cf
        au, al, rt = sp_.newton(bx_u, bx_l, c, cc)
        al += self.hc * cc
        dx, tau = sp_.solve(np.concatenate([(bx_u + au).reshape(-1), [bx_l + al]]), rt)
        ddu, ddl = dx[:-1].reshape(n, 2), dx[-1]
        gdx, gdc = G.apply(ddu, ddl)
        dz = np.einsum("mab,mb->ma", sp_.H0, gdx - c)
        dz[sp_.idx] += sp_.a * tau[:, None]
        dzc = self.hc * (gdc - cc)
        return [ddu, ddl, dz, dzc, bz - gdx, bzc - gdc]

    def solve(self, bx_u, bx_l, bz, bzc, bs, bsc):
        """``(du, dlam, dz, dzc, ds, dsc)``."""
        G = self.G
        d = self._once(bx_u, bx_l, bz, bzc, bs, bsc)
        for _ in range(REFINE):
            gu, gl = G.adjoint(d[2], d[3])
            gdx, gdc = G.apply(d[0], d[1])
            ds_s, dz_s = self.scaled(d)
            e3 = bs - _jprod(self.lm, ds_s + dz_s)
            e3c = bsc - self.lmc * (self.Wc * d[3] + d[5] / self.Wc)
            c = self._once(bx_u - gu, bx_l - gl, bz - gdx - d[4], bzc - gdc - d[5], e3, e3c)
            d = [x + y for x, y in zip(d, c, strict=True)]
        return d

    def scaled(self, d):
        """``(W^-T ds, W dz)`` of a direction."""
        return (np.einsum("mab,mb->ma", self.WinvT, d[4]),
                np.einsum("mab,mb->ma", self.W, d[2]))

    def max_step(self, d):
        """Largest step keeping ``s`` and ``z`` in their cones (in the scaled space, where the
        iterate is well centred and ``det`` loses no digits to cancellation)."""
        ds, dz = self.scaled(d)
        return min(_step(self.lm, self.lmc, ds, d[5] / self.Wc),
                   _step(self.lm, self.lmc, dz, d[3] * self.Wc))

    def central_step(self, d, nu, beta=None):
        """``0.99`` of :meth:`max_step`, shortened until every cone keeps
        ``sqrt(det s det z) >= beta mu`` (a wide neighbourhood of the central path)."""
        beta = CENTRAL if beta is None else beta
        alpha = min(1.0, 0.99 * self.max_step(d))
        ds, dz = self.scaled(d)
        dsc, dzc = d[5] / self.Wc, d[3] * self.Wc
        for _ in range(30):
            xs, xz = self.lm + alpha * ds, self.lm + alpha * dz
            xsc, xzc = self.lmc + alpha * dsc, self.lmc + alpha * dzc
            mu = (float(np.einsum("mc,mc->", xs, xz)) + xsc * xzc) / nu
            dl = np.sqrt(np.maximum(_jdet(xs), 0.0) * np.maximum(_jdet(xz), 0.0))
            if dl.min(initial=np.inf) >= beta * mu and xsc * xzc >= beta * mu:
                break
            alpha *= 0.8
        return alpha


def _needs_split(W):
    """Whether some cone is far enough into the ill-conditioned regime (``w0^2 >``
    :data:`.ipm_split.SPLIT_LATE`) for the split form to pay for itself."""
    from .ipm_split import SPLIT_LATE, split_parts

    return bool(split_parts(W)[2].max(initial=0.0) > SPLIT_LATE)


class _Scaled:
    """``N^-1`` from the Cholesky factor of ``D^-1 N D^-1`` (``D = sqrt(diag N)``)."""

    def __init__(self, cf, dg):
        self.cf, self.dg = cf, dg

    def solve(self, rhs):
        return sla.cho_solve(self.cf, rhs / self.dg, check_finite=False) / self.dg


def _step(x, xc, d, dc):
    a = _max_step(x, d)
    return min(a, -xc / dc) if dc < 0 else a
