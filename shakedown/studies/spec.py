"""The specification of the crack-network study (issue 4, issue 13; seed 002 s.4.1)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..model.errors import InputError

__all__ = ["SweepSpec", "SystemSource"]

_SOLVER_FIELDS = ("method", "steps_per_cycle", "max_cycles", "tol")
_SAMPLER_FIELDS = ("density", "half_length", "orientation", "min_spacing")
_MODEL_FIELDS = ("n_cracks", *_SAMPLER_FIELDS, "seed", "shear_modulus", "poisson_ratio",
                 "friction", "interaction_radius")


def _numbers(name: str, value) -> list[float]:
    """The entries of a list option as floats; :class:`InputError` naming ``name`` for text,
    booleans or nested objects (``[true, 1.0]`` would read as ``[1.0, 1.0]``)."""
    items = list(value) if isinstance(value, (list, tuple, np.ndarray)) else [value]
    out = []
    for x in items:
        if isinstance(x, (bool, np.bool_, str, bytes)) or not isinstance(
                x, (int, float, np.integer, np.floating)):
            raise InputError(f"{name!r} must be a list of numbers; got {type(x).__name__} "
                             f"{x!r} in {name} = {value!r}")
        try:
            out.append(float(x))
        except OverflowError:
            raise InputError(f"{name!r} holds an integer too large for a float") from None
    return out


@dataclass(frozen=True, eq=False)
class SystemSource:
    """One given system and load to sweep (any model: matrices, files, FE, half-plane, a crack
    set read from a file, 3-D kinds): the study's single realisation.

    Equal (and hashed) by ``name`` and a SHA-256 ``digest`` of every number of the system and
    the load, so that a store made with another model is refused on resume and the per-process
    caches key on the content.  ``W*`` is ``W`` itself for these models (no normalisation):
    ``[force x length]`` per cycle (``energy_unit``).

    Build with :meth:`of`.
    """

    name: str
    system: object
    load: object
    digest: str
    energy_unit: str = "[force x length]"

    @classmethod
    def of(cls, system, load, name: str = "model", energy_unit: str = "[force x length]"):
        """The source of ``system`` (a :class:`~shakedown.DiscreteSystem`) and ``load`` (a
        :class:`~shakedown.LoadCycle` with the same number of nodes)."""
        import hashlib

        import scipy.sparse as sp

        from ..model.loading import LoadCycle
        from ..model.system import DiscreteSystem

        if not isinstance(system, DiscreteSystem):
            raise InputError(f"system must be a DiscreteSystem; got {type(system).__name__}")
        if not isinstance(load, LoadCycle) or load.n_nodes != system.n_nodes:
            raise InputError(f"load must be a LoadCycle of {system.n_nodes} nodes; got {load!r}")
        h = hashlib.sha256()
        K = system.K
        for a in ((K.data, K.indices, K.indptr) if sp.issparse(K) else (K,)):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(np.ascontiguousarray(system.friction, float).tobytes())
        h.update(load.kind.encode())
        for key in ("q0", "p0", "q_cos", "q_sin", "p_cos", "p_sin", "q1", "p1"):
            a = getattr(load, key)
            if a is not None:
                h.update(key.encode() + np.ascontiguousarray(a, float).tobytes())
        return cls(str(name), system, load, h.hexdigest(), str(energy_unit))

    @property
    def n_nodes(self) -> int:
        return int(self.system.n_nodes)

    def normalised_dissipation(self, W, p0=None):
        """``W`` itself (these models have no crack-size normalisation)."""
        return W

    def __eq__(self, other):
        return (isinstance(other, SystemSource) and (self.name, self.digest)
                == (other.name, other.digest))

    def __hash__(self):
        return hash((self.name, self.digest))

    def to_dict(self) -> dict:
        return {"name": self.name, "digest": self.digest, "n_nodes": self.n_nodes}


@dataclass(frozen=True)
class SweepSpec:
    """The Monte Carlo crack-network study (issue 4; seed 002 section 4.1).

    Crack sets (one per realisation) are drawn by ``crack_networks.sample_crack_set`` and turned
    into a discrete system by ``crack_networks.kachanov_model``; the far field is
    ``S(t) = static + lam cyclic cos(2 pi t)`` (``(sxx, sxy, syy)``, tension positive).

    Parameters
    ----------
    n_cracks : int
    density, half_length, orientation, min_spacing
        Passed to ``sample_crack_set`` (``None``: its default; ``orientation="uniform"``:
        angles uniform in ``[0, pi)``).
    shear_modulus, poisson_ratio, friction : float
    interaction_radius : float, optional
        Truncate Kachanov's interaction to pairs closer than ``interaction_radius (a_i + a_j)``:
        each realisation's system is then sparse (``crack_networks.kachanov_model``; its error
        against the full interaction: ``benchmarks/RESULTS_kachanov_assembly.md``).
    static, cyclic : tuple of 3 floats
        Far-field stresses ``(sxx, sxy, syy)``; default the seed's ``S0 = p0 (-1, 0, -1)``,
        ``S1 = p0 (0, 1, 0)`` with ``p0 = 1``.
    n_realisations : int
    lams : "auto" or tuple of float
        Load factors.  ``"auto"``: chosen from each realisation's own bounds
        (:func:`shakedown.studies.design.lam_points`): ``n_lams`` points evenly spaced in
        ``lam / lam2`` over ``lam_span``, ``n_band`` inside ``(lam1, lam2)``, ``n_adj`` inside
        ``(lam_adj, lam1)``, then ``n_refine`` where min and max ``W*`` differ most and at the
        bracket of ``lam_u``.  A tuple: exactly these load factors for every realisation.
    n_lams, n_band, n_adj, n_refine : int
    lam_span : tuple of 2 floats
        Range of ``lam / lam2`` of the ``n_lams`` evenly spaced points.
    n_states : int
        Initial states per (realisation, lam) (:func:`shakedown.studies.design.initial_states`:
        zero, a safe state, the two uniform friction-limit corners, then random corners and
        random slips in a box of ``state_scale`` natural slip scales), the same states at every
        ``lam``.  The default 8 is chosen from the measured convergence of min and max with the
        number of states (``benchmarks/RESULTS_study.md``).
    state_scale : float
    seed : int
        Root of every random draw.
    method, steps_per_cycle, max_cycles, tol
        Passed to :func:`shakedown.solve_cycles`.
    stress_scale : float, optional
        ``p0`` of the normalisation of ``W*``; default ``max|static|`` (or ``max|cyclic|`` when
        the static stress is zero).
    source : SystemSource, optional
        Sweep this given system and load instead of drawing crack sets: one realisation, the
        crack-set and far-field fields unused, ``W* = W`` [force x length].  Load factors and
        initial states as above.
    """

    n_cracks: int = 100
    density: float | None = 0.1
    half_length: float | None = None
    orientation: str | float | None = None
    min_spacing: float | None = None
    shear_modulus: float = 1.0
    poisson_ratio: float = 0.25
    friction: float = 0.6
    interaction_radius: float | None = None
    static: tuple = (-1.0, 0.0, -1.0)
    cyclic: tuple = (0.0, 1.0, 0.0)
    n_realisations: int = 1
    lams: str | tuple = "auto"
    n_lams: int = 12
    lam_span: tuple = (0.5, 2.5)
    n_band: int = 5
    n_adj: int = 2
    n_refine: int = 2
    n_states: int = 8
    state_scale: float = 2.0
    seed: int = 0
    method: str = "implicit"
    steps_per_cycle: int = 64
    max_cycles: int = 200
    tol: float = 1e-10
    stress_scale: float | None = None
    source: SystemSource | None = None

    def __post_init__(self):
        def setv(name, value):
            object.__setattr__(self, name, value)

        if self.source is not None:
            if not isinstance(self.source, SystemSource):
                raise InputError(f"source must be a SystemSource (SystemSource.of(system, "
                                 f"load)); got {type(self.source).__name__}")
            if self.n_realisations != 1:
                raise InputError(f"n_realisations = {self.n_realisations}: a given system has "
                                 "one realisation; set n_realisations = 1 (only random crack "
                                 "networks draw several)")

        for name in ("static", "cyclic"):
            v = tuple(float(x) for x in np.ravel(getattr(self, name)))
            if len(v) != 3 or not np.all(np.isfinite(v)):
                raise InputError(f"{name} must be 3 finite stresses (sxx, sxy, syy); got {v}")
            setv(name, v)
        if not isinstance(self.lams, str):
            lams = tuple(_numbers("lams", self.lams))
            if not lams or not all(np.isfinite(x) and x >= 0 for x in lams):
                raise InputError(f"lams must be 'auto' or a list of load factors >= 0; got {lams}")
            setv("lams", lams)
        elif self.lams != "auto":
            raise InputError(f"lams must be 'auto' or a list of numbers; got {self.lams!r}")
        span = tuple(_numbers("lam_span", self.lam_span))
        if len(span) != 2 or not 0 <= span[0] < span[1] or not np.isfinite(span[1]):
            raise InputError(f"lam_span must be (low, high) with 0 <= low < high; got {span}")
        setv("lam_span", span)
        for name in ("half_length", "orientation"):
            if isinstance(getattr(self, name), list):
                setv(name, tuple(float(x) for x in getattr(self, name)))
        for name in ("n_cracks", "n_realisations", "n_lams", "n_states", "max_cycles",
                     "n_band", "n_adj", "n_refine"):
            v = getattr(self, name)
            low = 0 if name in ("n_band", "n_adj", "n_refine") else 1
            if not isinstance(v, int | np.integer) or isinstance(v, bool) or v < low:
                raise InputError(f"{name} must be an integer >= {low}; got {v!r}")
            setv(name, int(v))
        if self.method not in ("implicit", "events"):
            raise InputError(f"method must be 'implicit' or 'events'; got {self.method!r}")
        for name in ("shear_modulus", "state_scale"):
            if not float(getattr(self, name)) > 0:
                raise InputError(f"{name} must be > 0; got {getattr(self, name)!r}")
        r = self.interaction_radius
        if r is not None and (isinstance(r, bool) or not isinstance(r, int | float | np.floating)
                              or not np.isfinite(r) or not r > 0):
            raise InputError(f"interaction_radius must be a positive number of crack lengths "
                             f"(e.g. 12) or omitted; got {r!r}")
        if not max(map(abs, self.cyclic)) > 0:
            raise InputError("cyclic must not be zero: the study sweeps the cyclic load factor")

    @classmethod
    def from_scene(cls, model: dict, load: dict, options: dict | None = None) -> SweepSpec:
        """A spec from a scene's ``[model]`` (``kind = "crack_network"``, the keys of
        :mod:`shakedown.builders.crack_network`), ``[load]`` and ``[analyses.sweep]`` tables.

        The geometry and material keys are taken from ``[model]`` (``orientation_deg`` is
        converted to radians); the solver and sweep keys from ``options``.  A crack set read
        from a ``file``, the BEM model and per-crack friction are refused: the study draws
        random Kachanov networks.
        """
        model = {k: v for k, v in model.items() if k != "kind"}
        if "file" in model:
            raise InputError("[model] file: the sweep draws random crack sets (one per "
                             "realisation); give n_cracks, density, ... instead of a file")
        if model.get("method", "kachanov") != "kachanov":
            raise InputError(f"[model] method = {model['method']!r}: the sweep uses the "
                             "Kachanov model; remove the key or set it to 'kachanov'")
        if model.get("weighting", "uniform") != "uniform":
            raise InputError(f"[model] weighting = {model['weighting']!r}: the sweep uses "
                             "Kachanov's uniform averages; remove the key")
        if isinstance(model.get("friction"), list):
            raise InputError("[model] friction: the sweep needs one friction coefficient")
        kw = {k: model[k] for k in _MODEL_FIELDS if k in model}
        if "orientation_deg" in model:
            kw["orientation"] = np.radians(model["orientation_deg"]).tolist()
        for k in ("static", "cyclic"):
            if k in load:
                kw[k] = load[k]
        known = {f.name for f in fields(cls)} - set(_MODEL_FIELDS)
        for k, v in (options or {}).items():
            if k in known and v is not None:
                kw[k] = v
        return cls(**kw)

    @property
    def p0(self) -> float:
        """The stress scale of ``W*``."""
        if self.stress_scale is not None:
            return float(self.stress_scale)
        return max(map(abs, self.static)) or max(map(abs, self.cyclic))

    def solver_options(self) -> dict:
        return {k: getattr(self, k) for k in _SOLVER_FIELDS}

    @property
    def node_word(self) -> str:
        """What a node is in words: "crack" for the crack study, "node" otherwise."""
        return "node" if self.source is not None else "crack"

    @property
    def dissipation_name(self) -> str:
        """``"W*"`` (normalised, crack study) or ``"W"`` (a given system, with its unit)."""
        return "W" if self.source is not None else "W*"

    def describe(self) -> str:
        """The swept model in words, e.g. ``"1 realisation of 100 cracks, friction 0.6"`` or
        ``"the model 'two_node_coupled' (2 nodes)"``."""
        if self.source is not None:
            n = self.source.n_nodes
            return f"the model {self.source.name!r} ({n} node{'s' * (n != 1)})"
        r = self.n_realisations
        return (f"{r} realisation{'s' * (r != 1)} of {self.n_cracks} cracks, friction "
                f"{self.friction}")

    def to_dict(self) -> dict:
        d = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "source"}
        d = {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}
        if self.source is not None:  # absent for the crack study: its stores stay readable
            d["source"] = self.source.to_dict()
        return d
