"""The step problem's sign checks and residual (the Python step path's verifier, issue 25).

``ActiveSet._step_candidates`` (per-assignment masks cached by ``_sign_layout``) and the step
branch of ``ActiveSet.residuals`` against a node-by-node reference written from MODEL.md s.4
(plain Python per node), against the general rate-problem checks (``_violations`` with every
state allowed), and on assignments revisited in any order (the cache must not hand one
assignment's masks to another).  Random systems, states, increments and reactions at force
scales 1e-6 .. 1e12 (the checks are normalised: the same numbers at every scale).
"""

import numpy as np
import pytest

import shakedown as sd
from shakedown.evolution.complementarity import StepSolver
from shakedown.evolution.step_types import BACKWARD, FORWARD, SEPARATED, STICK


def _solver(rng, n, unit):
    M = rng.normal(size=(2 * n, 2 * n))
    K = unit * (M @ M.T + n * np.eye(2 * n))
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], friction=rng.uniform(0.1, 0.9, n))
    return StepSolver(s, kernel=False)


def _reference(sol, s, z, q, p, ft):
    """(4, N) candidates node by node (MODEL.md s.4; -inf where a check does not apply)."""
    n = sol.n
    dtol = ft / sol.diag
    out = np.full((4, n), -np.inf)
    for j in range(n):
        fp = sol.f[j] * p[j]
        if s[j] == STICK:
            out[FORWARD, j] = -(fp + q[j]) / ft
            out[BACKWARD, j] = (q[j] - fp) / ft
        elif s[j] == FORWARD:
            out[STICK, j] = -z[j] / dtol[j]
        elif s[j] == BACKWARD:
            out[STICK, j] = z[j] / dtol[j]
        else:
            out[STICK, j] = -z[n + j] / dtol[n + j]
        if s[j] != SEPARATED:
            out[SEPARATED, j] = -p[j] / ft
    return out


def _sample(rng, sol, unit):
    n = sol.n
    s = rng.integers(0, 4, n).astype(np.int8)
    F = unit * rng.uniform(0.5, 2.0)  # force scale
    q, p = F * rng.normal(size=n), F * rng.normal(size=n)
    z = rng.normal(size=2 * n) * F / sol.diag * rng.choice([1e-12, 1e-9, 1.0], 2 * n)
    return s, z, q, p, 1e-9 * F


@pytest.mark.parametrize("unit", [1e-6, 1.0, 1e12])
def test_step_candidates_match_node_by_node_reference(unit):
    rng = np.random.default_rng(7)
    sol = _solver(rng, 9, unit)
    samples = [_sample(rng, sol, unit) for _ in range(40)]
    # visit assignments repeatedly and interleaved: the cached masks must follow the assignment
    for s, z, q, p, ft in samples + samples[::-1]:
        dtol = ft / sol.diag
        got = sol._step_candidates(s, z, q, p, ft, dtol)
        ref = _reference(sol, s, z, q, p, ft)
        np.testing.assert_allclose(got, ref, rtol=1e-15, atol=0)
        assert np.array_equal(np.isinf(got), np.isinf(ref))
        # the general checks (every state allowed, no node held) name the same target
        mag, target = sol._violations(s, z, q, p, sol._all_allowed, sol._none_forced, ft, dtol)
        v = sol._violations_step(s, z, q, p, ft, dtol)
        if mag.max() <= 1.0:
            assert v is None
        else:
            assert np.array_equal(v[1], target)
            np.testing.assert_allclose(v[0], mag, rtol=1e-15)


@pytest.mark.parametrize("unit", [1e-6, 1.0, 1e12])
def test_step_residual_matches_general_and_flags_violations(unit):
    rng = np.random.default_rng(11)
    sol = _solver(rng, 7, unit)
    n = sol.n
    for _ in range(30):
        s, z, q, p, ft = _sample(rng, sol, unit)
        scale = ft / 1e-9
        got = sol.residuals(z, q, p, None, None, scale)
        gen = sol.residuals(z, q, p, sol._all_allowed, sol._none_forced, scale)
        assert got == pytest.approx(gen, rel=1e-13)
        # node by node: max |min(x, y)| of the three pairs, x scaled by K_jj / scale
        d = sol.diag
        ref = 0.0
        for j in range(n):
            fp = sol.f[j] * p[j]
            dv, w = z[j] * d[j] / scale, z[n + j] * d[n + j] / scale
            for x, y in ((w, p[j] / scale), (max(dv, 0.0), (fp + q[j]) / scale),
                         (max(-dv, 0.0), (fp - q[j]) / scale)):
                ref = max(ref, abs(min(x, y)))
        assert got == pytest.approx(ref, rel=1e-13)
    # a complementary answer has no residual; a negative gap or contact force is flagged
    z0, q0 = np.zeros(2 * n), np.zeros(n)
    p0 = np.ones(n) * unit
    assert sol.residuals(z0, q0, p0, None, None, unit) == 0.0
    bad = z0.copy()
    bad[n + 2] = -0.5 * unit / sol.diag[n + 2]
    assert sol.residuals(bad, q0, p0, None, None, unit) == pytest.approx(0.5, rel=1e-12)
    p1 = p0.copy()
    p1[3] = -0.25 * unit
    assert sol.residuals(z0, q0, p1, None, None, unit) == pytest.approx(0.25, rel=1e-12)
    # a slip against an unsaturated friction limit is flagged, forward and backward
    for sign, j in ((1.0, 1), (-1.0, 4)):
        zs = z0.copy()
        zs[j] = sign * 2.0 * unit / sol.diag[j]  # |dv| K_jj / scale = 2
        qs = q0.copy()
        qs[j] = -sign * (sol.f[j] * p0[j] - 0.3 * unit)  # f p -+ q = 0.3 scale: not at the limit
        assert sol.residuals(zs, qs, p0, None, None, unit) == pytest.approx(0.3, rel=1e-9)
