"""Kachanov assembly in blocks and the truncated (sparse) interaction (issue 14).

* the blocked assembly equals the one-shot formula ``K_ij = -k0 a_i/a_j Lam_ij`` exactly
  (the same products in the same order), for any block size;
* the truncated matrix equals the full one on the kept pairs and is zero elsewhere, so its
  error is the dropped interactions only: it falls as the radius grows and is zero once the
  radius covers every pair;
* a radius that is not a positive number is a clear error.
"""

import numpy as np
import pytest

import crack_networks as cn
from crack_networks.kachanov import stiffness_from_factors
from shakedown.model.errors import InputError


def _one_shot(Lam, a, mu, nu):
    n = Lam.shape[0]
    k0 = 4.0 * mu / (np.pi * (1.0 - nu))
    K4 = -k0 * (a[:, None] / a[None, :])[:, :, None, None] * Lam
    K4[np.arange(n), np.arange(n)] = k0 * np.eye(2)
    return np.ascontiguousarray(K4.transpose(0, 2, 1, 3)).reshape(2 * n, 2 * n)


@pytest.mark.parametrize("chunk", [1, 3, 7, None])
def test_blocked_assembly_equals_the_one_shot_formula(chunk):
    cs = cn.sample_crack_set(23, density=0.15, half_length=(0.5, 1.5), rng=5)
    Lam = cn.transmission_factors(cs, chunk_size=chunk)
    np.testing.assert_array_equal(Lam, cn.transmission_factors(cs, chunk_size=23))
    K = stiffness_from_factors(Lam, cs.half_lengths, 2.5e10, 0.3, chunk_size=chunk)
    np.testing.assert_array_equal(K, _one_shot(Lam, cs.half_lengths, 2.5e10, 0.3))


def test_truncated_interaction_keeps_near_pairs_exactly():
    cs = cn.sample_crack_set(40, density=0.1, half_length=(0.5, 1.5), rng=8)
    full = cn.kachanov_stiffness(cs, 3.0, 0.25)
    errors = []
    for radius in (1.5, 3.0, 6.0, 1e3):
        Ks = cn.kachanov_stiffness(cs, 3.0, 0.25, interaction_radius=radius)
        assert Ks.format == "csr" and Ks.shape == full.shape
        D = Ks.toarray()
        kept = D != 0
        # the kept entries are the same closed-form values (pairwise vs. row-block
        # vectorisation: equal to rounding, 1e-13 of the self stiffness)
        np.testing.assert_allclose(D[kept], full[kept], rtol=0, atol=1e-13 * full[0, 0])
        c, a = cs.centres, cs.half_lengths
        dist = np.linalg.norm(c[:, None] - c[None, :], axis=-1)
        near = np.repeat(np.repeat(dist < radius * (a[:, None] + a[None, :]), 2, 0), 2, 1)
        assert not np.any(kept & ~near)  # nothing beyond the radius
        errors.append(np.linalg.norm(D - full) / np.linalg.norm(full - np.diag(np.diag(full))))
    assert errors[0] > errors[1] > errors[2] and errors[3] < 1e-13
    m = cn.kachanov_model(cs, 3.0, 0.25, interaction_radius=1e3)
    assert m.is_sparse and m.system.is_sparse  # kept sparse (issue 14)
    np.testing.assert_allclose(m.stiffness_raw.toarray(), full, atol=1e-13 * full[0, 0], rtol=0)
    md = cn.kachanov_model(cs, 3.0, 0.25, interaction_radius=1e3, sparse=False)
    assert not md.is_sparse and not md.system.is_sparse
    np.testing.assert_array_equal(m.system.K.toarray(), md.system.K)


def test_sparse_model_matches_its_dense_twin():
    """A truncated model kept sparse: the same system, asymmetry, smallest eigenvalue and mean
    discontinuities as the same truncated matrix made dense."""
    cs = cn.sample_crack_set(80, density=0.1, min_spacing=0.1, rng=6)
    ms = cn.kachanov_model(cs, 2.0, 0.3, interaction_radius=4)
    md = cn.kachanov_model(cs, 2.0, 0.3, interaction_radius=4, sparse=False)
    np.testing.assert_array_equal(ms.system.K.toarray(), md.system.K)
    a, b = ms.asymmetry, md.asymmetry
    assert a.relative_norm == pytest.approx(b.relative_norm, rel=1e-12)
    assert a.max_pair == pytest.approx(b.max_pair, rel=1e-12) and a.worst_pair == b.worst_pair
    np.testing.assert_allclose(a.pair.toarray(), b.pair, rtol=1e-12, atol=1e-15)
    assert ms.min_eigenvalue == pytest.approx(md.min_eigenvalue, rel=1e-8)
    stress = (0.3, -0.2, -1.0)
    np.testing.assert_allclose(ms.mean_discontinuities(stress), md.mean_discontinuities(stress),
                               rtol=1e-10, atol=1e-14)
    for x, y in zip(ms.blocks(), md.blocks(), strict=True):
        np.testing.assert_array_equal(x.toarray(), y)
    with pytest.raises(InputError, match="sparse=True needs interaction_radius"):
        cn.kachanov_model(cs, sparse=True)


@pytest.mark.parametrize("bad", [0, -1.0, np.nan, np.inf])
def test_bad_interaction_radius(bad):
    cs = cn.sample_crack_set(5, density=0.05, rng=1)
    with pytest.raises(InputError, match="interaction_radius must be a positive number"):
        cn.kachanov_stiffness(cs, interaction_radius=bad)
