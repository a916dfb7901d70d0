"""The 3-D implicit step (MODEL.md s.8.4): cone complementarity solved by the semismooth Newton
method of shakedown/evolution/cone_kernel.py and verified by cone_step.verify_step.

What these tests prove: the verifier rejects each kind of wrong answer (outside the cone, slip
along the traction, gap with pressure, broken equilibrium); the solver agrees with an independent
convex solver (cvxpy/Clarabel SOCP) on uncoupled steps and with a single-node closed form; its
answers scale exactly with the units; the fallbacks (cold restart, block Gauss-Seidel) produce
verified answers; statuses follow the 3-D sufficient friction bound, which is itself checked
against the exact 2-D single-node value; bad input is refused by name.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.evolution import cone_kernel as ck
from shakedown.evolution.cone_step import ConeStepSolver, verify_step
from shakedown.model.errors import InputError, ShapeError


def random_3d(n, seed, friction=0.3, coupling=0.3, separation=False):
    """A random SPD 3-D system (well conditioned) and a random step's welded reactions."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    s = sd.DiscreteSystem(K[:2 * n, :2 * n], coupling * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                          friction=friction, dim=3)
    q_w = rng.normal(size=(n, 2))
    p_w = 0.5 + rng.random(n)
    if separation:
        p_w[: max(1, n // 4)] = -0.3  # pulled open
    return s, rng.normal(size=(n, 2)) * 0.1, q_w, p_w


def _slipping_answer():
    s, v, q_w, p_w = random_3d(6, 1)
    sol = ConeStepSolver(s)
    r = sol.solve(v, q_w, p_w)
    assert r.success and np.any(r.states == ck.SLIP)
    return s, sol, v, q_w, p_w, r


def test_verifier_accepts_the_answer_and_rejects_each_kind_of_wrong_answer():
    s, sol, v, q_w, p_w, r = _slipping_answer()
    d = sol.data
    rb = sol.base(v, q_w, p_w)
    u = np.column_stack([r.slip_increment, r.gap])
    R = np.column_stack([r.q, r.p])
    F = r.force_scale
    assert verify_step(d, rb, u, R, F).worst <= 1e-12
    j = int(np.flatnonzero(r.states == ck.SLIP)[0])
    tol = sol.feas_tol
    # slip along the traction instead of against it (reactions consistent with K)
    u2 = u.copy()
    u2[j, :2] *= -1
    res = verify_step(d, rb, u2, rb + (d.Kn @ u2.ravel()).reshape(-1, 3), F)
    assert res.direction > 1e3 * tol or res.cone > 1e3 * tol
    # the reaction pushed out of the cone (equilibrium not checked here)
    R2 = R.copy()
    R2[j, :2] *= 1.01
    assert verify_step(d, rb, u, R2, F, equilibrium=False).cone > 1e3 * tol
    # a slip rotated by 90 degrees with the reactions kept: direction residual
    u3 = u.copy()
    u3[j, :2] = [-u[j, 1], u[j, 0]]
    assert verify_step(d, rb, u3, R, F, equilibrium=False).direction > 1e3 * tol
    # an open gap under pressure
    u4 = u.copy()
    u4[0, 2] = 0.1 * F / d.kN[0]
    assert verify_step(d, rb, u4, R, F, equilibrium=False).normal > 1e3 * tol
    # broken equilibrium
    R5 = R.copy()
    R5[-1, 2] += 1e-6 * F
    res = verify_step(d, rb, u, R5, F)
    assert res.equilibrium > 1e2 * tol and res.worst > tol


def test_compiled_verifier_equals_the_numpy_one_on_right_and_wrong_answers():
    s, sol, v, q_w, p_w, r = _slipping_answer()
    rb = sol.base(v, q_w, p_w)
    rng = np.random.default_rng(0)
    u = np.column_stack([r.slip_increment, r.gap])
    for k in range(5):
        uk = u + (k > 0) * 1e-3 * rng.normal(size=u.shape)
        Rk = rb + (sol.data.Kn @ uk.ravel()).reshape(-1, 3) + (k > 2) * 1e-4
        a = verify_step(sol.data, rb, uk, Rk, r.force_scale)
        b = sol._verify(rb.ravel(), uk.ravel(), Rk.ravel(), r.force_scale, True)
        np.testing.assert_allclose([b.cone, b.direction, b.normal, b.equilibrium],
                                   [a.cone, a.direction, a.normal, a.equilibrium],
                                   rtol=1e-9, atol=1e-15)
        assert (a.worst > 1e-6) == (k > 0)


def test_a_failing_answer_gets_status_failed():
    s, sol, v, q_w, p_w, r = _slipping_answer()
    rb = sol.base(v, q_w, p_w)
    u = np.column_stack([r.slip_increment, r.gap])
    u[0, :2] += 1e-3  # not a solution
    R = rb + (sol.data.Kn @ u.ravel()).reshape(-1, 3)
    res = verify_step(sol.data, rb, u, R, r.force_scale)
    out = sol.result(v, u, R, r.active_set, "newton", 1, res, r.force_scale)
    assert not out.success and out.status == "failed" and "no verified solution" in out.message


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_uncoupled_step_equals_the_convex_minimisation_solved_by_clarabel(seed):
    """B = 0 and every node closed: the step is ``min 1/2 dv^T A dv + qb . dv + sum p_i
    |F_i dv_i|`` (p known), an SOCP solved independently by cvxpy with Clarabel."""
    cvxpy = pytest.importorskip("cvxpy")
    n = 8
    s, v, q_w, p_w = random_3d(n, seed, coupling=0.0)
    fx = np.random.default_rng(seed).uniform(0.2, 0.6, (n, 2))
    s = s.with_friction(fx)
    sol = ConeStepSolver(s)
    r = sol.solve(v, q_w, p_w)
    assert r.success and r.status == "unique"
    A = np.asarray(s.A)
    qb = (q_w + (A @ v.ravel()).reshape(n, 2)).ravel()
    x = cvxpy.Variable(2 * n)
    cost = 0.5 * cvxpy.quad_form(x, cvxpy.psd_wrap(A)) + qb @ x
    cost += sum(p_w[i] * cvxpy.norm(cvxpy.multiply(fx[i], x[2 * i:2 * i + 2]))
                for i in range(n))
    cvxpy.Problem(cvxpy.Minimize(cost)).solve(solver="CLARABEL", tol_gap_abs=1e-10,
                                              tol_gap_rel=1e-10, tol_feas=1e-10)
    scale = np.abs(qb).max() / np.diag(A).min()

    def J(dv):
        return 0.5 * dv @ A @ dv + qb @ dv + sum(
            p_w[i] * np.hypot(*(fx[i] * dv[2 * i:2 * i + 2])) for i in range(n))

    # ours is the minimiser: its cost is not above Clarabel's (interior point, ~1e-7 accurate)
    assert J(r.slip_increment.ravel()) <= J(x.value) + 1e-12 * np.abs(qb).max() * scale
    np.testing.assert_allclose(r.slip_increment.ravel(), x.value, rtol=0, atol=1e-5 * scale)
    assert np.any(r.states == ck.SLIP) and np.any(r.states == ck.STICK)


def test_single_isotropic_node_closed_form():
    """A = k I, B = 0, p = P, q = q_w + k dv (MODEL.md s.8 signs): from v = 0 under q_w = Q e
    with Q > f P the node slips by dv = -(Q - f P) / k e and q = f P e, opposite to dv."""
    k, f, P, Q = 3.0, 0.4, 2.0, 1.5
    s = sd.DiscreteSystem(k * np.eye(2), np.zeros((2, 1)), [[5.0]], friction=f, dim=3)
    e = np.array([0.6, -0.8])
    r = ConeStepSolver(s).solve(np.zeros((1, 2)), [Q * e], [P])
    np.testing.assert_allclose(r.slip_increment[0], -(Q - f * P) / k * e, rtol=1e-12)
    np.testing.assert_allclose(r.q[0], f * P * e, rtol=1e-12)
    assert r.state_names[0] == "slip" and r.gap[0] == 0


def test_separation_and_the_gauss_seidel_fallback_give_verified_answers():
    s, v, q_w, p_w = random_3d(10, 4, separation=True)
    sol = ConeStepSolver(s)
    r = sol.solve(v, q_w, p_w)
    assert r.success and np.any(r.states == ck.SEPARATED)
    assert np.all(r.p[r.states == ck.SEPARATED] <= 1e-12)
    # Newton allowed 1 iteration cannot finish: the block Gauss-Seidel fallback must
    sol1 = ConeStepSolver(s, max_iter=1)
    r1 = sol1.solve(v, q_w, p_w)
    assert sol1.totals["gauss_seidel"] == 1 and r1.method == "gauss_seidel" and r1.success
    np.testing.assert_allclose(r1.slip, r.slip, rtol=0, atol=1e-7 * r.force_scale)


def test_gmres_and_lu_paths_agree():
    s, v, q_w, p_w = random_3d(40, 5)
    a = ConeStepSolver(s, dense_max=10 ** 6).solve(v, q_w, p_w)
    b = ConeStepSolver(s, dense_max=4).solve(v, q_w, p_w)
    assert a.success and b.success
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-10 * a.force_scale)
    # warm-started (the inexact GMRES starts from the guess): a guess near the answer, and one
    # far from it, reach the same verified answer
    for scale in (1e-4, 1.0):
        rng = np.random.default_rng(1)
        guess = np.column_stack([a.slip_increment, a.gap])
        guess = guess + scale * np.abs(guess).max() * rng.normal(size=guess.shape)
        c = ConeStepSolver(s, dense_max=4).solve(v, q_w, p_w, guess=guess)
        assert c.success and c.method == "newton"
        np.testing.assert_allclose(c.q, a.q, rtol=0, atol=1e-10 * a.force_scale)


def test_gmres_with_separated_nodes_agrees_with_lu():
    """The GMRES path's block-Jacobi preconditioner with 3 x 3 blocks (separated nodes) beside
    the closed-form 2 x 2 inverses (slipping nodes): the same verified answer as LU."""
    s, v, q_w, p_w = random_3d(40, 6, separation=True)
    a = ConeStepSolver(s, dense_max=10 ** 6).solve(v, q_w, p_w)
    b = ConeStepSolver(s, dense_max=4).solve(v, q_w, p_w)
    assert a.success and b.success and b.method == "newton_cold"
    assert np.any(a.states == ck.SEPARATED) and np.any(a.states == ck.SLIP)
    np.testing.assert_allclose(b.q, a.q, rtol=0, atol=1e-10 * a.force_scale)
    np.testing.assert_allclose(b.gap, a.gap, rtol=0, atol=1e-10 * a.force_scale)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), fexp=st.integers(-6, 12), kexp=st.integers(-6, 12))
def test_step_answers_scale_with_the_units(seed, fexp, kexp):
    """Forces x 10^a, stiffness x 10^b: slips x 10^(a - b), reactions x 10^a, same states."""
    s, v, q_w, p_w = random_3d(5, seed, separation=seed % 2 == 0)
    r = ConeStepSolver(s).solve(v, q_w, p_w)
    a, b = 10.0 ** fexp, 10.0 ** kexp
    s2 = sd.DiscreteSystem(b * s.A, b * s.B, b * s.C, friction=s.friction, dim=3)
    r2 = ConeStepSolver(s2).solve(v * a / b, q_w * a, p_w * a)
    assert r.success and r2.success
    np.testing.assert_array_equal(r.states, r2.states)
    np.testing.assert_allclose(r2.slip * b / a, r.slip, rtol=0, atol=1e-9 * np.abs(r.slip).max())
    np.testing.assert_allclose(r2.q / a, r.q, rtol=0, atol=1e-9 * r.force_scale)


def test_statuses_follow_the_sufficient_friction_bound():
    s, v, q_w, p_w = random_3d(4, 6, coupling=0.8)
    crit = s.critical_friction()
    assert crit.method == "sufficient-bound-3d" and not crit.exact and np.isfinite(crit.factor)
    low = s.with_friction(0.5 * crit.value)
    high = s.with_friction(1.5 * crit.value)
    assert low.critical_friction().well_posed and not high.critical_friction().well_posed
    assert ConeStepSolver(low).solve(v, q_w, p_w).status == "unique"
    r = ConeStepSolver(high).solve(v, q_w, p_w)
    assert r.status in ("solved", "failed")
    assert sd.DiscreteSystem(s.A, 0 * s.B, s.C, friction=0.9, dim=3).critical_friction().method \
        == "uncoupled"


@pytest.mark.parametrize("a,b,c", [(2.0, 0.5, 1.0), (1.0, 0.7, 1.0), (1.0, 1 / np.sqrt(2), 1.0)])
def test_3d_bound_never_exceeds_the_exact_2d_single_node_value(a, b, c):
    """A node whose y direction is unloaded and uncoupled: the sufficient 3-D bound
    ``2 sqrt(a c - b^2) / c`` is at most the exact 2-D critical friction ``a / |b|``, with
    equality when ``a c = 2 b^2`` (the proof in shakedown/model/critical3d.py)."""
    s = sd.DiscreteSystem(np.diag([a, a]), [[b], [0.0]], [[c]], friction=1.0, dim=3)
    val = s.critical_friction().value
    np.testing.assert_allclose(val, 2 * np.sqrt(a * c - b * b) / c, rtol=1e-12)
    assert val <= a / abs(b) * (1 + 1e-12)
    if np.isclose(a * c, 2 * b * b):
        np.testing.assert_allclose(val, a / abs(b), rtol=1e-9)


def test_below_the_bound_every_start_finds_the_same_answer():
    """Uniqueness evidence: cold Newton, warm Newton from a far guess and block Gauss-Seidel
    reach one answer for a coupled system below the 3-D bound."""
    s, v, q_w, p_w = random_3d(6, 7, coupling=0.6)
    s = s.with_friction(0.9 * s.critical_friction().value)
    sol = ConeStepSolver(s)
    r0 = sol.solve(v, q_w, p_w)
    far = np.random.default_rng(0).normal(size=(6, 3))
    far[:, 2] = np.abs(far[:, 2])
    r1 = sol.solve(v, q_w, p_w, guess=far)
    r2 = ConeStepSolver(s, max_iter=1).solve(v, q_w, p_w)
    for r in (r1, r2):
        assert r.success
        np.testing.assert_allclose(r.slip, r0.slip, rtol=0, atol=1e-7 * np.abs(r0.slip).max())


def test_bad_input_is_refused_by_name():
    s, v, q_w, p_w = random_3d(3, 8)
    sol = ConeStepSolver(s)
    with pytest.raises(ShapeError, match="q_w"):
        sol.solve(v, q_w[:, 0], p_w)
    with pytest.raises(ShapeError, match="v_prev"):
        sol.solve(v.ravel(), q_w, p_w)
    with pytest.raises(InputError, match="finite"):
        sol.solve(v, q_w * np.nan, p_w)
    with pytest.raises(InputError, match="f_x and f_y"):
        ConeStepSolver(s.with_friction([[0.3, 0.0], [0.3, 0.3], [0.3, 0.3]]))


def test_warm_start_with_its_reactions_given_and_a_wrong_product_caught_by_the_verifier():
    """``solve_raw(..., ku0=K u0)`` (the cyclic driver's warm start, whose product with ``K`` it
    knows from earlier periods) gives the answer of the plain warm start.  A wrong product does
    not reach the answer when the Newton method takes a full step (it recomputes the reactions
    from scratch there); when the guess is accepted as it is, with the wrong reactions, the
    verifier's equilibrium check rejects it and the cold restart, which computes its own
    reactions, finds the right answer."""
    s, v, q_w, p_w = random_3d(12, 2)
    sol = ConeStepSolver(s)
    ref = sol.solve(v, q_w, p_w)
    rb = sol.base(v, q_w, p_w)
    u0 = np.column_stack([ref.slip_increment, ref.gap])
    u0 = u0 + 1e-3 * np.abs(u0).max() * np.random.default_rng(0).normal(size=u0.shape)
    ku0 = (sol.data.Kn @ u0.ravel()).reshape(-1, 3)
    plain = sol.solve_raw(rb, u0)
    given = sol.solve_raw(rb, u0, ku0=ku0)
    F = ref.force_scale
    assert given[3] == plain[3] == "newton" and given[5].worst <= sol.feas_tol
    np.testing.assert_allclose(given[1], plain[1], rtol=0, atol=1e-12 * F)
    wrong = sol.solve_raw(rb, u0, ku0=ku0 + 1e-6 * F)
    assert wrong[3] == "newton" and wrong[4] >= 1 and wrong[5].worst <= sol.feas_tol
    np.testing.assert_allclose(wrong[1][:, :2], ref.q, rtol=0, atol=1e-10 * F)
    # the answer as the guess, its product wrong on a stuck node (its residual does not see it)
    s, v, q_w, p_w = random_3d(12, 2, friction=1.0)
    sol = ConeStepSolver(s)
    ref = sol.solve(v, q_w, p_w)
    rb, F = sol.base(v, q_w, p_w), ref.force_scale
    exact = np.column_stack([ref.slip_increment, ref.gap])
    stuck = int(np.flatnonzero(ref.states == 0)[0])
    bad = (sol.data.Kn @ exact.ravel()).reshape(-1, 3)
    bad[stuck, 0] += 1e-6 * F
    caught = sol.solve_raw(rb, exact, ku0=bad)
    assert caught[3] == "newton_cold" and caught[5].worst <= sol.feas_tol
    np.testing.assert_allclose(caught[1][:, :2], ref.q, rtol=0, atol=1e-10 * F)


def test_buffers_shared_across_steps_give_the_answers_of_fresh_solvers():
    """One solver (its buffers for the unknowns and the reduced matrices are reused by every
    step, and a matrix kept from one Newton iteration is reused by the next,
    ``cone_reduced._newton_point``) through steps whose pieces differ and repeat gives, step by
    step, the answers, methods and iteration counts of a fresh solver per step: nothing stale
    is used across steps."""
    s, v, q_w, p_w = random_3d(12, 3, separation=True)
    shared = ConeStepSolver(s, dense_max=4)
    loads = [(q_w, p_w), (0.2 * q_w, np.abs(p_w) + 0.5), (3.0 * q_w, np.abs(p_w) + 0.5),
             (q_w, p_w), (q_w, p_w)]
    pieces = []
    for qk, pk in loads:
        a = shared.solve(v, qk, pk)
        b = ConeStepSolver(s, dense_max=4).solve(v, qk, pk)
        assert a.success and b.success
        assert (a.method, a.iterations) == (b.method, b.iterations) == ("newton_cold", b.iterations)
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12 * b.force_scale)
        np.testing.assert_allclose(a.gap, b.gap, rtol=0, atol=1e-12 * b.force_scale)
        pieces.append(tuple(a.states))
    assert len(set(pieces)) >= 3  # the pieces changed between steps (and repeated)


def test_a_warm_step_between_cold_ones_leaves_nothing_stale():
    """A step started near its answer (one Newton iteration, a small LU or GMRES matrix in the
    shared buffer) between two cold solves of another step: every answer, method and iteration
    count as with a fresh solver."""
    s, v, q_w, p_w = random_3d(12, 4, separation=True)
    load_b = (3.0 * q_w, np.abs(p_w) + 0.5)
    ref_b = ConeStepSolver(s, dense_max=4).solve(v, *load_b)
    guess = np.column_stack([ref_b.slip_increment, ref_b.gap]) * (1.0 + 1e-9)
    shared = ConeStepSolver(s, dense_max=4)
    for load, g in (((q_w, p_w), None), (load_b, guess), ((q_w, p_w), None)):
        a = shared.solve(v, *load, guess=g)
        b = ConeStepSolver(s, dense_max=4).solve(v, *load, guess=g)
        assert a.success and (a.method, a.iterations) == (b.method, b.iterations)
        assert a.method == ("newton" if g is not None else "newton_cold")
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12 * b.force_scale)
    assert not np.array_equal(ref_b.states, a.states)  # the middle step's piece differs
