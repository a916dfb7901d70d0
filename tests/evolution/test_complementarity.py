"""The incremental step (MODEL.md s.4): reference cases, an independent enumeration oracle,
the Lemke fallback, degenerate steps, factorization reuse, non-uniqueness and bad input."""

import itertools

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution.complementarity import FEAS_TOL, STATE_NAMES, StepSolver
from shakedown.evolution.lemke import lemke

# Answers are verified to FEAS_TOL (1e-9, relative to the step's force scale); the oracle below
# solves the same linear systems independently with np.linalg.solve, so two correct answers agree
# to ~1e-12 relative.  AGREE = 1e-8 leaves room for the conditioning of random systems.
AGREE = 1e-8


# ---------------------------------------------------------------------------- oracle
def oracle(system, v_prev, q_w, p_w, tol=1e-9):
    """Every solution of the step, by trying all 4^N node-state assignments (N <= 3).

    Built from system.K directly (not from the production code): per node the state fixes
    (dv, w) = 0 (stick), w = 0 and q +- f p = 0 (slip), or q = p = 0 (separated); each linear
    system is solved and kept if every sign condition holds.  Returns distinct (v, w, q, p).
    """
    n = system.n_nodes
    K, f = system.K, system.friction
    r0 = np.concatenate([q_w + system.A @ v_prev, p_w + system.B.T @ v_prev])
    scale = max(np.abs(r0).max(), np.abs(q_w).max(), np.abs(p_w).max(), 1e-300)
    ft = tol * scale
    out = []
    for states in itertools.product("SFBO", repeat=n):
        G = np.zeros((2 * n, 2 * n))
        h = np.zeros(2 * n)
        for j, st in enumerate(states):
            if st == "S":
                G[j, j] = G[n + j, n + j] = 1.0
            elif st in "FB":
                sg = 1.0 if st == "F" else -1.0
                G[j] = K[j] + sg * f[j] * K[n + j]
                h[j] = -(r0[j] + sg * f[j] * r0[n + j])
                G[n + j, n + j] = 1.0
            else:
                G[j], G[n + j] = K[j], K[n + j]
                h[j], h[n + j] = -r0[j], -r0[n + j]
        try:
            z = np.linalg.solve(G, h)
        except np.linalg.LinAlgError:
            continue
        r = r0 + K @ z
        q, p, dv, w = r[:n], r[n:], z[:n], z[n:]
        dt = ft / np.diag(K)
        ok = True
        for j, st in enumerate(states):
            if st == "S":
                ok &= p[j] >= -ft and abs(q[j]) <= f[j] * p[j] + ft
            elif st == "F":
                ok &= p[j] >= -ft and dv[j] >= -dt[j]
            elif st == "B":
                ok &= p[j] >= -ft and dv[j] <= dt[j]
            else:
                ok &= w[j] >= -dt[n + j]
        if ok and not any(np.allclose(z, z2, rtol=0, atol=1e-7 * scale / K.diagonal().min())
                          for z2, *_ in out):
            out.append((z, q, p))
    return [(v_prev + z[:n], z[n:], q, p) for z, q, p in out]


def random_system(rng, n, friction_fraction):
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 0.5 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    fc = s.critical_friction().value
    return s.with_friction(friction_fraction * min(fc, 3.0))


def check_answer(system, r, v_prev, q_w, p_w):
    """Independent verification of a StepResult from its fields (MODEL.md s.4 conditions)."""
    f = system.friction
    q = q_w + system.A @ r.slip + system.B @ r.gap
    p = p_w + system.B.T @ r.slip + system.C @ r.gap
    scale = r.force_scale
    np.testing.assert_allclose(q, r.q, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(p, r.p, rtol=0, atol=1e-10 * scale)
    dv = r.slip - v_prev
    ds = scale / np.diag(system.A)
    dw = scale / np.diag(system.C)
    pairs = [(r.gap / dw, p / scale), (np.maximum(dv, 0) / ds, (f * p + q) / scale),
             (np.maximum(-dv, 0) / ds, (f * p - q) / scale)]
    nat = max(np.abs(np.minimum(x, y)).max() for x, y in pairs)
    assert nat <= FEAS_TOL, nat
    assert r.residual <= FEAS_TOL
    # the reported residual is that of the reported fields (r.q, r.p, r.slip_increment): the
    # same formula on the same numbers, equal to a few roundings (1e-15); the old check
    # (abs=1e-12 against a recomputation) passed with a residual hard-wired to 0.  (The
    # residual of a correct answer is often ~1e-16, so the catching test for a zeroed residual
    # is test_step_self_checks.py, on ill-conditioned systems.)
    qq, pp, dvr = r.q, r.p, r.slip_increment
    own = [(r.gap / dw, pp / scale), (np.maximum(dvr, 0) / ds, (f * pp + qq) / scale),
           (np.maximum(-dvr, 0) / ds, (f * pp - qq) / scale)]
    nat_own = max(np.abs(np.minimum(x, y)).max() for x, y in own)
    assert abs(r.complementarity_residual - nat_own) <= 1e-6 * nat_own + 1e-15


# ---------------------------------------------------------------------------- reference cases
class TestSingleNode:
    """One node on springs k_t, k_n, uncoupled (MODEL.md s.1 sign check)."""

    s = sd.DiscreteSystem([[2.0]], [[0.0]], [[3.0]], friction=0.5)

    def test_forward_slip(self):
        # q_w = -F: the node slips forward until q = -f p: v = (F - f P) / k
        r = sd.solve_step(self.s, [0.0], [-4.0], [2.0])
        assert r.status == "unique" and r.state_names[0] == "forward"
        assert r.slip[0] == pytest.approx((4.0 - 1.0) / 2.0, abs=1e-14)
        assert r.q[0] == pytest.approx(-1.0, abs=1e-14)

    def test_backward_slip_and_stick(self):
        r = sd.solve_step(self.s, [0.0], [3.0], [2.0])
        assert r.state_names[0] == "backward" and r.slip[0] == pytest.approx(-1.0)
        r2 = sd.solve_step(self.s, r.slip, [1.5], [2.0], guess=r.active_set)
        assert r2.state_names[0] == "stick" and r2.slip[0] == pytest.approx(-1.0)

    def test_separation(self):
        # tensile welded reaction: the node opens, w = -p_w / C, q = 0 and v = -q_w / A
        r = sd.solve_step(self.s, [0.3], [1.0], [-6.0])
        assert r.state_names[0] == "separation"
        assert r.gap[0] == pytest.approx(2.0) and r.slip[0] == pytest.approx(-0.5)
        assert r.q[0] == pytest.approx(0.0, abs=1e-14) and r.p[0] == pytest.approx(0.0, abs=1e-14)


# ---------------------------------------------------------------------------- oracle agreement
@pytest.mark.parametrize("seed", range(6))
def test_agrees_with_enumeration_oracle_below_critical(seed):
    """Step by step along random load sequences (tension included: nodes open and close)."""
    rng = np.random.default_rng(seed)
    seen = set()
    for _ in range(8):
        n = int(rng.integers(1, 4))
        s = random_system(rng, n, rng.uniform(0.05, 0.95))
        v = rng.normal(size=n) * 0.3
        guess = None
        for _ in range(12):
            q_w, p_w = rng.normal(size=n) * 2, rng.normal(size=n) * 2 + 1.0
            r = sd.solve_step(s, v, q_w, p_w, guess=guess)
            sols = oracle(s, v, q_w, p_w)
            assert r.status == "unique" and len(sols) == 1
            vv, ww, qq, pp = sols[0]
            sc = r.force_scale
            np.testing.assert_allclose(r.slip, vv, rtol=0, atol=AGREE * sc / s.A.diagonal().min())
            np.testing.assert_allclose(r.gap, ww, rtol=0, atol=AGREE * sc / s.C.diagonal().min())
            np.testing.assert_allclose(r.p, pp, rtol=0, atol=AGREE * sc)
            check_answer(s, r, v, q_w, p_w)
            seen.update(r.state_names)
            v, guess = r.slip, r.active_set
    assert {"stick", "forward", "backward", "separation"} <= seen  # every state was exercised


def test_lemke_fallback_agrees_with_oracle():
    """max_iter=1 forces the (reaction-based, copositive) Lemke fallback on most steps."""
    rng = np.random.default_rng(11)
    n_lemke = 0
    for _ in range(30):
        n = int(rng.integers(1, 4))
        s = random_system(rng, n, rng.uniform(0.05, 0.95))
        solver = StepSolver(s, max_iter=1)
        v = rng.normal(size=n) * 0.3
        for _ in range(5):
            q_w, p_w = rng.normal(size=n) * 2, rng.normal(size=n) * 2 + 1.0
            r = solver.solve(v, q_w, p_w)
            n_lemke += r.method == "lemke"
            (vv, ww, _, _), = oracle(s, v, q_w, p_w)
            np.testing.assert_allclose(r.slip, vv, atol=1e-7)
            np.testing.assert_allclose(r.gap, ww, atol=1e-7)
            check_answer(s, r, v, q_w, p_w)
            v = r.slip
    assert n_lemke > 50


def test_above_critical_reports_multiple_solutions():
    """Friction above critical: every solution the oracle finds is reported, none hidden."""
    rng = np.random.default_rng(5)
    counts = {"unique": 0, "multiple_solutions": 0}
    for _ in range(40):
        n = int(rng.integers(2, 4))
        s = random_system(rng, n, rng.uniform(1.2, 3.0))
        v = np.zeros(n)
        for _ in range(5):
            q_w, p_w = rng.normal(size=n) * 2, rng.normal(size=n) * 2 + 1.0
            r = sd.solve_step(s, v, q_w, p_w)
            sols = oracle(s, v, q_w, p_w)
            assert r.n_solutions == len(sols) >= 1  # the discrete coercive step always has one
            counts[r.status] += 1
            if len(sols) > 1:
                assert r.status == "multiple_solutions" and len(r.alternative_slips) == len(sols) - 1
                found = [r.slip, *r.alternative_slips]
                for vv, *_ in sols:
                    assert any(np.allclose(vv, x, atol=1e-7) for x in found)
            else:
                assert r.status == "unique"
            check_answer(s, r, v, q_w, p_w)
            v = r.slip
    assert counts["multiple_solutions"] >= 3 and counts["unique"] >= 10


def test_large_system_above_sufficient_bound_is_not_called_unique():
    rng = np.random.default_rng(3)
    n = 6
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 0.5 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    s = s.with_friction(3.0 * s.critical_friction().upper_bound)
    r = sd.solve_step(s, np.zeros(n), rng.normal(size=n), rng.normal(size=n) + 2.0)
    assert r.status in ("solved", "failed") and "uniqueness not guaranteed" in r.message


# ---------------------------------------------------------------------------- degenerate steps
def test_degenerate_steps_terminate_with_verified_answers():
    s = sd.DiscreteSystem([[4.0, 1.0], [1.0, 3.0]], [[0.3, 0.1], [-0.2, 0.4]],
                          [[5.0, 0.5], [0.5, 4.0]], friction=[0.4, 0.6])
    f = s.friction
    cases = {
        # both nodes exactly at the forward friction limit, nothing moves
        "at limit": (np.zeros(2), -f * np.array([2.0, 1.0]), np.array([2.0, 1.0])),
        # zero normal reaction and zero tangential reaction: every state fits
        "zero normal reaction": (np.zeros(2), np.zeros(2), np.zeros(2)),
        # one node at zero p exactly, the other at the backward limit
        "tie mix": (np.zeros(2), np.array([0.0, 0.6]), np.array([0.0, 1.0])),
        # identically zero load
        "zero": (np.zeros(2), np.zeros(2), np.zeros(2)),
    }
    for name, (v, q_w, p_w) in cases.items():
        for guess in itertools.product(range(4), repeat=2):
            r = sd.solve_step(s, v, q_w, p_w, guess=np.array(guess))
            assert r.success, (name, guess, r.message)
            check_answer(s, r, v, q_w, p_w)
            np.testing.assert_allclose(r.slip, v, atol=1e-12)  # nothing moves in these cases


# ---------------------------------------------------------------------------- reuse
@pytest.mark.parametrize("kernel", [False, True])
def test_factorizations_are_reused_and_answers_unchanged(kernel):
    """A coupled N = 60 system through a slowly varying load: few nodes change per step.  The
    Python step's LU cache and Woodbury updates (``kernel=False``) or the compiled kernel's
    inverse cache and block updates solve the step's systems; the answers equal a fresh
    solver's."""
    rng = np.random.default_rng(2)
    n = 60
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=0.3)
    warm = StepSolver(s, check_uniqueness=False, update_min_size=16, kernel=kernel)
    q_a, q_b = rng.normal(size=n) * 20, rng.normal(size=n) * 20
    v, guess = np.zeros(n), None
    steps = 80
    for k in range(steps):
        t = k / steps
        q_w = q_a * np.cos(2 * np.pi * t) + q_b * np.sin(2 * np.pi * t)
        p_w = np.full(n, 15.0)
        r = warm.solve(v, q_w, p_w, guess)
        cold = StepSolver(s, check_uniqueness=False, kernel=False).solve(v, q_w, p_w)
        np.testing.assert_allclose(r.slip, cold.slip, rtol=0,
                                   atol=1e-9 * r.force_scale / s.A.diagonal().min())
        check_answer(s, r, v, q_w, p_w)
        v, guess = r.slip, r.active_set
    t = warm.totals
    assert t["updates"] + t["cache_hits"] > 0
    assert t["factorizations"] < steps / 2, t
    assert t["lemke_calls"] == 0


# ---------------------------------------------------------------------------- Lemke itself
def test_lemke_textbook_and_degenerate_problems():
    # Murty's example: M = [[2, 1], [1, 2]], q = [-5, -6]: z = (4/3, 7/3), w = 0
    res = lemke([[2.0, 1.0], [1.0, 2.0]], [-5.0, -6.0])
    assert res.success
    np.testing.assert_allclose(res.z, [4 / 3, 7 / 3], atol=1e-12)
    # degenerate (ties in the ratio test) P-matrix problem
    rng = np.random.default_rng(0)
    for _ in range(50):
        n = 6
        R = rng.normal(size=(n, n))
        M = R @ R.T + np.eye(n)
        q = -np.round(rng.uniform(0, 2, n))  # integer data: many ties
        res = lemke(M, q)
        assert res.success
        w = M @ res.z + q
        assert res.z.min() >= -1e-12 and w.min() >= -1e-10
        assert abs(res.z @ w) <= 1e-10


def test_lemke_reports_rays():
    res = lemke([[-1.0]], [-1.0])  # w = -z - 1 >= 0 impossible with z >= 0
    assert res.status == "ray" and not res.success


# ---------------------------------------------------------------------------- bad input
def test_bad_input_messages():
    s = sd.DiscreteSystem([[2.0]], [[0.0]], [[3.0]], friction=0.5)
    with pytest.raises(sd.ShapeError, match=r"v_prev must have shape \(1,\)"):
        sd.solve_step(s, [0.0, 1.0], [1.0], [1.0])
    with pytest.raises(sd.InputError, match="q_w must be finite"):
        sd.solve_step(s, [0.0], [np.nan], [1.0])
    with pytest.raises(sd.InputError, match="guess states must be among"):
        sd.solve_step(s, [0.0], [1.0], [1.0], guess=["sliding"])
    with pytest.raises(sd.InputError, match="guess codes must be 0..3"):
        sd.solve_step(s, [0.0], [1.0], [1.0], guess=[7])
    with pytest.raises(sd.InputError, match="system must be a DiscreteSystem"):
        sd.solve_step("not a system", [0.0], [1.0], [1.0])
    assert STATE_NAMES == ("stick", "forward", "backward", "separation")
