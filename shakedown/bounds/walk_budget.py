"""Walk or LP: which of the two decides the pruning's rows for fewer pivots (issue 26).

The pruning (:mod:`.pruning`) decides each row ``k`` (``lam_high_k >= t`` at the incumbent
``t``) by a walk over the vertices of ``H(t)`` towards it (:data:`~.pruning.WALK_CAP` pivots,
then :data:`~.pruning.LONG_WALK_CAP` more), or, where the walk does not decide it, by an exact
LP (:meth:`~.basis_lp.BasisLP.race`).  Which is cheaper depends on the problem:

* 2000-crack network i = 2 of ``benchmarks/bench_bounds_realizations.py``: 92 % of the walks
  reach their row, ~14 pivots each; an exact LP takes 2500-4700 pivots.  Walking is right.
* Random dense system i = 5 (``lam1`` 0.12 % below ``lam2``): 10 % of the walks reach their
  row; 1696 of them stop undecided after 60 pivots, 1693 of those go on for up to 400 more, and
  the exact LPs take ~100 pivots each.  The walks were 183 of the stage's 211 s CPU.

:class:`WalkBudget` counts, for the short walks, the long walks and the LPs separately, the
pivots spent and the rows they decided (rows proven ``lam_high >= t`` or solved exactly, at the
``t`` of the moment), and says a walk is worth trying while its pivots per decided row are at
most those of the LPs (an LP pivot weighted :data:`LP_PIVOT_WEIGHT` of a walk pivot).  The
counts are pivots, not seconds: the decisions, and with them every lower bound the pruning
returns, do not depend on the machine or its load.  Once the LPs turn out dearer than the walks
again, walking resumes.  Nothing is concluded from the counts: they only choose who decides a
row, and every decision is certified as before.
"""

from __future__ import annotations

#: The cost of one dual simplex pivot of an exact LP, in pivots of a walk (a walk pivot also
#: checks its new vertices in ``v``): 2000-crack network i = 2, 3.2 ms against 1.2-1.8 ms;
#: dense system i = 5, 0.45 ms against 0.22 ms.
LP_PIVOT_WEIGHT = 0.5
#: Walk attempts of a kind, and rows decided by LPs, before the counts are trusted (until then
#: walks are tried, as before).
MIN_WALKS = 32
MIN_LP_ROWS = 8


class WalkBudget:
    """Pivots spent and rows decided, per way of deciding rows (module docstring)."""

    def __init__(self):
        self.walks = {"short": [0, 0, 0], "long": [0, 0, 0]}  # [attempts, pivots, rows]
        self.lps = [0, 0]  # [pivots, rows]

    def walked(self, kind: str, pivots: int, rows: int) -> None:
        """One walk of ``kind`` (``"short"`` or ``"long"``) took ``pivots`` and decided
        ``rows`` rows."""
        w = self.walks[kind]
        w[0] += 1
        w[1] += int(pivots)
        w[2] += max(int(rows), 0)

    def solved(self, pivots: int, rows: int) -> None:
        """LPs took ``pivots`` (their dual simplex pivots) and decided ``rows`` rows."""
        self.lps[0] += int(pivots)
        self.lps[1] += max(int(rows), 0)

    def worth(self, kind: str) -> bool:
        """Whether a walk of ``kind`` is worth trying: ``True`` until :data:`MIN_WALKS` such
        walks and :data:`MIN_LP_ROWS` rows decided by LPs are counted; then whether its
        pivots per decided row are at most :data:`LP_PIVOT_WEIGHT` times the LPs'."""
        attempts, pivots, rows = self.walks[kind]
        lp_pivots, lp_rows = self.lps
        if attempts < MIN_WALKS or lp_rows < MIN_LP_ROWS:
            return True
        return pivots * lp_rows <= LP_PIVOT_WEIGHT * lp_pivots * rows
