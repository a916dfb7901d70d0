"""The reduced semismooth Newton system of the 3-D step (:mod:`.cone_kernel`, numba).

Per iteration the unknowns are the slips of the slip nodes and the slips and gaps of the
separated ones (:func:`_unknowns`); the matrix has two rows per slip node, ``M F^-1 K_q - g n
K_p`` plus ``c rho_T P F`` on its own slip (``n``, ``c``: the node's direction and factor at
the current point), and the three rows of ``K`` per separated node, restricted to the unknowns
and with the columns scaled to unit diagonal magnitude (``cs``).

The residual of the reduced system at the current point needs no product with the matrix: on a
slip node ``M q~ + c rho_T P v~ = q~ - c P t = q~`` (``P t = 0``), so the rows of ``J x0 - h``
are ``D r' + E v`` per node with ``r' = r - K u_off`` (``u_off``: the components of the point
that the piece sets to zero, usually none) (:func:`_start`).

The matrix of one iteration is kept for the next one of the same call when the piece (slip and
separated nodes) is the same: the rows of a slip node are refreshed only when its ``n`` or ``c``
moved by more than the iteration's forcing term ``eta`` (the kept rows then differ from the exact
ones by less than ``eta`` relative, an error of the size the inexact Newton method allows anyway,
whose ``eta`` keeps a factor 10 of margin to the tolerance); the residual ``r0`` is always the
exact one (:func:`_start`), so the solution is that of the exact Newton equations and only the
step towards it changes by the kept rows.  The solve of a kept matrix ends after one GMRES cycle
or is redone with a fresh matrix (:func:`.cone_linear._krylov` with ``exact=False``).  The
Newton method checks its own residual after every step, as before.  (Two Newton iterations per
warm step are typical; the rows whose directions moved less than ``eta`` are 20-50 % of them at
N = 100.)

With ``single`` the matrix of a GMRES solve is assembled (and kept, and refreshed) in single
precision only (:func:`.cone_linear._krylov`'s products; the preconditioner's blocks are
inverted from it too); when that solve does not converge within one restart cycle the matrix is
assembled in double and the solve goes on from where it got, to the same target
(:mod:`.cone_kernel`, "Precision").
"""

from __future__ import annotations

import numpy as np

from .cone_linear import _block_inverse, _krylov, _preconditioner
from .cone_states import SEPARATED, SLIP, STICK
from .kernel_jit import njit


@njit(cache=True)
def _unknowns(Kn, states, idx, cs):
    """The unknowns of the current piece ``idx`` (indices into ``u``: slips of the slip nodes,
    slips and gaps of the separated ones) and their column scales ``cs`` (unit diagonal
    magnitude before pivoting, any units); returns their number ``m``."""
    m = 0
    for i in range(states.size):
        if states[i] == SLIP:
            idx[m], idx[m + 1] = 3 * i, 3 * i + 1
            m += 2
        elif states[i] == SEPARATED:
            idx[m], idx[m + 1], idx[m + 2] = 3 * i, 3 * i + 1, 3 * i + 2
            m += 3
    for col in range(m):
        cs[col] = 1.0 / np.sqrt(max(abs(Kn[idx[col], idx[col]]), 1e-300))
    return m


@njit(cache=True)
def _slip_rows(J, row, i, Kn, idx, cs, m, nx, ny, c, sx, sy, g, rhoT):
    """Rows ``row, row + 1`` of the reduced matrix for slip node ``i`` with direction ``(nx,
    ny)`` and factor ``c``: ``M F^-1 K_q - g n K_p`` (the node's rows of ``Kn`` at the unknowns
    ``idx``, columns scaled by ``cs``) plus ``c rho_T P F`` on its own slip."""
    pxx, pxy, pyy = 1.0 - nx * nx, -nx * ny, 1.0 - ny * ny
    m11, m12, m22 = 1.0 - c * pxx, -c * pxy, 1.0 - c * pyy
    a1, a2 = m11 / sx[i], m12 / sy[i]
    b1, b2 = m12 / sx[i], m22 / sy[i]
    gx, gy = g[i] * nx, g[i] * ny
    J0, J1 = J[row], J[row + 1]
    Kx, Ky, Kp = Kn[3 * i], Kn[3 * i + 1], Kn[3 * i + 2]
    for col in range(m):
        k = idx[col]
        J0[col] = (a1 * Kx[k] + a2 * Ky[k] - gx * Kp[k]) * cs[col]
        J1[col] = (b1 * Kx[k] + b2 * Ky[k] - gy * Kp[k]) * cs[col]
    cr = c * rhoT[i]
    # the own slip columns sit at the own rows (rows and columns in the same order)
    J[row, row] += cr * pxx * sx[i] * cs[row]
    J[row + 1, row] += cr * pxy * sx[i] * cs[row]
    J[row, row + 1] += cr * pxy * sy[i] * cs[row + 1]
    J[row + 1, row + 1] += cr * pyy * sy[i] * cs[row + 1]


@njit(cache=True)
def _start(Kn, rb, r, u, states, nhat, cfac, sx, sy, g, rhoT, m):
    """The right-hand side ``h`` (m,) of the reduced system and its residual ``r0 = h - J x0``
    at the current point ``(u, r)`` without a product with ``J`` (module docstring)."""
    n = g.size
    rp = r.copy()
    for i in range(n):  # r' = r - K u_off (u_off: what the piece sets to zero)
        a_lo = 0 if states[i] == STICK else (2 if states[i] == SLIP else 3)
        for a in range(a_lo, 3):
            ua = u[3 * i + a]
            if ua != 0.0:
                Ka = Kn[3 * i + a]  # K symmetric: row access
                for j in range(3 * n):
                    rp[j] -= Ka[j] * ua
    h = np.empty(m)
    r0 = np.empty(m)
    row = 0
    for i in range(n):
        if states[i] == SLIP:
            nx, ny = nhat[2 * i], nhat[2 * i + 1]
            c = cfac[i]
            pxx, pxy, pyy = 1.0 - nx * nx, -nx * ny, 1.0 - ny * ny
            m11, m12, m22 = 1.0 - c * pxx, -c * pxy, 1.0 - c * pyy
            a1, a2 = m11 / sx[i], m12 / sy[i]
            b1, b2 = m12 / sx[i], m22 / sy[i]
            gx, gy = g[i] * nx, g[i] * ny
            k = 3 * i
            h[row] = -(a1 * rb[k] + a2 * rb[k + 1] - gx * rb[k + 2])
            h[row + 1] = -(b1 * rb[k] + b2 * rb[k + 1] - gy * rb[k + 2])
            cr = c * rhoT[i]
            vx, vy = sx[i] * u[k], sy[i] * u[k + 1]
            r0[row] = -(a1 * rp[k] + a2 * rp[k + 1] - gx * rp[k + 2] + cr * (pxx * vx + pxy * vy))
            r0[row + 1] = -(b1 * rp[k] + b2 * rp[k + 1] - gy * rp[k + 2]
                            + cr * (pxy * vx + pyy * vy))
            row += 2
        elif states[i] == SEPARATED:
            for a in range(3):
                h[row] = -rb[3 * i + a]
                r0[row] = -rp[3 * i + a]
                row += 1
    return h, r0


@njit(cache=True)
def new_buffers(n, single=True):
    """The buffers of :func:`_newton_point` for ``n`` nodes: ``(idx, cs, Jbuf, J32buf, tally)``,
    the unknowns, their column scales and room for reduced matrices of up to ``2n`` unknowns
    (larger ones are allocated; fresh pages for every matrix cost more than its assembly), in
    double and (``single``; else empty) in single precision for the Krylov solver's products,
    and the counts of single-precision solves tried and redone in double
    (:func:`.cone_kernel.newton_cached` stops trying them when most were redone)."""
    return (np.empty(3 * n, np.int64), np.empty(3 * n), np.empty(4 * n * n),
            np.empty(4 * n * n if single else 0, np.float32), np.zeros(2, np.int64))


@njit(cache=True)
def new_kept(n):
    """No matrix kept (see :func:`_newton_point`)."""
    return (np.empty((0, 0)), np.empty((0, 3)), np.empty(n + 1, np.int64),
            np.full(n, -1, np.int8), np.zeros((n, 3)), np.empty((0, 0), np.float32))


@njit(cache=True)
def _size(states):
    """The number of unknowns of the reduced system of the piece ``states`` (2 per slip node, 3
    per separated one) and the number of its node blocks."""
    m = 0
    nb = 0
    for i in range(states.size):
        if states[i] == SLIP or states[i] == SEPARATED:
            m += 2 if states[i] == SLIP else 3
            nb += 1
    return m, nb


@njit(cache=True)
def _newton_point(Kn, rb, r, sx, sy, g, rhoT, states, nhat, cfac, unew, dense_max, u, eta,
                  buffers, kept, single=False):
    """The reduced semismooth Newton step of the current piece at ``(u, r)``: ``unew`` (3N,);
    returns ``(ok, kept)``, ``ok`` False when the reduced matrix is singular.  ``eta``: the
    forcing term of the linear solve (:func:`.cone_linear._krylov`); ``buffers``:
    :func:`new_buffers`.  ``kept = (J, Pinv, starts, states, dirs, J32)``: the previous
    iteration's matrix (in double, or in single precision as ``J32``) and preconditioner, the
    piece and the ``(nx, ny, c)`` per node its rows were built with (:func:`new_kept`: none),
    reused when the piece is the same and the matrix larger than ``dense_max`` (module
    docstring).  ``single``: assemble the matrix of a GMRES solve in single precision (module
    docstring)."""
    n = g.size
    m, nb = _size(states)
    unew[:] = 0.0
    if m == 0:
        return True, kept
    idx, cs, Jbuf, J32buf, _ = buffers
    J, Pinv, starts, kst, dirs, J32 = kept
    none32 = J32buf[:0].reshape((0, 0))
    # single precision: the matrix is assembled in single precision only (Krylov products)
    fast = single and m > dense_max and J32buf.size > 0
    reuse = m > dense_max and (J32.shape[0] if fast else J.shape[0]) == m
    for i in range(n):
        if not reuse:
            break
        if states[i] != kst[i]:
            reuse = False
    if reuse:  # the same piece: idx and cs are those of the kept matrix
        if fast:
            _refresh(J32, Pinv, starts, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT,
                     dirs, eta)
        else:
            _refresh(J, Pinv, starts, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT,
                     dirs, eta)
        h, r0 = _start(Kn, rb, r, u, states, nhat, cfac, sx, sy, g, rhoT, m)
        x, ok = _krylov(J, h, r0, _point(u, idx, cs, m), eta, np.sqrt(np.sum(h * h)), Pinv,
                        starts, nb, False, J32 if fast else none32)
        if ok:
            return _scatter(x, idx, cs, m, unew), kept
    # a fresh matrix (in the buffer: the kept one is replaced)
    _unknowns(Kn, states, idx, cs)
    dirs = np.zeros((n, 3))
    h, r0 = _start(Kn, rb, r, u, states, nhat, cfac, sx, sy, g, rhoT, m)
    hn = np.sqrt(np.sum(h * h))
    x = _point(u, idx, cs, m)
    xs = x
    if fast:  # a solve that does not converge in one restart cycle goes on in double below
        J32 = (J32buf[:m * m].reshape((m, m)) if m * m <= J32buf.size
               else np.empty((m, m), np.float32))
        _assemble(J32, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT, dirs)
        Pinv, starts, nb = _preconditioner(J32, states, n)
        J = Jbuf[:0].reshape((0, 0))
        xs, ok = _krylov(J, h, r0, x, eta, hn, Pinv, starts, nb, False, J32)
        if ok:
            return _scatter(xs, idx, cs, m, unew), (J, Pinv, starts, states.copy(), dirs, J32)
    J = Jbuf[:m * m].reshape((m, m)) if m * m <= Jbuf.size else np.empty((m, m))
    _assemble(J, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT, dirs)
    if m <= dense_max:  # LU; never reused (and the buffer's old matrix is gone)
        return _scatter(np.linalg.solve(J, h), idx, cs, m, unew), new_kept(n)
    Pinv, starts, nb = _preconditioner(J, states, n)
    if fast:  # from where the single-precision cycle got, to the same target
        rx = h - J @ xs
        rn = np.sqrt(np.sum(rx * rx))
        etx = eta * np.sqrt(np.sum(r0 * r0)) / rn if rn > 0.0 else 1.0
        x, ok = _krylov(J, h, rx, xs, etx, hn, Pinv, starts, nb, True, none32)
    else:
        x, ok = _krylov(J, h, r0, x, eta, hn, Pinv, starts, nb, True, none32)
    return _scatter(x, idx, cs, m, unew), (J, Pinv, starts, states.copy(), dirs, none32)


@njit(cache=True)
def _point(u, idx, cs, m):
    """The current point in the scaled unknowns, ``u[idx] / cs``."""
    x0 = np.empty(m)
    for col in range(m):
        x0[col] = u[idx[col]] / cs[col]
    return x0


@njit(cache=True)
def _assemble(J, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT, dirs):
    """The reduced matrix of the piece ``states`` into ``J`` (double or single precision), and
    the ``(nx, ny, c)`` per slip node its rows are built with into ``dirs``."""
    row = 0
    for i in range(states.size):
        if states[i] == SLIP:
            nx, ny, c = nhat[2 * i], nhat[2 * i + 1], cfac[i]
            _slip_rows(J, row, i, Kn, idx, cs, m, nx, ny, c, sx, sy, g, rhoT)
            dirs[i, 0], dirs[i, 1], dirs[i, 2] = nx, ny, c
            row += 2
        elif states[i] == SEPARATED:
            for a in range(3):
                Ka = Kn[3 * i + a]
                for col in range(m):
                    J[row, col] = Ka[idx[col]] * cs[col]
                row += 1


@njit(cache=True)
def _refresh(J, Pinv, starts, Kn, states, nhat, cfac, idx, cs, m, sx, sy, g, rhoT, dirs, eta):
    """The rows of a kept matrix ``J`` (and their preconditioner blocks) of the slip nodes whose
    ``(nx, ny, c)`` moved by more than ``eta`` since they were built (module docstring)."""
    row = 0
    b = 0
    for i in range(states.size):
        if states[i] == SLIP:
            nx, ny, c = nhat[2 * i], nhat[2 * i + 1], cfac[i]
            if max(abs(nx - dirs[i, 0]), abs(ny - dirs[i, 1]), abs(c - dirs[i, 2])) > eta:
                _slip_rows(J, row, i, Kn, idx, cs, m, nx, ny, c, sx, sy, g, rhoT)
                _block_inverse(J, Pinv, starts, b)
                dirs[i, 0], dirs[i, 1], dirs[i, 2] = nx, ny, c
            row += 2
            b += 1
        elif states[i] == SEPARATED:  # rows independent of the directions
            row += 3
            b += 1


@njit(cache=True)
def _scatter(x, idx, cs, m, unew):
    """``unew[idx] = x cs``; False if not finite (a singular matrix)."""
    for col in range(m):
        v = x[col] * cs[col]
        if not np.isfinite(v):
            return False
        unew[idx[col]] = v
    return True


__all__ = ["_newton_point", "_unknowns", "_start", "_size", "new_buffers", "new_kept"]
