"""The reduced Newton system of the 3-D step (shakedown/evolution/cone_reduced.py).

What these tests prove: the residual of the reduced system at the current point, computed
without a product with the matrix (``_start``), is the product with the assembled matrix, also
at points off the piece (stick nodes that still carry a slip, slip nodes with a gap); a matrix
kept from the previous Newton iteration is refreshed exactly on the rows (and preconditioner
blocks) of the nodes whose directions moved by more than the forcing term and nowhere else; and
warm-started steps through the kept matrices reach the answers of exact LU solves in the same
number of Newton iterations, without restarts; the matrices assembled in single precision for
the Krylov products reach the answers of double-precision ones in the same number of Newton
iterations, a single-precision solve that cannot converge goes on in double, and a solver
whose single-precision solves mostly had to go on in double stops trying them.
"""

import itertools

import numpy as np
import pytest
from test_cone_step import random_3d  # (tests/evolution on the path)

import shakedown as sd
from shakedown.evolution import cone_kernel as ck
from shakedown.evolution import cone_reduced as cr
from shakedown.evolution.cone_step import ConeStepSolver


def _point(n=12, seed=5, separation=True):
    """A solver, base reactions and a random point ``u`` (every component non-zero, so that the
    piece sets some of them to zero) with its reactions and classification (friction 1: stick,
    slip and separated nodes)."""
    s, v, q_w, p_w = random_3d(n, seed, friction=1.0, separation=separation)
    sol = ConeStepSolver(s)
    d = sol.data
    rb = sol.base(v, q_w, p_w).ravel()
    rng = np.random.default_rng(seed)
    u = 0.05 * rng.normal(size=3 * n)
    r = rb + d.Kn @ u
    st, phi = np.empty(n, np.int8), np.empty(3 * n)
    nh, cf = np.zeros(2 * n), np.zeros(n)
    F = np.abs(rb).max()
    ck._classify(r, u, d.sx, d.sy, d.g, sol.rhoT, sol.rhoN, st, phi, nh, cf, 0.0)
    assert {ck.STICK, ck.SLIP, ck.SEPARATED} <= set(st.tolist())
    return sol, rb, u, r, st, nh, cf, F


def _assemble(sol, rb, u, r, st, nh, cf, eta=1e-3, buffers=None):
    """The fresh reduced matrix (returned in ``kept`` with ``dense_max = 0``), its ``kept``."""
    d = sol.data
    n = sol.n
    unew = np.empty(3 * n)
    buffers = cr.new_buffers(n) if buffers is None else buffers
    ok, kept = cr._newton_point(d.Kn, rb, r, d.sx, d.sy, d.g, sol.rhoT, st, nh, cf, unew, 0, u,
                                eta, buffers, cr.new_kept(n))
    assert ok
    return np.array(kept[0]), kept


def test_residual_without_a_product_equals_the_product_with_the_assembled_matrix():
    sol, rb, u, r, st, nh, cf, F = _point()
    d = sol.data
    J, _ = _assemble(sol, rb, u, r, st, nh, cf)
    idx, cs = np.empty(3 * sol.n, np.int64), np.empty(3 * sol.n)
    m = cr._unknowns(d.Kn, st, idx, cs)
    assert m == J.shape[0] and np.any(u[3 * np.flatnonzero(st == ck.STICK)] != 0)
    h, r0 = cr._start(d.Kn, rb, r, u, st, nh, cf, d.sx, d.sy, d.g, sol.rhoT, m)
    x0 = u[idx[:m]] / cs[:m]
    ref = h - J @ x0
    assert np.abs(ref).max() > 1e-3 * np.abs(h).max()  # off the piece: not a trivial residual
    np.testing.assert_allclose(r0, ref, rtol=0, atol=1e-12 * np.abs(h).max())


def test_kept_matrix_is_refreshed_exactly_where_the_directions_moved():
    sol, rb, u, r, st, nh, cf, F = _point()
    d = sol.data
    n = sol.n
    eta = 1e-4
    buffers = cr.new_buffers(n)  # a kept matrix lives in the buffers it was built in
    J0, kept = _assemble(sol, rb, u, r, st, nh, cf, eta, buffers)
    slip = np.flatnonzero(st == ck.SLIP)
    moved, kept_rows = slip[::2], slip[1::2]
    nh2, cf2 = nh.copy(), cf.copy()
    for i, delta in [(i, 10 * eta) for i in moved] + [(i, 0.1 * eta) for i in kept_rows]:
        a = np.arctan2(nh[2 * i + 1], nh[2 * i]) + delta
        nh2[2 * i], nh2[2 * i + 1] = np.cos(a), np.sin(a)
        cf2[i] = cf[i] * (1 - delta)
    unew = np.empty(3 * n)
    ok, kept2 = cr._newton_point(d.Kn, rb, r, d.sx, d.sy, d.g, sol.rhoT, st, nh2, cf2, unew, 0,
                                 u, eta, buffers, kept)
    assert ok
    fresh, fkept = _assemble(sol, rb, u, r, st, nh2, cf2, eta)
    J2 = np.array(kept2[0])
    rows = {i: 2 * int(np.sum(st[:i] == ck.SLIP)) + 3 * int(np.sum(st[:i] == ck.SEPARATED))
            for i in slip}
    for i in moved:  # refreshed: the fresh rows and preconditioner blocks
        k = rows[i]
        np.testing.assert_array_equal(J2[k:k + 2], fresh[k:k + 2])
        np.testing.assert_allclose(kept2[1][k:k + 2, :2], np.linalg.inv(fresh[k:k + 2, k:k + 2]),
                                   rtol=1e-12)
    for i in kept_rows:  # kept: the old rows (they differ from the fresh ones by ~0.1 eta)
        k = rows[i]
        np.testing.assert_array_equal(J2[k:k + 2], J0[k:k + 2])
        assert 0 < np.abs(J2[k:k + 2] - fresh[k:k + 2]).max() < eta * np.abs(fresh).max()
    np.testing.assert_array_equal(kept2[4][moved, 0], nh2[2 * moved])
    np.testing.assert_array_equal(kept2[4][kept_rows, 0], nh[2 * kept_rows])


def _warm_steps(n=30, seed=7, separation=True):
    """Steps of a random system under a load turning over eight directions: ``(v, q, p_w,
    start)`` per load, ``start`` its answer by exact LU solves."""
    s, v, q_w, p_w = random_3d(n, seed, separation=separation)
    lu = ConeStepSolver(s, dense_max=10 ** 6)
    loads = [q_w * np.cos(t) + np.roll(q_w, 1, axis=0) * np.sin(t)
             for t in np.linspace(0, 2 * np.pi, 8, endpoint=False)]
    return s, [(v, q, p_w, lu.solve(v, q, p_w)) for q in loads]


def test_warm_steps_through_kept_matrices_match_exact_solves():
    """Steps started from the answers of the same steps with slightly other slips (as a cyclic
    run starts period ``c`` from period ``c - 1``: the directions move little, so the second
    Newton iteration keeps most rows of the first one's matrix; N = 30, reduced systems of ~40
    unknowns solved by GMRES with ``dense_max = 4``) against exact LU solves (``dense_max``
    above the system size): the same answers to the step tolerance, no more Newton iterations,
    no restart."""
    s, steps = _warm_steps()
    it_ = ConeStepSolver(s, dense_max=4)
    lu = ConeStepSolver(s, dense_max=10 ** 6)
    rng = np.random.default_rng(3)
    assert it_.totals["steps"] == 0
    for (v, q, p_w, start), size in itertools.product(steps, (1e-4, 1e-5, 1e-6)):
        v2 = v + size * rng.normal(size=v.shape)  # 1e-6: all rows of the second iteration kept
        a = it_.solve(v2, q, p_w, guess=start)
        b = lu.solve(v2, q, p_w, guess=start)
        assert a.success and b.success and a.method == b.method == "newton"
        assert a.iterations <= b.iterations
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-10 * b.force_scale)
        np.testing.assert_allclose(a.slip, b.slip, rtol=0, atol=1e-10 * b.force_scale)
    assert it_.totals["cold_restarts"] == it_.totals["gauss_seidel"] == 0
    assert it_.totals["iterations"] > it_.totals["steps"]  # second iterations happened


@pytest.mark.parametrize("separation", [False, True])
def test_single_precision_products_reach_the_answers_of_double_ones(separation):
    """The solver's Krylov products in single precision (its default: the reduced matrix
    assembled in single precision only) against the same solver with double-precision buffers,
    on the warm steps of :func:`_warm_steps` (with and without separated nodes): the same answers to the step
    tolerance in the same number of Newton iterations, and the single-precision matrix was built
    (in the solver's buffer when it fits: up to 2N unknowns, i.e. without separated nodes)."""
    s, steps = _warm_steps(separation=separation)
    single = ConeStepSolver(s, dense_max=4)
    double = ConeStepSolver(s, dense_max=4)
    double._buffers = ck.new_buffers(s.n_nodes, False)
    single._buffers[3][:] = 0.0
    rng = np.random.default_rng(4)
    for (v, q, p_w, start), size in itertools.product(steps, (1e-3, 1e-5)):
        v2 = v + size * rng.normal(size=v.shape)
        a = single.solve(v2, q, p_w, guess=start)
        b = double.solve(v2, q, p_w, guess=start)
        assert a.success and b.success and a.method == b.method == "newton"
        assert a.iterations == b.iterations
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-11 * b.force_scale)
        np.testing.assert_allclose(a.slip, b.slip, rtol=0, atol=1e-11 * b.force_scale)
    assert np.any(single._buffers[3] != 0) != separation and double._buffers[3].size == 0


def test_single_precision_solves_that_do_not_converge_go_on_in_double():
    """An ill-conditioned stiffness (eigenvalues over 6.5 decades, random eigenvectors; N = 40,
    reduced systems of ~80 unknowns): the single-precision Krylov solve does not converge within
    one restart cycle, and goes on in double from where it got (counted in the solver's tally),
    with the answers (to the step tolerance) and the Newton iterations of the solver that has no
    single-precision buffers."""
    n = 40
    rng = np.random.default_rng(0)
    Q, _ = np.linalg.qr(rng.normal(size=(3 * n, 3 * n)))
    K = (Q * np.logspace(0, 6.5, 3 * n)) @ Q.T
    K = 0.5 * (K + K.T)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.3 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=0.2, dim=3)
    single, double = ConeStepSolver(s), ConeStepSolver(s)
    double._buffers = ck.new_buffers(n, False)
    v, q, p = np.zeros((n, 2)), rng.normal(size=(n, 2)), 0.5 + rng.random(n)
    start = double.solve(v, q, p)
    guess = np.column_stack([start.slip_increment, start.gap])
    guess = guess + 1e-3 * np.abs(guess).max() * rng.normal(size=guess.shape)
    a, b = single.solve(v, q, p, guess=guess), double.solve(v, q, p, guess=guess)
    assert a.success and b.success and a.method == b.method == "newton" and a.iterations > 2
    assert a.iterations == b.iterations
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-11 * b.force_scale)
    tried, redone = single._buffers[4]
    assert redone >= 1 and tried >= redone
    # once most of its single-precision solves went on in double (TRIES), the solver stops
    # trying them: its later steps are solved in double from the start, with the same answers
    for k in range(2 * ck.TRIES):
        g = guess * (1 + 1e-4 * k)
        a, b = single.solve(v, q, p, guess=g), double.solve(v, q, p, guess=g)
        assert a.success and a.iterations == b.iterations
    tried, redone = single._buffers[4]
    assert redone == ck.TRIES and tried < 2 * redone


@pytest.mark.parametrize("k_scale, f_scale", [(1e-40, 1e30), (1e-20, 1e-30), (1e40, 1e-30)])
def test_single_precision_products_at_extreme_units(k_scale, f_scale):
    """Stiffness and forces rescaled far beyond single precision's range of magnitudes (the
    matrix is assembled with its columns scaled to unit diagonal, so its entries are
    ``~sqrt(k)``; where they leave single precision's range the solve goes on in double):
    the answers of the double-precision solver to the step tolerance, in the same number of
    Newton iterations, warm steps from slightly other slips as above."""
    s, steps = _warm_steps()
    S = sd.DiscreteSystem(s.A * k_scale, s.B * k_scale, s.C * k_scale, friction=s.friction_xy,
                          dim=3)
    single, double = ConeStepSolver(S, dense_max=4), ConeStepSolver(S, dense_max=4)
    double._buffers = ck.new_buffers(S.n_nodes, False)
    rng = np.random.default_rng(1)
    for v, q, p, start in steps:
        g = np.column_stack([start.slip_increment, start.gap]) * f_scale / k_scale
        v2 = (v + 1e-3 * rng.normal(size=v.shape)) * f_scale / k_scale
        a = single.solve(v2, q * f_scale, p * f_scale, guess=g)
        b = double.solve(v2, q * f_scale, p * f_scale, guess=g)
        assert a.success and b.success and a.method == b.method == "newton"
        assert a.iterations == b.iterations >= 1
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-11 * b.force_scale)
