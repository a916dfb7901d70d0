"""Dense linear programs ``max e.x  s.t.  A x <= b`` (``x`` free) for the bounds engine.

Two solvers that exploit the small, dense structure of the shakedown LPs (``R = 2N + 1`` rows,
``n = N + 1`` columns, every entry non-zero):

* :func:`~.ipm.ipm` -- a Mehrotra predictor-corrector interior point on the normal equations,
  followed by a basis identification (:mod:`.ipm`), used for the master LPs;
* :func:`~.dual_simplex.batch_dual_simplex` -- the dual simplex method in inequality form, run
  in lock-step on many LPs that share ``A``, ``b`` and a dual-feasible starting basis and differ
  by rows that must hold with equality, with a Sherman-Morrison-Woodbury basis update and
  periodic reinversion (:mod:`.dual_simplex`).

Every answer is checked by its own optimality conditions (:mod:`.certificates`); a caller falls
back to HiGHS when an answer is not certified (status ``"failed"``).  :func:`solve_max` chains
the two: interior point, basis, dual simplex clean-up.
"""

from __future__ import annotations

import numpy as np

from .certificates import (
    CERT_TOL,
    FEAS_TOL,
    PIVOT_TOL,
    DenseAnswer,
    batch_residuals,
    kkt_residuals,
)
from .dual_simplex import Tableau, batch_dual_simplex
from .ipm import complete_basis, identify_basis, ipm, strongly_active

#: Rows of :func:`~.ipm.complete_basis`'s completion LP above which the crossover first finishes
#: the identified basis (:func:`finish_from`: clamped multipliers, dual simplex, primal finish).
#: Issue 26, 2000-crack network i = 9 of ``bench_bounds_realizations.py``: 4 strongly active
#: rows of 2001, a 1997-row dense ``linprog`` of 93 s (202 s for the whole ``lam2`` LP), where
#: the identified basis is finished to the same certified optimum in 4.9 s.
COMPLETION_LP_MAX = 100
#: Gondzio's correctors of a second interior point where the crossover from the first (without
#: them) is not certified (0: none; then HiGHS answers).
RETRY_CORRECTORS = 2

__all__ = [
    "CERT_TOL", "FEAS_TOL", "PIVOT_TOL", "DenseAnswer", "Tableau", "batch_dual_simplex",
    "batch_residuals", "complete_basis", "identify_basis", "ipm", "kkt_residuals", "solve_max",
]


def _primal_finish(A, b, e, tab, cap=None):
    """The optimal basis by primal simplex (:class:`~.facet_walk.FacetWalk`) from a basis that
    is primal feasible but not dual feasible (a stalled interior point names the right face but
    a slightly wrong basis); ``None`` if the start is not a certified feasible vertex or the walk
    does not end at an optimum.  The caller certifies the answer again."""
    from .facet_walk import FacetWalk, certified_rows

    # the start's vertex checked first from the tableau's LU (what the walk would check after
    # forming and, on failure, re-forming B^-1: issue 26, a 2000-crack network's identified
    # basis violated rows and the walk spent 1.3 s finding out)
    tight = certified_rows(tab.A, tab.b, tab.x0, Gx=tab.act0)
    if tight is None or not tight[tab.T0].all():
        return None
    walk = FacetWalk(tab.A, tab.b, tab.T0)
    if not walk.ok or not walk.maximise(e, cap or max(60, tab.n)):
        return None
    out = Tableau(A, b, e, np.sort(walk.T), like=tab)
    return out if not out.singular and out.dual_feasible else None


def solve_max(A, b, e, *, max_iter=80, interior=False, why=None, accept=None, stop=None,
              correctors=0):
    """``max e.x s.t. A x <= b``: interior point, basis identification, dual simplex clean-up.

    Returns ``(answer, tableau)`` with the tableau of the optimal basis (for warm starts), or
    ``(None, None)`` when the interior point finds no usable iterate (unbounded or infeasible
    LP, or numerical trouble) or the crossover does not end certified: the caller then uses
    HiGHS.  ``interior=True``: where the crossover fails, ``(answer, None)`` with status
    ``"interior"``: the interior point's best iterate ``x`` and multipliers ``y`` (row scale
    of ``A``), not a vertex and not certified -- the caller checks what it needs (the
    Chebyshev centre: :func:`~.engine.chebyshev_centre`).  ``why``: a dict that, on failure,
    receives ``"reason"`` (a short text) and ``"basis"`` (the best basis at hand, the rows the
    interior point named, or ``None``) for the caller's fallback (:mod:`.dense_path`).
    ``accept``: a callable given the interior point's answer (as with ``interior=True``) before
    any crossover; what it returns, if not ``None``, is the answer (with tableau ``None``).  The
    Chebyshev centre (:func:`~.engine._interior_centre`) needs no vertex, and on a 2000-crack
    network (issue 26, ``rng=77``) its crossover completed a basis of 2 strongly active rows by
    a dense 1999 x 3999 ``linprog`` (:func:`~.ipm.complete_basis`) that ran for minutes.
    ``stop``: a callable given the same kind of answer at each iterate of the interior point
    (from merit :data:`~.ipm.APPROX_TOL` on); ``True`` ends the interior point there
    (:func:`~.ipm.ipm`), and ``accept`` then decides.  ``correctors``: Gondzio's centrality
    correctors of the interior point (:func:`~.ipm.ipm`; 0 where a vertex is wanted).
    """
    R, n = A.shape
    rn = np.linalg.norm(A, axis=1)
    rn[rn == 0] = 1.0
    As, bs = A / rn[:, None], b / rn
    early = None
    if stop is not None:
        def early(x, s, z):
            return stop(DenseAnswer("interior", x, z / rn, np.zeros(0, int), 0, (np.nan,) * 4))
    x, s, z, status, it = ipm(As, bs, e, max_iter=max_iter, stop=early, correctors=correctors)
    if why is None:
        why = {}
    if status == "failed":
        why.update(reason="interior point failed (unbounded, infeasible or stalled)", basis=None)
        return None, None
    if accept is not None:
        got = accept(DenseAnswer("interior", x, z / rn, np.zeros(0, int), it, (np.nan,) * 4))
        if got is not None:
            return got, None
    T = identify_basis(As, z, s, n)
    ans, tab = _crossover(A, b, e, T, As, s, z, it)
    if ans is None and not correctors and accept is None and stop is None and RETRY_CORRECTORS:
        # once more with centrality correctors: another stalled iterate, another basis (issue
        # 26, FE strip i = 19 at N = 2000: certified with them, to HiGHS without)
        x2, s2, z2, status2, it2 = ipm(As, bs, e, max_iter=max_iter, correctors=RETRY_CORRECTORS)
        if status2 != "failed":
            ans, tab = _crossover(A, b, e, identify_basis(As, z2, s2, n), As, s2, z2, it + it2)
    if ans is None:  # (the identified basis once: 33 s at N = 2000 before it was blocked)
        why.update(reason="crossover from the interior point not certified", basis=T)
    if ans is None and interior:
        ans = DenseAnswer("interior", x, z / rn, np.zeros(0, int), it, (np.nan,) * 4)
    return ans, tab


def _crossover(A, b, e, T, As, s, z, it):
    """An optimal basis from the interior point's iterate (``T``: the basis it identifies,
    :func:`~.ipm.identify_basis`), finished by the simplex and certified (:func:`solve_max`);
    ``(None, None)`` if that fails."""
    n = A.shape[1]
    tab = Tableau(A, b, e, T) if T is not None else None
    first = completed = tab
    if tab is not None and not tab.singular and not tab.dual_feasible:
        tab = _primal_finish(A, b, e, tab) or tab  # a few primal pivots from a feasible basis
    if tab is None or tab.singular or not tab.dual_feasible:
        missing = n - len(strongly_active(z, s, n))
        if first is not None and not first.singular and missing > COMPLETION_LP_MAX:
            # a completion LP nearly as large as the LP itself: the identified basis first
            ans, out = finish_from(A, b, e, Tableau(A, b, e, first.T0, like=first), it)
            if ans is not None:
                return ans, out
            first = None  # (tried)
        # degenerate optimum (fewer than n strongly active rows): complete the active set so
        # that the multipliers stay non-negative, then let the dual simplex finish
        T = complete_basis(As, z, s, e, n)
        if T is None:
            return finish_from(A, b, e, first, it)
        tab = completed = Tableau(A, b, e, T, like=first)
        ymax = max(float(np.abs(tab.y0).max()), np.finfo(float).tiny)
        if not tab.singular and tab.y0.min() >= -1e-6 * ymax:
            # multipliers that are zero up to the interior point's accuracy; the final
            # answer is certified again below, so this cannot pass a wrong optimum
            tab.y0 = np.maximum(tab.y0, 0.0)
    if tab is not None and not tab.singular and not tab.dual_feasible:
        tab = _primal_finish(A, b, e, tab)
    if tab is None or tab.singular or not tab.dual_feasible:
        return _finish_any(A, b, e, (completed, first), it)
    ans = batch_dual_simplex(tab, [()])[0]
    if ans.status != "optimal":
        return _finish_any(A, b, e, (completed, first), it)
    if ans.iterations:
        tab = Tableau(A, b, e, ans.basis, like=tab)
    out = _optimal_basis(A, b, e, ans, tab, ans.iterations + it)
    if out[0] is not None:
        return out
    # (no primal finish: the dual simplex's answer, certified to CERT_TOL, as before)
    return DenseAnswer(ans.status, ans.x, ans.y, ans.basis, ans.iterations + it, ans.residuals), tab


def _optimal_basis(A, b, e, ans, tab, pivots):
    """The dual simplex's answer ``ans`` (any status) on its final basis ``tab`` as a certified
    :class:`DenseAnswer` whose multipliers are non-negative to 1e-9 (``tab.dual_feasible``),
    else ``(None, None)``.

    The dual simplex certifies its final basis to ``CERT_TOL``; a multiplier between
    ``-CERT_TOL`` and ``-1e-9`` of the largest means a vertex that need not be optimal (issue
    26: HiGHS's ``lam2`` basis on an FE strip, ``-1.2e-8``; a random dense system ``N = 1000``,
    seed 5006, whose crossover ended at ``-8.2e-8`` with ``lam2`` ``2.6e-8`` below the optimum).
    Such a basis is finished by primal pivots (:func:`_primal_finish`) and certified again."""
    if tab.singular:
        return None, None
    if not tab.dual_feasible:
        tab = _primal_finish(A, b, e, tab)  # None unless a feasible vertex (FacetWalk checks)
        if tab is None:
            return None, None
        ans = batch_dual_simplex(tab, [()])[0]  # certify (0 pivots at an optimum)
        pivots += ans.iterations
        if ans.iterations:
            tab = Tableau(A, b, e, ans.basis, like=tab)
    if ans.status != "optimal" or tab.singular or not tab.dual_feasible:
        return None, None
    return DenseAnswer(ans.status, ans.x, ans.y, ans.basis, pivots, ans.residuals), tab


def _finish_any(A, b, e, starts, it):
    """:func:`finish_from` from each distinct start in turn (the completed basis of
    :func:`~.ipm.complete_basis` first, then the identified one); the first certified answer.

    Issue 26 (FE strip, 500 contact nodes, seed 5017): only 37 of 500 rows are strongly
    active at the ``lam2`` optimum (a large optimal face), :func:`~.ipm.identify_basis` finds
    no non-singular basis among the rest (their ``z / s`` all ``~2.7e-7``), the completed
    basis reaches a primal feasible vertex in 2 dual pivots but keeps a multiplier of
    ``-6.4e-7`` (of ``0.69``); formerly only the identified basis (here none) was finished, so
    the LP went to HiGHS.  From the completed basis the primal finish ends certified."""
    seen = set()
    for t in starts:
        if t is None or t.singular or tuple(t.T0) in seen:
            continue
        seen.add(tuple(t.T0))
        ans, tab = finish_from(A, b, e, Tableau(A, b, e, t.T0, like=t), it)  # (a fresh y0: clamped)
        if ans is not None:
            return ans, tab
    return None, None


def finish_from(A, b, e, tab, it=0):
    """An optimal basis from any non-singular start ``tab``: clamp the multipliers, dual
    simplex, primal finish (last resort of :func:`solve_max`; also HiGHS's basis in
    :mod:`.dense_path` when its multipliers are not non-negative to our tolerance).

    Issue 14: a 2000-crack network whose stalled interior point names a basis that is neither
    primal nor dual feasible.  Issue 26 (``sample_crack_set(2000, density=0.1, rng=77)``): the
    interior point stalls at merit ``~1e-7`` (the normal matrix's diagonal spans ``1e13`` to
    ``1e22``, the barely active rows' multipliers ``~1e-8`` against slacks ``~1e-4``), so the
    identified basis has 8 multipliers down to ``-5.8e-4`` of the largest and 12 violated rows.
    The negative multipliers are set to 0 (a cost perturbation: the start is dual feasible for
    a nearby objective), the dual simplex
    (:func:`~.single_simplex.single_dual_simplex`, which recomputes ``x`` and ``y`` of its
    final basis from scratch) reaches a primal feasible basis, and where that basis is not
    dual feasible for the true objective (there: 2 multipliers of ``-1.3e-7``) the primal
    simplex (:func:`_primal_finish`) ends at the optimum.  Formerly multipliers below
    ``-1e-4`` of the largest were refused and the primal finish was not tried after the dual
    simplex: the LP went to HiGHS and with it every LP of the computation (37 min instead of
    one).  The answer counts only if certified by its own optimality conditions, else
    ``(None, None)``."""
    from .single_simplex import single_dual_simplex

    if tab is None or tab.singular:
        return None, None
    tab.y0 = np.maximum(tab.y0, 0.0)  # (a start only: the answer is certified)
    ans = single_dual_simplex(tab)
    pivots = ans.iterations
    tab = Tableau(A, b, e, np.sort(ans.basis), like=tab)
    if tab.singular:
        return None, None
    # (also when the dual simplex certified its final basis to CERT_TOL with a multiplier
    # below -1e-9: HiGHS's basis of issue 26, -1.2e-8 of the largest, was refused here without
    # a primal pivot)
    return _optimal_basis(A, b, e, ans, tab, pivots + it)
