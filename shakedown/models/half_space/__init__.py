"""Half-space frictional contact (MODEL.md s.8.5): sphere on flat and kin, 3-D discrete model.

Imports :mod:`shakedown.model` (and the material checks of the half-plane model) only.
:mod:`.influence`: closed-form cell influence coefficients; :mod:`.operators`: the compliance as
an FFT convolution; :mod:`.model`: :func:`half_space_model`; :mod:`.continuum`: Hertz,
Cattaneo-Mindlin and Mindlin-Deresiewicz; :mod:`.normal`: a frictionless normal solver
(Polonsky-Keer); :mod:`.tangential`: the tangential step by FISTA with FFT products;
:mod:`.matrix_free`: matrix-free steps and cycles (similar or dissimilar materials, constant or
varying ``P``; large grids); :mod:`.bounds`: Melan's ``lam2`` of a fretting load on similar
materials per node, matrix-free.
"""

from .model import DENSE_MAX_CELLS, HalfSpaceModel, gap_function, half_space_model

__all__ = ["DENSE_MAX_CELLS", "HalfSpaceModel", "gap_function", "half_space_model"]
