"""Builders of systems: :mod:`.fe` (scikit-fem static condensation onto contact nodes).

Each builder returns :class:`shakedown.DiscreteSystem` and :class:`shakedown.LoadCycle` objects.
May import :mod:`shakedown.model` only; the crack-network models live in the top-level package
:mod:`crack_networks`.
"""
