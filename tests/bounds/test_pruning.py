"""Fast ``lam1`` (issue 14): incumbent pruning with certified facet walks (``intervals="lam1"``).

The default path computes ``lam_high`` exactly only where ``lam1`` needs it; elsewhere it reports
a proven lower bound (``lam_high_exact`` False).  These tests compare it with every interval
computed exactly (``intervals=True``) and with HiGHS, force the pruning machinery to work on
small problems (``INIT_LPS`` patched down so that walks and capped LPs decide most rows), and
check the certificates the pruning relies on.  Tolerances: ``lam1`` / ``lam2`` agree to 1e-9
relative between the two dense variants (the same vertices), 1e-6 with HiGHS (its tolerance
1e-7, with margin).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_bounds import _uncoupled, check_certificate, random_problem

import crack_networks as cn
import shakedown as sd
from shakedown.bounds import facet_walk, pruning
from shakedown.bounds.basis_lp import BasisLP
from shakedown.bounds.facet_walk import FacetWalk, certified_rows

SAME = 1e-9


@pytest.fixture(params=[(32, 400), (1, 400), (1, 0)], ids=["init32", "init1", "init1-noscreen"])
def init_lps(request, monkeypatch):
    """Run each test with many start LPs, with a single one (pruning does the rest), and with a
    single one chosen without the screening by partial dual simplex runs (the start is then
    far from ``lam1`` and the walks, descents and capped LPs do most of the work).  The screen
    of "init1" runs in the coordinates of the lam2 basis, that of "init32" in ``v``."""
    monkeypatch.setattr(pruning, "SCREEN_BASIS_MIN_N", 0 if request.param[0] == 1 else 10**9)
    monkeypatch.setattr(pruning, "INIT_LPS", request.param[0])
    monkeypatch.setattr(pruning, "UNSCREENED_LPS", request.param[0])
    monkeypatch.setattr(pruning, "SCREEN_ROWS", request.param[1])
    monkeypatch.setattr(pruning, "SCREEN_MIN_N", 0)  # screen small problems too
    return request.param[0]


def assert_fast_matches_full(system, load):
    fast = sd.shakedown_bounds(system, load)
    full = sd.shakedown_bounds(system, load, intervals=True)
    assert fast.status == full.status
    assert fast.lam1 == pytest.approx(full.lam1, rel=SAME, abs=1e-300, nan_ok=True)
    assert fast.lam2 == pytest.approx(full.lam2, rel=SAME, nan_ok=True)
    assert full.lam_high_exact.all() or full.status != "bounded"
    np.testing.assert_allclose(fast.lam_low, full.lam_low, rtol=SAME, atol=1e-12)
    ex = fast.lam_high_exact
    np.testing.assert_allclose(fast.lam_high[ex], full.lam_high[ex], rtol=1e-8, atol=1e-12)
    # a lower bound is a true lower bound and never below lam1
    tol = 1e-9 * max(1.0, abs(full.lam2))
    assert np.all(fast.lam_high[~ex] <= full.lam_high[~ex] + tol)
    assert np.all(fast.lam_high[~ex] >= fast.lam1 - tol)
    if 0 < fast.lam1 < fast.lam2 and fast.limiting_constraint >= 0:
        k = fast.limiting_constraint
        assert ex[k] and fast.lam_high[k] == pytest.approx(fast.lam1, rel=SAME)
        assert full.lam_high[k] == pytest.approx(full.lam1, rel=1e-8)
    np.testing.assert_array_equal(fast.certificate, full.certificate)
    np.testing.assert_array_equal(fast.state_at_lam2, full.state_at_lam2)
    assert fast.lam_separation == full.lam_separation
    assert max(fast.residuals.values()) <= 1e-7
    if fast.status == "bounded":
        check_certificate(fast)
    return fast, full


@pytest.mark.parametrize("n,seed", [(5, 0), (12, 1), (30, 2), (60, 3), (60, 4)])
def test_random_systems(n, seed, init_lps):
    system, load = random_problem(n, seed, coupling=0.5)
    fast, _ = assert_fast_matches_full(system, load)
    h = sd.shakedown_bounds(system, load, solver="highs")
    assert fast.lam1 == pytest.approx(h.lam1, rel=1e-6)
    assert h.lam_high_exact.all()


@pytest.mark.parametrize("n,seed", [(40, 1), (120, 2)])
def test_kachanov_networks(n, seed, init_lps):
    cracks = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(seed))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    load = model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))
    fast, full = assert_fast_matches_full(model.system, load)
    assert 0 < fast.lam1 < fast.lam2
    if init_lps == 1 and n >= 120:
        assert not fast.lam_high_exact.all()  # the pruning did prune
    h = sd.shakedown_bounds(model.system, load, solver="highs", separation=False)
    assert fast.lam1 == pytest.approx(h.lam1, rel=1e-6)


@pytest.mark.parametrize("n,seed", [(1, 0), (6, 1), (25, 3)])
def test_uncoupled_lam1_equals_lam2(n, seed, init_lps):
    system, load = _uncoupled(n, seed)
    fast, full = assert_fast_matches_full(system, load)
    if fast.status == "bounded":
        assert fast.lam1 == fast.lam2


def test_duplicated_nodes(init_lps):
    """Two uncoupled copies of one coupled system: every value is tied with its twin."""
    s, load = random_problem(15, 5, coupling=0.5)
    z = np.zeros((15, 15))
    two = sd.DiscreteSystem(np.block([[s.A, z], [z, s.A]]), np.block([[s.B, z], [z, s.B]]),
                            np.block([[s.C, z], [z, s.C]]), np.r_[s.friction, s.friction])
    load2 = sd.LoadCycle.from_harmonics(
        np.r_[load.q0, load.q0], np.r_[load.p0, load.p0],
        q_cos=np.hstack([load.q_cos, load.q_cos]), q_sin=np.hstack([load.q_sin, load.q_sin]),
        p_cos=np.hstack([load.p_cos, load.p_cos]), p_sin=np.hstack([load.p_sin, load.p_sin]))
    fast, _ = assert_fast_matches_full(two, load2)
    one = sd.shakedown_bounds(s, load)
    assert fast.lam1 == pytest.approx(one.lam1, rel=SAME)


def _biased(seed):
    rng = np.random.default_rng(seed)
    n = 3
    M = rng.standard_normal((2 * n, 2 * n))
    K = M @ M.T + 0.3 * np.eye(2 * n)
    s = sd.DiscreteSystem(K[:n, :n], K[:n, n:], K[n:, n:], 0.8)
    p0 = 1 + rng.random(n)
    q0 = 0.64 * p0 * rng.uniform(-1, 1, n)
    load = sd.LoadCycle.from_harmonics(q0, p0, q_cos=rng.standard_normal(n),
                                       p_cos=0.5 * rng.standard_normal(n))
    return s, load


@pytest.mark.parametrize("seed,never", [(4, True), (7, False)])
def test_lam1_zero(seed, never, init_lps):
    """A facet redundant from lam = 0 on (never active: ``nan``) or first touched above 0
    (``lam_low > 0``): ``lam1 = 0`` and every interval is computed exactly."""
    s, load = _biased(seed)
    fast, full = assert_fast_matches_full(s, load)
    assert fast.lam1 == 0.0 and fast.lam2 > 0
    assert fast.lam_high_exact.all()
    assert np.isnan(fast.lam_high).any() == never
    assert (fast.lam_low > 0).any() != never


def test_lam1_does_not_depend_on_units(init_lps):
    cracks = cn.sample_crack_set(60, density=0.1, rng=4)
    ref = None
    for mu, p0, length in [(1.0, 1.0, 1.0), (3e10, 1e8, 1e-3), (2.0**20, 2.0**-10, 7.0)]:
        cr = cn.CrackSet(cracks.centres * length, cracks.half_lengths * length, cracks.angles)
        m = cn.kachanov_model(cr, shear_modulus=mu, friction=0.6)
        b = sd.shakedown_bounds(m.system, m.load_cycle((-p0, 0, -p0), (0, p0, 0)))
        if ref is None:
            ref = b
            continue
        assert b.lam1 == pytest.approx(ref.lam1, rel=SAME)
        assert b.lam2 == pytest.approx(ref.lam2, rel=SAME)
        assert b.limiting_constraint == ref.limiting_constraint


# ---------------------------------------------------------------------- certificates
def _polytope(seed=0, n=6):
    system, load = random_problem(n, seed)
    cs = sd.bounds.extreme_constraints(system, load)
    nrm = np.linalg.norm(cs.G, axis=1)
    G, b = cs.G / nrm[:, None], cs.offsets(0.0) / nrm
    from scipy.optimize import linprog

    res = linprog(-G[0], A_ub=G, b_ub=b, bounds=(None, None), method="highs-ds")
    T = np.flatnonzero(np.abs(b - G @ res.x) <= 1e-9 * (1 + np.abs(b)))[:n]
    return G, b, res.x, T


def test_certified_rows_accepts_a_vertex_and_rejects_perturbed_points():
    G, b, x, T = _polytope()
    tight = certified_rows(G, b, x)
    assert tight is not None and tight[T].all()
    # pushed outside through a tight row: rejected as a whole
    assert certified_rows(G, b, x + 1e-6 * G[T[0]]) is None
    # pulled inside: feasible, but the rows are no longer tight (no face point claimed)
    inner = x - 1e-6 * G[T].sum(axis=0)
    t2 = certified_rows(G, b, inner)
    assert t2 is not None and not t2[T].any()


def test_walk_rejects_a_wrong_start_vertex():
    G, b, x, T = _polytope()
    assert FacetWalk(G, b, T).ok
    n = G.shape[1]
    rng = np.random.default_rng(0)
    for _ in range(50):  # rows whose intersection point lies outside the polytope
        S = np.sort(rng.choice(G.shape[0], n, replace=False))
        p = np.linalg.solve(G[S], b[S])
        if np.max(G @ p - b) > 1e-3:
            break
    w = FacetWalk(G, b, S)
    assert not w.ok and not w.covered.any()
    # a corrupted point is never certified as it is: the check recomputes the vertex
    w = FacetWalk(G, b, T)
    w.x = w.x + 1e-6 * G[T[0]]
    assert w._certify() and certified_rows(G, b, w.x) is not None
    assert np.allclose(w.x, x, atol=1e-9)


def test_walk_certifies_every_face_it_reports():
    G, b, x, T = _polytope(1, 8)
    w = FacetWalk(G, b, T)
    assert w.ok
    for k in range(G.shape[0]):
        if w.walk_to(k, 200):
            assert w.covered[k]
    from scipy.optimize import linprog

    for k in np.flatnonzero(w.covered):  # each covered face is non-empty (independent LP)
        res = linprog(-G[k], A_ub=G, b_ub=b, bounds=(None, None), method="highs")
        assert -res.fun == pytest.approx(b[k], rel=1e-8, abs=1e-9)


def _unscreened_network(monkeypatch):
    """A 120-crack network and its load, pruning started from one unscreened exact LP (so the
    walk, its certificates and its descents decide most rows)."""
    monkeypatch.setattr(pruning, "INIT_LPS", 1)
    monkeypatch.setattr(pruning, "UNSCREENED_LPS", 1)
    monkeypatch.setattr(pruning, "SCREEN_ROWS", 0)
    cracks = cn.sample_crack_set(120, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(2))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    return model, model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))


def test_breaking_the_certificate_check_is_caught(monkeypatch):
    """A broken check (every point accepted, every row called tight) must make the fast lam1
    differ from the exact one on a network where pruning matters: the tests above would catch a
    wrong certificate."""
    model, load = _unscreened_network(monkeypatch)
    good = sd.shakedown_bounds(model.system, load)
    monkeypatch.setattr(facet_walk, "certified_rows",
                        lambda G, b, x, tol=0, Gx=None: np.ones(len(b), bool))
    monkeypatch.setattr(pruning, "certified_rows",
                        lambda G, b, x, tol=0, Gx=None: np.ones(len(b), bool))
    bad = sd.shakedown_bounds(model.system, load)
    assert bad.lam1 != pytest.approx(good.lam1, rel=1e-6)


def test_every_descent_lands_on_the_exact_lam_high(monkeypatch):
    """The parametric descents (face empty at the incumbent: follow lam down) end exactly at
    the row's lam_high of the full computation; a perturbed dual certificate is rejected."""
    model, load = _unscreened_network(monkeypatch)
    seen, rejected = [], []
    orig, land = FacetWalk.descend, FacetWalk._land

    def descend(self, k, c, m, lam, cap):
        out = orig(self, k, c, m, lam, cap)
        seen.append((k, out))
        return out

    def wrong_land(self, k, c, m, lam, x, y):
        rejected.append(land(self, k, c, m, lam, x, 1.01 * y + 1e-3) is None)
        return land(self, k, c, m, lam, x, y)

    monkeypatch.setattr(FacetWalk, "descend", descend)
    monkeypatch.setattr(FacetWalk, "_land", wrong_land)
    fast = sd.shakedown_bounds(model.system, load)
    full = sd.shakedown_bounds(model.system, load, intervals=True)
    done = [(k, lam) for k, lam in seen if lam is not None]
    assert done and all(rejected)
    from shakedown.bounds.constraints import Scales

    scale = Scales.of(full.constraints).load_factor  # descents work nondimensionally
    for k, lam in done:
        assert fast.lam_high_exact[k]
        assert lam * scale == pytest.approx(full.lam_high[k], rel=1e-9)
    assert fast.lam1 == pytest.approx(full.lam1, rel=SAME)



@pytest.mark.parametrize("seed,n,dup", [(0, 40, False), (1, 60, False), (2, 40, True)])
def test_walk_maximise_matches_linprog(seed, n, dup):
    """The walk's primal simplex (multipliers updated with the basis, refreshed every 32
    pivots and before an optimum is declared) ends at the optimum HiGHS finds, also with every
    row duplicated (ties in every ratio test), on walks longer than the refresh period."""
    from scipy.optimize import linprog

    G, b, x, T = _polytope(seed, n)
    R = len(b)
    if dup:
        G, b = np.vstack([G, G]), np.r_[b, b]
    rng = np.random.default_rng(seed)
    long_walks = 0
    for _ in range(4):
        g = rng.standard_normal(n)
        # start at the opposite vertex (the minimum of g): long walks
        low = linprog(g, A_ub=G[:R], b_ub=b[:R], bounds=(None, None), method="highs-ds").x
        T = np.flatnonzero(np.abs(b[:R] - G[:R] @ low) <= 1e-9 * (1 + np.abs(b[:R])))[:n]
        w = FacetWalk(G, b, T)
        assert w.ok
        assert w.maximise(g, 2000)
        long_walks += w.pivots > 32
        ref = linprog(-g, A_ub=G, b_ub=b, bounds=(None, None), method="highs")
        assert g @ w.x == pytest.approx(-ref.fun, rel=1e-9, abs=1e-9)
        tight = certified_rows(G, b, w.x)
        assert tight is not None and tight[w.T].all()
        y = np.linalg.solve(G[w.T].T, g)  # fresh multipliers: dual feasible at the end
        assert y.min() >= -1e-9 * np.abs(y).max()
    assert long_walks


@pytest.mark.parametrize("n,seed,coords", [(120, 2, "v"), (120, 2, "lam2 basis"),
                                           pytest.param(200, 3, "v", marks=pytest.mark.slow)])
def test_capped_batches_stopped_by_a_lower_incumbent(n, seed, coords, monkeypatch):
    """Short walks (most rows go to capped LPs) from an unscreened start: a capped LP that
    lowers the incumbent ends its batch, and the rows still running are decided again at the
    new incumbent (not by exact LPs at the old one).  lam1 and every exact lam_high stay those
    of the full computation.  ``coords="v"``: the LPs in ``v``, without the coordinates of the
    lam2 basis, as where they do not apply; ``"lam2 basis"``: the exact LPs in them, side by side
    (:meth:`.BasisLP.race`, issue 26: they too stop at the first value below the incumbent)."""
    if coords == "v":
        monkeypatch.setattr(pruning._Pruner, "simplex", lambda self: None)
    monkeypatch.setattr(pruning, "INIT_LPS", 1)
    monkeypatch.setattr(pruning, "UNSCREENED_LPS", 1)
    monkeypatch.setattr(pruning, "SCREEN_ROWS", 0)
    monkeypatch.setattr(pruning, "WALK_CAP", 2)
    monkeypatch.setattr(pruning, "LONG_WALK_CAP", 2)
    stopped = []
    orig = pruning._Pruner.capped_lps

    def capped_lps(self, walk, t, rows):
        failed = orig(self, walk, t, rows)
        if failed and self.best[0] < t:
            stopped.append(len(failed))
        return failed

    monkeypatch.setattr(pruning._Pruner, "capped_lps", capped_lps)
    races = []
    race = BasisLP.race

    def spy(self, rows, below=None, chunk=None):  # turns of 1 pivot: these LPs are short
        races.append((len(rows), below))
        return race(self, rows, below, chunk=1)

    monkeypatch.setattr(BasisLP, "race", spy)
    cracks = cn.sample_crack_set(n, density=0.1, half_length=1.0, min_spacing=0.1,
                                 rng=np.random.default_rng(seed))
    model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    load = model.load_cycle(static=(-1.0, 0.0, -1.0), cyclic=(0.0, 1.0, 0.0))
    fast, _ = assert_fast_matches_full(model.system, load)
    assert stopped  # some batches were cut short
    assert not fast.lam_high_exact.all()
    # in the lam2-basis coordinates the batches race (BasisLP.race) below the incumbent
    assert (coords == "v") == (not races)
    assert all(below is not None for _, below in races)
    assert coords == "v" or max(len_ for len_, _ in races) > 1
