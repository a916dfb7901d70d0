"""Fill numba's cache with the compiled kernels (2-D ``march`` and the 3-D cone step), as the
test session's background process (``tests/conftest.py``): on a cold cache (a fresh clone, as in
CI) compiling them costs ~100 s of CPU, which this process spends on the second core while the
first tests (bounds, crack networks) need no kernel; later tests then load them (~0.5 s).  On
a warm cache it only loads them (~3 s)."""

import numpy as np

import shakedown as sd
from shakedown.evolution.kernel_warm import warm_up


def main() -> None:
    warm_up()  # the 2-D kernel, with the argument types of every real call
    rng = np.random.default_rng(0)
    n = 4
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    system = sd.DiscreteSystem(K[:2 * n, :2 * n], 0.3 * K[:2 * n, 2 * n:], K[2 * n:, 2 * n:],
                               friction=0.3, dim=3)
    load = sd.LoadCycle.from_harmonics(q0=np.zeros((n, 2)), p0=np.ones(n),
                                       q_cos=rng.normal(size=(n, 2)),
                                       q_sin=rng.normal(size=(n, 2)))
    sd.solve_cycles(system, load, 1.0, steps_per_cycle=8)  # the 3-D cone kernel


if __name__ == "__main__":
    main()
