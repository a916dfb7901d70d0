"""The 3-D system and load types (MODEL.md s.8; docs/conventions.md s.8).

What these tests prove: the block layout (tangential unknowns node by node, then the gaps),
validation with messages naming the field, the load's shapes and exact extremes in a
direction, the sampling-error bound, and that a 2-D answer is unchanged when the same data
are given a second, unloaded and uncoupled tangential direction.
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import shakedown as sd
from shakedown.model.errors import InputError, ShapeError


def _random_3d(n, seed, friction=0.4, coupled=True):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    B = K[: 2 * n, 2 * n:] if coupled else np.zeros((2 * n, n))
    return sd.DiscreteSystem(K[: 2 * n, : 2 * n], B, K[2 * n:, 2 * n:], friction=friction,
                             dim=3), K


def test_blocks_and_reactions_follow_the_node_by_node_order():
    s, K = _random_3d(3, 0)
    assert (s.dim, s.n_nodes, s.n_tangential, s.K.shape) == (3, 3, 6, (9, 9))
    np.testing.assert_allclose(s.K, K, rtol=0, atol=1e-12 * np.abs(K).max())
    rng = np.random.default_rng(1)
    v, w = rng.normal(size=(3, 2)), rng.random(3)
    q_w, p_w = rng.normal(size=(3, 2)), rng.random(3)
    q, p = s.reactions(v, w, q_w, p_w)
    r = K @ np.concatenate([v.ravel(), w])  # (v_1x, v_1y, v_2x, ..., w_1, ...)
    np.testing.assert_allclose(q, q_w + r[:6].reshape(3, 2), rtol=1e-12)
    np.testing.assert_allclose(p, p_w + r[6:], rtol=1e-12)
    # batched states
    q2, p2 = s.reactions(np.stack([v, 2 * v]), np.stack([w, w]), q_w, p_w)
    assert q2.shape == (2, 3, 2) and p2.shape == (2, 3)
    np.testing.assert_allclose(q2[0], q, rtol=1e-12)


def test_subsystem_keeps_both_slips_of_each_node():
    s, K = _random_3d(4, 2)
    sub = s.subsystem([1, 3])
    rows = [2, 3, 6, 7, 8 + 1, 8 + 3]  # v_2x, v_2y, v_4x, v_4y, w_2, w_4
    np.testing.assert_allclose(sub.K, K[np.ix_(rows, rows)], rtol=1e-12)
    assert sub.dim == 3 and sub.n_nodes == 2


def test_sparse_and_dense_3d_systems_agree():
    s, _ = _random_3d(3, 3)
    sp_ = s.to_sparse()
    assert sp_.is_sparse and sp_.dim == 3
    np.testing.assert_array_equal(sp_.to_dense().K, s.K)
    assert s.with_friction(0.2).dim == 3


def test_friction_isotropic_and_anisotropic():
    s, _ = _random_3d(2, 4, friction=[[0.3, 0.5], [0.2, 0.2]])
    assert s.is_anisotropic and s.friction.shape == (2, 2)
    np.testing.assert_array_equal(s.friction_xy, [[0.3, 0.5], [0.2, 0.2]])
    iso, _ = _random_3d(2, 4, friction=[[0.3, 0.3], [0.2, 0.2]])  # equal columns: isotropic
    assert not iso.is_anisotropic and iso.friction.shape == (2,)
    np.testing.assert_array_equal(iso.friction_xy, [[0.3, 0.3], [0.2, 0.2]])
    two = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], 0.3)
    assert two.dim == 2 and not two.is_anisotropic
    with pytest.raises(InputError, match="friction_xy"):
        _ = two.friction_xy


@pytest.mark.parametrize("kwargs, error, field", [
    (dict(A=np.eye(3), B=np.zeros((3, 1)), C=[[1.0]]), ShapeError, "A must have shape \\(2N, 2N\\)"),
    (dict(A=np.eye(2), B=np.zeros((1, 1)), C=[[1.0]]), ShapeError, "B must have shape \\(2, 1\\)"),
    (dict(A=np.eye(2), B=np.zeros((2, 1)), C=np.eye(2)), ShapeError, "C must have shape"),
    (dict(A=np.eye(2), B=np.zeros((2, 1)), C=[[1.0]], friction=[[0.3, -0.1]]), InputError,
     "friction must be >= 0"),
    (dict(A=np.eye(2), B=np.zeros((2, 1)), C=[[1.0]], friction=[0.3, 0.3, 0.3]), ShapeError,
     "friction must be a scalar"),
    (dict(A=[[1.0, 2.0], [2.0, 1.0]], B=np.zeros((2, 1)), C=[[1.0]]), Exception,
     "positive definite"),
])
def test_bad_3d_systems_are_refused_naming_the_field(kwargs, error, field):
    kwargs.setdefault("friction", 0.3)
    with pytest.raises(error, match=field):
        sd.DiscreteSystem(dim=3, **kwargs)


@pytest.mark.parametrize("dim", [4, 1, True, "3"])
def test_dim_must_be_2_or_3(dim):
    with pytest.raises(InputError, match="dim must be 2 or 3"):
        sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], 0.3, dim=dim)


def test_anisotropic_friction_is_refused_in_2d():
    with pytest.raises(ShapeError, match="friction"):
        sd.DiscreteSystem(np.eye(2), np.zeros((2, 2)), np.eye(2), [[0.3, 0.2]] * 2)


# ------------------------------------------------------------------ loads
def _load3(n, seed, harmonics=1):
    rng = np.random.default_rng(seed)
    return sd.LoadCycle.from_harmonics(
        q0=rng.normal(size=(n, 2)), p0=1 + rng.random(n),
        q_cos=rng.normal(size=(harmonics, n, 2)), q_sin=rng.normal(size=(harmonics, n, 2)),
        p_cos=0.2 * rng.normal(size=(harmonics, n)))


def test_load_shapes_and_dimension():
    load = _load3(3, 0, harmonics=2)
    assert load.dim == 3 and load.n_nodes == 3 and load.q_cos.shape == (2, 3, 2)
    q, p = load.evaluate(np.array([0.1, 0.7]), 2.0)
    assert q.shape == (2, 3, 2) and p.shape == (2, 3)
    # one harmonic given as (N, 2) / (N,)
    one = sd.LoadCycle.from_harmonics(q0=np.zeros((2, 2)), p0=[1.0, 1.0],
                                      q_cos=[[1.0, 0.0], [0.0, 1.0]], p_sin=[0.1, 0.2])
    assert one.q_cos.shape == (1, 2, 2) and one.p_sin.shape == (1, 2)
    # the rotating load of MODEL.md s.8.1: Q (cos 2 pi t, sin 2 pi t)
    rot = sd.LoadCycle.from_harmonics(q0=[[0.0, 0.0]], p0=[1.0], q_cos=[[2.0, 0.0]],
                                      q_sin=[[0.0, 2.0]])
    t = np.linspace(0, 1, 17)
    np.testing.assert_allclose(np.linalg.norm(rot.q_w(t, 1.0), axis=-1), 2.0, rtol=1e-14)
    assert sd.LoadCycle.from_harmonics(q0=[0.0], p0=[1.0]).dim == 2


def test_samples_interpolate_vectors_linearly():
    load = _load3(2, 1).to_samples(8)
    assert load.q1.shape == (8, 2, 2)
    q_mid = load.periodic(1.5 / 8)[0]
    np.testing.assert_allclose(q_mid, 0.5 * (load.q1[1] + load.q1[2]), rtol=1e-13)


@given(st.integers(0, 10_000), st.integers(1, 3))
def test_periodic_min_in_a_direction_is_exact(seed, harmonics):
    load = _load3(2, seed, harmonics)
    rng = np.random.default_rng(seed + 1)
    d, cp = rng.normal(size=(2, 2)), rng.normal(size=2)
    m, t_min = load.periodic_min(d, cp)
    t = np.linspace(0, 1, 4001)
    q, p = load.periodic(t)
    g = (q * d).sum(-1) + cp * p
    scale = np.abs(g).max()
    assert np.all(m <= g.min(axis=0) + 1e-10 * scale)      # no sample is lower
    qm, pm = load.periodic(t_min)
    at = (qm * d).sum(-1) + cp * pm
    np.testing.assert_allclose(np.diag(at) if at.ndim == 2 else at, m, atol=1e-10 * scale)
    mx, _ = load.periodic_max(d, cp)
    assert np.all(mx >= g.max(axis=0) - 1e-10 * scale)


def test_periodic_min_of_samples_in_a_direction():
    load = _load3(3, 5).to_samples(12)
    d = np.array([1.0, -2.0])
    m, _ = load.periodic_min(d, 0.0)
    np.testing.assert_allclose(m, (load.q1 @ d).min(axis=0), rtol=1e-14)


@given(st.integers(0, 10_000), st.integers(3, 40))
def test_sampling_error_bounds_the_vector_error(seed, n_samples):
    load = _load3(2, seed, harmonics=2)
    err_q, err_p = load.sampling_error(n_samples)
    t = np.linspace(0, 1, 20 * n_samples + 1)
    exact = load.periodic(t)
    coarse = load.to_samples(n_samples).periodic(t)
    dq = np.linalg.norm(exact[0] - coarse[0], axis=-1).max(axis=0)
    dp = np.abs(exact[1] - coarse[1]).max(axis=0)
    assert np.all(dq <= err_q * (1 + 1e-12) + 1e-14)
    assert np.all(dp <= err_p * (1 + 1e-12) + 1e-14)


def test_sampling_error_of_samples_is_exact_in_norm():
    coarse = _load3(2, 3).to_samples(6)
    err_q, _ = coarse.sampling_error(9)
    t = np.linspace(0, 1, 36 * 20 + 1)
    diff = np.linalg.norm(coarse.periodic(t)[0] - coarse.to_samples(9).periodic(t)[0], axis=-1)
    np.testing.assert_allclose(err_q, diff.max(axis=0), rtol=1e-12)


def test_unloaded_second_direction_reduces_to_the_2d_load():
    rng = np.random.default_rng(7)
    qc, qs, pc = rng.normal(size=(2, 3)), rng.normal(size=(2, 3)), rng.normal(size=(2, 3))
    two = sd.LoadCycle.from_harmonics(q0=[0.1, 0.2, 0.3], p0=[1, 2, 3], q_cos=qc, q_sin=qs,
                                      p_cos=pc)
    pad = lambda a: np.stack([a, np.zeros_like(a)], axis=-1)
    three = sd.LoadCycle.from_harmonics(q0=pad(np.array([0.1, 0.2, 0.3])), p0=[1, 2, 3],
                                        q_cos=pad(qc), q_sin=pad(qs), p_cos=pc)
    t = rng.random(11)
    np.testing.assert_array_equal(three.q_w(t, 1.3)[..., 0], two.q_w(t, 1.3))
    np.testing.assert_array_equal(three.q_w(t, 1.3)[..., 1], 0.0)
    for d in (1.0, -1.0):
        np.testing.assert_allclose(three.periodic_min(np.array([d, 0.0]), 0.4)[0],
                                   two.periodic_min(d, 0.4)[0], rtol=1e-14)
    np.testing.assert_array_equal(three.sampling_error(10)[0], two.sampling_error(10)[0])
    np.testing.assert_array_equal(three.permuted([2, 0, 1]).q_cos[..., 0],
                                  two.permuted([2, 0, 1]).q_cos)


@pytest.mark.parametrize("call, field", [
    (lambda: sd.LoadCycle.from_harmonics(q0=np.zeros((2, 2)), p0=[1, 1], q_cos=[1.0, 2.0]),
     "q_cos must have shape"),
    (lambda: sd.LoadCycle.from_harmonics(q0=np.zeros((2, 3)), p0=[1, 1]), "q0 must have shape"),
    (lambda: sd.LoadCycle.from_harmonics(q0=np.zeros((2, 2)), p0=[1, 1, 1]), "q0 has 2 entries"),
    (lambda: sd.LoadCycle.from_samples(np.zeros((2, 2)), [1, 1], np.zeros((4, 2)),
                                       np.zeros((4, 2))), "q1 must have shape"),
    (lambda: sd.LoadCycle.from_harmonics(q0=np.zeros((2, 2)), p0=[1, 1],
                                         p_cos=np.zeros((2, 2, 2))), "p_cos must have shape"),
])
def test_bad_3d_loads_are_refused_naming_the_field(call, field):
    with pytest.raises(ShapeError, match=field):
        call()


def test_dimensions_of_system_and_load_must_agree():
    s3, _ = _random_3d(1, 0)
    load2 = sd.LoadCycle.from_harmonics(q0=[0.0], p0=[1.0], q_cos=[1.0])
    with pytest.raises(ShapeError, match="dim = 3 but the load has dim = 2"):
        sd.solve_cycles(s3, load2, 1.0)
    s2 = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], 0.3)
    with pytest.raises(ShapeError, match="dim = 2 but the load has dim = 3"):
        sd.shakedown_bounds(s2, _load3(1, 0))
