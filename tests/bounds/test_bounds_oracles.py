"""Independent oracles for the shakedown bounds (issue 15).

The oracles here share nothing with the engine but MODEL.md s.3:

* the extreme constraints are assembled in the test from the definitions (``I_j``, ``II_j`` and
  their extreme positions over the cycle: closed form ``-sqrt(a^2 + b^2)`` for one harmonic,
  the minimum over the samples for sampled loads), not taken from ``extreme_constraints``;
* ``lam2`` and every activity interval by scipy's ``linprog`` on that assembly;
* ``lam1`` by a route without LPs: for two nodes ``H(lam)`` is a polygon and a constraint is
  active iff its line meets the polygon, decided by clipping the line against the other
  half-planes; ``lam1`` is bracketed by bisection on that predicate;
* the dense-LP certificate (``kkt_residuals`` / ``batch_residuals``) is fed deliberately wrong
  answers and must flag each one.

Tolerances: the hand assembly repeats the engine's arithmetic on the same numbers, so it agrees
to round-off (1e-13 relative, 1e-12 for the hypot of the harmonic extremes).  The engine
certifies its LP answers to 1e-7 (``dense_lp.CERT_TOL``) and its
vertices agree with exact ones to ~1e-12 on these well-conditioned systems; scipy's HiGHS
works to its feasibility tolerance 1e-7, hence 1e-6 relative between the two.  The bisection
stops at 1e-10 relative.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import shakedown as sd
from shakedown.bounds import dense_lp


# ---------------------------------------------------------------------- the assembly, by hand
def constraints_from_model(system, q0, p0, q_of_t, p_of_t, harmonic=None):
    """Rows ``G v <= c + lam m`` of MODEL.md s.3, row k < N: I_k, k >= N: II_{k-N}.

    I_j:  ((A - f B^T) v)_j <= f p_w_j - q_w_j ;  II_j: -((A + f B^T) v)_j <= f p_w_j + q_w_j.
    The extreme offset is the minimum over the cycle of the right-hand side's periodic part:
    for one harmonic (a cos + b sin) it is -sqrt(a^2 + b^2); for samples, over the samples.
    """
    A, B, f = system.A, system.B, system.friction
    G = np.vstack([A - np.diag(f) @ B.T, -(A + np.diag(f) @ B.T)])
    c = np.concatenate([f * p0 - q0, f * p0 + q0])
    if harmonic is not None:
        qc, qs, pc, ps = harmonic
        aI, bI = f * pc - qc, f * ps - qs
        aII, bII = f * pc + qc, f * ps + qs
        m = -np.sqrt(np.concatenate([aI**2 + bI**2, aII**2 + bII**2]))
    else:
        rI = f * p_of_t - q_of_t  # (S, N)
        rII = f * p_of_t + q_of_t
        m = np.concatenate([rI.min(axis=0), rII.min(axis=0)])
    return G, c, m


def lp_lam(G, c, m, sense, tight=None):
    """max (sense=-1) or min (sense=+1) lam over {(v, lam): G v - m lam <= c, lam >= 0}, with
    row ``tight`` held with equality; nan if infeasible."""
    n = G.shape[1]
    Aub = np.hstack([G, -m[:, None]])
    kw = {}
    if tight is not None:
        keep = np.arange(len(c)) != tight
        kw = dict(A_eq=Aub[[tight]], b_eq=c[[tight]])
        Aub, cc = Aub[keep], c[keep]
    else:
        cc = c
    obj = np.r_[np.zeros(n), float(sense)]
    res = linprog(obj, A_ub=Aub, b_ub=cc, bounds=[(None, None)] * n + [(0, None)],
                  method="highs", **kw)
    if res.status == 2:
        return np.nan
    assert res.status == 0, res.message
    return float(res.x[-1])


def line_meets_polygon(G, b, k, tol):
    """Does {v in R^2: G v <= b} meet the line G_k v = b_k?  (No LP: clip the line.)"""
    g = G[k]
    p0 = g * b[k] / (g @ g)  # a point on the line
    d = np.array([-g[1], g[0]])  # its direction
    lo, hi = -np.inf, np.inf
    for i in range(len(b)):
        if i == k:
            continue
        a, r = G[i] @ d, b[i] - G[i] @ p0  # constraint on the line parameter s: a s <= r
        scale = tol * (np.abs(G[i]).sum() * (1 + np.abs(p0).max()) + abs(b[i]))
        if abs(a) <= 1e-14 * np.abs(G[i]).sum():
            if r < -scale:
                return False
        elif a > 0:
            hi = min(hi, (r + scale) / a)
        else:
            lo = max(lo, (r + scale) / a)
    return lo <= hi


def lam1_by_bisection(G, c, m, lam_max):
    """lam1 = sup{lam: every constraint active on [0, lam]} (two nodes), by bisection on the
    clipping predicate.  Assumes all constraints active at 0 (checked)."""
    def all_active(lam):
        b = c + lam * m
        return all(line_meets_polygon(G, b, k, 1e-12) for k in range(len(c)))

    assert all_active(0.0)
    if all_active(lam_max):
        return lam_max
    lo, hi = 0.0, lam_max
    while hi - lo > 1e-10 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if all_active(mid) else (lo, mid)
    return 0.5 * (lo + hi)


def harmonic_problem(n, seed, coupling):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n)) / np.sqrt(2 * n)
    K = M @ M.T + np.eye(2 * n)
    f = rng.uniform(0.2, 0.6, n)
    system = sd.DiscreteSystem(K[:n, :n], coupling * K[:n, n:], K[n:, n:], f)
    q0, p0 = 0.1 * rng.standard_normal(n), 1 + rng.random(n)
    qc, qs, pc = rng.standard_normal((3, n))
    pc = 0.3 * pc
    ps = np.zeros(n)
    load = sd.LoadCycle.from_harmonics(q0, p0, q_cos=qc, q_sin=qs, p_cos=pc)
    return system, load, (q0, p0, qc, qs, pc, ps)


# ---------------------------------------------------------------------- assembly and lam2
@pytest.mark.parametrize("units", [1.0, 1e-6, 3.3e9])
@pytest.mark.parametrize("seed", range(3))
def test_extreme_constraints_match_the_definitions(seed, units):
    """Harmonic loads (closed-form extremes) and sampled loads (extremes over the samples); the
    engine's G, c, m equal the hand assembly, in any units of force (stiffness and loads scaled
    together leave v unchanged, G and c scale, m scales)."""
    system, load, (q0, p0, qc, qs, pc, ps) = harmonic_problem(3, seed, 0.5)
    sysu = sd.DiscreteSystem(units * system.A, units * system.B, units * system.C,
                             system.friction)
    loadu = sd.LoadCycle.from_harmonics(units * q0, units * p0, q_cos=units * qc,
                                        q_sin=units * qs, p_cos=units * pc)
    cs = sd.bounds.extreme_constraints(sysu, loadu)
    G, c, m = constraints_from_model(sysu, units * q0, units * p0, None, None,
                                     harmonic=(units * qc, units * qs, units * pc, units * ps))
    # the same arithmetic on numbers of size ~units: round-off 1e-15 relative
    np.testing.assert_allclose(cs.G, G, rtol=1e-13, atol=1e-13 * units)
    np.testing.assert_allclose(cs.c, c, rtol=1e-13, atol=1e-13 * units)
    np.testing.assert_allclose(cs.m, m, rtol=1e-12, atol=1e-13 * units)
    rng = np.random.default_rng(seed + 100)
    q1, p1 = rng.standard_normal((2, 7, 3))
    sampled = sd.LoadCycle.from_samples(units * q0, units * p0, units * q1, units * p1)
    cs = sd.bounds.extreme_constraints(sysu, sampled)
    G, c, m = constraints_from_model(sysu, units * q0, units * p0, units * q1, units * p1)
    np.testing.assert_allclose(cs.m, m, rtol=1e-13, atol=1e-13 * units)
    np.testing.assert_allclose(cs.c, c, rtol=1e-13, atol=1e-13 * units)


@pytest.mark.parametrize("n,seed", [(2, 0), (3, 1), (5, 2), (8, 3)])
def test_lam2_and_activity_intervals_against_linprog_on_the_hand_assembly(n, seed):
    system, load, (q0, p0, qc, qs, pc, ps) = harmonic_problem(n, seed, 0.5)
    G, c, m = constraints_from_model(system, q0, p0, None, None, harmonic=(qc, qs, pc, ps))
    b = sd.shakedown_bounds(system, load, intervals=True)
    assert b.lam2 == pytest.approx(lp_lam(G, c, m, -1), rel=1e-6)
    hi = np.array([lp_lam(G, c, m, -1, k) for k in range(2 * n)])
    lo = np.array([lp_lam(G, c, m, +1, k) for k in range(2 * n)])
    np.testing.assert_allclose(b.lam_high, hi, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(b.lam_low, lo, rtol=1e-6, atol=1e-9)
    if n <= 3:  # and by vertex enumeration of {(v, lam)} on the hand assembly (no LP at all)
        from types import SimpleNamespace

        from test_bounds import brute_force

        lam2_v, lo_v, hi_v = brute_force(SimpleNamespace(n_nodes=n, G=G, c=c, m=m))
        assert b.lam2 == pytest.approx(lam2_v, rel=1e-8)
        np.testing.assert_allclose(b.lam_high, hi_v, rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(b.lam_low, lo_v, rtol=1e-8, atol=1e-12)
    # lam1 from the intervals (MODEL.md s.3 definition), if every constraint is active at 0
    if np.all(lo <= 1e-9):
        lam1 = min(np.nanmin(hi), b.lam2)
        assert b.lam1 == pytest.approx(lam1, rel=1e-6)
        if b.lam1 < b.lam2 * (1 - 1e-6):
            assert b.lam_high[b.limiting_constraint] == pytest.approx(b.lam1, rel=1e-6)


@pytest.mark.parametrize("seed", range(6))
def test_lam1_of_two_nodes_by_clipping_without_lp(seed):
    """Coupled two-node systems (lam1 < lam2 in the window the seed's Fig. 4 describes)."""
    system, load, (q0, p0, qc, qs, pc, ps) = harmonic_problem(2, seed, 0.9)
    G, c, m = constraints_from_model(system, q0, p0, None, None, harmonic=(qc, qs, pc, ps))
    b = sd.shakedown_bounds(system, load)
    lam1 = lam1_by_bisection(G, c, m, b.lam2)
    assert b.lam1 == pytest.approx(lam1, rel=1e-8, abs=1e-10)


def test_lam1_below_lam2_in_the_window_cases():
    # premise of the test above: some of its systems have lam1 < lam2 (otherwise picking the
    # wrong limiting constraint would go unseen)
    gaps = []
    for seed in range(6):
        system, load, _ = harmonic_problem(2, seed, 0.9)
        b = sd.shakedown_bounds(system, load)
        gaps.append(b.lam2 - b.lam1)
    assert sum(g > 1e-3 for g in gaps) >= 2, gaps


# ---------------------------------------------------------------------- certificates
def small_lp():
    """max x0 + x1  s.t.  x0 <= 1, x1 <= 2, x0 + x1 <= 2.5, -x0 <= 0, -x1 <= 0."""
    A = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    b = np.array([1.0, 2.0, 2.5, 0.0, 0.0])
    e = np.array([1.0, 1.0])
    return A, b, e


def test_certificate_accepts_a_true_optimum_and_flags_wrong_answers():
    A, b, e = small_lp()
    # optimum: any x on the face x0 + x1 = 2.5 within the box; y = (0, 0, 1, 0, 0)
    x, y = np.array([1.0, 1.5]), np.array([0.0, 0.0, 1.0, 0.0, 0.0])
    assert max(dense_lp.kkt_residuals(A, b, e, x, y)) <= 1e-15
    cert = dense_lp.CERT_TOL
    wrong = {
        # infeasible point (violates row 0)
        "primal": (np.array([1.5, 1.0]), y, 0),
        # negative multiplier on an inequality row
        "dual sign": (x, np.array([-0.5, -0.5, 1.5, 0.0, 0.0]), 1),  # A^T y = e still holds
        # multipliers that do not reproduce the objective (stationarity)
        "stationarity": (x, np.array([1.0, 0.0, 0.0, 0.0, 0.0]), 2),
        # feasible non-optimal point with multipliers on a slack row (complementarity):
        # x = (0.5, 0.5) and y = (1, 1, 0, 0, 0) satisfy A^T y = e, y >= 0, but rows 0, 1 slack
        "complementarity": (np.array([0.5, 0.5]), np.array([1.0, 1.0, 0.0, 0.0, 0.0]), 3),
    }
    for name, (xw, yw, which) in wrong.items():
        res = dense_lp.kkt_residuals(A, b, e, xw, yw)
        assert res[which] > 100 * cert, (name, res)
        # the batched version used by the dual simplex flags it too (unit-norm rows)
        rn = np.linalg.norm(A, axis=1)
        batch = dense_lp.batch_residuals(A / rn[:, None], b / rn, e, xw[None, :],
                                         (yw * rn)[None, :], np.zeros((1, len(b)), bool))
        assert batch[0, which] > 100 * cert, (name, batch)
        assert max(batch[0]) > cert


def test_dense_answers_certified_as_optimal_are_optimal():
    """Answers returned as optimal carry residuals <= CERT_TOL, and they are right (linprog)."""
    rng = np.random.default_rng(4)
    n, R = 5, 14
    A = np.vstack([rng.standard_normal((R, n)), np.eye(n), -np.eye(n)])
    b = np.r_[rng.random(R) + 0.1, np.full(2 * n, 3.0)]
    e = rng.standard_normal(n)
    ans, tab = dense_lp.solve_max(A, b, e)
    ref = linprog(-e, A_ub=A, b_ub=b, bounds=[(None, None)] * n, method="highs")
    assert ans.status == "optimal" and max(ans.residuals) <= dense_lp.CERT_TOL
    assert e @ ans.x == pytest.approx(-ref.fun, rel=1e-7)
    for eq, a in zip([(k,) for k in range(6)], dense_lp.batch_dual_simplex(tab, [(k,) for k in range(6)]),
                     strict=True):
        r = linprog(-e, A_ub=A, b_ub=b, A_eq=A[list(eq)], b_eq=b[list(eq)],
                    bounds=[(None, None)] * n, method="highs")
        if r.status == 2:
            assert a.status != "optimal"
            continue
        assert a.status == "optimal" and max(a.residuals) <= dense_lp.CERT_TOL
        assert e @ a.x == pytest.approx(-r.fun, rel=1e-7, abs=1e-9)
