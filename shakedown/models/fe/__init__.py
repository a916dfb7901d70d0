"""Finite-element models condensed onto their contact nodes (MODEL.md s.6), with scikit-fem.

Pipeline: mesh (:func:`rectangle`, :func:`trapezoid`, :func:`polygon`, :func:`from_file`; in
3-D :func:`box`, :func:`extrude` or a Gmsh file of tetrahedra or hexahedra) + material
(:func:`isotropic`, :func:`transversely_isotropic`; ``plane="3d"`` for 3-D) -> :class:`FEModel` (held,
contact, interface and periodic boundaries; load cases) -> :meth:`FEModel.condense` ->
:class:`CondensedModel` (``.system`` a :class:`shakedown.DiscreteSystem`, ``.load_cycle``,
``.M``, ``.dynamic_stiffness``).  Frame and sign conventions: :mod:`shakedown.fe.condense`.
"""

from .analytic import layer_uniform_stiffness
from .assembled import tangent_frames
from .assembly import Body, BodyForce, Displacement, Pressure, Traction
from .condense import FEModel
from .condensed import CondensedModel
from .materials import Material, isotropic, rotate_voigt, transversely_isotropic
from .meshes import ELEMENTS, PATTERNS, FEMesh, from_file, rectangle, trapezoid
from .meshes3d import box, extrude
from .polygons import polygon
from .uncondensed import UncondensedModel

__all__ = [
    "layer_uniform_stiffness",
    "Body", "BodyForce", "Displacement", "Pressure", "Traction",
    "CondensedModel", "FEModel", "UncondensedModel",
    "Material", "isotropic", "transversely_isotropic", "rotate_voigt",
    "ELEMENTS", "PATTERNS", "FEMesh", "from_file", "polygon", "rectangle", "trapezoid",
    "box", "extrude", "tangent_frames",
]
