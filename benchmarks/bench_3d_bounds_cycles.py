"""Cyclic runs from many initial states against the 3-D bounds (evidence for docs/guide/bounds_3d.md).

Uncoupled systems (B = 0): below lam2 every run must shake down (Klarbring, Ciavarella & Barber
2007), above it every run must keep slipping.  Coupled systems: the polyhedral candidate
lam_adj_cone (inscribed k-gons) claims shakedown from every initial state below it; runs at
0.9 and 0.99 lam_adj_cone test the claim, runs between lam_adj_cone and lam2 and above lam2 show
what happens there.  A run "shakes down" when the solver says so, or its last cycle dissipates
less than 1e-8 of W_scale = F s (force scale x natural slip), or less than 1e-2 of the cycle
half-way through the run (a decaying dissipation: asymptotic shakedown is slow near lam2); else
it "keeps slipping".

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_bounds_cycles.py [out.json]
    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_3d_bounds_cycles.py --probe out_probe.json
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

import shakedown as sd
from shakedown.evolution.steady_maps import sample_initial_slips

N, STATES, STEPS, CYCLES, FACETS = 3, 5, 24, 60, 16


def random_3d(n, seed, coupled):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    B = K[: 2 * n, 2 * n:] if coupled else np.zeros((2 * n, n))
    return sd.DiscreteSystem(K[: 2 * n, : 2 * n], B, K[2 * n:, 2 * n:], friction=0.4, dim=3)


def random_load(n, seed):
    rng = np.random.default_rng(seed)
    return sd.LoadCycle.from_harmonics(
        q0=0.2 * n * rng.normal(size=(n, 2)), p0=n * (1 + rng.random(n)),
        q_cos=n * rng.normal(size=(n, 2)), q_sin=n * rng.normal(size=(n, 2)),
        p_cos=0.2 * n * rng.normal(size=n), p_sin=0.2 * n * rng.normal(size=n))


def runs_at(system, load, lam, seed):
    V0 = sample_initial_slips(system, load, STATES, rng=seed)
    runs = sd.solve_cycles(system, load, lam, initial_slip=V0, steps_per_cycle=STEPS,
                           max_cycles=CYCLES, tol=1e-9)
    F = float(np.max(np.abs(load.p0)) * 0.4 + np.abs(load.q0).max()
              + lam * np.abs(load.q_cos).max())
    s_nat = F / float(np.min(np.diag(system.A)))
    out = []
    for r in runs:
        W = np.asarray(r.dissipation, float) / (F * s_nat)
        w_last = float(W[-1]) if W.size else float("nan")
        w_half = float(W[W.size // 2]) if W.size else float("nan")
        # decaying: the last cycle dissipates < 1e-8, or less than 1e-2 of the mid-run cycle
        # (asymptotic shakedown near lam2 is slow); persisting: neither
        down = bool(r.shook_down) or (np.isfinite(w_last) and (
            w_last <= 1e-8 or w_last <= 1e-2 * w_half))
        out.append(dict(shook_down=down, w_last=w_last, w_half=w_half, status=r.status,
                        cycles=int(r.n_cycles)))
    return out


def cases(probe):
    """(coupled, seed, n) of the systems: the first pass, or ``--probe`` (more coupled
    systems, N = 3 and 4, load factors close to lam_adj_cone)."""
    if probe:
        return [(True, seed, n) for n in (3, 4) for seed in range(3, 7)]
    return [(True, seed, N) for seed in range(3)] + [(False, seed, N) for seed in range(2)]


def main(path, probe=False):
    rows = []
    for coupled, seed, n in cases(probe):
        s = random_3d(n, 100 + seed, coupled)
        load = random_load(n, 200 + seed)
        b = sd.shakedown_bounds(s, load, adjacency=True, intervals=False, facets=FACETS)
        lam2, adj = b.lam2, b.lam_adj_cone
        if probe:
            lams = {"0.99 lam_adj": 0.99 * adj, "1.02 lam_adj": 1.02 * adj,
                    "1.1 lam_adj": 1.1 * adj}
        elif coupled:
            lams = {"0.95 lam_adj": 0.95 * adj, "mid(lam_adj, lam2)": 0.5 * (adj + lam2),
                    "1.05 lam2": 1.05 * lam2}
        else:
            lams = {"0.9 lam2": 0.9 * lam2, "1.1 lam2": 1.1 * lam2}
        for name, lam in lams.items():
            t0 = time.perf_counter()
            res = runs_at(s, load, lam, seed)
            rows.append(dict(coupled=coupled, seed=seed, n=n, lam2=lam2, lam_adj_cone=adj,
                             lam1_cone=b.lam1_cone, where=name, lam=lam,
                             n_shook_down=sum(r["shook_down"] for r in res),
                             n_states=len(res), runs=res,
                             seconds=time.perf_counter() - t0))
            print(coupled, seed, n, name, f"lam={lam:.5g}", rows[-1]["n_shook_down"], "/",
                  len(res), [f"{r['w_half']:.1e}->{r['w_last']:.1e}" for r in res], flush=True)
            with open(path, "w") as fh:
                json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--probe"]
    main(args[0] if args else "benchmarks/bounds_3d_cycles.json", probe="--probe" in sys.argv)
