"""The power iteration of seed 000 s.6 for MCEIP (Hassani, Ionescu & Sakki 2007).

Seed 000 eqs. (48)-(53), in the condensed notation of :mod:`.pencil`: given a normalized
"load" ``g_n`` on the slip nodes (the role of the normal stress ``p_n`` of the seed, with
the sign that makes it push the nodes forward), solve the bound-constrained convex QP (49)

    x_{n+1} = argmin_{x >= 0}  1/2 x^T K0 x - g_n^T x          (chi v_t >= 0)

then update (50)-(51): ``h = -K1 x_{n+1}`` (minus the normal reaction the mode induces,
times the friction profile), ``mu_{n+1} = ||g_n|| / ||h||``, ``g_{n+1} = h / ||h||``.  A fixed
point satisfies ``g = -mu K1 x`` and the QP's KKT conditions
``K0 x - g >= 0, x >= 0, x . (K0 x - g) = 0``, i.e. exactly MCEIP.  For a linear operator
this is the power method (it converges to the largest ``|1/mu|``); for the nonlinear one there
is no convergence proof (seed 000 s.6) and different starts may reach different solutions.

Each QP is solved exactly as a non-negative least-squares problem
``min ||R x - R^-T g||`` with ``K0 = R^T R`` (Lawson-Hanson active set, ``scipy.optimize.nnls``).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.optimize import nnls

from ..model import citations
from .linear import restricted_eigenpairs
from .pencil import SlipPencil
from .result import VERIFY_TOL, MCEIPResult, make_result, no_solution


def bound_qp(R: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``argmin_{x >= 0} 1/2 x^T R^T R x - g^T x`` (exact, via NNLS)."""
    b = sla.solve_triangular(R, g, trans="T", check_finite=False)
    try:
        x, _ = nnls(R, b, maxiter=50 * R.shape[0] + 100)
    except RuntimeError:  # pragma: no cover - nnls iteration limit
        x, _ = nnls(R, b, maxiter=500 * R.shape[0] + 1000)
    return x


def power_iteration(
    pencil: SlipPencil,
    *,
    g0=None,
    tol: float = 1e-10,
    maxiter: int = 2000,
    polish: bool = True,
    polish_after: int | None = 10,
    shift="auto",
    verify_tol: float = VERIFY_TOL,
    rng=None,
) -> MCEIPResult:
    """MCEIP by the nonlinear power iteration of seed 000 s.6.

    Parameters
    ----------
    pencil : SlipPencil
    g0 : array_like, shape (n,), optional
        Initial load (default: ones; with ``rng``, uniform random in (0, 1)).
    tol : float
        Stop when ``|mu_{n+1} - mu_n| <= tol mu_n`` and ``||g_{n+1} - g_n||_2 <= tol``
        (seed 000: "stops when ``|mu_{n+1} - mu_n| + ||U_{n+1} - U_n||`` is small").
    maxiter : int
    polish : bool
        After convergence, re-solve the eigenproblem on the converged support (one dense
        eigen-solve of that size) so the verification reaches machine precision; the raw
        iterates stay in ``history``.
    polish_after : int or None
        Support acceleration: once the support of the iterate has not changed for this many
        iterations, try the polished eigenpair on it; stop if it verifies.  The power method
        converges linearly with the ratio of the two largest ``|1/mu|``, which is close to 1
        when the pencil has nearly opposite eigenvalues (a nearly symmetric body: mirroring
        turns ``mu`` into ``-mu``); the iteration then still finds the support quickly.
        ``None``: the plain iteration of the seed.
    shift : float or "auto"
        Shifted operator ``g -> -K1 P(g) + c g`` (same fixed points, ``1/mu`` shifted by
        ``c``).  The seed's iteration is ``c = 0``; it does not converge when ``1/mu*`` and
        ``-1/mu*`` are both eigenvalues (a mirror-symmetric body: mirroring reverses ``chi``,
        i.e. turns ``mu`` into ``-mu``).  A shift ``c > 0`` favours the positive one;
        ``"auto"`` uses ``c = 1 / mu_n`` with the current estimate ``mu_n``.
    verify_tol : float
        Tolerance of the verification.
    rng : numpy.random.Generator or int, optional
        For a random start.

    Returns
    -------
    MCEIPResult
        ``method="power"``; ``history`` holds ``mu_n``; ``iterations`` the QPs solved.
    """
    citations.register("hassani2007")
    n = pencil.size
    R = sla.cholesky(pencil.K0, lower=False, check_finite=False)
    if g0 is not None:
        g = np.asarray(g0, dtype=float).copy()
    elif rng is not None:
        g = np.random.default_rng(rng).uniform(0.0, 1.0, n)
    else:
        g = np.ones(n)
    g /= np.linalg.norm(g)
    history = []
    mu_prev = np.inf
    x = np.zeros(n)
    converged = False
    last_sup, same = None, 0
    for it in range(1, maxiter + 1):
        x = bound_qp(R, g)
        if not np.any(x > 0):
            return no_solution(
                pencil, method="power", status="none", iterations=it, history=history,
                message="the QP returned x = 0 (the load pulls every node backwards): the "
                "iteration collapsed; no solution reached from this start",
            )
        h = -(pencil.K1 @ x)
        hn = np.linalg.norm(h)
        if hn == 0:
            return no_solution(pencil, method="power", iterations=it, history=history,
                               message="K1 x = 0: the mode does not load the normal reactions")
        if shift == 0.0:
            mu = 1.0 / hn  # seed 000 eq. (50) with ||g|| = 1
        else:
            gam = float(g @ h)  # Rayleigh estimate of 1/mu
            mu = 1.0 / gam if gam > 0 else np.inf
            c = (1.0 / mu if np.isfinite(mu) else 0.0) if shift == "auto" else float(shift)
            h = h + c * g
            hn = np.linalg.norm(h)
        history.append(mu)
        g_new = h / hn
        if np.isfinite(mu) and abs(mu - mu_prev) <= tol * mu and np.linalg.norm(g_new - g) <= tol:
            converged = True
            g = g_new
            break
        g, mu_prev = g_new, mu
        sup = x > 1e-6 * x.max()
        if last_sup is not None and np.array_equal(sup, last_sup):
            same += 1
        else:
            same, last_sup = 0, sup
        if polish_after is not None and same >= polish_after and same % polish_after == 0:
            pol = _polish(pencil, x, mu, verify_tol, it, history)
            if pol is not None and pol.verified:
                return pol
    if not converged:
        res = make_result(pencil, mu, x, method="power", tol=verify_tol, iterations=maxiter,
                          history=history)
        from dataclasses import replace

        return replace(res, status="not-converged", verified=False,
                       message=f"no convergence in {maxiter} iterations (last mu = {mu:.6g}); "
                       "the dominant 1/mu may be negative or complex: try method='enumeration' "
                       "or 'active-set'")
    raw = make_result(pencil, mu, x, method="power", tol=verify_tol, iterations=it,
                      history=history, message=f"converged in {it} iterations")
    if not polish:
        return raw
    pol = _polish(pencil, x, mu, verify_tol, it, history)
    if pol is None:
        return raw
    return pol if pol.verified or not raw.verified else raw


def _polish(pencil, x, mu, verify_tol, it, history):
    """The eigenpair of the support of ``x`` nearest ``mu`` (dense solve), verified."""
    J = np.flatnonzero(x > 1e-6 * x.max())
    pairs = [p for p in restricted_eigenpairs(pencil.K0, pencil.K1, J) if p[2]]
    if not pairs:
        return None
    mu_p, xJ, _ = min(pairs, key=lambda p: abs(p[0] - mu))
    xp = np.zeros(pencil.size)
    xp[J] = np.clip(xJ, 0.0, None)
    return make_result(pencil, mu_p, xp, method="power", tol=verify_tol, iterations=it,
                       history=history,
                       message=f"{it} iterations (last raw mu = {mu:.12g}); polished on the "
                       f"support of {J.size} nodes")
