"""Rank-major numbering: every rank owns one contiguous range of each kind of node.

PETSc gives each rank one contiguous range of rows of a matrix or entries of a vector. The serial
numbering (docs/conventions.md §2) interleaves what different ranks own, so the distributed path
renumbers: within each kind (solid nodes, the nodes of each beam group, the rotation nodes of each
beam group with a material frame, the multiplier (LM) nodes of each beam group) the nodes of rank 0
come first, then those of rank 1, ..., each rank's in their serial order. A node is owned by the
rank of the lowest-index element that uses it (the solid's and the beams' own elements; a rotation
node, an element's middle node among them, by the lowest-index beam element whose triads it
interpolates); an interior LM node by its beam element's rank.

A kind's renumbering is ``new = new_of_old[old]`` with ``ranges[r]:ranges[r + 1]`` the new ids
that rank r owns; DOFs follow their node (``dofs_per_node * node + component``).
"""
from dataclasses import dataclass

import numpy as np

from ..elements.multiplier import multiplier as multiplier_type


@dataclass(frozen=True)
class Renumbering:
    """One kind of node in rank-major order.

    Attributes
    ----------
    owner : (n,) int64
        Rank of every node (serial id).
    new_of_old : (n,) int64
        Rank-major id of every serial id.
    ranges : (n_parts + 1,) int64
        Rank r owns the new ids ``ranges[r]:ranges[r + 1]``.
    """

    owner: np.ndarray
    new_of_old: np.ndarray
    ranges: np.ndarray

    @classmethod
    def from_owner(cls, owner, n_parts):
        owner = np.asarray(owner, dtype=np.int64)
        order = np.lexsort((np.arange(len(owner)), owner))
        new_of_old = np.empty(len(owner), dtype=np.int64)
        new_of_old[order] = np.arange(len(owner))
        ranges = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=n_parts))]).astype(np.int64)
        return cls(owner, new_of_old, ranges)

    @property
    def n(self):
        return len(self.owner)

    def count(self, rank):
        """Nodes that ``rank`` owns."""
        return int(self.ranges[rank + 1] - self.ranges[rank])

    def dofs(self, old_dofs, per_node):
        """Rank-major DOF ids of serial DOF ids (``per_node`` DOFs per node)."""
        old_dofs = np.asarray(old_dofs, dtype=np.int64)
        return self.new_of_old[old_dofs // per_node] * per_node + old_dofs % per_node


def node_owner(elements, element_part, n_nodes):
    """Rank of every node: the rank of the lowest-index element using it (-1 entries ignored; a
    node no element uses goes to rank 0)."""
    elements = np.asarray(elements)
    owner = np.zeros(n_nodes, dtype=np.int64)
    first = np.full(n_nodes, len(elements), dtype=np.int64)
    ids = np.repeat(np.arange(len(elements)), elements.shape[1])
    nodes = elements.ravel()
    keep = nodes >= 0
    np.minimum.at(first, nodes[keep], ids[keep])
    used = first < len(elements)
    owner[used] = np.asarray(element_part)[first[used]]
    return owner


def lm_renumbering(node_owner, element_part, lm, n_parts):
    """LM nodes of the multiplier type ``lm`` on one beam group in rank-major order: the beam's
    nodes (``node_owner``: their ranks), then the interior LM nodes of each element (its rank,
    ``element_part``), as :func:`~mortar1d3d.mortar.assemble.lm_numbering` numbers them."""
    n_int = multiplier_type(lm).n_interior
    return Renumbering.from_owner(np.concatenate([node_owner, np.repeat(element_part, n_int)]), n_parts)


@dataclass(frozen=True)
class Numbering:
    """The rank-major numbering of a partitioned model.

    Attributes
    ----------
    solid : Renumbering
        Solid nodes.
    beams : list of Renumbering
        Centreline nodes of each beam group.
    lm : list of Renumbering
        LM nodes of each beam group (numbered as :func:`~mortar1d3d.mortar.assemble.lm_numbering`).
    rotations : list of (Renumbering or None)
        Rotation nodes of each beam group (:meth:`~mortar1d3d.physics.beam_types.BeamType.rotation_nodes`:
        the mesh nodes, then one middle node per element); None for a group without them.
    """

    solid: Renumbering
    beams: list
    lm: list
    rotations: list = ()

    @classmethod
    def of(cls, partition, solid, beam_meshes, lm="line2", beam_types=None):
        """The numbering of ``partition``; ``beam_types`` (one :class:`~mortar1d3d.physics.beam_types.BeamType`
        per group) numbers the rotation nodes of the groups whose type has them."""
        n = partition.n_parts
        solid_num = Renumbering.from_owner(node_owner(solid.connectivity, partition.solid_part, solid.n_nodes), n)
        beams, lms, rotations = [], [], []
        types = [None] * len(beam_meshes) if beam_types is None else list(beam_types)
        for mesh, part, kind in zip(beam_meshes, partition.beam_part, types):
            owner = node_owner(mesh.elements, part, mesh.n_nodes)
            beams.append(Renumbering.from_owner(owner, n))
            lms.append(lm_renumbering(owner, part, lm, n))
            table = None if kind is None else kind.rotation_nodes(mesh)
            rotations.append(None if table is None or table.shape[1] == 0 else Renumbering.from_owner(
                node_owner(table, part, kind.n_rotation_nodes(mesh)), n))
        return cls(solid_num, beams, lms, rotations)
