"""The safe state: the Chebyshev centre of ``H(lam)`` (largest ball inside the safe region).

When the crossover after the interior point fails (issue 14: on a 2000-crack network the largest
balls form a face, not a vertex, and HiGHS then took 358 s) the interior point's iterate is
accepted if its multipliers prove the radius optimal to ``CENTRE_RTOL``.  Checked against HiGHS
(the ``"highs"`` solver) with the crossover forced to fail, and on wrong multipliers and a moved
centre (both must be refused).  Also the interior point's other hand-over to the crossover: a
stalled iterate of a condensed FE interface (``ipm.APPROX_TOL``).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_bounds import random_problem

import shakedown as sd
from shakedown.bounds import dense_lp, engine


def _ball_inside(cs, lam, v, r):
    nrm = np.linalg.norm(cs.G, axis=1)
    return np.all(cs.G @ v + r * nrm <= cs.offsets(lam) + 1e-9 * (1 + np.abs(cs.offsets(lam))))


@pytest.mark.parametrize("n,seed", [(10, 0), (60, 1), (150, 2)])
def test_interior_centre_when_the_crossover_fails(n, seed, monkeypatch):
    system, load = random_problem(n, seed)
    cs = sd.bounds.extreme_constraints(system, load)
    lam2 = sd.shakedown_bounds(system, load, only=("lam2",)).lam2
    for lam in (0.0, 0.5 * lam2, 0.95 * lam2):
        v_h, r_h = sd.bounds.chebyshev_centre(cs, lam, solver="highs")
        v_a, r_a = sd.bounds.chebyshev_centre(cs, lam)
        assert r_a == pytest.approx(r_h, rel=1e-7)
        with monkeypatch.context() as mp:
            mp.setattr(dense_lp, "_crossover", lambda *a: (None, None))
            highs = []

            def no_highs(*a, highs=highs, orig=engine.ReusableLP, **k):
                highs.append(1)
                return orig(*a, **k)

            mp.setattr(engine, "ReusableLP", no_highs)
            v_i, r_i = sd.bounds.chebyshev_centre(cs, lam)
        assert not highs  # the interior iterate was accepted
        assert r_i == pytest.approx(r_h, rel=1e-7) and r_i <= r_h * (1 + 1e-9)
        assert _ball_inside(cs, lam, v_i, r_i)


def test_interior_centre_refuses_wrong_multipliers_and_a_moved_centre():
    system, load = random_problem(40, 3)
    cs = sd.bounds.extreme_constraints(system, load)
    b = cs.offsets(0.0)
    norms = np.linalg.norm(cs.G, axis=1)
    rows = np.hstack([cs.G, norms[:, None]])
    cap = 1e6 * max(1.0, np.abs(b).max() / norms.min())
    top = np.r_[np.zeros(cs.n_nodes), 1.0]
    A, bb = np.vstack([rows, top]), np.r_[b, cap]
    rn = np.linalg.norm(A, axis=1)
    x, s, z, status, it = dense_lp.ipm(A / rn[:, None], bb / rn, top)
    ans = dense_lp.DenseAnswer("interior", x, z / rn, np.zeros(0, int), it, (np.nan,) * 4)
    good = engine._interior_centre(cs.G, norms, b, cap, ans)
    assert good is not None and max(good.residuals) <= engine.CENTRE_RTOL
    scaled = dense_lp.DenseAnswer("interior", x, 0.5 * z / rn, ans.basis, it, ans.residuals)
    assert engine._interior_centre(cs.G, norms, b, cap, scaled) is None
    moved = dense_lp.DenseAnswer("interior", x + 1e-3 * np.r_[cs.G[0], 0.0], z / rn,
                                 ans.basis, it, ans.residuals)
    assert engine._interior_centre(cs.G, norms, b, cap, moved) is None


def test_condensed_fe_strip_takes_the_dense_path(monkeypatch):
    """A strip pressed on an obstacle and sheared cyclically, 500 contact nodes: its interior
    point stalls with merit between 1e-5 and 1e-4 (the condensed ``K`` of a thin strip is ill
    conditioned).  The crossover from there ends certified, so the LPs stay on the dense path
    (0.9 s) instead of HiGHS (36 s, and a ``lam2`` 1.4e-5 too high: its point violates rows by
    8.6e-6).  Checked: no HiGHS path, the ``lam2`` state feasible to 1e-10, the Farkas
    certificate of ``lam2``."""
    from shakedown import fe

    def no_highs(*a, **k):
        raise AssertionError("the HiGHS path was taken")

    monkeypatch.setattr(engine, "solve_highs", no_highs)
    nx = 499
    loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shake": fe.Traction("top", (0.4, 0.0))}
    model = fe.FEModel(fe.rectangle(nx / 100, 0.1, nx, 8), fe.isotropic(1.0, 0.3),
                       dirichlet={"left": "xy"}, contact=["bottom"], loads=loads, friction=0.5)
    cm = model.condense()
    b = sd.shakedown_bounds(cm.system, cm.load_cycle(static="dead", cyclic="shake"))
    assert b.status == "bounded" and 0 < b.lam1 < b.lam2
    cs = b.constraints
    off = cs.offsets(b.lam2)
    assert (cs.G @ b.state_at_lam2 - off).max() <= 1e-10 * np.abs(off).max()
    assert max(b.residuals.values()) <= 1e-9
    # Farkas certificate of lam2 (multipliers >= 0 to the certificates' 1e-9)
    y = b.certificate
    ys = np.abs(y).max()
    assert y.min() >= -1e-9 * ys
    assert np.abs(cs.G.T @ y).max() <= 1e-9 * np.abs(cs.G).max() * ys
    assert cs.c @ y / (-(cs.m @ y)) == pytest.approx(b.lam2, rel=1e-8)


def _centre_at_half_lam2(n, seed):
    """A random problem's constraint set, ``lam = lam2 / 2`` and HiGHS's Chebyshev radius there."""
    system, load = random_problem(n, seed)
    cs = sd.bounds.extreme_constraints(system, load)
    lam = 0.5 * sd.shakedown_bounds(system, load, only=("lam2",)).lam2
    _, r_h = sd.bounds.chebyshev_centre(cs, lam, solver="highs")
    return cs, lam, r_h


@pytest.mark.parametrize("n,seed", [(30, 5), (80, 6)])
def test_the_certified_interior_centre_needs_no_crossover(n, seed, monkeypatch):
    """Issue 26: on a 2000-crack network (``rng=77``) the centre LP's crossover completed a
    basis of 2 strongly active rows by a dense 1999 x 3999 ``linprog`` for minutes, after the
    bounds were done.  The interior point's centre is now tried first: no crossover when its
    multipliers certify it, and the radius is HiGHS's.  Where it is refused, the crossover runs
    as before (and the centre is a vertex, again HiGHS's radius)."""
    cs, lam, r_h = _centre_at_half_lam2(n, seed)
    calls = []
    real = dense_lp._crossover

    def counted(*a):
        calls.append(1)
        return real(*a)

    monkeypatch.setattr(dense_lp, "_crossover", counted)
    v, r = sd.bounds.chebyshev_centre(cs, lam)
    assert not calls
    assert r == pytest.approx(r_h, rel=engine.CENTRE_RTOL) and _ball_inside(cs, lam, v, r)
    monkeypatch.setattr(engine, "_interior_centre", lambda *a: None)
    v, r = sd.bounds.chebyshev_centre(cs, lam)
    assert len(calls) == 1
    assert r == pytest.approx(r_h, rel=1e-9) and _ball_inside(cs, lam, v, r)


@pytest.mark.parametrize("n,seed", [(60, 7), (150, 9)])
def test_the_interior_point_stops_once_its_centre_is_proven(n, seed, monkeypatch):
    """Issue 26: the centre LP's interior point stops at the first iterate whose centre its
    multipliers prove within ``CENTRE_EARLY`` of the largest radius (on 2000-crack networks 5 of
    26 iterations of ~0.8 s were saved), not at full convergence.  The radius is HiGHS's to
    ``CENTRE_EARLY`` and the ball inside ``H``; a looser ``CENTRE_EARLY`` stops earlier than
    none at all."""
    cs, lam, r_h = _centre_at_half_lam2(n, seed)
    iters = []
    real = dense_lp.ipm

    def counted(*a, **k):
        out = real(*a, **k)
        iters.append(out[4])
        return out

    monkeypatch.setattr(dense_lp, "ipm", counted)
    for early in (engine.CENTRE_EARLY, 1e-3, 0.0):
        monkeypatch.setattr(engine, "CENTRE_EARLY", early)
        v, r = sd.bounds.chebyshev_centre(cs, lam)
        assert r_h * (1 - max(early, 1e-9)) <= r <= r_h * (1 + 1e-9), early
        assert _ball_inside(cs, lam, v, r)
    assert iters[1] < iters[2] and iters[1] <= iters[0] <= iters[2]
