"""Beam types: what a scene's ``beams[i].model`` names, one frozen descriptor per type.

The registry :data:`BEAM_TYPES` is the only place that knows which models exist. The scene
validates ``model`` against it, the build step looks a beam's model up once
(:func:`beam_type`), and everything downstream asks the descriptor: the centreline element type
and its DOFs per node, whether the beam bends (needs EI, takes end moments), whether its
reference centreline may be curved, the class that implements its physics, and the fields
written to ``beams_<k>.vtu``.

Adding a beam type is its own module(s) (physics, and the centreline element if it is new) and
one line here. :data:`PLANNED_BEAM_TYPES` lists models a scene may name but that are not
implemented yet (the scene says so instead of calling the name unknown).
"""
import importlib
from dataclasses import dataclass

import numpy as np

from ..elements.beam import BEAM_ELEMENTS, BeamElementType

__all__ = ["BeamType", "BEAM_TYPES", "PLANNED_BEAM_TYPES", "DEFAULT_BEAM_TYPE", "beam_type"]


@dataclass(frozen=True, eq=False)
class BeamType:
    """Descriptor of a beam model.

    Attributes
    ----------
    name : str
        The scene's ``beams[i].model``.
    element : BeamElementType
        Centreline interpolation (its ``dofs_per_node`` are the beam's centreline DOFs per node).
    label : str
        How messages name the centreline (``"Hermite centreline"``).
    bending : bool
        The beam has bending stiffness: ``section.EI`` is required (derived from a radius),
        ``moment`` loads act on it. Without it ``EI`` is 0 and ignored.
    curved_reference : bool
        Whether the reference centreline may be curved (the torsion-free beam needs it straight).
    physics : str
        ``"module:Class"`` of the physics, imported on first use (:meth:`physics_class`) so that
        the physics may consult this registry; built by :meth:`make_physics`: without triads
        ``Class(mesh, EA, EI, model=name)`` with ``evaluate(d, tangent)`` (internal force,
        tangent) and ``sample(d, eta)``; with triads ``Class(mesh, sections, reference_triads=...)``
        with ``evaluate(d, psi, tangent)``, ``sample(d, psi, eta)`` and ``update(psi, dtheta)``
        (ψ: the rotations block, one row per rotation node), and the module has ``Section``,
        ``reference_triads`` and ``check_triads``.
    output_fields : tuple of str
        Keys of ``sample`` written per sample point to ``beams_<k>.vtu`` (``g1``, ``g2``, ``g3``:
        the columns of its ``triads``).
    rotations_per_node : int
        DOFs per rotation node in the rotations block of the DOF map (0: a centreline-only beam).
    triads : str or None
        How the beam's material frame is interpolated, which fixes its rotation nodes
        (:meth:`rotation_nodes`): None (no frame, no rotation DOFs) or ``"line3"`` (three triad
        nodes per element: the mesh's nodes, shared by adjacent elements, then one middle node per
        element, numbered ``n_nodes + e``).
    symmetric_tangent : bool
        Whether the beam's tangent stiffness is symmetric in nonlinear analyses (CG and MINRES need
        it; a beam without it runs with the direct solver).
    section_law : str
        Which section keys the scene takes: ``"axial_bending"`` (``{E, radius}`` or ``{EA, EI}``)
        or ``"shear_torsion"`` (axial, shear, torsion and two bending stiffnesses, see
        :mod:`mortar1d3d.scene`).
    """

    name: str
    element: BeamElementType
    label: str
    bending: bool
    curved_reference: bool
    physics: str
    output_fields: tuple = ("displacement", "axial_force", "curvature")
    rotations_per_node: int = 0
    triads: str = None
    section_law: str = "axial_bending"
    symmetric_tangent: bool = True

    @property
    def dofs_per_node(self):
        """Centreline DOFs per node: the element type's."""
        return self.element.dofs_per_node

    def physics_class(self):
        """The class implementing this beam's physics."""
        module, name = self.physics.split(":")
        return getattr(importlib.import_module(module), name)

    def physics_module(self):
        """The module of this beam's physics."""
        return importlib.import_module(self.physics.split(":")[0])

    def make_physics(self, mesh, sections, triads=None, force_rules=None, virtual_spins=None):
        """The physics of a beam group.

        Parameters
        ----------
        mesh : BeamMesh
        sections : list of (n_elements_i, dict)
            Per beam of the group in mesh order: its number of elements and its normalised
            scene section (``EA``, ``EI``; with triads also ``GA2, GA3, GI_T, EI2, EI3``).
        triads : (n_rotation_nodes, 3, 3) array, optional
            Reference triads (beams with triads only; default: the physics' own rule).
        force_rules : list of str or None, optional
            Per beam, the rule of its force term (``force_rule`` of the physics; None: its
            default). Beams with triads only.
        virtual_spins : list of str or None, optional
            Per beam, the test functions of its spin rows (``virtual_spins`` of the physics; None:
            its default). Beams with triads only.
        """
        cls = self.physics_class()
        if self.triads is None:
            EA = np.concatenate([np.full(n, s["EA"]) for n, s in sections])
            EI = np.concatenate([np.full(n, s["EI"]) for n, s in sections])
            return cls(mesh, EA, EI, model=self.name)
        Section = self.physics_module().Section
        per_beam = [Section(**{k: s[k] for k in ("EA", "GA2", "GA3", "GI_T", "EI2", "EI3")}) for _, s in sections]
        per_element = [section for (n, _), section in zip(sections, per_beam) for _ in range(n)]
        options = {}
        for key, per_beam, default in (("force_rule", force_rules, "gauss"), ("virtual_spins", virtual_spins, "exact")):
            if per_beam is not None and any(r is not None for r in per_beam):
                options[key] = [r or default for (n, _), r in zip(sections, per_beam) for _ in range(n)]
        return cls(mesh, per_element, reference_triads=triads, **options)

    def reference_triads(self, mesh, normal=None, given=None):
        """Reference triads at the rotation nodes of ``mesh``: ``given`` checked (orthonormal,
        right-handed, g1 along the tangent), or carried along each beam by parallel transport from
        ``normal`` (ValueError naming the rotation nodes otherwise)."""
        module = self.physics_module()
        if given is not None:
            return module.check_triads(mesh, given)
        return module.reference_triads(mesh, normal)

    def rotation_nodes(self, mesh):
        """(n_elements, k) int64: the rotation nodes of each element (``k = 0`` without triads;
        line3 order: start, end, middle)."""
        if self.triads is None:
            return np.zeros((mesh.n_elements, 0), dtype=np.int64)
        ends = mesh.elements[:, :2].astype(np.int64)
        middle = mesh.n_nodes + np.arange(mesh.n_elements, dtype=np.int64)
        return np.column_stack([ends, middle])

    def n_rotation_nodes(self, mesh):
        """Rotation nodes of ``mesh`` (the rows of its rotations block in the DOF map)."""
        return 0 if self.triads is None else mesh.n_nodes + mesh.n_elements


BEAM_TYPES = {t.name: t for t in (
    BeamType("torsion_free", BEAM_ELEMENTS["hermite"], "Hermite centreline", bending=True, curved_reference=False,
             physics="mortar1d3d.physics.beam:BeamModel"),
    BeamType("truss", BEAM_ELEMENTS["line"], "line", bending=False, curved_reference=True,
             physics="mortar1d3d.physics.beam:BeamModel"),
    BeamType("simo_reissner", BEAM_ELEMENTS["hermite"], "Hermite centreline with line3 triads", bending=True,
             curved_reference=True, physics="mortar1d3d.physics.simo_reissner:SimoReissnerBeam",
             output_fields=("displacement", "axial_force", "curvature", "g1", "g2", "g3", "n", "m", "Gamma", "K"),
             rotations_per_node=3, triads="line3", section_law="shear_torsion", symmetric_tangent=False),
    BeamType("beam3eb", BEAM_ELEMENTS["hermite"], "Hermite centreline (4C's BEAM3EB)", bending=True,
             curved_reference=False, physics="mortar1d3d.physics.beam3eb:Beam3ebModel", symmetric_tangent=False),
)}
PLANNED_BEAM_TYPES = ()
DEFAULT_BEAM_TYPE = "torsion_free"


def beam_type(name):
    """The :class:`BeamType` registered as ``name``.

    Raises
    ------
    NotImplementedError
        ``name`` is planned (:data:`PLANNED_BEAM_TYPES`), not implemented yet.
    ValueError
        ``name`` is unknown.
    """
    try:
        return BEAM_TYPES[name]
    except (KeyError, TypeError):
        pass
    if name in PLANNED_BEAM_TYPES:
        known = " or ".join(f"{t.name!r} ({t.label})" for t in BEAM_TYPES.values())
        raise NotImplementedError(f"beam model {name!r} is not implemented yet; use {known}")
    raise ValueError(f"unknown beam model {name!r}; known models: {', '.join(BEAM_TYPES)}")
