"""The DOF map: where each kind of unknown lives in the global vector ``z``.

``z = [solid | centreline of beam group 0 | group 1 | ... | rotations of group 0 | group 1 | ... |
multipliers]``, every block a contiguous range ``start:stop`` of nodes × DOFs per node (the
multipliers: one per coupled constraint row):

===========  ==================================================  ===============
block        unknowns                                            DOFs per node
===========  ==================================================  ===============
solid        displacements, ``3 * node + i``                     3
centreline   one block per beam group (beams of one type):       the element
             Hermite ``[r, t]`` per node, positions for a truss  type's
rotations    one block per beam group: the total spatial        3
             rotation vectors ψ of the rotation nodes of
             beams with a material frame (``simo_reissner``:
             the mesh's nodes, then one middle node per
             element; empty for the other types)
multipliers  Lagrange multipliers of the coupling rows           1
===========  ==================================================  ===============

The displacement unknowns (everything but the multipliers) come first, so that
``z[:n_displacement]`` is what the physics evaluates. Because a block is a node range times a
fixed number of DOFs, a contiguous range of its nodes is a contiguous range of unknowns
(:meth:`Block.node_range`): a distributed run can own node sub-ranges of every block.
"""
from dataclasses import dataclass

import numpy as np

KINDS = ("solid", "centreline", "rotations", "multipliers")


@dataclass(frozen=True)
class Block:
    """A contiguous range of unknowns of one kind.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    start, stop : int
        The block is ``z[start:stop]``.
    dofs_per_node : int
        Unknowns per node (per constraint row for multipliers).
    group : int or None
        Beam group of a centreline or rotations block.
    """

    kind: str
    start: int
    stop: int
    dofs_per_node: int
    group: int = None

    @property
    def size(self):
        return self.stop - self.start

    @property
    def slice(self):
        return slice(self.start, self.stop)

    def node_range(self, first, last):
        """``(start, stop)`` of the unknowns of nodes ``first .. last - 1`` of this block."""
        return self.start + self.dofs_per_node * first, self.start + self.dofs_per_node * last

    def dofs(self, nodes, components):
        """Global unknowns of ``components`` (offsets in a node's DOFs) at ``nodes``:
        (len(nodes) * len(components),) int64, node-major."""
        base = self.start + self.dofs_per_node * np.asarray(nodes, dtype=np.int64)[:, None]
        return (base + np.asarray(components, dtype=np.int64)[None, :]).ravel()


class DofMap:
    """The blocks of the unknowns, in order (see the module docstring).

    Build with :meth:`layout`; the multipliers' count is known once the coupling rows are
    (:meth:`with_multipliers`).
    """

    def __init__(self, blocks):
        blocks = tuple(blocks)
        position = 0
        for b in blocks:
            if b.kind not in KINDS or b.start != position or b.stop < b.start:
                raise ValueError(f"DOF map blocks must be contiguous and in order, got {blocks}")
            position = b.stop
        kinds = [KINDS.index(b.kind) for b in blocks]
        if kinds != sorted(kinds) or kinds.count(0) != 1 or kinds.count(1) != kinds.count(2) or kinds.count(3) != 1:
            raise ValueError(f"DOF map: expected one solid block, the centreline blocks and as many rotations "
                             f"blocks (one per beam group), one multipliers block, in this order, got "
                             f"{[b.kind for b in blocks]}")
        self.blocks = blocks

    @classmethod
    def layout(cls, n_solid_nodes, beams=(), n_multipliers=0):
        """The map of a model.

        Parameters
        ----------
        n_solid_nodes : int
        beams : sequence of (centreline DOFs per node, rotations per node, n_nodes[, n_rotation_nodes])
            One per beam group, in group order (rotations per node: 0 or 3; rotation nodes:
            default ``n_nodes``).
        n_multipliers : int
        """
        blocks = [Block("solid", 0, 3 * n_solid_nodes, 3)]
        for kind, column in (("centreline", 0), ("rotations", 1)):
            for k, group in enumerate(beams):
                start = blocks[-1].stop
                nodes = group[2] if kind == "centreline" or len(group) < 4 else group[3]
                blocks.append(Block(kind, start, start + group[column] * nodes, group[column] or 3, group=k))
        blocks.append(Block("multipliers", blocks[-1].stop, blocks[-1].stop + n_multipliers, 1))
        return cls(blocks)

    def with_multipliers(self, n):
        """The same map with ``n`` multipliers."""
        m = self.multipliers
        return DofMap(self.blocks[:-1] + (Block("multipliers", m.start, m.start + n, 1),))

    @property
    def solid(self):
        return self.blocks[0]

    @property
    def centreline(self):
        """Centreline blocks, one per beam group."""
        return tuple(b for b in self.blocks if b.kind == "centreline")

    @property
    def rotations(self):
        """Rotations blocks, one per beam group."""
        return tuple(b for b in self.blocks if b.kind == "rotations")

    @property
    def multipliers(self):
        return self.blocks[-1]

    @property
    def n_displacement(self):
        """Unknowns before the multipliers: what the physics evaluates."""
        return self.multipliers.start

    @property
    def n_unknowns(self):
        return self.multipliers.stop

    def __repr__(self):
        parts = ", ".join(f"{b.kind}{'' if b.group is None else f'[{b.group}]'} {b.start}:{b.stop}"
                          for b in self.blocks)
        return f"DofMap({parts})"
