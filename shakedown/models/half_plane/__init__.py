"""Half-plane frictional contact (seed ``002`` s.4.2): discrete model and continuum reference.

Imports :mod:`shakedown.model` only.  Experiments (loading paths ``OA``, the ``beta`` study) are in
:mod:`shakedown.studies.half_plane`, pictures in :mod:`shakedown.plotting.half_plane`, the scene
kind ``"half_plane"`` in :mod:`shakedown.scenes.builders.half_plane`.
"""

from .model import HalfPlaneModel, half_plane_model, profile_function, rigid_indenter_materials

__all__ = [
    "HalfPlaneModel",
    "half_plane_model",
    "profile_function",
    "rigid_indenter_materials",
]
