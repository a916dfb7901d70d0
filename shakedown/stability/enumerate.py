"""Exact MCEIP by enumeration of the support of the mode (small slip sets).

For every non-empty support ``J`` of the slip nodes: the real ``mu > 0`` of the generalized
eigenproblem ``(K0 + mu K1)_JJ x_J = 0`` whose eigenvector is positive, then the sign
conditions ``y_j >= 0`` off ``J``.  ``2^n - 1`` dense eigenproblems of size ``<= n``: the
smallest verified ``mu`` is certified minimal (barring multiple eigenvalues whose eigenspace
holds a positive vector that no computed eigenvector is, a non-generic case).
"""

from __future__ import annotations

import itertools

import numpy as np

from ..model.errors import InputError
from .linear import restricted_eigenpairs
from .pencil import SlipPencil
from .result import VERIFY_TOL, MCEIPResult, make_result, no_solution

#: Default largest slip set enumerated (4095 supports, ~0.5 s).
MAX_ENUMERATION_NODES = 12


def enumerate_solutions(pencil: SlipPencil, *, tol: float = VERIFY_TOL,
                        max_nodes: int = 16) -> list[MCEIPResult]:
    """Every verified solution (one per support and eigenvalue), sorted by ``mu``."""
    n = pencil.size
    if n > max_nodes:
        raise InputError(
            f"support enumeration of {n} slip nodes needs 2^{n} eigenproblems; the limit is "
            f"max_nodes = {max_nodes}: use method='power', 'linear' or 'active-set', or raise it"
        )
    found = []
    count = 0
    for size in range(1, n + 1):
        for J in itertools.combinations(range(n), size):
            count += 1
            for mu, xJ, positive in restricted_eigenpairs(pencil.K0, pencil.K1, list(J)):
                if not positive:
                    continue
                x = np.zeros(n)
                x[list(J)] = np.clip(xJ, 0.0, None)
                res = make_result(pencil, mu, x, method="enumeration", tol=tol,
                                  iterations=count)
                if res.verified and res.support.size == size:
                    found.append(res)
    found.sort(key=lambda r: r.mu)
    return found


def enumeration(pencil: SlipPencil, *, tol: float = VERIFY_TOL,
                max_nodes: int = 16) -> MCEIPResult:
    """The smallest MCEIP solution, certified by enumerating all ``2^n - 1`` supports."""
    sols = enumerate_solutions(pencil, tol=tol, max_nodes=max_nodes)
    n_sup = 2**pencil.size - 1
    if not sols:
        return no_solution(
            pencil, method="enumeration", iterations=n_sup, minimal=True,
            message=f"no solution on any of the {n_sup} supports: no bifurcation for any mu > 0",
        )
    from dataclasses import replace

    best = sols[0]
    return replace(best, minimal=True, iterations=n_sup,
                   message=f"certified minimal over {n_sup} supports; {len(sols)} solutions")
