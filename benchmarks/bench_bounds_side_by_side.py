"""Before / after on chosen FE strips of ``bench_bounds_realizations.py`` (issue 26), side by side.

Two frozen source trees (``git archive <commit> | tar -x -C DIR``), each realization run in its
own process with every thread pool pinned to one thread, alternately old and new:

    python3 benchmarks/bench_bounds_side_by_side.py /tmp/fc/old /tmp/fc/snap 1 14 16 17 \\
        > /tmp/fc/side.jsonl

One JSON line per run: CPU and wall seconds of ``shakedown_bounds``, load, ``lam1``, ``lam2``,
the stages (stage, path, fallbacks, seconds), the time outside the stages, peak RSS [GB].
"""

import json
import os
import subprocess
import sys

ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
           NUMBA_NUM_THREADS="1")
CODE = r'''
import sys, time, os, json, resource
root = sys.argv[1]; i = int(sys.argv[2])
sys.path.insert(0, root); sys.path.insert(0, root + "/benchmarks")
from bench_bounds_realizations import build
import shakedown as sd
s, load, p = build("fe", 500, i)
t, c = time.perf_counter(), time.process_time()
b = sd.shakedown_bounds(s, load)
sec, cpu = time.perf_counter() - t, time.process_time() - c
print(json.dumps(dict(root=root, i=i, cpu=cpu, wall=sec, load=os.getloadavg()[0], lam2=b.lam2,
    lam1=b.lam1, fallbacks=sum(st.fallbacks for st in b.stages),
    stages=[(st.stage, st.path, st.fallbacks, round(st.seconds, 2)) for st in b.stages],
    unstaged=b.solve_time - sum(st.seconds for st in b.stages),
    rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6)))
'''

if __name__ == "__main__":
    old, new, reps, *idx = sys.argv[1:]
    for _ in range(int(reps)):
        for i in idx:
            for root in (old, new):
                p = subprocess.run([sys.executable, "-c", CODE, root, i], capture_output=True,
                                   text=True, env=ENV, cwd="/tmp")
                line = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
                print(line[-1] if line else json.dumps(dict(root=root, i=int(i),
                                                            error=p.stderr[-500:])),
                      flush=True)
