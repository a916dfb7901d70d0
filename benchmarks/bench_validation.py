"""Cost of the input checks added for issue 10 (conditioning of K, checks in slip_pencil).

Times, side by side in one run, the construction of a DiscreteSystem and of a SlipPencil for
N contact nodes with the current code and with another checkout given by --baseline (a folder
holding an older ``shakedown`` package, e.g. from ``git archive <commit> shakedown``).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_validation.py --baseline /tmp/rel_base

Prints median wall times [ms] of --repeat runs and the ratio new / baseline.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

CODE = r"""
import json, sys, time
import numpy as np
import shakedown as sd
from shakedown import stability as st
out = {}
for n in (50, 200, 500):
    rng = np.random.default_rng(n)
    M = rng.standard_normal((2 * n, 2 * n))
    K = M @ M.T / (2 * n) + np.eye(2 * n)
    A, B, C = K[:n, :n], 0.3 * K[:n, n:], K[n:, n:]
    part = st.NodePartition.all_slip(n, 1.0)
    ts, tp = [], []
    for _ in range(int(sys.argv[1])):
        t0 = time.perf_counter(); s = sd.DiscreteSystem(A, B, C, 0.5); ts.append(time.perf_counter() - t0)
        t0 = time.perf_counter(); st.slip_pencil(s, part); tp.append(time.perf_counter() - t0)
    out[n] = (sorted(ts)[len(ts) // 2] * 1e3, sorted(tp)[len(tp) // 2] * 1e3)
print(json.dumps(out))
"""


def run(root: Path, repeat: int) -> dict:
    env = {"PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"}
    res = subprocess.run([sys.executable, "-c", CODE, str(repeat)], env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, type=Path)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    here = Path(__file__).resolve().parents[1]
    rounds = [(run(args.baseline, args.repeat), run(here, args.repeat)) for _ in range(3)]
    print("| N | system base [ms] | system new [ms] | ratio | pencil base [ms] | "
          "pencil new [ms] | ratio |")
    print("|---|---|---|---|---|---|---|")
    for n in rounds[0][0]:
        sb = statistics.median(r[0][n][0] for r in rounds)
        sn = statistics.median(r[1][n][0] for r in rounds)
        pb = statistics.median(r[0][n][1] for r in rounds)
        pn = statistics.median(r[1][n][1] for r in rounds)
        print(f"| {n} | {sb:.2f} | {sn:.2f} | {sn / sb:.2f} | {pb:.2f} | {pn:.2f} | "
              f"{pn / pb:.2f} |")


if __name__ == "__main__":
    main()
