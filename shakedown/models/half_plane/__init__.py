"""Half-plane frictional contact (seed ``002`` s.4.2): discrete model and continuum reference."""

from .model import HalfPlaneModel, half_plane_model, profile_function, rigid_indenter_materials

__all__ = [
    "HalfPlaneModel",
    "half_plane_model",
    "profile_function",
    "rigid_indenter_materials",
]
