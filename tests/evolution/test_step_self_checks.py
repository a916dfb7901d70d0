"""Self-checks of the step solver proven able to fail (issue 15).

* The residual a ``StepResult`` reports must be the natural complementarity residual of the
  answer it reports (MODEL.md s.4, StepResult docstring), recomputed here from the result's
  own fields: on ill-conditioned systems the residual of a correct answer is measurably
  non-zero (up to ~1e-12), so a residual hard-wired to 0 is caught.
* The public verification (``StepSolver.residuals``) flags deliberately wrong answers.
* Lemke's lexicographic ratio test: degenerate LCPs (integer data, ties in the ratio test)
  on which Lemke with a plain tie rule (first / last row, ratio only) ends on a ray or cycles
  until its pivot budget; the lexicographic rule must solve every one of them.
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution.complementarity import FEAS_TOL, StepSolver
from shakedown.evolution.lemke import lemke


def natural_residual(system, r):
    """The documented residual, from the reported fields only (``slip_increment``, ``gap``,
    ``q``, ``p``, ``force_scale``): max |min(x, y)| over (w, p), (dv+, f p + q), (dv-, f p - q),
    forces scaled by force_scale, slips and gaps of node j by force_scale / K_jj."""
    n = system.n_nodes
    f, sc = system.friction, r.force_scale
    d = np.diag(system.K)
    dv = r.slip_increment
    x = np.concatenate([r.gap * d[n:], np.maximum(dv, 0) * d[:n], np.maximum(-dv, 0) * d[:n]]) / sc
    y = np.concatenate([r.p, f * r.p + r.q, f * r.p - r.q]) / sc
    return float(np.abs(np.minimum(x, y)).max())


def ill_conditioned(seed, n=4, cond=1e6):
    """SPD K with eigenvalues spread geometrically over ``cond`` (random eigenvectors)."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(2 * n, 2 * n)))
    K = (Q * np.geomspace(1.0, 1.0 / cond, 2 * n)) @ Q.T
    K = 0.5 * (K + K.T)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=1.0)
    return s.with_friction(0.5 * min(s.critical_friction().value, 1.0)), rng


def test_reported_residual_is_the_residual_of_the_reported_answer():
    worst = 0.0
    for seed in range(8):
        s, rng = ill_conditioned(seed)
        v = np.zeros(s.n_nodes)
        for _ in range(5):
            r = sd.solve_step(s, v, rng.normal(size=s.n_nodes), rng.normal(size=s.n_nodes) + 1)
            assert r.status == "unique"
            nat = natural_residual(s, r)
            # same quantity from the same fields: equal up to the order of a few roundings of
            # numbers of size 1 (1e-15 = 5 ulp); measured difference 0.0
            assert abs(r.complementarity_residual - nat) <= 1e-6 * nat + 1e-15, (seed, nat)
            assert r.residual >= r.complementarity_residual
            # the acceptance rule (StepResult.residual): 10 FEAS_TOL for the Lemke fallback
            # (numpy 2.4.6 / OpenBLAS 0.3.31: seed 6, first step: Lemke, residual 1.4e-9)
            assert r.residual <= (10 if r.method == "lemke" else 1) * FEAS_TOL
            worst = max(worst, nat)
            v = r.slip
    # premise: round-off leaves a visible residual on these systems (measured max 1.2e-12 at
    # condition number 1e6), so a reported residual of 0 cannot pass the check above
    assert worst > 1e-13


def test_residuals_flag_deliberately_wrong_answers():
    s = sd.DiscreteSystem([[4.0, 1.0], [1.0, 3.0]], [[0.3, 0.1], [-0.2, 0.4]],
                          [[5.0, 0.5], [0.5, 4.0]], friction=[0.4, 0.6])
    solver = StepSolver(s)
    q_w, p_w = np.array([-3.0, 0.5]), np.array([2.0, -1.0])  # node 0 slips forward, 1 opens
    r = solver.solve(np.zeros(2), q_w, p_w)
    assert r.success and list(r.state_names) == ["forward", "separation"]
    z = np.concatenate([r.slip_increment, r.gap])

    def res(z):
        q = q_w + s.A @ z[:2] + s.B @ z[2:]
        p = p_w + s.B.T @ z[:2] + s.C @ z[2:]
        return solver.residuals(z, q, p, None, None, r.force_scale)

    assert res(z) <= FEAS_TOL
    # wrong answers, each violating one condition of MODEL.md s.4 by a visible amount:
    bad = {
        "slip reversed": z * np.array([-1.0, 1.0, 1.0, 1.0]),
        "node 0 stuck (q beyond the cone)": z * np.array([0.0, 1.0, 1.0, 1.0]),
        "node 1 closed (tensile p)": z * np.array([1.0, 1.0, 1.0, 0.0]),
        "gap doubled (p != 0 while open)": z * np.array([1.0, 1.0, 1.0, 2.0]),
        "slip overshoot (q beyond f p)": z * np.array([1.5, 1.0, 1.0, 1.0]),
    }
    for name, zb in bad.items():
        assert res(zb) > 100 * FEAS_TOL, name


# Degenerate LCPs found by a search over integer data (tools/mutation_check.py reproduces the
# tie-rule mutations): the plain rules end on a ray or cycle, the lexicographic rule solves them.
DEGENERATE = [
    # defeat "first tied row"
    ([[-2, 2, -2, -2], [-2, -1, 2, 2], [-1, 1, -1, 2], [1, 0, -1, -2]], [0, 0, -1, 1]),
    ([[0, 1, -2, 0], [1, 1, 0, 1], [2, 2, 0, 2], [-1, 1, -2, 2]], [-2, -2, 1, -2]),
    ([[3, -1, 2, 2, -2], [0, 2, -1, -1, 0], [1, -1, 2, -1, 0], [3, 0, 0, 4, -1],
      [-1, 0, -1, 0, 2]], [-2, -2, -2, -1, 0]),
    ([[3, 1, -1, 4], [1, 2, -2, 1], [0, -1, 3, 0], [3, 0, 1, 4]], [-1, -1, -1, -1]),
    ([[0, 2, -2], [0, 2, -1], [2, 1, -1]], [-1, -1, -2]),
    # defeat "last tied row" (cycling)
    ([[2, -1, -2], [-1, 2, 2], [2, 1, -1]], [-1, -1, -1]),
    ([[2, -2, -2], [1, 0, 0], [2, 1, -1]], [-1, -1, -1]),
]


@pytest.mark.parametrize("M, q", DEGENERATE)
def test_lexicographic_lemke_solves_degenerate_problems(M, q):
    M, q = np.array(M, float), np.array(q, float)
    res = lemke(M, q)
    assert res.success, res.status
    w = M @ res.z + q
    # integer data of size <= 5: exact pivots up to round-off ~1e-15
    assert res.z.min() >= -1e-12 and w.min() >= -1e-12
    assert np.abs(res.z * w).max() <= 1e-12
    np.testing.assert_allclose(res.w, w, atol=1e-12)


# ---------------------------------------------------------------------------- energy identity
class _WrongReactions(StepSolver):
    """Returns every step with the tangential reactions of slipping nodes 2% too large (a
    wrong friction force that the step's own residual fields do not show)."""

    def solve(self, v_prev, q_w, p_w, guess=None, **kw):
        import dataclasses

        r = super().solve(v_prev, q_w, p_w, guess, **kw)
        slipping = r.slip_increment != 0
        return dataclasses.replace(r, q=np.where(slipping, 1.02 * r.q, r.q))


class _WrongSlips(StepSolver):
    """Returns every step with its slip increment 2% too large (reactions unchanged)."""

    def solve(self, v_prev, q_w, p_w, guess=None, **kw):
        import dataclasses

        r = super().solve(v_prev, q_w, p_w, guess, **kw)
        dv = 1.02 * r.slip_increment
        return dataclasses.replace(r, slip=v_prev + dv, slip_increment=dv)


@pytest.mark.parametrize("wrong", [_WrongReactions, _WrongSlips])
def test_energy_identity_flags_wrong_steps(wrong):
    """The exact discrete energy balance of the implicit steps (EnergyIdentity) holds to
    round-off for the real solver (measured 1e-16 relative) and is violated visibly (>1e-4)
    when the steps' answers are wrong by 2%."""
    s = sd.DiscreteSystem([[2.0, 0.5], [0.5, 2.0]], [[0.2, 0.1], [-0.1, 0.3]],
                          [[3.0, 0.0], [0.0, 3.0]], friction=0.4)
    load = sd.LoadCycle.from_harmonics([0.0, 0.1], [1.0, 1.0], q_cos=[1.0, 0.0],
                                       q_sin=[0.0, 1.0])
    kw = dict(steps_per_cycle=40, max_cycles=30)
    good = sd.solve_cycles(s, load, 0.9, **kw)
    assert good.status == "periodic" and good.steady_dissipation > 0
    assert good.energy_identity.discrete_relative_difference <= 1e-12
    bad = sd.solve_cycles(s, load, 0.9, solver=wrong(s, kernel=False), **kw)  # Python steps
    # Two self-checks guard the steps: the equilibrium of every period recomputed with K
    # (wrong reactions stop the run) and the discrete energy balance (wrong slips keep the
    # equilibrium but break the balance).  One of them must object.
    if bad.status == "step_failed":
        assert "equilibrium residual" in bad.message, bad.message
    else:
        assert bad.energy_identity is not None, bad.message
        assert bad.energy_identity.discrete_relative_difference > 1e-4, bad.energy_identity
