"""An uncondensed system (issue 14: "sparse K where the model gives one"): ``K`` the Schur
complement of a sparse ``K_z``, never formed.  Its runs, bounds and certificates equal those of
the dense twin, whose ``K`` is condensed here independently (numpy ``solve`` on the dense
``K_z``), on random sparse SPD ``K_z`` with interior DOFs."""

import pickle

import numpy as np
import pytest
import scipy.sparse as sp
from test_sparse_step import assert_same_run  # (this folder: the same comparison of two runs)

import shakedown as sd
from shakedown.evolution import schur_step
from shakedown.evolution.complementarity import StepSolver
from shakedown.model.errors import InputError, NotPositiveDefiniteError, NotSymmetricError
from shakedown.model.schur import SchurStiffness
from shakedown.model.uncondensed import UncondensedSystem


def random_kz(n, m, seed, scale=1.0):
    """A random sparse SPD ``K_z`` (``R^T R + 0.2 I``, ``R`` about 3 entries per row) over ``2n``
    contact unknowns and ``m`` interior DOFs, and its dense condensation by numpy."""
    rng = np.random.default_rng(seed)
    size = 2 * n + m
    R = sp.random(size, size, density=min(1.0, 3.0 / size), random_state=rng,
                  data_rvs=rng.standard_normal) + sp.eye(size)
    Kz = (R.T @ R + 0.2 * sp.eye(size)).tocsr() * scale
    D = Kz.toarray()
    c = 2 * n
    K = D[:c, :c] - D[:c, c:] @ np.linalg.solve(D[c:, c:], D[c:, :c])
    return Kz, 0.5 * (K + K.T)


def pair(n, m, seed, friction=None, scale=1.0):
    """``(uncondensed, dense twin)``, friction half the twin's sufficient bound (at most 0.8)."""
    Kz, K = random_kz(n, m, seed, scale)
    d = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], 1.0)
    f = friction if friction is not None else 0.5 * min(d.critical_friction().value, 1.6)
    return UncondensedSystem(Kz, n, f), d.with_friction(f)


# ---------------------------------------------------------------------- the operator
def test_schur_products_and_entries_equal_numpy():
    n, m = 9, 40
    Kz, K = random_kz(n, m, 1)
    S = SchurStiffness(Kz, n)
    rng = np.random.default_rng(0)
    x = rng.standard_normal(2 * n)
    X = rng.standard_normal((2 * n, 5))
    tol = 1e-12 * np.abs(K).max()
    np.testing.assert_allclose(S @ x, K @ x, atol=tol * 10)
    np.testing.assert_allclose(S @ X, K @ X, atol=tol * 10)
    np.testing.assert_allclose(X.T @ S, X.T @ K, atol=tol * 10)
    np.testing.assert_allclose(S.toarray(), K, atol=tol)
    np.testing.assert_allclose(S.diagonal(), np.diag(K), atol=tol)
    np.testing.assert_allclose(S.columns([3, 11]), K[:, [3, 11]], atol=tol)
    np.testing.assert_allclose(S[4], K[4], atol=tol)
    rows, cols = [0, 2, 12], [1, 5]
    np.testing.assert_allclose(S[np.ix_(rows, cols)], K[np.ix_(rows, cols)], atol=tol)
    u = UncondensedSystem(Kz, n, 0.3)
    for blk, ref in ((u.A, K[:n, :n]), (u.B, K[:n, n:]), (u.C, K[n:, n:]), (u.B.T, K[n:, :n])):
        np.testing.assert_allclose(blk.toarray(), ref, atol=tol)
        np.testing.assert_allclose(blk @ x[:n], ref @ x[:n], atol=10 * tol)
        np.testing.assert_allclose(blk.diagonal(), np.diag(ref), atol=tol)
    assert u.condition_number == pytest.approx(np.linalg.cond(K), rel=1e-6)
    assert u.is_coupled and u.is_sparse and u.nnz == Kz.nnz
    sub = u.subsystem([1, 4])
    np.testing.assert_allclose(sub.B, K[np.ix_([1, 4], [n + 1, n + 4])], atol=tol)


def test_uncoupled_and_one_node_limits():
    """``B = 0`` (contact slips and gaps not coupled, directly or through the interior):
    ``is_coupled`` is False and the critical friction infinite; one node: the exact bound."""
    Kz1, _ = random_kz(4, 10, 2)
    Kz2, _ = random_kz(4, 10, 3)
    D1, D2 = Kz1.toarray(), Kz2.toarray()
    # slips + interior from one matrix, gaps alone: [[Kvv, 0, Kvi], [0, Kww, 0], [Kiv, 0, Kii]]
    Kz = np.zeros((18, 18))
    v, w, i = np.arange(4), np.arange(4, 8), np.arange(8, 18)
    Kz[np.ix_(v, v)], Kz[np.ix_(w, w)] = D1[:4, :4], D2[4:8, 4:8]
    Kz[np.ix_(i, i)], Kz[np.ix_(v, i)], Kz[np.ix_(i, v)] = D1[8:, 8:], D1[:4, 8:], D1[8:, :4]
    u = UncondensedSystem(sp.csr_matrix(Kz), 4, 0.5)
    assert not u.is_coupled
    assert u.critical_friction().factor == np.inf
    one, K1 = random_kz(1, 6, 4)
    s1 = UncondensedSystem(one, 1, 0.5)
    cf = s1.critical_friction()
    assert cf.method == "single-node" and cf.exact
    assert cf.factor == pytest.approx(K1[0, 0] / abs(K1[0, 1]) / 0.5, rel=1e-12)


# ---------------------------------------------------------------------- the cyclic solver
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("lam", [0.4, 1.5])
def test_uncondensed_runs_equal_dense_runs(seed, lam, harmonic_load):
    """Shakedown to cyclic slip, with separation for seeds 2-3 (normal load dips below 0)."""
    rng = np.random.default_rng(seed)
    u, d = pair(20, 60, seed)
    load = harmonic_load(rng, d, p_mean=1.0 if seed < 2 else 0.2, p_amp=0.3 if seed < 2 else 0.6)
    a = sd.solve_cycles(u, load, lam, steps_per_cycle=24, max_cycles=40)
    b = sd.solve_cycles(d, load, lam, steps_per_cycle=24, max_cycles=40)
    assert_same_run(a, b, d)
    if b.energy_identity is not None:
        assert a.energy_identity.discrete_relative_difference < 1e-9
        assert a.energy_identity.closed_integral == pytest.approx(
            b.energy_identity.closed_integral, rel=1e-9, abs=1e-12)


def test_uncondensed_solver_never_forms_k(monkeypatch, harmonic_load):
    """The step factorizes the assignment systems with the interior DOFs (one sparse LU each)
    and never forms ``K``: ``toarray`` of the Schur complement is never called."""
    rng = np.random.default_rng(7)
    u, d = pair(40, 120, 7)
    load = harmonic_load(rng, d, amp=3.0)

    def forbidden(self, *a, **k):
        raise AssertionError("K was formed")

    monkeypatch.setattr(SchurStiffness, "toarray", forbidden)
    solver = StepSolver(u)
    assert solver.schur and not solver.kernel
    run = sd.solve_cycles(u, load, 1.2, steps_per_cycle=32, max_cycles=20, solver=solver)
    assert run.status in ("periodic", "shakedown")
    assert solver.totals["factorizations"] > 0 and solver.totals["lemke_calls"] == 0
    F = next(iter(solver._cache.values()))
    assert isinstance(F.lu, schur_step.AugmentedLU)


def test_uncondensed_many_nodes_change_state_at_once(harmonic_load):
    """A load jump from zero to beyond gross slip: most nodes slip in the first step."""
    rng = np.random.default_rng(3)
    u, d = pair(120, 200, 3)
    load = harmonic_load(rng, d, amp=6.0)
    a = sd.solve_cycles(u, load, 1.0, steps_per_cycle=8, max_cycles=6)
    b = sd.solve_cycles(d, load, 1.0, steps_per_cycle=8, max_cycles=6,
                        solver=StepSolver(d, kernel=False))
    assert_same_run(a, b, d)
    assert np.mean(a.cycle_start_slips[1] != 0) > 0.5  # most nodes slipped in the first cycle


def test_uncondensed_multistate_events_and_steady_cycle_equal_dense(harmonic_load):
    rng = np.random.default_rng(5)
    u, d = pair(15, 50, 5)
    load = harmonic_load(rng, d)
    V0 = 0.2 * rng.normal(size=(4, 15)) / d.A.diagonal().min()
    ra = sd.solve_cycles(u, load, 1.0, initial_slip=V0, steps_per_cycle=16, max_cycles=30)
    rb = sd.solve_cycles(d, load, 1.0, initial_slip=V0, steps_per_cycle=16, max_cycles=30)
    for a, b in zip(ra, rb, strict=True):
        assert_same_run(a, b, d)
    ea = sd.solve_cycles(u, load, 1.0, method="events", steps_per_cycle=16, max_cycles=20)
    eb = sd.solve_cycles(d, load, 1.0, method="events", steps_per_cycle=16, max_cycles=20)
    assert_same_run(ea, eb, d)
    sa = sd.steady_cycle(u, load, 1.5, steps_per_cycle=16)
    sb = sd.steady_cycle(d, load, 1.5, steps_per_cycle=16)
    assert sa.status == sb.status == "converged"
    assert sa.steady_dissipation == pytest.approx(sb.steady_dissipation, rel=1e-9, abs=1e-300)


@pytest.mark.parametrize("force, length", [(1e6, 1.0), (1.0, 1e-4)])
def test_uncondensed_run_units(force, length, harmonic_load):
    """Forces x F, lengths x L: K_z x F / L, slips x L, dissipation x F L."""
    rng = np.random.default_rng(11)
    u, d = pair(12, 30, 11)
    u2 = UncondensedSystem(u.Kz * (force / length), 12, u.friction)
    load = harmonic_load(rng, d)
    parts = {k: getattr(load, k) * force for k in ("q_cos", "q_sin", "p_cos", "p_sin")
             if getattr(load, k) is not None}
    load2 = sd.LoadCycle.from_harmonics(load.q0 * force, load.p0 * force, **parts)
    a = sd.solve_cycles(u, load, 1.3, steps_per_cycle=16, max_cycles=30)
    b = sd.solve_cycles(u2, load2, 1.3, steps_per_cycle=16, max_cycles=30)
    assert a.n_cycles == b.n_cycles and a.status == b.status
    np.testing.assert_allclose(b.dissipation, a.dissipation * force * length, rtol=1e-8,
                               atol=1e-10 * abs(a.dissipation).max() * force * length)
    np.testing.assert_allclose(b.final_slip, a.final_slip * length, rtol=1e-7,
                               atol=1e-9 * length * abs(a.final_slip).max())
    ba, bb = sd.shakedown_bounds(u, load), sd.shakedown_bounds(u2, load2)
    assert bb.lam1 == pytest.approx(ba.lam1, rel=1e-9)
    assert bb.lam2 == pytest.approx(ba.lam2, rel=1e-9)


def test_wrong_schur_factor_is_caught(monkeypatch, harmonic_load):
    """Every augmented solve 1e-3 off: the answers fail their own checks (the run stops with
    ``step_failed``), never a silently wrong dissipation."""
    rng = np.random.default_rng(2)
    u, d = pair(20, 60, 2)
    load = harmonic_load(rng, d, amp=3.0)
    real = schur_step.factor

    def wrong(*a, **k):
        lu = real(*a, **k)
        if lu is not None:
            good = lu.lu

            class Off:
                L, U, shape = good.L, good.U, good.shape

                def solve(self, b, trans="N"):
                    return good.solve(b, trans) * (1 + 1e-3)

            lu.lu = Off()
        return lu

    monkeypatch.setattr(schur_step, "factor", wrong)
    bad = sd.solve_cycles(u, load, 1.5, steps_per_cycle=16, max_cycles=20)
    assert bad.status == "step_failed", "a 1e-3 error in every solve must not pass the checks"


# ---------------------------------------------------------------------- bounds, certificates
@pytest.mark.parametrize("seed", [0, 3])
def test_uncondensed_bounds_and_critical_friction_equal_dense(seed, harmonic_load):
    rng = np.random.default_rng(seed)
    u, d = pair(25, 70, seed)
    load = harmonic_load(rng, d, p_mean=0.4, p_amp=0.6)
    a = sd.shakedown_bounds(u, load, adjacency=True)
    b = sd.shakedown_bounds(d, load, adjacency=True)
    assert a.status == b.status == "bounded"
    for q in ("lam1", "lam2", "lam_adj", "lam_separation"):
        assert getattr(a, q) == pytest.approx(getattr(b, q), rel=1e-9), q
    ca, cb = u.critical_friction(), d.critical_friction()
    assert ca.method == cb.method == "sufficient-bound"
    assert ca.factor == pytest.approx(cb.factor, rel=1e-8)
    assert ca.upper_bound == pytest.approx(cb.upper_bound, rel=1e-10)
    # beyond the dense-C budget: Lanczos with products by C (the same value)
    from shakedown.model import schur
    from shakedown.model.uncondensed import UncondensedSystem as U

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(schur, "DENSE_C_BYTES", 0)
        lz = U(u.Kz, u.n_nodes, u.friction)
        assert lz.K.dense_C() is None
        assert lz.critical_friction().factor == pytest.approx(cb.factor, rel=1e-8)
    small_u, small_d = pair(3, 8, seed)  # enumeration (exact) through the dense twin
    assert small_u.critical_friction().factor == pytest.approx(
        small_d.critical_friction().factor, rel=1e-9)


def test_pickled_system_runs_the_same(harmonic_load):
    """Pickling drops the SuperLU factor (refactorized on first use)."""
    rng = np.random.default_rng(9)
    u, d = pair(10, 30, 9)
    load = harmonic_load(rng, d)
    u.K.diagonal()  # factorized before pickling
    v = pickle.loads(pickle.dumps(u))
    assert "UncondensedSystem(n_nodes=10, interior_dofs=30" in repr(v)
    a = sd.solve_cycles(u, load, 1.2, steps_per_cycle=16, max_cycles=20)
    b = sd.solve_cycles(v, load, 1.2, steps_per_cycle=16, max_cycles=20)
    assert_same_run(a, b, d)
    w = u.with_friction(0.1)
    assert w.K is u.K and np.all(w.friction == 0.1)


# ---------------------------------------------------------------------- bad input
def test_bad_kz_is_named():
    Kz, _ = random_kz(3, 6, 0)
    bad = Kz.tolil()
    bad[0, 7] += 1.0  # not symmetric
    with pytest.raises(NotSymmetricError, match="Kz"):
        UncondensedSystem(bad.tocsr(), 3, 0.3)
    neg = Kz - 50.0 * sp.eye(Kz.shape[0])
    with pytest.raises(NotPositiveDefiniteError, match="Kz"):
        UncondensedSystem(neg.tocsr(), 3, 0.3)
    # an interior DOF with no stiffness at all: exactly singular
    sing = Kz.tolil()
    sing[10, :] = 0.0
    sing[:, 10] = 0.0
    with pytest.raises(NotPositiveDefiniteError, match="Kz"):
        UncondensedSystem(sing.tocsr(), 3, 0.3)
    with pytest.raises(Exception, match="Kz"):
        UncondensedSystem(Kz, 7, 0.3)  # fewer than 2 N rows
    nan = Kz.copy()
    nan.data[0] = np.nan
    with pytest.raises(InputError, match="Kz"):
        UncondensedSystem(nan, 3, 0.3)
    with pytest.raises(InputError, match="friction"):
        UncondensedSystem(Kz, 3, -0.1)
    # an ill-conditioned Schur complement (a contact unknown 1e-14 as stiff as the rest)
    ill = Kz.tolil()
    ill[0, :] = 0.0
    ill[:, 0] = 0.0
    ill[0, 0] = 1e-14
    with pytest.raises(NotPositiveDefiniteError, match="condition"):
        UncondensedSystem(ill.tocsr(), 3, 0.3)


def test_stability_takes_an_uncondensed_system():
    """The complementarity eigenproblem (dense) on an uncondensed system: ``K`` densified once,
    the same ``mu*`` as the dense twin."""
    from shakedown import stability as st

    u, d = pair(6, 20, 1)
    part = st.NodePartition.all_slip(6)
    a, b = st.mceip_mu(u, part), st.mceip_mu(d, part)
    assert a.verified and b.verified
    assert a.mu == pytest.approx(b.mu, rel=1e-9)
