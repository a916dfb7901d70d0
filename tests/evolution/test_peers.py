"""Cross-method agreement with an external peer: Siconos numerics LCP solvers (issue 3).

Siconos (Debian ``python3-siconos``) imports only under ``/usr/bin/python3``; the LCPs of a few
implicit steps are handed to ``benchmarks/siconos_lcp_worker.py`` in a subprocess (as the
benchmark ``benchmarks/bench_evolution.py --parts s`` does).  Marked ``peers``: it runs in the
peers job (``python3 -m pytest -m peers``, recorded in benchmarks/RESULTS_peers.md) and is
skipped with that reason in the default run; in the peers job a missing Siconos is a skip that
names the Debian package to install.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from shakedown.evolution.complementarity import StepSolver

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_evolution.py"


def _bench():
    spec = importlib.util.spec_from_file_location("bench_evolution", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.peers
def test_siconos_pivoting_solvers_agree_with_the_step_solver(tmp_path):
    """N = 5 coupled system (friction at half the sufficient critical value, so each step has
    exactly one solution, MODEL.md s.4): 8 steps along the first load period.  Siconos'
    lexicographic Lemke (``SICONOS_LCP_LEMKE``) and its generic pivoting solver
    (``SICONOS_LCP_PIVOT``) must reproduce the package's slips, gaps and reactions to 1e-8 (forces ~1, stiffness ~10: LU / pivoting round-off is ~1e-13,
    1e-8 leaves room for the pivot tolerances of both codes without admitting a different
    vertex), and their answers must satisfy the LCP conditions themselves.  (Siconos 4.4's
    ``SICONOS_LCP_ENUM`` is not used: it reports no solution on most steps where a node slips,
    see benchmarks/RESULTS_evolution.md.)"""
    bench = _bench()
    if not bench.siconos_available():
        pytest.skip("Siconos is unavailable under /usr/bin/python3: apt-get install python3-siconos")
    s, load = bench.coupled_system(5, seed=105)
    solver = StepSolver(s)
    steps = 8
    qw, pw = load.evaluate(np.arange(1, steps + 1) / steps, 1.0)
    v = np.zeros(5)
    guess = None
    starts, answers = [], []
    for k in range(steps):
        r = solver.solve(v, qw[k], pw[k], guess)
        assert r.success and r.status == "unique"
        starts.append(v)
        answers.append(r)
        v, guess = r.slip, r.active_set
    starts = np.array(starts)
    # the steps must exercise slip (otherwise the comparison proves little)
    assert any(np.any(r.states != 0) for r in answers)
    M, Q = bench.step_lcps(s, starts, qw, pw)
    out = bench.run_siconos(M, Q, ("lemke", "pivot"), workdir=tmp_path)
    for name in ("lemke", "pivot"):
        assert np.all(out[f"{name}_info"] == 0), name
        z = out[f"{name}_z"]
        wlcp = z @ M.T + Q
        scale = np.abs(Q).max()
        assert z.min() >= -1e-12 * scale and wlcp.min() >= -1e-10 * scale, name
        assert np.abs(z * wlcp).max() <= 1e-10 * scale**2, name
        v_s, g_s, q_s, p_s = bench.lcp_to_step(s, z, starts, qw, pw)
        for k, r in enumerate(answers):
            np.testing.assert_allclose(v_s[k], r.slip, rtol=0, atol=1e-8, err_msg=name)
            np.testing.assert_allclose(g_s[k], r.gap, rtol=0, atol=1e-8, err_msg=name)
            np.testing.assert_allclose(q_s[k], r.q, rtol=0, atol=1e-8, err_msg=name)
            np.testing.assert_allclose(p_s[k], r.p, rtol=0, atol=1e-8, err_msg=name)
