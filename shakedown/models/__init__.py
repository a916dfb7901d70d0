"""Builders of discrete frictional systems from continuum models (half-plane contact, ...)."""
