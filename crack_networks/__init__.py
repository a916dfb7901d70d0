"""crack_networks: random 2-D crack sets and their frictional interaction (MODEL.md s.6).

``CrackSet`` / ``sample_crack_set`` build the geometry; ``kachanov_model`` turns it into a
:class:`shakedown.DiscreteSystem` with one node per crack (Kachanov 1987); ``bem_model`` is a
higher-fidelity displacement-discontinuity model of the same network, condensed to the same
kind of system, to measure Kachanov's error.

Examples
--------
>>> import crack_networks as cn
>>> cracks = cn.sample_crack_set(20, density=0.05, rng=7)
>>> model = cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
>>> model.system.n_nodes
20
"""

from .bem import BEMModel, bem_model
from .cracks import (
    KACHANOV_GAP_RATIO,
    TOUCH_RTOL,
    CrackSet,
    KachanovAccuracyWarning,
    load_csv,
    save_csv,
    segment_distance,
)
from .fields import crack_stress, isolated_compliance, segment_average_traction
from .kachanov import (
    Asymmetry,
    CrackNetworkModel,
    KachanovModel,
    far_field_tractions,
    kachanov_model,
    kachanov_stiffness,
    transmission_factors,
)
from .sampling import sample_crack_set

__all__ = [
    "KachanovAccuracyWarning",
    "KACHANOV_GAP_RATIO",
    "TOUCH_RTOL",
    "CrackSet",
    "sample_crack_set",
    "load_csv",
    "save_csv",
    "segment_distance",
    "crack_stress",
    "segment_average_traction",
    "isolated_compliance",
    "transmission_factors",
    "far_field_tractions",
    "kachanov_model",
    "kachanov_stiffness",
    "KachanovModel",
    "CrackNetworkModel",
    "Asymmetry",
    "bem_model",
    "BEMModel",
]
