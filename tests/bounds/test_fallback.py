"""Issue 26: an LP the dense path cannot certify falls back alone, and the result says so.

* A forced failure of the dense ``lam2`` LP: HiGHS solves that LP, its optimal basis comes back
  to the dense machinery, and every other LP stays on the dense path; the answer is the same
  as without the failure (and as HiGHS's reference path).
* The crossover's last resort (:func:`~shakedown.bounds.dense_lp.finish_from`) from a wrong
  basis ends at HiGHS's optimum, certified.
* The records (``stages``), the verdict's sentence on a costly fallback, the progress display.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_basis_lp import _tensile_problem
from test_lp import highs_max, random_lp

import shakedown as sd
from shakedown import dense_lp
from shakedown.bounds import dense_path, highs_path
from shakedown.bounds.provenance import STAGES, StageRecord, costly_fallback


def _problem():
    return _tensile_problem(40, 3)


def _force_lam2_failure(monkeypatch):
    """The dense lam2 LP fails (as the interior point's crossover did in issue 26); every
    HiGHS LP is counted."""
    real = dense_lp.solve_max
    calls = {"highs": [], "lam2": 0}

    def failing(A, b, e, *, why=None, **kw):
        if kw.get("interior"):  # the Chebyshev centre: not the lam2 LP
            return real(A, b, e, why=why, **kw)
        calls["lam2"] += 1
        if why is not None:
            why.update(reason="forced failure", basis=None)
        return None, None

    run = highs_path.HighsModel.run

    def counted(self, sense, tight=(), separation=False, **kw):
        calls["highs"].append((sense, tuple(tight), separation))
        return run(self, sense, tight=tight, separation=separation, **kw)

    monkeypatch.setattr(dense_path.dense_lp, "solve_max", failing)
    monkeypatch.setattr(highs_path.HighsModel, "run", counted)
    return calls


def _same(a, b, rtol=1e-9):
    scale = max(1.0, float(np.nanmax(np.abs(b))))
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = ~np.isnan(b)
    assert np.all(np.abs(np.asarray(a)[ok] - np.asarray(b)[ok]) <= rtol * scale)


def test_a_failed_lam2_lp_falls_back_alone(monkeypatch):
    system, load = _problem()
    ref = sd.shakedown_bounds(system, load)
    assert ref.stages[0].stage == "lam2" and ref.stages[0].path == "dense"
    before = {s.stage: s for s in ref.stages}
    calls = _force_lam2_failure(monkeypatch)
    b = sd.shakedown_bounds(system, load)
    assert calls["lam2"] == 1
    # only the lam2 LP went to HiGHS, besides the LPs that fall back without the failure
    # (here one lam_low LP whose dense answer is not certified)
    assert calls["highs"][0] == ("max", (), False)
    assert len(calls["highs"]) == 1 + sum(s.fallbacks for s in ref.stages)
    st = {s.stage: s for s in b.stages}
    assert st["lam2"].path == "highs" and st["lam2"].fallbacks == 1
    assert st["lam2"].reasons == ("forced failure (1)",)
    assert [(k, s.fallbacks, s.reasons) for k, s in st.items() if k != "lam2"] == \
        [(k, s.fallbacks, s.reasons) for k, s in before.items() if k != "lam2"]
    assert st["lam_low"].dense_lps > 0 and "dense" in st["lam_high"].path
    assert "LP(s) re-solved by HiGHS" in b.message and "lam2: 1" in b.message
    for name in ("lam1", "lam2", "lam_separation"):
        _same(np.array([getattr(b, name)]), np.array([getattr(ref, name)]))
    _same(b.lam_low, ref.lam_low)
    _same(np.where(b.lam_high_exact, b.lam_high, np.nan),
          np.where(ref.lam_high_exact, ref.lam_high, np.nan))
    assert b.limiting_constraint == ref.limiting_constraint
    # the certificate of the HiGHS basis, certified again in the dense coordinates
    cs = b.constraints
    y = b.certificate
    assert np.all(y >= -1e-12 * np.abs(y).max())
    assert np.abs(cs.G.T @ y).max() <= 1e-9 * np.abs(cs.G).max() * np.abs(y).max()
    assert (cs.c @ y) / (-(cs.m @ y)) == pytest.approx(b.lam2, rel=1e-9)


def test_the_reference_path_agrees(monkeypatch):
    system, load = _problem()
    ref = sd.shakedown_bounds(system, load, solver="highs")
    _force_lam2_failure(monkeypatch)
    b = sd.shakedown_bounds(system, load)
    assert b.lam2 == pytest.approx(ref.lam2, rel=1e-9)
    assert b.lam1 == pytest.approx(ref.lam1, rel=1e-9)
    assert ref.stages[0].path == "highs" and ref.stages[0].fallbacks == 0


@pytest.mark.parametrize("seed", range(4))
def test_finish_from_a_wrong_basis_reaches_the_optimum(seed):
    """The crossover's last resort (issue 26: 8 negative multipliers, 12 violated rows) from a
    basis that is neither primal nor dual feasible: clamp, dual simplex, primal finish."""
    A, b, e = random_lp(8, 30, seed)
    rng = np.random.default_rng(seed)
    for _ in range(50):
        T = np.sort(rng.choice(len(b), 8, replace=False))
        tab = dense_lp.Tableau(A, b, e, T)
        if not tab.singular and not tab.dual_feasible \
                and np.any(tab.act0 > tab.b + 1e-6):
            break
    else:
        pytest.fail("no wrong start basis drawn")
    ans, out = dense_lp.finish_from(A, b, e, tab)
    assert ans is not None and ans.status == "optimal" and out.dual_feasible
    assert e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-9)
    assert max(dense_lp.kkt_residuals(A, b, e, ans.x, ans.y)) <= dense_lp.CERT_TOL


def test_highs_basis_round_trip():
    """HiGHS's optimal basis read as dense rows is the dense optimum's basis, and handed back
    as a start it needs no pivot."""
    from shakedown.bounds.constraints import Scales, extreme_constraints

    system, load = _problem()
    cs = extreme_constraints(system, load)
    ch = Scales.of(cs).nondimensional(cs)
    n = ch.n_nodes
    A = np.vstack([np.hstack([ch.G, -ch.m[:, None]]), np.r_[np.zeros(n), -1.0][None, :]])
    main, _ = dense_lp.solve_max(A, np.r_[ch.c, 0.0], np.r_[np.zeros(n), 1.0])
    model = highs_path.HighsModel(ch)
    ans = model.run("max")
    T = model.tight_basis()
    assert T is not None and set(T) == set(main.basis)
    again = highs_path.HighsModel(ch)
    assert again.start_from(T)
    warm = again.run("max")
    assert warm.iterations == 0 and warm.x[-1] == pytest.approx(ans.x[-1], rel=1e-12)


def _record(stage, fallbacks, seconds, fallback_seconds):
    return StageRecord(stage, "highs" if fallbacks else "dense", 1, 0, fallbacks, fallbacks,
                       ("forced failure (1)",) if fallbacks else (), seconds, fallback_seconds)


def test_the_verdict_mentions_a_fallback_that_cost_more_than_the_rest():
    system, load = _problem()
    b = sd.shakedown_bounds(system, load)
    costly = (_record("lam2", 1, 9.0, 8.0), _record("lam_low", 0, 2.0, 0.0))
    cheap = (_record("lam2", 1, 3.0, 2.0), _record("lam_low", 0, 8.0, 0.0))
    text = dataclasses.replace(b, stages=costly, solve_time=11.0).verdict()
    assert "1 LP(s) (1 lam2) could not be certified by the dense path (forced failure (1))" \
        in text and "8 s of the 11 s" in text
    assert "HiGHS" not in dataclasses.replace(b, stages=cheap, solve_time=11.0).verdict()
    assert "HiGHS" not in b.verdict()
    assert costly_fallback((), 1.0) == ""


def test_stages_drive_the_progress_display():
    system, load = _problem()
    seen = []

    def progress(iterable, total=None, desc=""):
        seen.append((total, desc))
        for item in iterable:
            seen.append(item)
            yield item

    b = sd.shakedown_bounds(system, load, progress=progress)
    assert seen[0] == (6, "shakedown bounds")
    assert seen[1:] == ["lam2", "lam_low", "lam_high", "adjacency", "separation", "safe_state"]
    assert [s.stage for s in b.stages][:3] == ["lam2", "lam_low", "lam_high"]
    assert b.stages[-1].stage == "safe_state" and b.stages[-1].dense_lps == 1
    assert b.to_dict()["stages"][0]["stage"] == "lam2"


def test_a_highs_lp_that_stops_without_an_answer_is_not_read_as_infeasible(monkeypatch):
    """Issue 26: the 2000-crack lam2 LP hit HiGHS's time limit under load and the result said
    "infeasible" (lam1 = lam2 = nan).  A time limit in a forced lam2 fallback now raises."""
    from shakedown.bounds.lp import LPAnswer, ReusableLP
    from shakedown.bounds.outcome import value
    from shakedown.model.errors import SolverError

    e = np.zeros(0)
    stopped = LPAnswer("Time limit reached", np.nan, e, e, e, *(np.nan,) * 4, 12)
    with pytest.raises(SolverError, match="Time limit reached"):
        value(stopped)
    assert np.isnan(value(dataclasses.replace(stopped, status="infeasible")))
    system, load = _problem()
    _force_lam2_failure(monkeypatch)
    monkeypatch.setattr(ReusableLP, "solve", lambda self: stopped)
    with pytest.raises(SolverError, match="time_limit"):
        sd.shakedown_bounds(system, load)
    with pytest.raises(SolverError):
        sd.shakedown_bounds(system, load, solver="highs")


@pytest.mark.parametrize("seed", range(4))
def test_finish_from_a_feasible_basis_with_a_slightly_negative_multiplier(seed):
    """Issue 26 (FE strip, seed 5017): HiGHS's optimal ``lam2`` basis is primal feasible in the
    dense coordinates, its smallest multiplier ``-1.2e-8`` of the largest: inside CERT_TOL, not
    dual feasible to 1e-9, and it was refused without a primal pivot.  Here such a basis is
    made by tilting the objective of an optimal one; the finish must end at HiGHS's optimum
    of the tilted LP, certified."""
    A, b, e = random_lp(8, 30, seed)
    ans, tab = dense_lp.solve_max(A, b, e)
    T = np.sort(ans.basis)
    B = A[T] / np.linalg.norm(A[T], axis=1)[:, None]
    y = np.linalg.solve(B.T, e)
    j = int(np.argmax(y))
    e2 = e - (y[j] + 3e-8 * np.abs(y).max()) * B[j]  # y_j -> -3e-8 |y|, the rest unchanged
    tab2 = dense_lp.Tableau(A, b, e2, T)
    assert not tab2.dual_feasible and tab2.y0.min() > -1e-7 * np.abs(tab2.y0).max()
    assert np.all(tab2.act0 <= tab2.b + 1e-12)  # primal feasible
    got, out = dense_lp.finish_from(A, b, e2, tab2)
    assert got is not None and got.status == "optimal" and out.dual_feasible
    # (HiGHS at its default dual tolerance 1e-7 stops at the tilted basis itself: tightened)
    from shakedown.bounds.lp import ReusableLP

    lp = ReusableLP(A, np.full(len(b), -np.inf), b, np.full(8, -np.inf), np.full(8, np.inf), e2)
    for opt in ("primal_feasibility_tolerance", "dual_feasibility_tolerance"):
        lp._h.setOptionValue(opt, 1e-10)
    ref = lp.solve()
    assert e2 @ got.x == pytest.approx(ref.objective, rel=1e-9)
    assert e2 @ got.x > e2 @ tab2.x0 + 1e-10  # (the tilted basis itself is not the optimum)
    assert max(dense_lp.kkt_residuals(A, b, e2, got.x, got.y)) <= dense_lp.CERT_TOL


def test_a_safe_state_fallback_is_recorded_and_costly_ones_are_said(monkeypatch):
    """Issue 26: the safe state (Chebyshev centre) took 30 s of a 32 s computation on FE
    strips, outside every stage.  It is now the stage ``safe_state``: dense when certified;
    forced to fail here, HiGHS with its reason, counted as a fallback, in the message, and in
    the verdict when it cost more than the rest.  The centre is HiGHS's; the dense one is
    certified within ``CENTRE_RTOL`` below it."""
    from test_bounds import random_problem

    from shakedown.bounds import engine

    system, load = random_problem(40, 1)
    ref = sd.shakedown_bounds(system, load)
    st = ref.stages[-1]
    assert st.stage == "safe_state" and st.path == "dense" and st.fallbacks == 0
    assert ref.lam1 > 0 and ref.safe_margin > 0
    real = dense_lp.solve_max

    def no_centre(A, b, e, **kw):  # the centre LP's interior point and crossover fail
        return (None, None) if kw.get("interior") else real(A, b, e, **kw)

    monkeypatch.setattr(dense_lp, "solve_max", no_centre)
    b = sd.shakedown_bounds(system, load)
    st = b.stages[-1]
    assert (st.stage, st.path, st.highs_lps, st.fallbacks) == ("safe_state", "highs", 1, 1)
    assert "centre not certified" in st.reasons[0] and "safe_state: 1" in b.message
    assert b.lam2 == ref.lam2 and b.safe_lam == ref.safe_lam
    r_h, r_d = b.safe_margin, ref.safe_margin
    assert r_h * (1 - engine.CENTRE_RTOL) <= r_d <= r_h * (1 + 1e-9)
    costly = dataclasses.replace(b, solve_time=1.5 * st.fallback_seconds).verdict()
    assert "1 LP(s) (1 safe_state) could not be certified by the dense path" in costly
    assert "HiGHS" not in dataclasses.replace(b, solve_time=10 * st.fallback_seconds).verdict()


def _fe_strip_5017():
    """The FE strip of ``benchmarks/bench_bounds_realizations.py`` (``--kind fe``, N = 500,
    realization 17, seed 5017), where issue 26's cliff was found on FE strips."""
    from shakedown import fe

    rng = np.random.default_rng(5017)
    friction = float(rng.uniform(0.3, 0.9))
    shear, press, rot = rng.uniform(0.2, 0.6), rng.uniform(-0.3, 0.3), rng.uniform(0.0, 0.3)
    loads = {"dead": fe.Traction("top", (0.0, -1.0)), "shear": fe.Traction("top", (1.0, 0)),
             "press": fe.Traction("top", (0.0, 1.0))}
    model = fe.FEModel(fe.rectangle(4.99, 0.1, 499, 8), fe.isotropic(1.0, 0.3),
                       dirichlet={"left": "xy"}, contact=["bottom"], loads=loads,
                       friction=friction)
    cm = model.condense()
    return cm.system, cm.load_cycle(static="dead", cyclic={"shear": shear, "press": press},
                                    cyclic_sin={"shear": rot})


def _farkas(b, rtol=1e-9):
    cs, y = b.constraints, b.certificate
    ys = np.abs(y).max()
    assert y.min() >= -rtol * ys
    assert np.abs(cs.G.T @ y).max() <= rtol * np.abs(cs.G).max() * ys
    assert cs.c @ y / (-(cs.m @ y)) == pytest.approx(b.lam2, rel=rtol)
    off = cs.offsets(b.lam2)
    assert (cs.G @ b.state_at_lam2 - off).max() <= 1e-10 * np.abs(off).max()


@pytest.mark.slow
def test_fe_strip_5017_stays_dense_and_a_forced_lam2_failure_comes_back(monkeypatch):
    """Issue 26, FE strip seed 5017 (500 contact nodes): the dense ``lam2`` LP was not
    certified (37 strongly active rows, no non-singular basis among the rest; the completed
    basis was never finished), HiGHS's optimal basis was refused in the dense coordinates (a
    multiplier of -1.2e-8 of the largest: no primal pivot was tried), so all 1999 LPs went to
    HiGHS: 79 s against 1.9 s.  Now every stage is dense; and with the dense ``lam2`` LP forced
    to fail, HiGHS's basis comes back certified and only that LP falls back, same answer."""
    system, load = _fe_strip_5017()
    ref = sd.shakedown_bounds(system, load)
    assert all(s.fallbacks == 0 and "highs" not in s.path for s in ref.stages)
    assert ref.stages[0].path == "dense" and ref.stages[-1].stage == "safe_state"
    _farkas(ref)
    calls = _force_lam2_failure(monkeypatch)
    b = sd.shakedown_bounds(system, load)
    assert calls["lam2"] == 1 and len(calls["highs"]) == 1
    assert [s.fallbacks for s in b.stages] == [1] + [0] * (len(b.stages) - 1)
    assert b.lam2 == pytest.approx(ref.lam2, rel=1e-9) and b.lam1 == pytest.approx(ref.lam1,
                                                                                  rel=1e-9)
    _farkas(b)


@pytest.mark.parametrize("stage", STAGES)
def test_the_verdict_names_a_costly_fallback_in_any_stage(stage):
    system, load = _problem()
    b = sd.shakedown_bounds(system, load)
    others = tuple(_record(s, 0, 1.0, 0.0) for s in STAGES if s != stage)
    costly = others + (_record(stage, 1, 7.0, 6.0),)
    text = dataclasses.replace(b, stages=costly, solve_time=11.0).verdict()
    assert f"1 LP(s) (1 {stage}) could not be certified" in text and "6 s of the 11 s" in text
    cheap = others + (_record(stage, 1, 7.0, 5.0),)  # 5 s against 6 s for the rest
    assert "HiGHS" not in dataclasses.replace(b, stages=cheap, solve_time=11.0).verdict()


@pytest.mark.parametrize("limit", [0, 100])
def test_a_large_completion_lp_is_not_tried_first(monkeypatch, limit):
    """Issue 26 (2000-crack network i = 9): at a stalled interior point with 4 strongly active
    rows of 2001, completing them to a basis is a 1997-row dense LP (93 s), while the basis the
    interior point names reaches the certified optimum in 4.9 s (:func:`finish_from`).  Above
    ``COMPLETION_LP_MAX`` missing rows the crossover finishes the named basis first; below, the
    completion comes first, as before.  Either way the answer is HiGHS's optimum."""
    A, b, e = random_lp(8, 30, 11)
    n = A.shape[1]
    rng = np.random.default_rng(11)
    for _ in range(200):  # a named basis neither primal nor dual feasible
        T = np.sort(rng.choice(len(b), n, replace=False))
        tab = dense_lp.Tableau(A, b, e, T)
        if not tab.singular and not tab.dual_feasible and np.any(tab.act0 > tab.b + 1e-6):
            break
    else:
        pytest.fail("no wrong start basis drawn")
    # an iterate that names T, with one strongly active row (n - 1 rows missing)
    s = np.ones(len(b))
    z = np.full(len(b), 1e-6)
    z[T] = 1.0
    z[T[0]] = 1e8
    As = A / np.linalg.norm(A, axis=1)[:, None]
    assert len(dense_lp.strongly_active(z, s, n)) == 1
    calls = []
    for name in ("finish_from", "complete_basis"):
        real = getattr(dense_lp, name)
        monkeypatch.setattr(dense_lp, name,
                            lambda *a, _r=real, _n=name, **k: (calls.append(_n), _r(*a, **k))[1])
    monkeypatch.setattr(dense_lp, "COMPLETION_LP_MAX", limit)
    ans, out = dense_lp._crossover(A, b, e, T, As, s, z, 0)
    assert ans is not None and ans.status == "optimal" and out.dual_feasible
    assert e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-9)
    assert max(dense_lp.kkt_residuals(A, b, e, ans.x, ans.y)) <= dense_lp.CERT_TOL
    if limit < n - 1:
        assert calls == ["finish_from"]
    else:
        assert calls[0] == "complete_basis"


@pytest.mark.parametrize("retry", [2, 0])
def test_a_failed_crossover_is_retried_with_correctors(monkeypatch, retry):
    """Issue 26 (FE strip i = 19 at N = 2000): the crossover from the interior point without
    centrality correctors is not certified, from one with them it is.  ``solve_max`` runs the
    interior point once more with ``RETRY_CORRECTORS`` before giving up (then HiGHS answers in
    :mod:`~shakedown.bounds.dense_path`); with 0 it gives up at once."""
    A, b, e = random_lp(8, 30, 5)
    real_ipm, real_cross = dense_lp.ipm, dense_lp._crossover
    runs, crossings = [], []

    def ipm(*a, **k):
        runs.append(k.get("correctors", 0))
        return real_ipm(*a, **k)

    def crossover(*a, **k):
        crossings.append(1)
        return (None, None) if len(crossings) == 1 else real_cross(*a, **k)  # the first fails

    monkeypatch.setattr(dense_lp, "ipm", ipm)
    monkeypatch.setattr(dense_lp, "_crossover", crossover)
    monkeypatch.setattr(dense_lp, "RETRY_CORRECTORS", retry)
    why = {}
    ans, tab = dense_lp.solve_max(A, b, e, why=why)
    if retry:
        assert runs == [0, retry] and len(crossings) == 2
        assert ans is not None and ans.status == "optimal" and tab.dual_feasible
        assert e @ ans.x == pytest.approx(highs_max(A, b, e), rel=1e-9)
        assert max(dense_lp.kkt_residuals(A, b, e, ans.x, ans.y)) <= dense_lp.CERT_TOL
    else:
        assert runs == [0] and ans is None and "crossover" in why["reason"]
