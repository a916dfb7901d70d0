"""An upper bound on the 3-D ``lam2`` that holds whatever the multipliers (MODEL.md s.8.3).

The cuts ``m = (i, t)`` of a relaxation read ``s_m = h_m - G_m x`` in ``SOC_3`` with ``x = (u,
lam)`` (:mod:`.socp`).  For *any* multipliers ``z_m`` in ``SOC_3`` and ``y_cap >= 0`` (of
``lam <= cap``), every state feasible for those cuts has ``sum_m z_m . s_m + y_cap (cap - lam)
>= 0`` (the cone is self-dual), i.e.

    lam D  <=  num + r . u ,     D = y_cap - sum_m z_m . (b1_m, a1_m),
                                 num = sum_m z_m . (b0_i, a0_i) + cap y_cap,
                                 r_i = sum_{m at i} z_m12 + (E^T y)_i,  y_i = sum_{m at i} z_m0 .

Exact multipliers have ``r = 0`` and prove ``lam <= num / D``.  Computed ones never do, so the
term ``r . u`` is bounded over the feasible set instead of being ignored:

*A-priori bound on the state.*  Take at every node ``i`` one constraint of the problem (one of
its cuts, or ``t = 0`` for a node without one; any constraint of the semi-infinite problem will
do, since the bound is about ``lam2``): ``|a_i + u_i| <= p_i`` with ``a_i = a0_i + lam
a1_i(t_i)``, ``p_i = b_i + (E u)_i``, ``b_i = b0_i + lam b1_i(t_i)``.  Then ``p_i >= 0``,
``|u_i| <= p_i + |a_i|``, so with Euclidean norms over the nodes and ``e >= ||E||_2``,

    |p| <= |b| + e |u| ,   |u| <= |p| + |a|   =>   |u| <= (|a| + |b|) / (1 - e)    (e < 1),

and, ``lam`` being ``>= 0``, ``|u| <= U0 + lam U1`` with ``U0 = (|a0| + |b0|) / (1 - e)``,
``U1 = (|a1(t)| + |b1(t)|) / (1 - e)``.  Therefore

    lam (D - |r| U1)  <=  num + |r| U0      =>      lam2  <=  (num + |r| U0) / (D - |r| U1)

whenever the denominator is positive (else no bound: ``inf``).  ``e = ||E||_2 < 1`` says that no
residual state wedges the nodes (``|u_i| <= (E u)_i`` at every node only for ``u = 0``); ``e`` is
certified by one Cholesky factorisation (:func:`coupling_norm`, :mod:`shakedown.model.verified`).
For ``e >= 1`` the bound is finite only for ``r = 0`` exactly (uncoupled systems have ``E = 0``).

*Cones.*  Multipliers outside ``SOC_3`` are first moved into it (``z_m0 <- max(z_m0,
|z_m12|)``, rounded up), which only changes ``r``, ``num`` and ``D``; negative ``y_cap`` is set to
0.  So a wrong or perturbed dual (in or out of its cones, stationary or not) gives a weaker
bound, never a wrong one.

*Projection.*  The residual ``r`` is mostly removed first (:func:`polish`): node ``i``'s
residual is taken off the tangential parts of its cuts and the cones restored by raising
``z_m0`` by at most ``|r_i|``, which leaves the residual ``E^T dy``, ``|dy| <= |r|``: one pass
shrinks ``|r|`` by the factor ``e`` (the same condition ``e < 1``).  The polished multipliers
prove a bound close to the exact dual value (the correction costs ``~ r . u*``, not the
worst case ``|r| |u|``), and the rounding-level residual left is charged as above.  The bound
reported is the smaller of those of the given and the polished multipliers (both proven).

*Rounding.*  ``r``, ``num`` and ``D`` are sums of floating-point products; each is widened by
``gamma_k`` times the sum of the absolute values of its terms (Higham, *Accuracy and Stability
of Numerical Algorithms*, 2nd ed., section 3.1), and the final quotient is rounded outwards.
What is not covered: the accuracy of ``E = B^T A^-1 diag(f)`` itself (one backward-stable
Cholesky solve, :mod:`.data`), on which the whole reduced problem rests.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ...model.verified import EPS, certified_upper_eig, gamma


def coupling_norm(E) -> float:
    """A proven upper bound of ``||E||_2`` (``0`` for ``E is None``; ``inf`` if none proven).

    ``||E||_2^2 = lambda_max(E E^T)``: the estimate of a dense symmetric eigensolver on the
    computed ``fl(E E^T)``, proven by a Cholesky factorisation of ``t I - fl(E E^T)``
    (:func:`shakedown.model.verified.certified_upper_eig`), plus the rounding of the product
    (``|fl(E E^T) - E E^T| <= gamma_{2N} |E| |E|^T``, whose norm is at most ``gamma_{2N}
    ||E||_F^2``).
    """
    if E is None:
        return 0.0
    E = np.asarray(E, float)
    n, k = E.shape
    G = E @ E.T
    G = 0.5 * (G + G.T)
    est = float(sla.eigvalsh(G, subset_by_index=[n - 1, n - 1], check_finite=False)[0])
    up = certified_upper_eig(G, est)
    if not np.isfinite(up):
        return np.inf
    fro2 = float(np.einsum("ij,ij->", E, E)) * (1 + gamma(n * k))
    return float(np.sqrt(max(up, 0.0) + gamma(k + 2) * fro2) * (1 + 4 * EPS))


def _up(x):
    """``x`` rounded outwards (towards ``+inf``) by a few units of round-off."""
    return x * (1 + 8 * EPS) if x >= 0 else x * (1 - 8 * EPS)


def residual(data, nodes, z):
    """``r`` (N, 2): the ``u`` rows ``sum_{m at i} z_m12 + (E^T y)_i`` of multipliers ``z``."""
    n = data.n_nodes
    r = np.zeros((n, 2))
    np.add.at(r, nodes, z[:, 1:])
    if data.coupled:
        y = np.bincount(nodes, weights=z[:, 0], minlength=n)
        r += (data.E.T @ y).reshape(n, 2)
    return r


def polish(data, nodes, z, passes=40):
    """Multipliers moved towards the dual feasible set (module docstring, *Projection*).

    Each pass removes node ``i``'s residual ``r_i`` from the tangential parts of its cuts (in
    proportion to their ``z_m0``) and restores the cones by raising ``z_m0`` by at most that
    much, which leaves the residual ``E^T dy`` with ``|dy| <= |r|``: the residual shrinks by
    ``||E||_2`` per pass at least.  Stops when it no longer shrinks.
    """
    z = np.array(z, float).reshape(-1, 3)
    nodes = np.asarray(nodes, int)
    n = data.n_nodes
    z[:, 0] = np.maximum(z[:, 0], np.linalg.norm(z[:, 1:], axis=1))
    y = np.bincount(nodes, weights=z[:, 0], minlength=n)
    cnt = np.bincount(nodes, minlength=n)
    w = np.where(y[nodes] > 0, z[:, 0] / np.where(y[nodes] > 0, y[nodes], 1.0),
                 1.0 / np.maximum(cnt[nodes], 1))
    best, best_z = np.inf, z.copy()
    for _ in range(passes):
        r = residual(data, nodes, z)
        rn = float(np.linalg.norm(r))
        if not rn < 0.5 * best:
            if rn < best:
                best, best_z = rn, z.copy()
            break
        best, best_z = rn, z.copy()
        z[:, 1:] -= w[:, None] * r[nodes]
        z[:, 0] = np.maximum(z[:, 0], np.linalg.norm(z[:, 1:], axis=1))
    return best_z


def certified_bound(data, nodes, times, z, y_cap=0.0, *, cap, e=None):
    """The smaller of :func:`bound_of` the multipliers ``z`` as given and polished
    (:func:`polish`): both are proven bounds (same parameters and returns)."""
    b1, p1 = bound_of(data, nodes, times, z, y_cap, cap=cap, e=e)
    if not np.all(np.isfinite(np.asarray(z, float))) or len(nodes) == 0:
        return b1, p1
    b2, p2 = bound_of(data, nodes, times, polish(data, nodes, z), y_cap, cap=cap, e=e)
    return (b2, p2) if b2 < b1 else (b1, p1)


def bound_of(data, nodes, times, z, y_cap=0.0, *, cap, e=None):
    """``lam2 <= bound`` (nondimensional) from any multipliers (module docstring).

    Parameters
    ----------
    data : ConeData
    nodes : ndarray of int, shape (M,)
    times : ndarray, shape (M,)
        The cuts (cycles).
    z : ndarray, shape (M, 3)
        Multipliers of the cuts (any values; non-finite ones give ``inf``).
    y_cap : float
        Multiplier of ``lam <= cap``.
    cap : float
        The cap of the relaxations (:data:`.socp.LAM_CAP`).
    e : float, optional
        A proven upper bound of ``||E||_2`` (default ``data.coupling_bound``, computed once by
        :func:`coupling_norm`).

    Returns
    -------
    bound : float
        ``inf`` when the multipliers prove nothing.
    parts : dict
        ``"residual"``: the proven ``|r|_2`` after moving ``z`` into its cones, relative to
        ``max |z|``; ``"state_bound"``: ``U0 + lam U1`` at ``lam = bound``; ``"coupling_norm"``:
        ``e``.
    """
    z = np.array(z, float).reshape(-1, 3)
    nodes = np.asarray(nodes, int)
    n, m = data.n_nodes, z.shape[0]
    y_cap = max(float(y_cap), 0.0)
    if not (np.all(np.isfinite(z)) and np.isfinite(y_cap)) or m == 0:
        return np.inf, {"residual": np.inf, "state_bound": np.nan, "coupling_norm": np.nan}
    nz = np.linalg.norm(z[:, 1:], axis=1) * (1 + 4 * EPS)
    z[:, 0] = np.maximum(z[:, 0], nz)  # now z_m in SOC_3 exactly
    a1, b1 = data.periodic(times, nodes)
    col = np.column_stack([b1, a1])
    h = np.column_stack([data.b0[nodes], data.a0[nodes]])
    # residual r (N, 2) and a bound of its rounding error, per entry
    r = np.zeros((n, 2))
    np.add.at(r, nodes, z[:, 1:])
    rabs = np.zeros((n, 2))
    np.add.at(rabs, nodes, np.abs(z[:, 1:]))
    y = np.bincount(nodes, weights=z[:, 0], minlength=n)  # >= 0: every term is
    if data.coupled:
        r = r + (data.E.T @ y).reshape(n, 2)
        rabs = rabs + (np.abs(data.E).T @ y).reshape(n, 2)
    rerr = gamma(m + n + 4) * rabs * (1 + gamma(m + n + 4))
    rnorm = _up(float(np.linalg.norm(r)) + float(np.linalg.norm(rerr)))
    # num and D with their rounding
    k = 3 * m + 2
    num = float(np.einsum("mc,mc->", h, z)) + cap * y_cap
    num_err = gamma(k) * (float(np.einsum("mc,mc->", np.abs(h), np.abs(z))) + cap * y_cap) * 1.01
    D = y_cap - float(np.einsum("mc,mc->", col, z))
    D_err = gamma(k) * (float(np.einsum("mc,mc->", np.abs(col), np.abs(z))) + y_cap) * 1.01
    e = data.coupling_bound if e is None else float(e)
    zs = max(float(np.abs(z).max()), y_cap, 1e-300)
    parts = {"residual": rnorm / zs, "state_bound": np.nan, "coupling_norm": e}
    if rnorm > 0 and not e < 1:
        return np.inf, parts
    U0 = U1 = 0.0
    if rnorm > 0:
        ti = np.zeros(n)
        first = np.full(n, -1)
        first[nodes[::-1]] = np.arange(m)[::-1]  # the first cut of each node
        ti[first >= 0] = np.asarray(times, float)[first[first >= 0]]
        a1n, b1n = data.periodic(ti, np.arange(n))
        inv = _up(1.0 / _up(1.0 - e))
        U0 = _up(_up(float(np.linalg.norm(data.a0)) + float(np.linalg.norm(data.b0))) * inv)
        U1 = _up(_up(float(np.linalg.norm(a1n)) + float(np.linalg.norm(b1n))) * inv)
    den = (D - D_err) - _up(rnorm * U1)
    if not den > 0:
        return np.inf, parts
    numer = _up(num + num_err + _up(rnorm * U0))
    if numer >= 0:
        bound = _up(numer / den)
    else:  # no state with lam >= 0 at all; the largest denominator gives the weakest bound
        bound = _up(numer / (D + D_err))
    parts["state_bound"] = U0 + max(bound, 0.0) * U1
    return float(bound), parts
