"""Build: a :class:`~mortar1d3d.scene.Scene` to meshes, beam groups, named sets and the DOF map.

The first stage of ``solve``: everything that follows from the scene's geometry alone. Meshes
are generated (``box``), read (:mod:`.readers`) or sampled from curves (:mod:`.curves`) and
checked (unused or duplicate nodes, curved centrelines of beams that need them straight);
beams of one type are joined into one :class:`BeamGroup`; :class:`~.dofmap.DofMap` numbers the
unknowns. A beam's ``model`` name is looked up in the beam-type registry here, once: everything
downstream asks the group's :class:`~mortar1d3d.physics.beam_types.BeamType`.
"""
from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshError, format_ids
from ..generate import box as box_mesh
from ..mesh import BeamMesh, SolidMesh
from ..physics.beam_types import beam_type
from ..scene import Scene, SceneError
from .curves import curve_mesh
from .dofmap import DofMap
from .readers import reader
from .sets import NamedSets


@dataclass
class BeamGroup:
    """Beams of one type in one BeamMesh (entries keep their order)."""

    type: object                       # BeamType
    entries: list                      # scene beam indices
    mesh: BeamMesh = None
    node_offsets: list = field(default_factory=list)     # first node of each entry in ``mesh``
    element_offsets: list = field(default_factory=list)
    entry_elements: list = field(default_factory=list)   # (start, stop) element range per entry
    dofs: object = None                # its centreline Block of the DOF map
    rotations: object = None           # its rotations Block (empty for centreline-only types)
    triads: object = None              # reference triads (n_rotation_nodes, 3, 3) of types with triads
    physics: object = None             # the type's physics (BeamModel)
    operators: object = None           # MortarOperators
    coupling: object = None            # Coupling
    rotational: object = None          # RotationalCoupling (coupling.rotational, groups with rotations)

    @property
    def model(self):
        """The beam type's name (the scene's ``beams[i].model``)."""
        return self.type.name

    @property
    def dof_offset(self):
        """First unknown of the group's centreline block."""
        return self.dofs.start


@dataclass(frozen=True, eq=False)
class BuiltScene:
    """What :func:`build` makes of a scene; the input of :class:`~mortar1d3d.model.Model`.

    Attributes
    ----------
    scene : Scene
    solid_mesh : SolidMesh or None
    groups : list of BeamGroup
        Beam groups in order of first appearance of their type.
    entry_group : list of BeamGroup
        The group of every ``beams[i]``.
    sets : NamedSets
    dofmap : DofMap
        Without multipliers (their number is known once the coupling is assembled).
    """

    scene: Scene
    solid_mesh: SolidMesh
    groups: list
    entry_group: list
    sets: NamedSets
    dofmap: DofMap


def as_scene(scene):
    """``scene``, or the scene of a TOML file if it is a path."""
    if isinstance(scene, (str, bytes)) or hasattr(scene, "__fspath__"):
        return Scene.from_toml(scene)
    return scene


def build(scene):
    """Meshes, beam groups, named sets and the DOF map of ``scene`` (a Scene or a TOML file).

    Raises
    ------
    SceneError
        A mesh that cannot be read or built, has unused or duplicate nodes, or a curved
        reference centreline where the beam type needs a straight one.
    """
    scene = as_scene(scene)
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a Scene, got {type(scene).__name__}")
    solid_mesh = build_solid_mesh(scene.solid) if scene.solid is not None else None
    if solid_mesh is not None:
        check_rational(scene, solid_mesh)
    types = [beam_type(b["model"]) for b in scene.beams]
    meshes = [build_beam_mesh(b, t, f"beams[{i}]") for i, (b, t) in enumerate(zip(scene.beams, types))]
    for i, (t, mesh) in enumerate(zip(types, meshes)):
        if not t.curved_reference:
            check_straight(mesh, f"beams[{i}]")
    # beams grouped by type, entry order kept inside each group
    groups, entry_group = [], []
    for i, t in enumerate(types):
        group = next((g for g in groups if g.type is t), None)
        if group is None:
            group = BeamGroup(type=t, entries=[])
            groups.append(group)
        group.entries.append(i)
        entry_group.append(group)
    for g in groups:
        parts = [meshes[i] for i in g.entries]
        g.mesh = parts[0] if len(parts) == 1 else BeamMesh.join(parts)
        g.node_offsets = list(np.cumsum([0] + [p.n_nodes for p in parts[:-1]]))
        g.element_offsets = list(np.cumsum([0] + [p.n_elements for p in parts[:-1]]))
        g.entry_elements = [(int(o), int(o) + p.n_elements) for o, p in zip(g.element_offsets, parts)]
    for g in groups:
        if g.type.triads is not None:
            g.triads = group_triads(g, [scene.beams[i] for i in g.entries])
    n_solid_nodes = solid_mesh.n_nodes if solid_mesh is not None else 0
    dofmap = DofMap.layout(n_solid_nodes, [(g.type.dofs_per_node, g.type.rotations_per_node, g.mesh.n_nodes,
                                            g.type.n_rotation_nodes(g.mesh)) for g in groups])
    for g, centreline, rotations in zip(groups, dofmap.centreline, dofmap.rotations):
        g.dofs, g.rotations = centreline, rotations
    return BuiltScene(scene=scene, solid_mesh=solid_mesh, groups=groups, entry_group=entry_group,
                      sets=NamedSets(solid_mesh, entry_group), dofmap=dofmap)


# --------------------------------------------------------------------------------------------
# meshes
# --------------------------------------------------------------------------------------------
def build_solid_mesh(spec):
    """SolidMesh of a validated ``solid`` entry: generated box, mesh object or file."""
    mesh = spec["mesh"]
    try:
        if isinstance(mesh, dict) and any(k in mesh for k in ("pipe", "brick", "patches")):
            from ..nurbs.scene import NURBS_MESHES
            (kind, table), = mesh.items()
            mesh = NURBS_MESHES[kind][1](table)[0]
        elif isinstance(mesh, dict):
            return box_mesh(mesh["box"][0], mesh["box"][1], mesh["cells"], mesh["element"])
        if not isinstance(mesh, SolidMesh):
            mesh = reader(mesh).read_solid(mesh, "solid.mesh")
    except (MeshError, OSError) as exc:
        raise SceneError(f"solid.mesh: {exc}") from None
    check_solid_nodes(mesh, "solid.mesh")
    return mesh


def check_rational(scene, mesh):
    """SceneError naming the coupling key when rational (NURBS) elements meet a coupling that evaluates
    only the polynomial part of the solid's functions (Gauss-point constraint, rotational coupling)."""
    rational = sorted({d.name for d, _ in mesh.blocks if d.rational})
    if not (rational and scene.coupled):
        return
    if scene.coupling["constraint"] == "gauss_point":
        raise SceneError(f"coupling.constraint: 'gauss_point' is not implemented for rational elements {rational} "
                         "(NURBS spans); use the default 'mortar'")
    if scene.coupling.get("rotational") is not None:
        raise SceneError(f"coupling.rotational: not implemented for rational elements {rational} (NURBS spans)")


def build_beam_mesh(spec, kind, path):
    """BeamMesh of one validated ``beams[i]`` entry with the centreline element of its type ``kind``."""
    try:
        if "mesh" in spec:
            mesh = spec["mesh"]
            if isinstance(mesh, BeamMesh):
                check_beam_nodes(mesh, f"{path}.mesh")
                return mesh
            beams = reader(mesh).read_beams(mesh, kind.element, f"{path}.mesh")
            check_beam_nodes(beams, f"{path}.mesh {str(mesh)!r}")
            return beams
        return curve_mesh(spec["curve"], spec["elements"], kind.element)
    except MeshError as exc:
        raise SceneError(f"{path}: {exc}") from None


def group_triads(g, specs):
    """Reference triads (n_rotation_nodes, 3, 3) of a beam group with triads: per beam its given
    ``triads`` (checked) or the parallel-transport frame from its ``normal`` (default rule without).

    Raises SceneError naming ``beams[i].triads`` or ``beams[i].normal``.
    """
    mesh = g.mesh
    rows = g.type.rotation_nodes(mesh)
    out = np.empty((g.type.n_rotation_nodes(mesh), 3, 3))
    by_normal = {}
    for k, (entry, spec) in enumerate(zip(g.entries, specs)):
        a, b = g.entry_elements[k]
        nodes = np.unique(rows[a:b])
        if spec.get("triads") is not None:
            # given per rotation node of this beam: its mesh nodes, then one middle node per element
            given = np.asarray(spec["triads"], dtype=float)
            full = g.type.reference_triads(mesh)
            if given.shape != (len(nodes), 3, 3):
                raise SceneError(f"beams[{entry}].triads: expected shape ({len(nodes)}, 3, 3) (its {len(nodes) - (b - a)} "
                                 f"nodes, then one middle node per element), got {given.shape}")
            full[nodes] = given
            try:
                checked = g.type.reference_triads(mesh, given=full)
            except ValueError as exc:
                raise SceneError(f"beams[{entry}].triads: {exc}") from None
            out[nodes] = checked[nodes]
            continue
        key = None if spec.get("normal") is None else tuple(spec["normal"])
        if key not in by_normal:
            try:
                by_normal[key] = g.type.reference_triads(mesh, normal=spec.get("normal"))
            except ValueError as exc:
                raise SceneError(f"beams[{entry}].normal: {exc}") from None
        out[nodes] = by_normal[key][nodes]
    return out


def check_straight(mesh, path):
    """SceneError naming ``path`` if a beam's reference centreline is curved (for beam types whose
    ``curved_reference`` is False: the torsion-free beam).

    Curved is decided by :func:`~mortar1d3d.physics.beam.curved_elements` (curvature times
    element length above 1e-8).
    """
    from ..physics.beam import curved_elements, curved_torsion_free_message
    ids, values = curved_elements(mesh)
    if ids.size:
        raise SceneError(f"{path}.model: {curved_torsion_free_message(ids, values, mesh.n_elements)}")


def check_solid_nodes(mesh, where):
    """SceneError naming node ids if ``mesh`` has nodes no element uses (their stiffness is zero)
    or distinct nodes at the same place (a crack: the elements on either side do not connect).

    Two nodes coincide when they are closer than 1e-10 of the mesh's bounding-box diagonal.
    """
    used = np.zeros(mesh.n_nodes, dtype=bool)
    used[mesh.connectivity[mesh.connectivity >= 0]] = True
    if not used.all():
        unused = np.flatnonzero(~used)
        raise SceneError(f"{where}: nodes not used by any element: {format_ids(unused)} (remove them)")
    from scipy.spatial import cKDTree
    X = mesh.points
    size = float(np.linalg.norm(np.ptp(X, axis=0)))
    pairs = cKDTree(X).query_pairs(1e-10 * size, output_type="ndarray")
    if len(pairs):
        raise SceneError(f"{where}: duplicate nodes at the same position: {_node_pairs(pairs)}; the elements on either "
                         "side are not connected (merge the duplicates)")


def _node_pairs(pairs, limit=5):
    """``"1 and 12, 4 and 13 (and 2 more pairs)"``: node pairs in a fixed order for messages."""
    pairs = np.sort(np.asarray(pairs), axis=1)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    more = f" (and {len(pairs) - limit} more pairs)" if len(pairs) > limit else ""
    return ", ".join(f"{a} and {b}" for a, b in pairs[:limit]) + more


def check_beam_nodes(mesh, where):
    """SceneError naming node ids if the beam mesh ``mesh`` has nodes no element uses (their
    stiffness is zero: the solve would fail as singular) or two chain ends at the same place (one
    beam split in two pieces that do not connect, the beam counterpart of a crack).

    Coincident nodes elsewhere are allowed: fibres that cross or touch at a node of one of them
    are separate beams on purpose. Two nodes coincide when they are closer than 1e-10 of the
    mesh's bounding-box diagonal.
    """
    used = np.zeros(mesh.n_nodes, dtype=bool)
    used[mesh.elements] = True
    if not used.all():
        raise SceneError(f"{where}: nodes not used by any element: {format_ids(np.flatnonzero(~used))} (remove them)")
    # columns 0 and 1 are the element's end nodes for every beam element type (line3: ends, then middle)
    ends = np.bincount(mesh.elements[:, :2].ravel(), minlength=mesh.n_nodes) == 1
    from scipy.spatial import cKDTree
    X = mesh.positions[ends]
    size = float(np.linalg.norm(np.ptp(mesh.positions, axis=0)))
    pairs = np.flatnonzero(ends)[cKDTree(X).query_pairs(1e-10 * size, output_type="ndarray")] if len(X) > 1 else []
    if len(pairs):
        raise SceneError(f"{where}: beam ends at the same position: {_node_pairs(pairs)}; the elements on either side "
                         "are not connected (use one node there)")
