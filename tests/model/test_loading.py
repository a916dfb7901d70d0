"""LoadCycle: exact extremes of harmonic loads vs dense sampling, samples, bad input (MODEL.md s.2).

Dense sampling at 2**16 points finds a smooth minimum to O((2 pi H / 2**16)^2) ~ 1e-7 relative
for H <= 3 harmonics, hence the 1e-6 tolerance; the exact extreme can never be above a sample.
"""

from __future__ import annotations

import numpy as np
import pytest

import shakedown as sd


@pytest.mark.parametrize("harmonics", [1, 2, 3])
def test_harmonic_extremes_vs_sampling(harmonics):
    rng = np.random.default_rng(harmonics)
    n = 5
    sh = (harmonics, n)
    load = sd.LoadCycle.from_harmonics(
        np.zeros(n), np.ones(n), q_cos=rng.standard_normal(sh), q_sin=rng.standard_normal(sh),
        p_cos=rng.standard_normal(sh), p_sin=rng.standard_normal(sh),
    )
    f = rng.uniform(0.1, 1.0, n)
    m, tmin = load.periodic_min(-1.0, f)
    t = np.arange(2**16) / 2**16
    q, p = load.periodic(t)
    dense = (-q + f * p).min(axis=0)
    assert np.all(m <= dense + 1e-12)
    # a 2^16-point grid misses the true minimum by at most g'' (dt)^2 / 8 ~ 1e-8 of the
    # amplitude for these harmonics: 1e-6 relative / 1e-9 absolute covers it
    np.testing.assert_allclose(m, dense, rtol=1e-6, atol=1e-9)
    qt, pt = load.periodic(tmin)
    # the reported time reproduces the minimum (root of g' polished by Newton: ~1e-14)
    np.testing.assert_allclose(np.diag(-qt + f * pt), m, rtol=1e-10, atol=1e-12)
    M, _ = load.periodic_max(-1.0, f)
    np.testing.assert_allclose(M, (-q + f * p).max(axis=0), rtol=1e-6, atol=1e-9)


def test_samples_interpolation_and_round_trip():
    rng = np.random.default_rng(0)
    q1, p1 = rng.standard_normal((8, 3)), rng.standard_normal((8, 3))
    load = sd.LoadCycle.from_samples(np.zeros(3), np.ones(3), q1, p1)
    q, p = load.periodic(np.array([0.0, 1 / 16, 1.0]))
    np.testing.assert_allclose(q[0], q1[0])
    np.testing.assert_allclose(q[1], 0.5 * (q1[0] + q1[1]))
    np.testing.assert_allclose(q[2], q1[0])  # periodic
    assert load.to_samples(8).q1 == pytest.approx(q1)
    m, _ = load.periodic_min(1.0, 0.0)
    np.testing.assert_allclose(m, q1.min(axis=0))
    qw, pw = load.evaluate(0.25, 2.0)
    np.testing.assert_allclose(qw, 2.0 * q1[2])
    np.testing.assert_allclose(pw, 1.0 + 2.0 * p1[2])


def test_bad_input_messages():
    # a length mismatch names both vectors (issue 9: a wrong q0 used to be reported as p0)
    with pytest.raises(sd.ShapeError, match="q0 has 2 entries but p0 has 1"):
        sd.LoadCycle.from_harmonics([0.0, 0.0], [1.0])
    with pytest.raises(sd.ShapeError, match="q0 has 3 entries but p0 has 2"):
        sd.LoadCycle.from_samples([0.0, 0.0, 1.0], [1.0, 1.0], np.ones((3, 2)), np.ones((3, 2)))
    with pytest.raises(sd.InputError, match="q0 must be finite"):
        sd.LoadCycle.from_harmonics([np.inf], [1.0])
    with pytest.raises(sd.ShapeError, match="q_cos must have shape"):
        sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=np.ones((2, 3)))
    with pytest.raises(sd.InputError, match="at least 2 samples"):
        sd.LoadCycle.from_samples([0.0], [1.0], [[1.0]], [[0.0]])
    with pytest.raises(sd.ShapeError, match="q1 and p1 must have the same shape"):
        sd.LoadCycle.from_samples([0.0], [1.0], np.ones((3, 1)), np.ones((4, 1)))
    with pytest.raises(sd.InputError, match="n_samples must be an integer >= 2"):
        sd.LoadCycle.static([0.0], [1.0]).to_samples(1)
