"""An FE interface kept uncondensed: the sparse stiffness ``K_z`` in the contact unknowns and the
interior DOFs, for many contact nodes (frame and signs: :mod:`shakedown.fe.condense`).

The condensed ``K`` of ``N`` contact nodes is dense: ``4 N^2`` numbers, and a dense trailing
factor when it is formed by the boundary-layer ordering (at ``N = 2000`` on a strip, 17 s and
2.3 GB).  :meth:`FEModel.uncondensed` assembles ``K_z`` only; its ``system`` is an
:class:`~shakedown.model.uncondensed.UncondensedSystem`, whose cyclic steps factorize each
node-state assignment together with the interior DOFs (sparse LU, ``O(nnz)`` memory).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model.errors import InputError
from .condensed import CondensedModel


@dataclass(frozen=True, repr=False)
class UncondensedModel(CondensedModel):
    """An FE model with ``K`` kept as the sparse ``K_z`` (see module doc).

    Same attributes and loads as :class:`CondensedModel` (``load_cycle``,
    ``welded_reactions``, ``displacements``, ``node_coordinates``, ...), except that ``K`` is
    ``None`` and ``system`` is an :class:`~shakedown.model.uncondensed.UncondensedSystem`
    (cyclic runs and bounds without the dense ``K``); ``condensed()`` forms the dense model
    when an analysis needs it (the dynamic stiffness of the stability checks: use
    ``FEModel.condense(mass=True)``).
    """

    @property
    def n_nodes(self) -> int:
        return int(self.node_coordinates.shape[0])

    @property
    def A(self):
        return self.system.A

    @property
    def B(self):
        return self.system.B

    @property
    def C(self):
        return self.system.C

    @property
    def system(self):
        """:class:`~shakedown.model.uncondensed.UncondensedSystem` with the model's friction."""
        return self._lazy["system"]

    def with_friction(self, friction):
        return self.system.with_friction(friction)

    def condensed(self) -> CondensedModel:
        """The dense :class:`CondensedModel` (``2N`` sparse solves in blocks; kept)."""
        if "condensed" not in self._lazy:
            K = self.system.K.toarray()
            K.setflags(write=False)
            cm = CondensedModel(
                model=self.model, K=K, M=None, node_coordinates=self.node_coordinates,
                normals=self.normals, tangents=self.tangents, node_body=self.node_body,
                node_index=self.node_index, node_kind=self.node_kind, welded=self.welded,
                from_cache=False, timings=dict(self.timings), counts=dict(self.counts),
                dim=self.dim)
            cm._lazy["assembled"] = self._lazy["assembled"]
            self._lazy["condensed"] = cm
        return self._lazy["condensed"]

    def dynamic_stiffness(self, s: float):
        raise InputError("dynamic_stiffness needs the condensed mass: use "
                         "model.condense(mass=True)")

    def _interior_solve(self):
        return self.system.K.solve_interior  # (no condensation's factor is formed)

    def _to_arrays(self) -> dict:  # pragma: no cover - not cached: assembling is cheap
        raise InputError("an uncondensed model is not cached")

    def __repr__(self) -> str:
        return (f"UncondensedModel(N={self.n_nodes}, interior_dofs="
                f"{self.counts['n_interior_dofs']}, nnz={self.system.nnz}, "
                f"cases={sorted(self.welded)})")


def uncondensed(asm) -> UncondensedModel:
    """The :class:`UncondensedModel` of an assembled model (:class:`.assembled.Assembled`)."""
    import time

    from ...model.uncondensed import UncondensedSystem

    t0 = time.perf_counter()
    extra = {"dim": 3} if asm.dim == 3 else {}
    system = UncondensedSystem(asm.Kz, asm.N, asm.model.friction, **extra)
    solve = system.K.solve_interior
    welded = {case: asm.welded(case, solve=solve) for case in asm.model.load_cases}
    um = UncondensedModel(
        model=asm.model, K=None, M=None, node_coordinates=asm.coords, normals=asm.normals,
        tangents=asm.tangents, node_body=np.array([nd[1] for nd in asm.nodes]),
        node_index=np.array([nd[2] for nd in asm.nodes]),
        node_kind=tuple(nd[0] for nd in asm.nodes), welded=welded, from_cache=False,
        timings={"assembly": asm.t_assembly, "factorization": time.perf_counter() - t0,
                 "condensation": 0.0},
        counts={"n_full_dofs": asm.n_full, "n_interior_dofs": asm.n_int,
                "n_contact_nodes": asm.N, "nnz_K_ii": int(asm.Kii.nnz)},
        dim=asm.dim,
    )
    um._lazy["assembled"] = asm
    um._lazy["system"] = system
    return um
