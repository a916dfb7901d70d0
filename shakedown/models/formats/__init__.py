"""Bring your own model: stiffness matrices, full FE stiffness exports and load records.

* :func:`read_matrix`, :func:`read_vector`: Matrix Market ``.mtx``, MATLAB ``.mat``, ``.npz``,
  CSV (:mod:`.readers`);
* :func:`condense_stiffness`: a full stiffness with named contact DOFs (Abaqus, ANSYS,
  Code_Aster exports) condensed onto the contact nodes, with its sign conventions
  (:mod:`.stiffness`); :func:`uncondensed_stiffness` keeps it sparse instead (many contact
  nodes);
* :func:`read_load_record`: a measured load history (CSV, any sampling) resampled to one period
  with a stated error (:mod:`.records`).

Gmsh meshes are read by :func:`shakedown.fe.from_file` (meshio; physical groups name the
boundaries).  The scene builders ``matrices`` and ``fe`` use these readers
(:mod:`shakedown.scenes.builders`).
"""

from .readers import SUFFIXES, ModelFileError, read_matrix, read_vector
from .records import RecordFit, read_load_record
from .stiffness import (
    CondensedStiffness,
    UncondensedStiffness,
    condense_stiffness,
    uncondensed_stiffness,
)

__all__ = ["SUFFIXES", "ModelFileError", "read_matrix", "read_vector", "RecordFit",
           "read_load_record", "CondensedStiffness", "condense_stiffness",
           "UncondensedStiffness", "uncondensed_stiffness"]
