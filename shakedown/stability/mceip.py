"""MCEIP-mu: the critical friction of a node partition and its mode (MODEL.md s.5).

Find the smallest ``mu* > 0`` with ``x >= 0, x != 0, y = (K0 + mu K1) x >= 0, x . y = 0``
(quasi-static bifurcation; seed 000 s.5, seed 001 eqs. (6)-(10)).  Methods:

``"enumeration"``
    every support of ``x`` (exact, certified minimal; ``n <= max_enumeration``).
``"linear"`` / ``"linear-dense"`` / ``"linear-arpack"``
    the linear eigenproblem ``K0 x = -mu K1 x``; a one-signed eigenvector is a full-support
    solution (ARPACK for ``n > 200`` with ``"linear"``).
``"power"``
    the nonlinear power iteration of seed 000 s.6 (one bound-constrained QP per step).
``"active-set"``
    support updates from the full set (drop nodes that would slip backwards, add nodes
    pushed out of their cone).
``"auto"``
    enumeration for small slip sets, else linear, then power, then active set; the first
    verified answer is returned.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model import citations
from ..model.errors import InputError
from .classify import NodePartition
from .enumerate import MAX_ENUMERATION_NODES, enumerate_solutions, enumeration
from .linear import active_set, linear_arpack, linear_dense
from .pencil import SlipPencil, slip_pencil
from .power import power_iteration
from .result import VERIFY_TOL, MCEIPResult

METHODS = ("auto", "enumeration", "linear", "linear-dense", "linear-arpack", "power",
           "active-set")

#: ``"linear"`` switches from the dense QZ solve to ARPACK above this many slip nodes.
ARPACK_MIN_NODES = 200


def _pencil(stiffness, partition, lam, friction_profile, mass) -> SlipPencil:
    if isinstance(stiffness, SlipPencil):
        if partition is not None:
            raise InputError("pass either a SlipPencil or (stiffness, partition), not both")
        return stiffness
    if partition is None:
        raise InputError(
            "partition is required with a stiffness: build one with classify_nodes(...) or "
            "NodePartition.all_slip(n, chi)"
        )
    return slip_pencil(stiffness, partition, lam=lam, friction_profile=friction_profile,
                       mass=mass)


def mceip_mu(
    stiffness,
    partition: NodePartition | None = None,
    *,
    method: str = "auto",
    lam: float = 0.0,
    friction_profile=None,
    mass=None,
    max_enumeration: int = MAX_ENUMERATION_NODES,
    tol: float = VERIFY_TOL,
    **options,
) -> MCEIPResult:
    """Critical friction ``mu*`` and mode of a node partition (MCEIP-mu).

    Parameters
    ----------
    stiffness
        A :class:`SlipPencil`, or a DiscreteSystem / array ``K`` (2N, 2N) / condensed FE model
        / callable ``s -> K(s)`` together with ``partition``.
    partition : NodePartition
        Node states and slip directions (see :func:`classify_nodes`).
    method : str
        One of ``METHODS`` (see the module docstring).
    lam : float
        Growth rate at which ``K(lam^2)`` is taken (0: quasi-static MCEIP-mu).
    friction_profile : array_like, shape (N,), optional
        Relative friction per node: node ``j`` has friction ``mu * profile_j``.
    mass : array_like, optional
        Contact-DOF mass for ``K + lam^2 M`` (only with an array / system ``stiffness``).
    max_enumeration : int
        ``"auto"`` enumerates supports up to this many slip nodes.
    tol : float
        Verification tolerance (relative residuals).
    **options
        Passed to the method (``g0``, ``maxiter``, ``rng``, ``polish`` for ``"power"``;
        ``k`` for ``"linear-arpack"``; ``support`` for ``"active-set"``).

    Returns
    -------
    MCEIPResult
        ``status == "found"`` with a verified mode, or ``"none"`` / ``"not-converged"``.

    Examples
    --------
    >>> import numpy as np
    >>> from shakedown.stability import NodePartition, mceip_mu
    >>> K = np.array([[2.0, 1.0], [1.0, 3.0]])   # one node: A = 2, B = 1, C = 3
    >>> r = mceip_mu(K, NodePartition.all_slip(1, chi=-1.0))
    >>> round(r.mu, 12), r.status            # mu* = A / |B| with chi = -sign(B)
    (2.0, 'found')
    """
    citations.register("agwa2007")
    if method not in METHODS:
        raise InputError(f"method must be one of {METHODS}; got {method!r}")
    pen = _pencil(stiffness, partition, lam, friction_profile, mass)
    n = pen.size
    if method == "enumeration":
        return enumeration(pen, tol=tol, max_nodes=options.get("max_nodes", max(16, n)))
    if method == "linear-dense":
        return linear_dense(pen, tol=tol)
    if method in ("linear-arpack", "linear"):
        if method == "linear" and n <= ARPACK_MIN_NODES:
            return linear_dense(pen, tol=tol)
        return linear_arpack(pen, tol=tol, **options)
    if method == "power":
        return power_iteration(pen, verify_tol=tol, **options)
    if method == "active-set":
        return active_set(pen, tol=tol, **options)
    # auto
    if n <= max_enumeration:
        return enumeration(pen, tol=tol, max_nodes=max_enumeration)
    tried = []
    for fn in (
        lambda: linear_dense(pen, tol=tol) if n <= ARPACK_MIN_NODES else linear_arpack(pen, tol=tol),
        lambda: power_iteration(pen, verify_tol=tol, **options),
        lambda: active_set(pen, tol=tol),
    ):
        res = fn()
        if res.found:
            if tried:
                res = replace(res, message=res.message + "; before: " + "; ".join(tried))
            return res
        tried.append(f"{res.method}: {res.message}")
    return replace(res, method="auto", message="; ".join(tried))


def mceip_mu_all(
    stiffness,
    partition: NodePartition | None = None,
    *,
    lam: float = 0.0,
    friction_profile=None,
    mass=None,
    max_enumeration: int = MAX_ENUMERATION_NODES,
    tol: float = VERIFY_TOL,
    n_starts: int = 4,
    rng=None,
) -> list[MCEIPResult]:
    """All MCEIP solutions found (every branch), sorted by ``mu``.

    Exact (every support) for ``n <= max_enumeration``; otherwise the union of the linear
    (full-support) solutions, the active-set solution and power iterations from ``n_starts``
    starts (the first from ones, the others random from ``rng``), duplicates removed.
    """
    pen = _pencil(stiffness, partition, lam, friction_profile, mass)
    if pen.size <= max_enumeration:
        return enumerate_solutions(pen, tol=tol, max_nodes=max_enumeration)
    from .linear import restricted_eigenpairs
    from .result import make_result

    sols = []
    for mu, x, pos in restricted_eigenpairs(pen.K0, pen.K1):
        if pos:
            r = make_result(pen, mu, np.clip(x, 0, None), method="linear-dense", tol=tol)
            if r.verified:
                sols.append(r)
    sols.append(active_set(pen, tol=tol))
    gen = np.random.default_rng(rng)
    for k in range(n_starts):
        g0 = None if k == 0 else gen.uniform(0, 1, pen.size)
        sols.append(power_iteration(pen, g0=g0, verify_tol=tol))
    out = []
    for r in sorted((r for r in sols if r.found), key=lambda r: r.mu):
        if not any(abs(r.mu - o.mu) <= 1e-8 * o.mu and np.array_equal(r.support, o.support)
                   for o in out):
            out.append(r)
    return out
