"""Studies over many runs: Monte Carlo sweeps over realisations x load factors x initial
states (:mod:`.sweep`) and their resumable result store with local or Dask workers
(:mod:`.store`).

May import :mod:`shakedown.model`, :mod:`shakedown.bounds`, :mod:`shakedown.evolution`,
:mod:`shakedown.stability` and :mod:`shakedown.plotting`.
"""
