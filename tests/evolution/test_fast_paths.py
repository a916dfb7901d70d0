"""The step solver's fast paths against reference paths (issue 14 item 7).

Fast paths: cached factors with their rows of ``K`` and a base carried over from the previous
step (``StepSolver.next_base``), Woodbury updates, several initial states stepped together
(``solve_cycles`` with a 2-D ``initial_slip``).  References: a fresh solver (fresh LU, no cache),
lexicographic Lemke from scratch, independent runs.  Also: each self-check (complementarity
residual, the per-period equilibrium check, the energy identity) flags a deliberately wrong
answer, and the answers are scale-free (stiffness and loads in other units).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.evolution import multistate
from shakedown.evolution.complementarity import FEAS_TOL, StepSolver
from shakedown.evolution.cycle_results import _energy


def coupled(rng, n, fraction=0.5):
    """Random coupled SPD K (M M^T + N I), friction at ``fraction`` of the sufficient bound."""
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T + n * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    return s.with_friction(fraction * min(s.critical_friction().value, 2.0))


def harmonic_load(rng, s, amp=2.0):
    n = s.n_nodes
    f = float(s.friction.max())
    return sd.LoadCycle.from_harmonics(0.1 * rng.normal(size=n), np.ones(n),
                                       q_cos=amp * f * rng.normal(size=n),
                                       p_sin=0.3 * rng.normal(size=n))


def slip_tol(s, scale):
    # the step's own zero (FEAS_TOL * force / K_jj) times 10: LU answers of these well-conditioned
    # systems agree to ~1e-13 relative (measured max 3e-14), far below it
    return 10 * FEAS_TOL * scale / s.A.diagonal().min()


# ---------------------------------------------------------------------------- single steps
@pytest.mark.parametrize("seed", range(4))
def test_warm_steps_equal_fresh_solver_and_lemke(seed):
    """A period of warm steps (cache hits, K rows kept, base carried over) against a fresh
    solver and Lemke from scratch at every step; the load reverses, so at some steps many nodes
    change state at once (all stick -> all slip -> all slip the other way)."""
    rng = np.random.default_rng(seed)
    n = 12
    s = coupled(rng, n)
    warm = StepSolver(s)
    q_a = 3.0 * rng.uniform(0.5, 1.5, n)
    p_w = np.full(n, 1.0)
    v = np.zeros(n)
    guess, base = None, None
    changed_max = 0
    steps = 24
    prev_q = r = None
    for _ in range(2):
        for k in range(steps):
            t = (k + 1) / steps
            q_w = q_a * np.sign(np.cos(2 * np.pi * t)) * (0.2 + abs(np.cos(2 * np.pi * t)))
            if r is not None:
                base = warm.next_base(r.q, r.p, r.gap, q_w - prev_q, 0.0 * p_w)
            r = warm.solve(v, q_w, p_w, guess, base=base)
            cold = StepSolver(s).solve(v, q_w, p_w)
            q0, p0 = q_w + s.A @ v, p_w + s.B.T @ v
            lem = StepSolver(s)._lemke_flexibility(q0, p0, r.force_scale)
            assert r.success and cold.success and lem.success
            tol = slip_tol(s, r.force_scale)
            np.testing.assert_allclose(r.slip, cold.slip, rtol=0, atol=tol)
            np.testing.assert_allclose(r.slip, v + lem.z[:n], rtol=0, atol=tol)
            np.testing.assert_array_equal(r.states, cold.states)
            assert r.equilibrium_residual <= FEAS_TOL
            if guess is not None:
                changed_max = max(changed_max, int(np.count_nonzero(r.active_set != guess)))
            v, guess, prev_q = r.slip, r.active_set, q_w
    assert changed_max >= n // 2  # the reversal switched many nodes in one step
    assert warm.totals["cache_hits"] > 0


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("rank", [dict(max_update_rank=8, update_fraction=0.0),
                                  dict(max_update_rank=0, update_fraction=0.9)])
def test_woodbury_updates_equal_refactorisation(seed, rank):
    """Low-rank updates forced on every changed assignment (a fixed rank cap, or up to 90 % of
    the factorized system's order) against fresh LU factors only."""
    rng = np.random.default_rng(10 + seed)
    n = 40
    s = coupled(rng, n, 0.4)
    upd = StepSolver(s, update_min_size=0, kernel=False, **rank)  # the Python LU path
    ref = StepSolver(s, max_update_rank=0, update_fraction=0.0, kernel=False)
    load = harmonic_load(rng, s, 1.0)
    qg, pg = load.evaluate(np.arange(1, 41) / 40, 1.0)
    v1 = v2 = np.zeros(n)
    g1 = g2 = None
    for q_w, p_w in zip(qg, pg, strict=True):
        r1 = upd.solve(v1, q_w, p_w, g1)
        r2 = ref.solve(v2, q_w, p_w, g2)
        np.testing.assert_allclose(r1.slip, r2.slip, rtol=0, atol=slip_tol(s, r1.force_scale))
        np.testing.assert_array_equal(r1.states, r2.states)
        v1, g1, v2, g2 = r1.slip, r1.active_set, r2.slip, r2.active_set
    assert upd.totals["updates"] > 0 and ref.totals["updates"] == 0


# ---------------------------------------------------------------------------- batched states
@pytest.mark.parametrize("seed", range(3))
def test_batched_states_equal_independent_runs(seed, monkeypatch):
    """Several initial states run together give the steady W, stuck nodes and final states of
    independent runs, to the solver tolerance; duplicated states go through the shared
    multi-right-hand-side path of the Python step (counted; the compiled kernel, tested in
    test_kernel.py, is switched off here)."""
    calls = []
    real = multistate._group
    monkeypatch.setattr(multistate, "_group",
                        lambda *a, **k: (calls.append(a[2].size), real(*a, **k))[1])
    rng = np.random.default_rng(20 + seed)
    n = 8
    s = coupled(rng, n)
    load = harmonic_load(rng, s)
    V0 = sd.sample_initial_slips(s, load, 3, rng=rng)
    V0 = np.vstack([V0, V0[1]])  # a duplicate: shares every active set with state 1
    kw = dict(steps_per_cycle=24, tol=1e-10)
    for lam in (0.5, 1.5):
        batch = sd.solve_cycles(s, load, lam, initial_slip=V0,
                                solver=StepSolver(s, kernel=False), **kw)
        assert isinstance(batch, list) and len(batch) == len(V0)
        for v0, b in zip(V0, batch, strict=True):
            ind = sd.solve_cycles(s, load, lam, initial_slip=v0,
                                  solver=StepSolver(s, kernel=False), **kw)
            assert b.status == ind.status == "periodic"
            # W is a sum of N * steps products of forces and slips each exact to ~1e-13
            # relative: 1e-9 relative to the dissipation scale F^2 / K is far above that
            Wscale = b.force_scale ** 2 / s.A.diagonal().min()
            assert b.steady_dissipation == pytest.approx(ind.steady_dissipation, rel=0,
                                                         abs=1e-9 * Wscale)
            np.testing.assert_array_equal(b.stuck_nodes, ind.stuck_nodes)
            np.testing.assert_array_equal(b.final_active_sets, ind.final_active_sets)
            np.testing.assert_allclose(b.final_slip, ind.final_slip, rtol=0,
                                       atol=slip_tol(s, b.force_scale))
            assert b.n_cycles == ind.n_cycles
        # BLAS kernels may round the columns of one multi-RHS solve differently (measured
        # 8e-15 relative): equal to the solver tolerance, not bit for bit
        np.testing.assert_allclose(batch[1].final_slip, batch[3].final_slip, rtol=0,
                                   atol=slip_tol(s, batch[1].force_scale))
    assert calls and max(calls) >= 2


def test_batched_states_bad_input():
    rng = np.random.default_rng(1)
    s = coupled(rng, 3)
    load = harmonic_load(rng, s)
    with pytest.raises(sd.InputError, match=r"initial_slip\[1\]"):
        sd.solve_cycles(s, load, 1.0, initial_slip=[[0.0] * 3, [0.0, np.nan, 0.0]])
    with pytest.raises(sd.InputError, match="initial_gap must have shape"):
        sd.solve_cycles(s, load, 1.0, initial_slip=np.zeros((2, 3)), initial_gap=np.zeros((3, 3)))
    with pytest.raises(sd.InputError, match="n_states >= 1"):
        sd.solve_cycles(s, load, 1.0, initial_slip=np.zeros((0, 3)))
    with pytest.raises(sd.InputError, match=r"update_fraction must be in \[0, 1\); got 1.5"):
        StepSolver(s, update_fraction=1.5)


# ---------------------------------------------------------------------------- self-checks
def test_self_checks_flag_wrong_answers():
    """Complementarity residual, per-period equilibrium check and energy identity, each on a
    deliberately wrong answer."""
    rng = np.random.default_rng(3)
    n = 6
    s = coupled(rng, n)
    load = harmonic_load(rng, s)
    solver = StepSolver(s)
    q_w, p_w = load.evaluate(0.25, 1.0)
    r = solver.solve(np.zeros(n), q_w, p_w)
    z = np.concatenate([r.slip_increment, r.gap])
    assert solver.residuals(z, r.q, r.p, None, None, r.force_scale) <= FEAS_TOL
    j = int(np.argmax(np.abs(r.slip_increment) + (r.states == 0)))
    zbad = z.copy()
    zbad[j] += 1e-6 * r.force_scale / s.A[j, j]  # a slip at a stuck node, or a wrong slip
    qb, pb = solver._reactions(zbad, q_w + s.A @ np.zeros(n), p_w)
    assert solver.residuals(zbad, qb, pb, None, None, r.force_scale) > 100 * FEAS_TOL

    run = sd.solve_cycles(s, load, 1.5, steps_per_cycle=16)
    qg, pg = load.evaluate(np.arange(1, 17) / 16, 1.5)
    V = np.vstack([run.final_slip] * 17)
    Wg = np.zeros_like(V)
    Q, P = s.reactions(V, Wg, np.vstack([qg[-1], qg]), np.vstack([pg[-1], pg]))
    scales = np.full(16, run.force_scale)
    worst, msg = multistate._check_period(solver, 1, V, Wg, Q, P, qg, pg, scales, 0.0)
    assert worst <= 1e-12 and msg == ""
    Q[5, 2] += 1e-6 * run.force_scale
    worst, msg = multistate._check_period(solver, 1, V, Wg, Q, P, qg, pg, scales, 0.0)
    assert worst > 1e-7 and "step 5 of period 1" in msg

    class Rec:  # one closed orbit whose dissipation is wrong by 1 %
        pass

    ok = run.energy_identity
    assert ok.discrete_relative_difference <= 1e-9
    tab = run.steady_table
    times = np.unique(tab["t"].to_numpy())
    rec = Rec()
    rec.t = times
    rec.v = tab.pivot(index="t", columns="node", values="slip").to_numpy()
    rec.w = tab.pivot(index="t", columns="node", values="gap").to_numpy()
    rec.p = tab.pivot(index="t", columns="node", values="p").to_numpy()
    rec.dissipation = run.steady_dissipation
    good = _energy([rec], run.load, 1.5, solver.diag, run.force_scale, run.tol, K=s.K,
                   implicit=True)
    assert good.discrete_relative_difference <= 1e-9
    rec.dissipation = 1.01 * run.steady_dissipation
    bad = _energy([rec], run.load, 1.5, solver.diag, run.force_scale, run.tol, K=s.K,
                  implicit=True)
    assert bad.discrete_relative_difference > 1e-3


# ---------------------------------------------------------------------------- units
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), k_exp=st.floats(-6, 12), f_exp=st.floats(-6, 12))
def test_answers_are_scale_free(seed, k_exp, f_exp):
    """K times sK and loads times sF (any factors in 1e-6 .. 1e12, not powers of two): the
    steady W scales as sF^2 / sK, slips as sF / sK, node states and stuck nodes are
    identical."""
    sK, sF = 10.0 ** k_exp, 10.0 ** f_exp
    rng = np.random.default_rng(seed)
    n = 5
    s = coupled(rng, n)
    load = harmonic_load(rng, s)
    s2 = sd.DiscreteSystem(sK * s.A, sK * s.B, sK * s.C, friction=s.friction)
    load2 = sd.LoadCycle.from_harmonics(sF * load.q0, sF * load.p0, q_cos=sF * load.q_cos,
                                        q_sin=sF * load.q_sin, p_cos=sF * load.p_cos,
                                        p_sin=sF * load.p_sin)
    v0 = sd.sample_initial_slips(s, load, 2, rng=rng)[1]
    kw = dict(steps_per_cycle=16)
    a = sd.solve_cycles(s, load, 1.2, initial_slip=v0, **kw)
    b = sd.solve_cycles(s2, load2, 1.2, initial_slip=v0 * sF / sK, **kw)
    assert a.status == b.status == "periodic"
    assert a.n_cycles == b.n_cycles
    np.testing.assert_array_equal(a.final_active_sets, b.final_active_sets)
    np.testing.assert_array_equal(a.stuck_nodes, b.stuck_nodes)
    # every quantity is computed in the same floating-point operations up to the two scale
    # factors, so the relative agreement is rounding (measured <= 1e-12); W is a difference of
    # sums, hence compared against its natural scale F^2 / K
    Wscale = a.force_scale ** 2 / s.A.diagonal().min()
    assert b.steady_dissipation * sK / sF ** 2 == pytest.approx(a.steady_dissipation, rel=0,
                                                                abs=1e-9 * Wscale)
    np.testing.assert_allclose(b.final_slip * sK / sF, a.final_slip, rtol=0,
                               atol=slip_tol(s, a.force_scale))


@pytest.mark.parametrize("sK, sF", [(3.7e-6, 2.1e11), (4.3e9, 7.7e-5), (1.0, 1.0)])
def test_lemke_fallbacks_are_scale_free(sK, sF):
    """Both Lemke fallbacks on the same step in other units give the same answer rescaled."""
    rng = np.random.default_rng(5)
    n = 6
    s = coupled(rng, n)
    s2 = sd.DiscreteSystem(sK * s.A, sK * s.B, sK * s.C, friction=s.friction)
    q0 = 2.0 * rng.normal(size=n)
    p0 = rng.uniform(-0.5, 1.5, n)  # some nodes pulled open
    scale = float(max(np.abs(q0).max(), np.abs(p0).max()))
    allowed, forced = np.ones((n, 4), bool), np.zeros(n, bool)
    ref = StepSolver(s)._lemke_flexibility(q0, p0, scale)
    assert ref.success
    for name in ("flex", "mixed"):
        a = (StepSolver(s)._lemke_flexibility(q0, p0, scale) if name == "flex" else
             StepSolver(s)._lemke(q0, p0, allowed, forced, scale))
        b = (StepSolver(s2)._lemke_flexibility(sF * q0, sF * p0, sF * scale) if name == "flex"
             else StepSolver(s2)._lemke(sF * q0, sF * p0, allowed, forced, sF * scale))
        assert a.success and b.success
        np.testing.assert_array_equal(a.s, b.s)
        # the slip tolerance of the step (answers of the same pivots, rounding ~1e-14)
        tol = np.concatenate([slip_tol(s, scale) * np.ones(n), slip_tol(s, scale) * np.ones(n)])
        np.testing.assert_array_less(np.abs(b.z * sK / sF - a.z), tol)
        np.testing.assert_array_less(np.abs(a.z - ref.z), tol)


def test_critical_friction_once_per_system(monkeypatch):
    """Solvers and runs of one system share one critical-friction computation; another
    friction (a new frozen system) gets its own."""
    rng = np.random.default_rng(7)
    s = coupled(rng, 5)
    load = harmonic_load(rng, s)
    calls = []
    import shakedown.model.system as system_module

    real = system_module.critical_friction_2d
    monkeypatch.setattr(system_module, "critical_friction_2d",
                        lambda self, k: (calls.append(k), real(self, k))[1])
    first = s.critical_friction()
    for _ in range(3):
        sd.solve_cycles(s, load, 1.0, steps_per_cycle=8, max_cycles=2)
    sd.solve_cycles(s, load, 1.0, initial_slip=np.zeros((2, 5)), steps_per_cycle=8,
                    max_cycles=2)
    assert s.critical_friction() is first and len(calls) == 1
    s2 = s.with_friction(0.5 * s.friction)
    assert s2.critical_friction().factor == pytest.approx(2 * first.factor, rel=1e-12)
    assert len(calls) == 2


# ------------------------------------------------ issue 25: the Python step's shortcuts
FIELDS = ("slip", "gap", "slip_increment", "q", "p", "states", "active_set")


@pytest.mark.parametrize("seed", range(6))
def test_stick_step_equals_the_general_step(seed):
    """An all-stick guess that holds is answered without the active-set machinery
    (``StepSolver._stick_step``): the same fields as the general path (``verify=True`` takes
    it), bit for bit; a guess whose signs fail goes the general way (the answer slips)."""
    rng = np.random.default_rng(seed)
    n = 8
    s = coupled(rng, n)
    solver = StepSolver(s, kernel=False)
    v = 0.01 * rng.normal(size=n)
    f = float(s.friction.max())
    p_w = np.full(n, 1.0)
    for amp, sticks in ((0.05 * f, True), (5.0 * f, False)):
        q_w = amp * rng.uniform(-1.0, 1.0, n) - s.A @ v
        fast = solver.solve(v, q_w, p_w, np.zeros(n, np.int8), verify=False)
        ref = StepSolver(s, kernel=False).solve(v, q_w, p_w, np.zeros(n, np.int8))
        assert fast.success and ref.success and fast.status == ref.status == "unique"
        assert (not np.any(fast.active_set)) is sticks
        for name in FIELDS:
            assert np.array_equal(getattr(fast, name), getattr(ref, name)), name
        assert fast.complementarity_residual == pytest.approx(ref.complementarity_residual,
                                                              rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("seed", range(3))
def test_predicted_assignments_change_no_answer(seed, monkeypatch):
    """The previous period's assignments tried first (``StepSolver._probe``, accepted only
    strictly inside their checks): the runs equal those without the probe (discrete outcomes
    exactly, dissipation and slips to round-off), and the probe was used."""
    rng = np.random.default_rng(100 + seed)
    n = 6
    s = coupled(rng, n)
    load = harmonic_load(rng, s)
    V0 = 0.2 * rng.normal(size=(2, n))
    opts = dict(steps_per_cycle=32, max_cycles=40)
    accepted = []
    probe = StepSolver._probe

    def counting(self, *args):
        out = probe(self, *args)
        accepted.append(out is not None)
        return out

    monkeypatch.setattr(StepSolver, "_probe", counting)
    runs = [sd.solve_cycles(s, load, 1.5, initial_slip=v0, **opts,
                            solver=StepSolver(s, kernel=False))
            for v0 in V0]
    assert sum(accepted) > 0
    monkeypatch.setattr(StepSolver, "_probe", lambda self, *args: None)
    refs = [sd.solve_cycles(s, load, 1.5, initial_slip=v0, **opts,
                            solver=StepSolver(s, kernel=False))
            for v0 in V0]
    for a, b in zip(runs, refs, strict=True):
        assert (a.status, a.period, a.cycles_to_steady, a.shook_down) == (
            b.status, b.period, b.cycles_to_steady, b.shook_down)
        assert a.steady_dissipation == pytest.approx(b.steady_dissipation, rel=1e-9, abs=1e-12)
        scale = a.force_scale / s.A.diagonal().min()
        assert np.max(np.abs(a.final_slip - b.final_slip)) <= 1e-8 * scale
