"""The cone engine: 3-D shakedown bounds on second-order friction cones (MODEL.md s.8.3).

Modules, in the order of the pipeline:

* :mod:`.data` -- the problem in cone units, nondimensional (``s = A v`` as unknowns; the
  coupling ``E = B^T A^-1 diag(f)``);
* :mod:`.separation` -- every node's exact worst time (roots of a trigonometric polynomial);
* :mod:`.socp` -- the relaxations on finite sets of cuts (Clarabel) and their dual bound;
* :mod:`.dual` -- the upper bound proven by multipliers of any accuracy (cones projected,
  residual polished and charged against an a-priori bound on the state);
* :mod:`.dense_ipm` -- the same relaxations by a dense interior point on the ``2N + 1`` normal
  equations (coupled systems; the default path), with :mod:`.ipm_split` (the Newton systems
  in a split augmented form, for brackets tighter than ``1e-7``);
* :mod:`.rounds` -- one relaxation by the dense path, checked, Clarabel where the check fails,
  and the record of which path answered each SOCP;
* :mod:`.melan` -- ``lam2`` by cutting planes with a certified bracket;
* :mod:`.certify` -- the certificates checked from scratch (safe state, dual bound);
* :mod:`.polygon` -- the polyhedral candidates ``lam_adj_cone`` / ``lam1_cone`` on inscribed
  ``k``-gons by the 2-D LP engine;
* :mod:`.engine`, :mod:`.result` -- :func:`~.engine.cone_bounds` (what
  :func:`shakedown.shakedown_bounds` calls for ``system.dim == 3``) and :class:`~.result.ConeBounds`.

May import :mod:`shakedown.model` and :mod:`shakedown.bounds` only.
"""
