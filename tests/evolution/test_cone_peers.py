"""Cross-check of the 3-D step with an external peer: Siconos FC3D (issue 22).

Siconos (Debian ``python3-siconos``) imports only under ``/usr/bin/python3``; the steps of one
period are written as FC3D problems (``u = W r + q`` in the contact frame, normal first, De
Saxce's formulation; ``benchmarks/bench_cone_step.py:to_fc3d``) and solved by
``benchmarks/siconos_fc3d_worker.py`` in a subprocess.  Marked ``peers``: skipped with a reason in
the default run (``python3 -m pytest -m peers`` runs it).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_cone_step.py"


def _bench():
    spec = importlib.util.spec_from_file_location("bench_cone_step", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.peers
def test_siconos_fc3d_solvers_agree_with_the_cone_step():
    """N = 12 coupled system, the 32 steps of the third period (most nodes slip on some step):
    Siconos' NSGS and NSN_AC (tolerance 1e-12) reproduce this code's reactions and
    displacements to 1e-8 of the force scale (stiffness ~1: the same scale for slips)."""
    bench = _bench()
    if not bench.siconos_available():
        pytest.skip("Siconos is unavailable under /usr/bin/python3: apt-get install python3-siconos")
    s, load = bench.coupled_system_3d(12, seed=2)
    sol, RB, U0, _, U, R = bench.period_steps(s, load, 0.8, S=32)
    assert np.mean([np.mean(np.hypot(*u[:, :2].T) > 0) for u in U]) > 0.3
    W, Q, perm = bench.to_fc3d(sol.data.Kn, RB)
    out = bench.run_siconos(W, Q, s.friction_xy[:, 0], ("nsgs", "nsn_ac"), warm=True)
    F = np.abs(RB).max()
    ours_r = R.reshape(len(R), -1)[:, perm]
    ours_u = U.reshape(len(U), -1)[:, perm]
    for name in ("nsgs", "nsn_ac"):
        assert np.all(out[f"{name}_info"] == 0), name
        np.testing.assert_allclose(out[f"{name}_r"], ours_r, rtol=0, atol=1e-8 * F, err_msg=name)
        np.testing.assert_allclose(out[f"{name}_u"], ours_u, rtol=0, atol=1e-8 * F, err_msg=name)
