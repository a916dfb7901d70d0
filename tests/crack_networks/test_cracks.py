"""Crack sets: validation, geometry, sampling, CSV input/output (crack_networks.cracks/sampling)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import crack_networks as cn
from shakedown.model.errors import InputError, ShapeError

# ----------------------------------------------------------------- segment distance


def _brute_distance(p0, p1, q0, q1, n=1001):
    s = np.linspace(0, 1, n)
    P = p0 + s[:, None] * (p1 - p0)
    Q = q0 + s[:, None] * (q1 - q0)
    return np.min(np.linalg.norm(P[:, None] - Q[None], axis=-1))


coord = st.floats(-3, 3, allow_nan=False)


@settings(max_examples=30, deadline=None)
@given(st.lists(coord, min_size=8, max_size=8))
def test_segment_distance_matches_dense_sampling(xs):
    p0, p1, q0, q1 = (np.array(xs[k : k + 2]) for k in range(0, 8, 2))
    d = cn.segment_distance(p0, p1, q0, q1)
    brute = _brute_distance(p0, p1, q0, q1)
    # sampling with 1001 points per segment overestimates by at most one step, 6 sqrt2 / 1000
    assert d <= brute + 1e-12
    assert brute - d <= 0.0085


def test_segment_distance_crossing_is_zero():
    assert cn.segment_distance([-1, 0], [1, 0], [0, -1], [0, 1]) == 0.0


# ----------------------------------------------------------------- CrackSet validation


def test_crackset_basic_geometry():
    cs = cn.CrackSet([[0.0, 0.0], [3.0, 1.0]], [1.0, 0.5], [0.0, np.pi / 2])
    np.testing.assert_allclose(cs.normals[0], [0, 1], atol=1e-15)  # t rotated by +90 deg
    np.testing.assert_allclose(cs.tangents[1], [0, 1], atol=1e-15)
    p0, p1 = cs.tips
    np.testing.assert_allclose(p1[1], [3.0, 1.5], atol=1e-15)
    assert cs.min_distance() == pytest.approx(np.sqrt(4.25), rel=1e-14)  # tip (1, 0) to tip (3, 0.5)
    assert cs.mean_half_length == 0.75


@pytest.mark.parametrize(
    "args, exc, words",
    [
        (([[0, 0, 0]], [1.0], [0.0]), ShapeError, "centres must have shape (N, 2)"),
        (([[0, 0]], [1.0, 2.0], [0.0]), ShapeError, "half_lengths must have shape (1,)"),
        (([[0, 0]], [0.0], [0.0]), InputError, "half_lengths must be > 0; crack 0"),
        (([[0, np.nan]], [1.0], [0.0]), InputError, "centres must be finite; crack 0"),
        (([[0, 0]], [1.0], [np.inf]), InputError, "angles must be finite"),
        (([[0, 0], [0, 0.5]], [1.0, 1.0], [0.0, 1.0]), InputError, "cracks 1 (centre"),
        ((np.zeros((0, 2)), [], []), InputError, "at least one crack"),
        (("abc", [1.0], [0.0]), InputError, "centres must be a real array"),
    ],
)
def test_crackset_bad_input_messages(args, exc, words):
    with pytest.raises(exc) as info:
        cn.CrackSet(*args)
    assert words in str(info.value)


def test_touching_cracks_are_rejected():
    # crack 0's tip (1, 0) lies on crack 1 (a T junction)
    with pytest.raises(InputError, match="must not intersect or touch"):
        cn.CrackSet([[0, 0], [1, 0]], [1.0, 1.0], [0.0, np.pi / 2])


def test_rotation_and_permutation_keep_distances():
    cs = cn.sample_crack_set(30, density=0.1, rng=1)
    d = cs.distances()
    r = cs.rotated(0.7, origin=(1.0, 2.0))
    np.testing.assert_allclose(r.distances(), d, rtol=1e-12)
    order = np.random.default_rng(0).permutation(30)
    np.testing.assert_allclose(cs.permuted(order).distances(), d[np.ix_(order, order)])


# ----------------------------------------------------------------- CSV


def test_csv_round_trip(tmp_path):
    cs = cn.sample_crack_set(25, density=0.1, half_length=(0.5, 1.5), rng=3)
    path = tmp_path / "cracks.csv"
    cs.save_csv(path)
    back = cn.load_csv(path)
    np.testing.assert_array_equal(back.to_array(), cs.to_array())  # %.17g is exact


def test_csv_angle_in_degrees_and_column_order(tmp_path):
    path = tmp_path / "c.csv"
    path.write_text("angle_deg,half_length,y,x,label\n90,1,0,0,7\n0,0.5,0,3,8\n")
    cs = cn.load_csv(path)
    np.testing.assert_allclose(cs.angles, [np.pi / 2, 0.0])
    np.testing.assert_allclose(cs.centres, [[0, 0], [3, 0]])


def test_csv_bad_files(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        cn.load_csv(tmp_path / "missing.csv")
    p = tmp_path / "bad.csv"
    p.write_text("x,y,length\n0,0,1\n")
    with pytest.raises(InputError, match="must have a header with columns x, y, half_length"):
        cn.load_csv(p)
    p.write_text("x,y,half_length,angle\n0,0,one,0\n")
    with pytest.raises(InputError, match="non-numeric"):
        cn.load_csv(p)


# ----------------------------------------------------------------- sampling


def test_sampling_is_reproducible_and_seed_dependent():
    a = cn.sample_crack_set(200, density=0.15, rng=11)
    b = cn.sample_crack_set(200, density=0.15, rng=11)
    c = cn.sample_crack_set(200, density=0.15, rng=12)
    np.testing.assert_array_equal(a.to_array(), b.to_array())
    assert not np.array_equal(a.centres, c.centres)


@pytest.mark.parametrize("density, spacing", [(0.05, 0.0), (0.1, 0.1), (0.3, 0.5)])
def test_sampling_density_and_spacing(density, spacing):
    cs = cn.sample_crack_set(300, density=density, half_length=(0.5, 1.5), min_spacing=spacing,
                             rng=5)
    a = cs.half_lengths
    side = np.sqrt(np.sum(a**2) / density)
    # centres are uniform in the square window whose area makes sum a^2 / area = density
    assert cs.centres.min() >= 0 and cs.centres.max() <= side
    assert cs.centres.max() > 0.95 * side  # 300 uniform points fill the window
    d = cs.distances()
    mean_a = 0.5 * (a[:, None] + a[None, :])
    assert np.all(d > spacing * mean_a)
    assert np.all(d > 0)


def test_sampling_distributions():
    cs = cn.sample_crack_set(400, density=0.05, half_length=(0.5, 2.0), orientation=(0.1, 0.2),
                             rng=2)
    assert cs.half_lengths.min() >= 0.5 and cs.half_lengths.max() <= 2.0
    assert cs.angles.min() >= 0.1 and cs.angles.max() <= 0.2
    fixed = cn.sample_crack_set(50, density=0.05, orientation=0.3, rng=2)
    np.testing.assert_allclose(fixed.angles, 0.3)
    custom = cn.sample_crack_set(
        50, density=0.05, half_length=lambda rng, n: rng.lognormal(0.0, 0.3, n),
        orientation=lambda rng, n: rng.normal(0.0, 0.1, n), rng=2,
    )
    assert np.all(custom.angles >= 0) and np.all(custom.angles < np.pi)  # folded into [0, pi)
    uni = cn.sample_crack_set(2000, density=0.05, rng=4)
    # uniform in [0, pi): the mean of 2000 draws is pi/2 within 5 standard errors
    assert abs(uni.angles.mean() - np.pi / 2) < 5 * np.pi / np.sqrt(12 * 2000)


def test_sampling_ten_thousand_cracks():
    cs = cn.sample_crack_set(10_000, density=0.1, rng=7)
    assert cs.n_cracks == 10_000
    assert cs.min_distance() > 0.1 * cs.half_lengths.min()


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(n=0), "n must be a positive integer"),
        (dict(n=5, density=-1.0), "density must be a finite number > 0"),
        (dict(n=5, min_spacing=-0.1), "min_spacing must be a finite number >= 0"),
        (dict(n=5, half_length=(2.0, 1.0)), "needs lo <= hi"),
        (dict(n=5, half_length=-1.0), "half_length must give values > 0"),
        (dict(n=5, orientation="x"), "orientation must be a number"),
        (dict(n=5, half_length=lambda rng, n: np.ones(n + 1)), "must return an array of shape (5,)"),
        (dict(n=200, density=2.0, min_spacing=1.0, max_attempts=20_000), "could place only"),
    ],
)
def test_sampling_bad_input(kwargs, words):
    with pytest.raises(InputError) as info:
        cn.sample_crack_set(rng=0, **kwargs)
    assert words in str(info.value)


def test_plotting_runs_and_returns_axes():
    import matplotlib

    matplotlib.use("Agg")
    from crack_networks.plotting import plot_collinear_accuracy, plot_cracks

    cs = cn.sample_crack_set(20, density=0.1, rng=1)
    ax = plot_cracks(cs, values=np.arange(20), numbers=True)
    assert len(ax.collections) == 1
    assert cs.plot(ax=ax) is ax
    ax2 = plot_collinear_accuracy([0.1, 1.0], [1.2, 1.07], {"k": [1.25, 1.08]})
    assert len(ax2.lines) == 1


@pytest.mark.parametrize("centres,half", [([[0.0, 0.0], [1.3e154, 1.3e154]], [1.0, 1.0]),
                                          ([[0.0, 0.0], [1e151, 0.0]], [1.0, 2e150])])
def test_lengths_whose_squares_overflow_are_refused_by_name(centres, half):
    """The fuzz test's example: centres at 1.3e154 overflowed the k-d tree's squared distances
    (a bare scipy ``ValueError``); now an ``InputError`` naming the fields and the fix."""
    with pytest.raises(InputError, match="centres and half_lengths .* other length units"):
        cn.CrackSet(centres, half, [0.0, 0.0])
    cn.CrackSet(np.asarray(centres) * 1e-10, np.asarray(half) * 1e-10, [0.0, 0.0])
