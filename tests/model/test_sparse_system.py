"""A DiscreteSystem with a sparse K (issue 14): the same system as its dense twin, checked
without densifying, with clear errors on bad sparse input."""

import numpy as np
import pytest
import scipy.sparse as sp

import shakedown as sd
from shakedown.model.errors import InputError, NotPositiveDefiniteError, NotSymmetricError, ShapeError


def test_sparse_twin_has_the_same_matrices_and_checks(banded_system):
    d = banded_system(40)
    s = d.to_sparse()
    assert s.is_sparse and not d.is_sparse
    assert sp.issparse(s.K) and sp.issparse(s.A) and sp.issparse(s.B)
    assert s.nnz < 0.2 * d.nnz
    np.testing.assert_array_equal(s.K.toarray(), d.K)
    np.testing.assert_array_equal(s.diagonal(), d.diagonal())
    assert s.is_coupled == d.is_coupled
    assert s.condition_number == pytest.approx(d.condition_number, rel=1e-8)
    cs, cd = s.critical_friction(), d.critical_friction()
    assert (cs.method, cs.exact) == (cd.method, cd.exact)
    assert cs.factor == pytest.approx(cd.factor, rel=1e-8)  # Schur eigenvalue by solves
    rng = np.random.default_rng(1)
    v, w = rng.normal(size=(3, 40)), rng.uniform(size=(3, 40))
    for a, b in zip(s.reactions(v, w, 1.0, 2.0), d.reactions(v, w, 1.0, 2.0), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-13)
    assert s.subsystem([0, 3, 7]).is_sparse and s.with_friction(0.1).is_sparse
    assert not s.to_dense().is_sparse and s.to_sparse() is s
    assert "sparse" in repr(s)


def test_small_sparse_system_enumerates_like_the_dense_one(banded_system):
    d = banded_system(3, seed=4, coupling=0.8)
    s = d.to_sparse()
    assert s.critical_friction().method == d.critical_friction().method == "enumeration"
    assert s.critical_friction().factor == pytest.approx(d.critical_friction().factor, rel=1e-12)


@pytest.mark.parametrize("unit", [1e-6, 1e9])
def test_sparse_checks_do_not_depend_on_units(unit, banded_system):
    d = banded_system(30, seed=2)
    s = sd.DiscreteSystem(sp.csr_matrix(d.A * unit), sp.csr_matrix(d.B * unit),
                          sp.csr_matrix(d.C * unit), 0.3)
    assert s.condition_number == pytest.approx(d.condition_number, rel=1e-8)
    assert s.critical_friction().factor == pytest.approx(d.critical_friction().factor, rel=1e-8)


def test_bad_sparse_input_is_named(banded_system):
    d = banded_system(10)
    A, B, C = (sp.csr_matrix(M) for M in (d.A, d.B, d.C))
    bad = A.tolil()
    bad[2, 5] = 7.0
    with pytest.raises(NotSymmetricError, match=r"A row 3, column 6|A row 6, column 3"):
        sd.DiscreteSystem(bad.tocsr(), B, C, 0.3)
    nan = C.tolil()
    nan[4, 4] = np.nan
    with pytest.raises(InputError, match=r"C must be finite; C row 5, column 5"):
        sd.DiscreteSystem(A, B, nan.tocsr(), 0.3)
    with pytest.raises(ShapeError, match="B must have shape"):
        sd.DiscreteSystem(A, sp.csr_matrix((9, 9)), C, 0.3)
    with pytest.raises(InputError, match="complex"):
        sd.DiscreteSystem(A.astype(complex), B, C, 0.3)
    with pytest.raises(ShapeError, match="square"):
        sd.DiscreteSystem(sp.csr_matrix(np.ones((3, 4))), B, C, 0.3)


def test_indefinite_and_singular_sparse_K_are_refused(banded_system):
    d = banded_system(10)
    A, B, C = (sp.csr_matrix(M) for M in (d.A, d.B, d.C))
    neg = A.tolil()
    neg[3, 3] = -1.0  # one negative pivot
    with pytest.raises(NotPositiveDefiniteError, match="non-positive pivot"):
        sd.DiscreteSystem(neg.tocsr(), B, C, 0.3)
    # a nearly singular K: one node 1e-14 as stiff as the others (cond ~ 1e14 > 1e12)
    D = np.diag(np.r_[1e-7, np.ones(19)])
    Kw = sp.csr_matrix(D @ d.K @ D)
    with pytest.raises(NotPositiveDefiniteError, match="numerically singular"):
        sd.DiscreteSystem(Kw[:10, :10], Kw[:10, 10:], Kw[10:, 10:], 0.3)
    # the same matrix, dense: the same verdict
    with pytest.raises(NotPositiveDefiniteError, match="numerically singular"):
        sd.DiscreteSystem(Kw[:10, :10].toarray(), Kw[:10, 10:].toarray(),
                          Kw[10:, 10:].toarray(), 0.3)


def test_mixed_dense_and_sparse_blocks_give_a_sparse_system(banded_system):
    d = banded_system(8)
    s = sd.DiscreteSystem(sp.csr_matrix(d.A), d.B, d.C, d.friction)
    assert s.is_sparse
    np.testing.assert_array_equal(s.K.toarray(), d.K)


def test_sparse_system_pickles(banded_system):
    """Studies send systems to worker processes: a sparse system survives pickling."""
    import pickle

    s = banded_system(12).to_sparse()
    t = pickle.loads(pickle.dumps(s))
    assert t.is_sparse
    np.testing.assert_array_equal(t.K.toarray(), s.K.toarray())
    assert t.condition_number == pytest.approx(s.condition_number, rel=1e-10)
