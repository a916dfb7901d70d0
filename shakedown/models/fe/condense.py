r"""Static condensation of FE models onto their contact nodes (MODEL.md s.1, s.6).

Frame and signs
---------------
Every contact node ``j`` has the outward unit normal ``n_j`` of the body and the tangent
``t_j = (-n_y, n_x)`` (the boundary run counter-clockwise, seed 000 s.2): on a bottom side
``n = (0, -1)``, ``t = (+1, 0)``; on a top side ``n = (0, 1)``, ``t = (-1, 0)``; on a left side
``t = (0, -1)``; on a right side ``t = (0, +1)``.  With the node's displacement ``u_j``:

- slip ``v_j = t_j . u_j``; gap ``w_j = -n_j . u_j`` (opening: the node moves *away from the
  obstacle*, i.e. into the body, along ``-n``);
- the reaction ``R_j`` exerted by the obstacle on the body: ``q_j = t_j . R_j`` and
  ``p_j = -n_j . R_j`` (a push into the body, i.e. compression, is positive).

Both pairs use the *same* orthonormal frame ``e_1 = t``, ``e_2 = -n`` per node, so with the
rotation ``T`` (``(v, w) = T u_c``, ``(q, p) = T R_c``) the equilibrium of the body,
``K_full u = f + R``, condensed on the contact DOFs reads

    (q, p) = T S T^T (v, w) - T g_c,     S = K_cc - K_ci K_ii^-1 K_ic,

``g_c = f_c - K_ci K_ii^-1 f_i`` (external loads, including prescribed displacements).  Hence
``K = T S T^T`` is a congruence of the SPD Schur complement: symmetric positive definite, and
``q_w, p_w = -T g_c`` are the welded reactions (reactions with ``v = w = 0``).  Check of the
signs: opening a gap (``w > 0``, the bottom pushed *up* into a body held at its top) needs a
compressive reaction, ``p = C w > 0``; a tangential push ``F`` on a body gives
``q_w = -F . t`` (MODEL.md s.1 sanity check).

Interfaces between two bodies ``a`` and ``b`` use the relative displacement
``d = u_a - u_b`` in the frame of body ``a``: ``v = t_a . d``, ``w = -n_a . d`` (opening),
``q, p`` the reaction of body ``b`` on body ``a`` (``R_b = -R_a``, so ``q v + p w`` is the work).

Every constraint is an affine map ``u = P z + P_D u_D`` of the unknowns ``z = (z_c, z_i)``
(``z_c = (v_1..v_N, w_1..w_N)``): held DOFs (``u_D``), periodic copies, node frames and
interface relative displacements; ``K_z = P^T K P``.  ``K_ii`` is factorized once (sparse LU,
minimum-degree order with the *boundary layer* -- the interior DOFs coupled to contact DOFs --
ordered last, see :class:`~shakedown.fe.condensed.SchurFactor`): then the ``2 N`` contact
right-hand sides need only the dense trailing block of the factor, and the same factor serves
every load case, field recovery and the mass.
"""

from __future__ import annotations

import numpy as np

from ...model import citations
from ...model.errors import InputError
from .assembly import Body
from .condensed import CondensedModel, factorize
from .materials import Material
from .meshes import FEMesh

CACHE_FORMAT = "shakedown-fe-condensed-v1"


def _as_list(x):
    if x is None:
        return []
    if isinstance(x, (str, tuple)):
        return [x]
    return list(x)


class FEModel:
    """A 2-D linear elastic FE model with contact (and interface) boundaries.

    Parameters
    ----------
    mesh : FEMesh, optional
        Single-body model: the mesh (with ``material``).  Use ``bodies`` for several bodies.
    material : Material, optional
    dirichlet : list of str or dict, optional
        Held boundaries of the single body (see :class:`~shakedown.fe.assembly.Body`).
    contact : str or list
        Boundaries in contact with a rigid obstacle: names (body 0) or ``(body, name)``.
    loads : dict name -> load(s), optional
        Load cases of the single body (``Traction``, ``Pressure``, ``BodyForce``,
        ``Displacement``).
    periodic : tuple, optional
        ``(master, slave)`` boundary names of body 0 (or a list of ``(body, master, slave)``):
        the slave side's displacements equal those of the master side (translation).
    friction : float or array_like
        Friction coefficient of the contact nodes (default 0), passed to the system.
    bodies : list of Body, optional
        Multi-body model (then ``mesh``, ``material``, ``dirichlet``, ``loads`` are not used).
    interfaces : list of (int, str, int, str), optional
        ``(a, name_a, b, name_b)``: bonded-by-contact boundaries of bodies ``a`` and ``b`` with
        matching nodes.  Slip/gap are relative (``u_a - u_b``) in body ``a``'s frame.
    thickness : float
        Out-of-plane thickness of the single body (default 1: forces per unit thickness).

    Examples
    --------
    >>> from shakedown import fe
    >>> m = fe.FEModel(fe.rectangle(1, 1, 4, 4), fe.isotropic(1.0, 0.3),
    ...                dirichlet=["top"], contact=["bottom"])
    >>> cm = m.condense()
    >>> cm.K.shape          # 5 bottom nodes: (v_1..v_5, w_1..w_5)
    (10, 10)
    """

    def __init__(self, mesh: FEMesh | None = None, material: Material | None = None,
                 dirichlet=None, contact=None, loads=None, periodic=None, friction=0.0, *,
                 bodies=None, interfaces=None, thickness: float = 1.0):
        if bodies is None:
            if mesh is None or material is None:
                raise InputError("FEModel needs mesh and material (or bodies=[Body(...), ...])")
            bodies = [Body(mesh, material, dirichlet, loads, thickness)]
        else:
            if mesh is not None or material is not None or loads is not None or dirichlet:
                raise InputError(
                    "with bodies=..., give mesh/material/dirichlet/loads inside each Body"
                )
            bodies = list(bodies)
            for k, b in enumerate(bodies):
                if not isinstance(b, Body):
                    raise InputError(f"bodies[{k}] must be a fe.Body; got {b!r}")
        self.bodies = tuple(bodies)
        nb = len(self.bodies)

        def body_index(k, what):
            if not (isinstance(k, (int, np.integer)) and 0 <= k < nb):
                raise InputError(f"{what}: body index must be 0..{nb - 1}; got {k!r}")
            return int(k)

        self.contact = []
        for c in _as_list(contact):
            b, name = (0, c) if isinstance(c, str) else c
            b = body_index(b, f"contact {c!r}")
            self.bodies[b].mesh.facets(name)
            self.contact.append((b, str(name)))
        self.interfaces = []
        for it in _as_list(interfaces):
            try:
                a, na, b, nb_ = it
            except (TypeError, ValueError) as exc:
                raise InputError(f"interfaces entries are (a, name_a, b, name_b); got {it!r}") \
                    from exc
            a, b = body_index(a, "interface"), body_index(b, "interface")
            if a == b:
                raise InputError(f"interface {it!r} joins body {a} to itself")
            self.bodies[a].mesh.facets(na)
            self.bodies[b].mesh.facets(nb_)
            self.interfaces.append((a, str(na), b, str(nb_)))
        if not self.contact and not self.interfaces:
            raise InputError(
                "the model has no contact boundary: give contact=['bottom'] (a boundary name) or "
                "interfaces=[(a, name_a, b, name_b)]; condensation needs at least one contact node"
            )
        per = []
        if periodic is not None:
            items = [periodic] if isinstance(periodic[0], str) else list(periodic)
            for p in items:
                if len(p) == 2:
                    p = (0, *p)
                b, m_, s_ = p
                b = body_index(b, f"periodic {p!r}")
                self.bodies[b].mesh.facets(m_)
                self.bodies[b].mesh.facets(s_)
                per.append((b, str(m_), str(s_)))
        self.periodic = per
        self.friction = friction

    # ------------------------------------------------------------------ description
    def key(self, mass: bool) -> dict:
        """JSON-able definition of the condensed products (for the cache key)."""
        return {
            "version": CACHE_FORMAT,
            "bodies": [b.key() for b in self.bodies],
            "contact": self.contact,
            "interfaces": self.interfaces,
            "periodic": self.periodic,
            "mass": bool(mass),
        }

    @property
    def load_cases(self) -> tuple[str, ...]:
        names = []
        for b in self.bodies:
            names += [k for k in b.loads if k not in names]
        return tuple(names)

    def condense(self, mass: bool = False, cache_dir=None, *,
                 allow_rigid_body_modes: bool = False) -> CondensedModel:
        """Condense onto the contact nodes.

        Parameters
        ----------
        mass : bool
            Also condense the consistent mass (Guyan: ``T^T M T``, ``T = [I; -K_ii^-1 K_ic]``).
        cache_dir : path-like, optional
            Folder of the on-disk cache; a second call with the same model definition reads
            the condensed matrices from there (``cm.from_cache``).
        allow_rigid_body_modes : bool
            Return a singular (positive semi-definite) ``K`` instead of raising when the body
            is held by its contact nodes only (``cm.system`` then raises).

        Raises
        ------
        InputError
            No support (rigid-body modes), non-matching interface or periodic nodes, ...
        """
        citations.register("gustafsson2020")
        from . import cache

        key = None
        if cache_dir is not None:
            try:
                key = cache.model_hash(self.key(mass))
            except TypeError:
                raise InputError(
                    "this model has loads given as callables, which cannot be cached; "
                    "use constant loads or cache_dir=None"
                ) from None
            hit = cache.load(cache_dir, key, mass)
            if hit is not None:
                cm = CondensedModel._from_arrays(self, hit)
                cm._check_rigid(allow_rigid_body_modes)
                return cm
        asm = self.assemble(mass)
        cm = asm.condensed()
        cm._check_rigid(allow_rigid_body_modes)
        if key is not None:
            cache.save(cache_dir, key, cm._to_arrays())
        return cm

    def uncondensed(self):
        """The model with its stiffness kept sparse in the contact unknowns and the interior
        DOFs (:class:`~shakedown.fe.uncondensed.UncondensedModel`): no condensation, memory
        ``O(nnz)``; its ``system`` runs the cyclic solver without ever forming the dense ``K``
        (for many contact nodes); the bounds form their ``N`` constraint rows by ``N`` sparse
        solves, the stability checks (and ``condensed()``) the dense ``K``.

        Raises
        ------
        InputError, NotPositiveDefiniteError
            As :meth:`condense` (no support, non-matching nodes, a singular stiffness).
        """
        citations.register("gustafsson2020")
        from .uncondensed import uncondensed

        return uncondensed(self.assemble(False))

    def assemble(self, mass: bool = False):
        """The assembled model (:class:`~shakedown.fe.assembled.Assembled`): constraint maps,
        the factorised interior block, welded reactions; ``mass=True`` also the Guyan mass."""
        from .assembled import Assembled

        return Assembled(self, mass)

    def __repr__(self) -> str:
        return (f"FEModel({len(self.bodies)} bodies, contact={self.contact}, "
                f"interfaces={self.interfaces}, periodic={self.periodic})")


__all__ = ["FEModel", "CondensedModel", "factorize"]
