"""Node classification of an equilibrium or a snapshot (MODEL.md s.5).

Every contact node is

* ``free``: open, gap ``w > 0`` (its reactions vanish);
* ``stick``: closed, ``abs(q) < f p``;
* ``slip``: closed and in *impending slip*, ``abs(q) = f p > 0``, with the direction
  ``chi = -sign(q)`` in which it would slip (MODEL.md s.1: forward slip needs ``q = -f p``);
* ``frictionless``: closed with ``f = 0`` (``q = 0``): it slides freely both ways, so its
  tangential reaction stays zero and its tangential DOF is condensed out like a free node's.

The decision uses explicit tolerances; nodes close to a threshold are reported as
*borderline* with the reason, so that the user can see whether the partition (and hence the
eigenvalue check) is sensitive to the tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import InputError, ShapeError
from ..model.validation import check_count, real_array, require_two_dimensional

FREE, STICK, SLIP, FRICTIONLESS = "free", "stick", "slip", "frictionless"
STATES = (FREE, STICK, SLIP, FRICTIONLESS)

#: Default relative tolerance of the classification: a closed node is in impending slip when
#: ``f p - abs(q) <= CLASSIFY_RTOL * force_scale`` (``force_scale = max(p, abs(q))`` over the
#: nodes).  Reactions from an LCP/LP solver are accurate to ~1e-9 relative; 1e-7 leaves room.
CLASSIFY_RTOL = 1e-7


@dataclass(frozen=True, eq=False)
class NodePartition:
    """Partition of the contact nodes into free / stick / slip / frictionless.

    Attributes
    ----------
    states : ndarray of str, shape (N,)
        One of ``"free"``, ``"stick"``, ``"slip"``, ``"frictionless"`` per node.
    chi : ndarray, shape (N,)
        Slip direction ``-sign(q)`` (``+1`` forward, ``-1`` backward) at ``slip`` nodes, 0
        elsewhere.
    margin : ndarray, shape (N,)
        Relative distance to the neighbouring state: ``(f p - abs(q)) / force_scale`` for
        closed nodes, ``w / gap_scale`` for free nodes (``nan`` when built by hand).
    borderline : ndarray of int
        Nodes whose state is within ``borderline_rtol`` of another state.
    borderline_reasons : tuple of str
        One reason per borderline node.
    """

    states: np.ndarray
    chi: np.ndarray
    margin: np.ndarray
    borderline: np.ndarray
    borderline_reasons: tuple = ()

    def __post_init__(self):
        states = np.asarray(self.states, dtype=object)
        if states.ndim != 1:
            raise ShapeError(f"states must be 1-D (N,); got shape {states.shape}")
        bad = [s for s in states if s not in STATES]
        if bad:
            raise InputError(f"states must be in {STATES}; got {bad[0]!r}")
        chi = real_array("chi", self.chi)
        if chi.shape != states.shape:
            raise ShapeError(f"chi must have shape {states.shape}; got {chi.shape}")
        slip = states == SLIP
        if np.any(np.abs(chi[slip]) != 1.0):
            j = int(np.flatnonzero(slip & (np.abs(chi) != 1.0))[0])
            raise InputError(f"chi must be +1 or -1 at slip nodes; node {j + 1} has chi = {chi[j]}")
        chi = np.where(slip, chi, 0.0)
        margin = real_array("margin", self.margin)
        if margin.shape not in ((), states.shape):
            raise ShapeError(f"margin must be a number or have shape {states.shape}")
        margin = np.broadcast_to(margin, states.shape).copy()
        for name, arr in (("states", states), ("chi", chi), ("margin", margin)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        bl = np.asarray(self.borderline, dtype=int).reshape(-1)
        bl.setflags(write=False)
        object.__setattr__(self, "borderline", bl)
        object.__setattr__(self, "borderline_reasons", tuple(self.borderline_reasons))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_states(cls, states, chi=None) -> NodePartition:
        """A hand-made partition, e.g. ``from_states(["slip"] * 11, chi=-1)``.

        ``chi`` (scalar or shape (N,)) is required when some node slips.
        """
        states = np.asarray(states, dtype=object)
        if states.ndim != 1 or states.shape[0] == 0:
            raise ShapeError(f"states must be a non-empty list of node states; got {states!r}")
        n = states.shape[0]
        if chi is None:
            if np.any(states == SLIP):
                raise InputError("chi is required when some node is in impending slip")
            chi = np.zeros(n)
        chi = real_array("chi", chi)
        if chi.shape not in ((), (n,)):
            raise ShapeError(f"chi must be a number or have shape ({n},); got {chi.shape}")
        chi = np.broadcast_to(chi, (n,))
        return cls(states, chi, np.full(n, np.nan), np.zeros(0, int), ())

    @classmethod
    def all_slip(cls, n_nodes: int, chi=1.0) -> NodePartition:
        """Every node in impending slip in direction ``chi`` (seed 000 s.7.1)."""
        return cls.from_states([SLIP] * check_count("n_nodes", n_nodes, 1), chi)

    # ------------------------------------------------------------------ views
    @property
    def n_nodes(self) -> int:
        return self.states.shape[0]

    def nodes(self, state: str) -> np.ndarray:
        """Indices of the nodes in ``state``."""
        return np.flatnonzero(self.states == state)

    @property
    def slip(self) -> np.ndarray:
        return self.nodes(SLIP)

    @property
    def stick(self) -> np.ndarray:
        return self.nodes(STICK)

    @property
    def free(self) -> np.ndarray:
        return self.nodes(FREE)

    @property
    def frictionless(self) -> np.ndarray:
        return self.nodes(FRICTIONLESS)

    def key(self) -> tuple:
        """Hashable key (states and directions) to detect partition changes."""
        return tuple(zip(self.states.tolist(), self.chi.astype(int).tolist(), strict=True))

    def counts(self) -> dict:
        return {s: int(np.sum(self.states == s)) for s in STATES}

    def table(self):
        """A ``pandas.DataFrame`` with one row per node: state, chi, margin, borderline."""
        import pandas as pd

        reason = dict(zip(self.borderline.tolist(), self.borderline_reasons, strict=True))
        return pd.DataFrame(
            {
                "node": np.arange(self.n_nodes),
                "state": self.states.astype(str),
                "chi": self.chi.astype(int),
                "margin": self.margin,
                "borderline": [reason.get(j, "") for j in range(self.n_nodes)],
            }
        )

    def __repr__(self) -> str:
        c = self.counts()
        return (
            f"NodePartition(free={c[FREE]}, stick={c[STICK]}, slip={c[SLIP]}, "
            f"frictionless={c[FRICTIONLESS]}, borderline={self.borderline.size})"
        )


def _vector(name, value, n=None):
    arr = real_array(name, value)
    if arr.ndim == 0 and n is not None:
        arr = np.full(n, float(arr))
    if arr.ndim != 1 or (n is not None and arr.shape[0] != n):
        want = f"({n},)" if n is not None else "(N,)"
        raise ShapeError(f"{name} must have shape {want}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite")
    return arr


def classify_nodes(
    gap,
    q,
    p,
    friction,
    *,
    rtol: float = CLASSIFY_RTOL,
    gap_atol: float | None = None,
    borderline_rtol: float = 1e-3,
) -> NodePartition:
    """Classify contact nodes from gaps and reactions (MODEL.md s.5).

    Parameters
    ----------
    gap : array_like, shape (N,)
        Gaps ``w >= 0`` [length].
    q, p : array_like, shape (N,)
        Tangential and normal reactions [force], compression positive.
    friction : float or array_like, shape (N,)
        Friction coefficients ``f >= 0``.
    rtol : float
        Relative tolerance of ``abs(q) = f p`` and of ``p = 0``, relative to
        ``force_scale = max_j max(p_j, abs(q_j))``.
    gap_atol : float, optional
        A node is free when ``w > gap_atol`` [length].  Default: ``rtol`` times the largest
        gap (exact zeros are closed).
    borderline_rtol : float
        Nodes within this relative distance of another state are reported as borderline
        (a closed node with ``p <= borderline_rtol * force_scale`` is *grazing*; it is
        classified free when its reactions vanish within ``rtol``).

    Returns
    -------
    NodePartition
    """
    w = _vector("gap", gap)
    n = w.shape[0]
    q = _vector("q", q, n)
    p = _vector("p", p, n)
    f = _vector("friction", friction, n)
    if np.any(f < 0):
        raise InputError(f"friction must be >= 0; got min {f.min()}")
    if not (0 < rtol < 1):
        raise InputError(f"rtol must be in (0, 1); got {rtol}")
    force_scale = max(float(np.max(np.abs(p), initial=0.0)), float(np.max(np.abs(q), initial=0)))
    force_scale = max(force_scale, np.finfo(float).tiny)
    gap_scale = max(float(np.max(w, initial=0.0)), np.finfo(float).tiny)
    if gap_atol is None:
        gap_atol = rtol * gap_scale if np.any(w > 0) else 0.0
    ftol = rtol * force_scale
    states = np.empty(n, dtype=object)
    chi = np.zeros(n)
    margin = np.zeros(n)
    bl, reasons = [], []
    for j in range(n):
        cone = f[j] * p[j] - abs(q[j])
        if w[j] > gap_atol or (abs(p[j]) <= ftol and abs(q[j]) <= ftol):
            states[j] = FREE
            margin[j] = w[j] / gap_scale
            if w[j] <= max(borderline_rtol * gap_scale, gap_atol):
                bl.append(j)
                reasons.append(f"grazing: gap {w[j]:.3g}, p {p[j]:.3g}, q {q[j]:.3g}")
            continue
        margin[j] = cone / force_scale
        if f[j] == 0.0:
            states[j] = FRICTIONLESS
        elif cone <= ftol:
            if p[j] <= ftol:
                raise InputError(
                    f"node {j + 1} is closed with p = {p[j]:.6g} <= 0 and q = {q[j]:.6g}: not an "
                    "admissible contact state; pass reactions with compression positive"
                )
            states[j] = SLIP
            chi[j] = -1.0 if q[j] > 0 else 1.0
            if cone < -ftol:
                bl.append(j)
                reasons.append(f"outside the cone: abs(q) - f p = {-cone:.3g}")
        else:
            states[j] = STICK
            if cone <= borderline_rtol * force_scale:
                bl.append(j)
                reasons.append(f"stick close to slip: (f p - abs(q)) / scale = {margin[j]:.3g}")
        if states[j] != FREE and p[j] <= borderline_rtol * force_scale:
            bl.append(j)
            reasons.append(f"nearly unloaded: p / scale = {p[j] / force_scale:.3g}")
    return NodePartition(states, chi, margin, np.array(bl, int), tuple(reasons))


def classify_state(system, slip, gap, q_w, p_w, **kwargs) -> NodePartition:
    """Classify a state ``(v, w)`` of a :class:`~shakedown.DiscreteSystem` under welded
    reactions ``(q_w, p_w)`` (reactions from MODEL.md s.1).  Keywords as :func:`classify_nodes`.
    """
    require_two_dimensional(system, "classify_state")
    q, p = system.reactions(slip, gap, q_w, p_w)
    return classify_nodes(gap, q, p, system.friction, **kwargs)
