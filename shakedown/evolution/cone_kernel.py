"""Compiled semismooth Newton method of the 3-D implicit step (MODEL.md s.8.4).

The step at ``t_{k+1}`` from slips ``v_k``: unknowns ``u_i = (dv_ix, dv_iy, w_i)`` per node,
reactions ``r_i = (q_ix, q_iy, p_i)``, ``r = r_b + K_n u`` with ``K_n`` the stiffness in node
order (``3i, 3i + 1``: tangential ``x, y``; ``3i + 2``: normal) and ``r_b = (q_w + A v_k,
p_w + B^T v_k)``.  Per node the Coulomb law with the (elliptic) cone
``|F_i^-1 q_i| <= g_i p_i``, ``F_i = diag(s_ix, s_iy)`` (``s = f`` and ``g = 1`` for a
frictional node; ``s = 1``, ``g = 0`` for a frictionless one).

Formulation (Alart & Curnier 1991, in the scaled variables ``q~ = F^-1 q``, ``v~ = F dv`` in
which the cone is circular and the maximal-dissipation law reads ``q~ = -R v~ / |v~|``)::

    p  = max(0, p - rho_N w) =: R                      (normal)
    q~ = proj_{disk(g R)}(t),  t = q~ - rho_T v~       (tangential)

``rho_T = k_T / s^2``, ``rho_N = C_ii`` (``k_T``: the node's tangential stiffness), so that both
terms of each argument are forces of the same order.  Each iteration classifies the nodes at
the current point (``p - rho_N w <= 0``: separated; ``|t| <= g R``: stick; else slip), and takes
the semismooth Newton step of that piece.  The step is *reduced*: on a stick node it sets
``dv = 0, w = 0`` (exact, the AC equations are linear there), on a slip node ``w = 0`` and two
rows ``M q~+ - g n p+ + c rho_T P v~+ = 0`` remain (``n = t / |t|``, ``c = g R / |t|``,
``P = I - n n^T``, ``M = I - c P``; derived from the linearization, the right-hand side
vanishes identically), on a separated node ``q+ = 0, p+ = 0``.  The unknowns are the slips of
the slip and separated nodes and the gaps of the separated nodes: a dense system of that size,
solved by LU with partial pivoting (LAPACK through numba) up to ``DENSE_MAX`` unknowns, beyond by
GMRES started from the current point to a relative residual tied to the AC residual (an inexact
Newton method, :func:`.cone_linear._krylov`; the stopping test below is unchanged).  The reduced
system, its residual at the current point and the reuse of an iteration's matrix by the next
one (rows refreshed where the directions moved): :mod:`.cone_reduced`.
Globalisation: backtracking on the
merit ``sum |phi|^2`` of the AC residual (in force units) from the Newton point towards the
current one; the iteration stops when the residual is below ``tol`` of the force scale or stalls.

Precision.  The matrix of a GMRES solve is assembled in single precision only, for its
products (half the memory traffic of the products that dominate the step; a relative
perturbation of ~1e-7 of the Newton matrix, i.e. a slightly more inexact Newton direction);
a solve that does not converge within one restart cycle goes on in double from where it got
(:func:`.cone_reduced._newton_point`), and the attempt continues in double once that happened
or a single-precision direction is not accepted in full or does not reduce ``max |phi|``
tenfold (:func:`newton_cached`); a solver whose single-precision solves mostly had to go on in
double (:data:`TRIES`, an ill-conditioned system) stops trying them.  Everything else is
double: the residual ``phi`` and the stopping test, and the reactions, which are recomputed
from scratch (``r = r_b + K u``) at every full Newton step, so that the answer's equilibrium
holds by construction and needs no second product to be checked (:func:`attempt`; a damped
last step or a guess accepted as it is are checked).

The caller (:class:`~.cone_step.ConeStepSolver`) verifies every answer by its own conditions,
independently of this formulation.  Without numba the same functions run as Python (slow).
"""

from __future__ import annotations

import numpy as np

from .cone_linear import DENSE_MAX
from .cone_reduced import _newton_point, _size, new_buffers, new_kept
from .cone_states import SEPARATED, SLIP, STICK
from .kernel_jit import HAVE_KERNEL, njit

#: Single-precision solves redone in double (and more than half of those tried) after which a
#: solver's later steps use double precision only (:func:`newton_cached`).
TRIES = 8

#: Exit codes of :func:`newton`.
CONVERGED, STALLED, MAX_ITER, SINGULAR = 0, 1, 2, 3


@njit(cache=True)
def _reactions(Kn, rb, u, r):
    """``r = rb + Kn u`` using only the non-zero entries of ``u`` (stick nodes are zero)."""
    m = u.size
    r[:] = rb
    for k in range(m):
        uk = u[k]
        if uk != 0.0:
            for j in range(m):
                r[j] += Kn[k, j] * uk  # K symmetric: row access


@njit(cache=True)
def _classify(r, u, sx, sy, g, rhoT, rhoN, states, phi, nhat, cfac, slack):
    """States at the point ``(u, r)``, the AC residual ``phi`` (force units, (3N,)) and, per slip
    node, ``n = t / |t|`` and ``c = g R / |t|``; returns ``sum phi^2``.  ``slack`` [force]: a
    node whose trial traction exceeds the cone by at most this is taken as stuck (the 2-D active
    set accepts the same, up to its feasibility tolerance, so that slips far below the
    verification tolerance do not linger)."""
    n = g.size
    merit = 0.0
    for i in range(n):
        qx, qy, p = r[3 * i], r[3 * i + 1], r[3 * i + 2]
        vx, vy, w = u[3 * i], u[3 * i + 1], u[3 * i + 2]
        R = p - rhoN[i] * w
        if R <= 0.0:
            states[i] = SEPARATED
            phi[3 * i] = qx
            phi[3 * i + 1] = qy
            phi[3 * i + 2] = p
        else:
            phi[3 * i + 2] = rhoN[i] * w  # p - R
            qtx, qty = qx / sx[i], qy / sy[i]
            tx = qtx - rhoT[i] * sx[i] * vx
            ty = qty - rhoT[i] * sy[i] * vy
            tn = np.sqrt(tx * tx + ty * ty)
            rad = g[i] * R
            if tn <= rad + slack / min(sx[i], sy[i]):
                states[i] = STICK
                phi[3 * i] = sx[i] * (qtx - tx)  # = rho_T s^2 dv: a force
                phi[3 * i + 1] = sy[i] * (qty - ty)
            else:
                states[i] = SLIP
                nx, ny = tx / tn, ty / tn
                nhat[2 * i], nhat[2 * i + 1] = nx, ny
                cfac[i] = rad / tn
                phi[3 * i] = sx[i] * (qtx - rad * nx)
                phi[3 * i + 1] = sy[i] * (qty - rad * ny)
        merit += phi[3 * i] ** 2 + phi[3 * i + 1] ** 2 + phi[3 * i + 2] ** 2
    return merit


@njit(cache=True)
def newton(Kn, rb, sx, sy, g, rhoT, rhoN, u, r, states, tol, max_iter, dense_max=DENSE_MAX,
           slack=0.0, scale=0.0, given_r=False):
    """:func:`newton_cached` with fresh buffers (arguments and returns as there)."""
    return newton_cached(Kn, rb, sx, sy, g, rhoT, rhoN, u, r, states, tol, max_iter, dense_max,
                         slack, scale, given_r, new_buffers(g.size))


@njit(cache=True)
def newton_cached(Kn, rb, sx, sy, g, rhoT, rhoN, u, r, states, tol, max_iter, dense_max, slack,
                  scale, given_r, buffers):
    """Semismooth Newton on the Alart-Curnier equations from the guess ``u`` (in place).

    Parameters
    ----------
    Kn : ndarray, shape (3N, 3N)
        Stiffness in node order.
    rb : ndarray, shape (3N,)
        Reactions at ``u = 0`` [force].
    sx, sy, g, rhoT, rhoN : ndarray, shape (N,)
        Cone scaling, cone factor (0 or 1) and the AC parameters (see module docstring).
    u : ndarray, shape (3N,)
        Guess on entry, answer on exit.
    r : ndarray, shape (3N,)
        Reactions of the answer (output); with ``given_r``, on entry the reactions ``rb + Kn u``
        of the guess (known to the caller, e.g. from earlier steps' products with ``Kn``).
    states : ndarray of int8, shape (N,)
        States of the answer's piece (output).
    tol : float
        Absolute stopping tolerance on ``max |phi|`` [force].
    max_iter : int
    dense_max : int
        Reduced systems up to this size by LU, larger ones by GMRES first.
    slack : float
        Stick acceptance beyond the cone [force] (see :func:`_classify`).
    scale : float
        Force scale of the step [force]: with ``scale > 0`` the iterative linear solves of large
        reduced systems are inexact, to the relative residual ``eta = max(min(1e-2, res /
        scale), 0.1 tol / res)`` (``res = max |phi|``: quadratic convergence is kept, and no
        solve goes below a tenth of ``tol``); ``0``: exact solves.
    given_r : bool
        ``r`` holds the guess's reactions on entry (one product with ``Kn`` saved).
    buffers : tuple
        :func:`.cone_reduced.new_buffers` of ``N`` nodes (the solver's, reused by every call).

    Returns
    -------
    code, iterations, residual, constructed : int, int, float, bool
        ``code`` in (CONVERGED, STALLED, MAX_ITER, SINGULAR); ``residual = max |phi|``;
        ``constructed``: ``r`` is the product ``rb + Kn u`` computed from scratch at the final
        ``u`` (a full Newton step, or the start without ``given_r``), so that the answer's
        equilibrium holds by construction (else ``r`` was carried along a damped step or given).
    """
    n = g.size
    phi = np.empty(3 * n)
    nhat = np.zeros(2 * n)
    cfac = np.zeros(n)
    unew = np.empty(3 * n)
    utry = np.empty(3 * n)
    rtry = np.empty(3 * n)
    st_try = np.empty(n, np.int8)
    phi_try = np.empty(3 * n)
    nh_try = np.zeros(2 * n)
    cf_try = np.zeros(n)
    dr = np.empty(3 * n)
    r1 = np.empty(3 * n)
    kept = new_kept(n)
    # single-precision Krylov products until a direction fails, unless most such solves of this
    # solver (its buffers) had to be redone in double (an ill-conditioned system)
    tally = buffers[4]
    single = buffers[3].size > 0 and not (tally[1] >= TRIES and 2 * tally[1] > tally[0])
    constructed = not given_r
    if not given_r:
        _reactions(Kn, rb, u, r)
    merit = _classify(r, u, sx, sy, g, rhoT, rhoN, states, phi, nhat, cfac, slack)
    it = 0
    while it < max_iter:
        if np.max(np.abs(phi)) <= tol:
            return CONVERGED, it, np.max(np.abs(phi)), constructed
        it += 1
        res = np.max(np.abs(phi))
        eta = max(min(1e-2, res / scale), 0.1 * tol / res) if scale > 0.0 else 0.0
        ok, kept = _newton_point(Kn, rb, r, sx, sy, g, rhoT, states, nhat, cfac, unew, dense_max,
                                 u, eta, buffers, kept, single)
        if not ok:
            return SINGULAR, it, np.max(np.abs(phi)), constructed
        used = single and _size(states)[0] > dense_max  # (else solved by LU)
        if used:
            tally[0] += 1
            if kept[5].shape[0] == 0:  # the single-precision solve did not converge and was
                tally[1] += 1  # redone in double: double for the rest of the attempt
                single = used = False
        # the reactions at the Newton point from scratch (r1 = rb + K unew), and the direction
        _reactions(Kn, rb, unew, r1)
        for k in range(3 * n):
            unew[k] -= u[k]
            dr[k] = r1[k] - r[k]
        alpha = 1.0
        accepted = False
        redo = False
        for _ls in range(30):
            for k in range(3 * n):
                utry[k] = u[k] + alpha * unew[k]
                rtry[k] = r[k] + alpha * dr[k] if alpha < 1.0 else r1[k]
            mt = _classify(rtry, utry, sx, sy, g, rhoT, rhoN, st_try, phi_try, nh_try, cf_try,
                           slack)
            full = alpha == 1.0
            if mt <= (1.0 - 1e-4 * alpha) * merit or (full and mt <= merit
                                                     and np.max(np.abs(phi_try)) <= tol):
                accepted = True
                break
            if full and used:  # the direction is recomputed in double before backtracking
                redo = True
                break
            alpha *= 0.5
        if used and (redo or np.max(np.abs(phi_try)) > 0.1 * res):
            single = False  # double precision for the rest of the attempt
        if redo:
            continue
        if not accepted:
            return STALLED, it, np.max(np.abs(phi)), constructed
        constructed = alpha == 1.0
        u[:] = utry
        r[:] = rtry
        states[:] = st_try
        phi[:] = phi_try
        nhat[:] = nh_try
        cfac[:] = cf_try
        merit = mt
    if np.max(np.abs(phi)) <= tol:
        return CONVERGED, it, np.max(np.abs(phi)), constructed
    return MAX_ITER, it, np.max(np.abs(phi)), constructed


@njit(cache=True)
def gauss_seidel(Kn, rb, sx, sy, g, rhoT, rhoN, u, r, states, tol, max_sweeps, local_iter,
                 slack=0.0):
    """Projected block Gauss-Seidel (the fallback): each node's own 3 x 3 problem solved exactly
    by :func:`newton` with the other nodes frozen, sweeps until the global AC residual is below
    ``tol`` [force].  Converges for small enough friction; slow (linear) but independent of the
    global Newton's globalisation.  Returns (code, sweeps, residual) like :func:`newton`."""
    n = g.size
    Kl = np.empty((3, 3))
    rbl = np.empty(3)
    ul = np.empty(3)
    rl = np.empty(3)
    stl = np.empty(1, np.int8)
    phi = np.empty(3 * n)
    nhat = np.zeros(2 * n)
    cfac = np.zeros(n)
    _reactions(Kn, rb, u, r)
    for sweep in range(max_sweeps):
        for i in range(n):
            for a in range(3):
                for b in range(3):
                    Kl[a, b] = Kn[3 * i + a, 3 * i + b]
                ul[a] = u[3 * i + a]
            for a in range(3):  # the reactions without the node's own displacement
                s = r[3 * i + a]
                for b in range(3):
                    s -= Kl[a, b] * ul[b]
                rbl[a] = s
            newton(Kl, rbl, sx[i:i + 1], sy[i:i + 1], g[i:i + 1], rhoT[i:i + 1],
                   rhoN[i:i + 1], ul, rl, stl, 1e-3 * tol, local_iter, 10, slack)
            for b in range(3):
                d = ul[b] - u[3 * i + b]
                if d != 0.0:
                    for j in range(3 * n):
                        r[j] += Kn[3 * i + b, j] * d
                    u[3 * i + b] = ul[b]
        _classify(r, u, sx, sy, g, rhoT, rhoN, states, phi, nhat, cfac, slack)
        res = np.max(np.abs(phi))
        if res <= tol:
            return CONVERGED, sweep + 1, res
    return MAX_ITER, max_sweeps, np.max(np.abs(phi))


__all__ = ["newton", "newton_cached", "new_buffers", "attempt", "gauss_seidel", "STICK", "SLIP",
           "SEPARATED", "HAVE_KERNEL", "CONVERGED", "STALLED", "MAX_ITER", "SINGULAR"]


@njit(cache=True)
def residuals(Kn, rb, sx, sy, g, kT, kN, u, r, F, equilibrium):
    """The compiled twin of :func:`~.cone_step.verify_step` (the same four conditions, same
    scaling; the step solver's per-step check): returns ``(cone, direction, normal,
    equilibrium)``, each dimensionless (equilibrium 0 when not asked)."""
    n = g.size
    cone = 0.0
    direc = 0.0
    normal = 0.0
    eq = 0.0
    for i in range(n):
        qx, qy, p = r[3 * i], r[3 * i + 1], r[3 * i + 2]
        vx, vy, w = u[3 * i], u[3 * i + 1], u[3 * i + 2]
        c = (np.sqrt((qx / sx[i]) ** 2 + (qy / sy[i]) ** 2) - g[i] * p) * min(sx[i], sy[i])
        cone = max(cone, c)
        d = qx * vx + qy * vy + g[i] * p * np.sqrt((sx[i] * vx) ** 2 + (sy[i] * vy) ** 2)
        direc = max(direc, abs(d) * kT[i])
        normal = max(normal, abs(min(kN[i] * w, p)))
    if equilibrium:  # r = rb + K u recomputed with K's rows by BLAS (the solver used columns)
        Ku = Kn @ u
        for j in range(3 * n):
            eq = max(eq, abs(rb[j] + Ku[j] - r[j]))
    return cone / F, direc / (F * F), normal / F, eq / F


@njit(cache=True)
def attempt(Kn, rb, sx, sy, g, rhoT, rhoN, kT, kN, u, r, states, feas_tol, max_iter, dense_max,
            stick_slack, given_r, buffers, equilibrium):
    """One Newton attempt of the step and the verification of its answer in one call (the
    step solver's path, :meth:`~.cone_step.ConeStepSolver.solve_raw`): the force scale ``F =
    max |rb|`` (1 if zero), :func:`newton_cached` to ``tol = 1e-3 feas_tol F`` with the stick
    slack ``stick_slack feas_tol F`` and inexact solves at the scale ``F``, then
    :func:`residuals`.  Arguments as there (``u``, ``r``, ``states`` in place).  The
    equilibrium is recomputed (with ``equilibrium``) only when ``r`` is not the product ``rb + K
    u`` computed from scratch at the answer by the Newton method (a damped last step, or the
    guess accepted with the reactions ``given_r``); else it holds by construction and is
    reported as 0.  Returns ``(code, iterations, F, cone, direction, normal, equilibrium)``."""
    F = 0.0
    for k in range(rb.size):
        F = max(F, abs(rb[k]))
    F = F if F > 0.0 else 1.0
    code, it, _, constructed = newton_cached(
        Kn, rb, sx, sy, g, rhoT, rhoN, u, r, states, 1e-3 * feas_tol * F, max_iter, dense_max,
        stick_slack * feas_tol * F, F, given_r, buffers)
    # equilibrium: by construction when r was computed from scratch at the answer, else checked
    cone, direc, normal, eq = residuals(Kn, rb, sx, sy, g, kT, kN, u, r, F,
                                        equilibrium and not constructed)
    return code, it, F, cone, direc, normal, eq
