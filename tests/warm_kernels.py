"""Fill numba's cache with the compiled kernels (2-D ``march`` and the 3-D cone step), as the
test session's background process (``tests/conftest.py``): on a cold cache (a fresh clone, as in
CI) compiling them costs ~100 s of CPU, which this process spends on the second core while the
first tests (bounds, crack networks) need no kernel; later tests then load them (~0.5 s).  On
a warm cache it only loads them (~3 s)."""

import numpy as np

import shakedown as sd
from shakedown.evolution.kernel_warm import warm_up


def bounds_kernels() -> None:
    """The bounds engine's compiled pivots (first: the bounds tests, which run first, use
    them within seconds), with the kernels forced on for a small problem."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent / "bounds"))
    from test_barycentric_walk import _problem, _vertex
    from test_basis_lp import _setup
    from test_single_simplex import _kachanov

    from shakedown.bounds import basis_lp
    from shakedown.bounds.barycentric_walk import BarycentricWalk, SimplexFrame

    basis_lp.KERNEL_MIN_N = 0
    f, tab, _ = _setup(*_kachanov(60, 3))
    basis_lp.BasisLP(f, tab).solve(int(f.J[0]))
    G, c, m, B, x2, lam2 = _problem(30, 1)
    frame, t = SimplexFrame.of(G, c, m, B, x2, lam2), 0.9 * lam2
    walk = BarycentricWalk(frame, t, _vertex(G, c + t * m, 1))
    for k in frame.J[:8]:
        walk.walk_to(int(k), 50)


def main() -> None:
    bounds_kernels()
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
