"""HiGHS prints nothing (issue 25: its banner appeared in notebook 03 and on the stdout of
``shakedown bounds`` for the half-plane scene, before the verdict).

HiGHS writes its banner to the C-level standard output when a process constructs its first
model; ``lp.quiet_highs`` constructs that one with the output sent to the null device.
"""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import numpy as np
from shakedown.bounds.lp import ReusableLP
# max x + y  s.t.  x + 2 y <= 4,  0 <= x, y <= 3
lp = ReusableLP(np.array([[1.0, 2.0]]), [-np.inf], [4.0], [0.0, 0.0], [3.0, 3.0], [1.0, 1.0])
ans = lp.solve()
print("objective", ans.objective)
import highspy
highspy.Highs()  # a later model of the same process prints nothing either
print("done")
"""


def test_the_lp_prints_no_highs_banner():
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                       cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    lines = r.stdout.splitlines()
    assert lines == ["objective 3.5", "done"], r.stdout  # the LP ran and printed nothing else
    assert "HiGHS" not in r.stderr, r.stderr
