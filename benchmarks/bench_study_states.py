"""How min and max W* over initial states converge with the number of states (issue 13).

    python benchmarks/bench_study_states.py [--states 48] [--realisations 2]

For realisations of the default crack network (100 cracks, density 0.1, f = 0.6), at load
factors inside (lam1, lam2) and above lam2, run ``--states`` initial states of the study's
family (:func:`shakedown.studies.design.initial_states`: zero, safe, corner+, corner-, then
random corners and random box states alternately) and, as the old baseline family, the zero
state plus random box states only.  Prints, for k = 1, 2, 4, 8, 16, ..., the largest gap of
max over the first k states below the max over all states of both families (relative), and
the same for the min.  Deterministic (no timing).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--states", type=int, default=48)
    ap.add_argument("--realisations", type=int, default=2)
    ap.add_argument("--cracks", type=int, default=100)
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    from shakedown.bounds.engine import shakedown_bounds
    from shakedown.evolution.complementarity import StepSolver
    from shakedown.studies.crack_study import realisation_model
    from shakedown.studies.design import initial_states
    from shakedown.studies.runs import initial_slip, run_row
    from shakedown.studies.spec import SweepSpec

    spec = SweepSpec(n_cracks=args.cracks, density=0.1, half_length=1.0, min_spacing=0.1,
                     seed=2024, steps_per_cycle=64)
    opts = spec.solver_options()
    ks = [k for k in (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64) if k <= args.states]
    out = []
    for r in range(args.realisations):
        _, model, load = realisation_model(spec, r)
        s = model.system
        b = shakedown_bounds(s, load, separation=False)
        fam = {"study": initial_states(s, load, args.states, (spec.seed, r, 1),
                                       safe_state=b.state_at_lam2),
               "random": np.array([initial_slip(s, load, j, (spec.seed, r, 1))
                                   for j in range(args.states)])}
        lams = {"band 0.5": b.lam1 + 0.5 * (b.lam2 - b.lam1), "band 0.98":
                b.lam1 + 0.98 * (b.lam2 - b.lam1), "1.05 lam2": 1.05 * b.lam2,
                "1.2 lam2": 1.2 * b.lam2}
        for name, lam in lams.items():
            W = {}
            for f, states in fam.items():
                solver = StepSolver(s)
                W[f] = np.array([float(model.normalised_dissipation(
                    run_row(s, load, lam, v, opts, step_solver=solver)["W"])) for v in states])
            top = max(W["study"].max(), W["random"].max())
            bot = min(W["study"].min(), W["random"].min())
            row = dict(realisation=r, lam=name, W_max=top, W_min=bot,
                       argmax_study=int(np.argmax(W["study"])))
            for f in fam:
                row[f"{f}_max_gap"] = [float((top - np.max(W[f][:k])) / top) if top > 0 else 0.0
                                       for k in ks]
                row[f"{f}_min_gap"] = [float((np.min(W[f][:k]) - bot) / top) if top > 0 else 0.0
                                       for k in ks]
            out.append(row)
            print(json.dumps(row), flush=True)
    print("k =", ks)


if __name__ == "__main__":
    main()
