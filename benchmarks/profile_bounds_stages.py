"""Where the bounds engine's time goes on one realization (issue 26): walk pivots, LPs in the
coordinates of the ``lam2`` basis, the pruning's steps.

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1 \\
        python3 benchmarks/profile_bounds_stages.py issue 2000 0 --out /tmp/prof_issue
    ... crack 2000 1 --out /tmp/prof_c1 --cprofile

The realization is that of ``bench_bounds_realizations.py`` (``KIND N I``).  CPU seconds
(``time.process_time``) and call counts are collected around :class:`.BarycentricWalk`
(``_pivot`` with the working-basis size ``m``, ``walk_to`` with its target, result and pivot
count, ``_refactor``, ``_flush``), :class:`.BasisLP` (``solve``: row, pivot cap, status,
pivots; ``race``: its rows, bound and answers) and the pruning's steps (``screen``,
``exact_lps``, ``capped_lps``); printed as one JSON line (with the stages of the result), the
raw records pickled to ``OUT.pkl``, ``cProfile`` stats to ``OUT.prof`` with ``--cprofile``.
The counters add a few percent.
"""

from __future__ import annotations

import argparse
import collections
import cProfile
import json
import os
import pickle
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this repository's package
sys.path.insert(0, str(Path(__file__).resolve().parent))


def _wrap(log, cls, name, key, info=None):
    f = getattr(cls, name)

    def g(self, *a, **k):
        t = time.process_time()
        r = f(self, *a, **k)
        log[key].append((time.process_time() - t, info(self, a, k, r) if info else None))
        return r

    setattr(cls, name, g)


def instrument(log):
    from shakedown.bounds import barycentric_walk as bw
    from shakedown.bounds import basis_lp as bl
    from shakedown.bounds import pruning as pr

    _wrap(log, bw.BarycentricWalk, "_pivot", "walk_pivot", lambda s, a, k, r: len(s.P))
    _wrap(log, bw.BarycentricWalk, "walk_to", "walk_to",
          lambda s, a, k, r: (int(a[0]), r, s.pivots, s.t))
    _wrap(log, bw.BarycentricWalk, "_flush", "walk_check")
    _wrap(log, bw.BarycentricWalk, "_refactor", "walk_refactor", lambda s, a, k, r: len(s.P))
    _wrap(log, bl.BasisLP, "solve", "basis_lp",
          lambda s, a, k, r: (None if a[0] is None else int(a[0]), k.get("max_pivots"),
                              None if r is None else r.status,
                              None if r is None else r.iterations,
                              None if r is None or r.x is None else float(r.x[-1])))
    for name in ("screen", "exact_lps", "capped_lps"):
        _wrap(log, pr._Pruner, name, "pruning_" + name)
    race = bl.BasisLP.race

    def raced(self, rows, below=None, chunk=None):  # CPU of the race's own steps, its answers
        spent, got = 0.0, []
        steps = race(self, rows, below, chunk)
        try:
            while True:
                t = time.process_time()
                try:
                    k, ans = next(steps)
                except StopIteration:
                    return
                finally:
                    spent += time.process_time() - t
                got.append((k, None if ans is None else (ans.status, ans.iterations,
                                                         None if ans.x is None else float(ans.x[-1]))))
                yield k, ans
        finally:
            log["basis_lp_race"].append((spent, (len(rows), below, got)))

    bl.BasisLP.race = raced


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind")
    ap.add_argument("n", type=int)
    ap.add_argument("i", type=int)
    ap.add_argument("--out", default="/tmp/profile_bounds")
    ap.add_argument("--cprofile", action="store_true")
    a = ap.parse_args()
    from bench_bounds_realizations import build

    import shakedown as sd

    system, load, params = build(a.kind, a.n, a.i)
    log = collections.defaultdict(list)
    instrument(log)
    prof = cProfile.Profile() if a.cprofile else None
    t, c = time.perf_counter(), time.process_time()
    if prof:
        prof.enable()
    b = sd.shakedown_bounds(system, load)
    if prof:
        prof.disable()
        prof.dump_stats(a.out + ".prof")
    sec, cpu = time.perf_counter() - t, time.process_time() - c
    m = np.array([x[1] for x in log["walk_pivot"]] or [0])
    rec = dict(kind=a.kind, n=a.n, i=a.i, **params, seconds=sec, cpu_seconds=cpu,
               lam1=b.lam1, lam2=b.lam2, limiting=b.limiting_label,
               stages=[s.to_dict() for s in b.stages], load=os.getloadavg()[0],
               walk_m_percentiles=np.percentile(m, [0, 50, 100]).tolist(),
               counters={k: (len(v), round(sum(x[0] for x in v), 3)) for k, v in log.items()},
               exact_lps=[x[1] for x in log["basis_lp"] if x[1][1] is None])
    print(json.dumps(rec, default=str))
    with open(a.out + ".pkl", "wb") as fh:
        pickle.dump(dict(log), fh)


if __name__ == "__main__":
    main()
