"""Distributed assembly of the mortar operators D, M and κ into PETSc matrices and vectors.

Each rank takes its owned beam elements (:class:`~.partition.Partition`) and the solid elements
they can reach, in their serial order, as two small meshes and runs the unchanged serial
pipeline on them (:func:`~mortar1d3d.assemble_mortar`: search, segmentation, Numba kernels). The
lowest-index ownership rule of docs/conventions.md §1 gives the same owner on the small solid
mesh, since it holds every element that a beam element's box overlaps, in the same order. The
rank's local rows and columns are mapped to the rank-major numbering (:mod:`.numbering`) and
added into PETSc ``MPIAIJ`` matrices through PETSc's COO assembly: an entry of a row another rank
owns (an LM node at a beam node shared with a beam element of another rank) is sent there and
summed by PETSc, never by this library.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements.multiplier import multiplier as multiplier_type
from ..mesh import BeamMesh, SolidMesh
from ..mortar.assemble import assemble_mortar, lm_numbering
from .petsc import coo_matrix, gather_matrix, gather_vector, petsc, summed_vector


def _used_nodes(element_ids, connectivity):
    """``element_ids`` as int64 and the ascending serial nodes their rows of ``connectivity`` use
    (padding -1 left out); None for the nodes when there are no elements."""
    element_ids = np.asarray(element_ids, dtype=np.int64)
    if not len(element_ids):
        return element_ids, None
    conn = connectivity[element_ids]
    return element_ids, np.unique(conn[conn >= 0])


def solid_submesh(solid, element_ids):
    """The solid elements ``element_ids`` (ascending) as a mesh of their own nodes, in the same order.

    Returns the mesh (None for no elements) and the serial ids of its nodes (ascending).
    """
    element_ids, nodes = _used_nodes(element_ids, solid.connectivity)
    if nodes is None:
        return None, np.zeros(0, np.int64)
    cells, start = {}, 0
    for descriptor, block in solid.blocks:
        pick = element_ids[(element_ids >= start) & (element_ids < start + len(block))] - start
        if len(pick):
            # blocks keep the serial order, so the elements' local order is their serial order
            cells[descriptor.name] = np.searchsorted(nodes, block[pick])
        start += len(block)
    weights = solid.weights[nodes] if solid.weights is not None else None
    return SolidMesh(solid.points[nodes], cells, weights=weights), nodes


def beam_submesh(beams, element_ids):
    """The beam elements ``element_ids`` (ascending) as a mesh of their own nodes, in the same order.

    Returns the mesh (None for no elements) and the serial ids of its nodes (ascending).
    """
    element_ids, nodes = _used_nodes(element_ids, beams.elements)
    if nodes is None:
        return None, np.zeros(0, np.int64)
    tangents = beams.tangents[nodes] if beams.tangents is not None else None
    return BeamMesh(beams.element_type.name, beams.positions[nodes], np.searchsorted(nodes, beams.elements[element_ids]),
                    tangents=tangents), nodes


@dataclass
class LocalOperators:
    """What one rank assembled for one beam group, with its rows and columns in the rank-major numbering.

    Attributes
    ----------
    D, M : (rows, cols, values) int64, int64, float64
        Scalar-component triplets: rows ``3 * lm + i``, columns the group's centreline DOFs
        (``dofs_per_node * node + k``) for D and ``3 * solid node + i`` for M, all rank-major.
    kappa : (lm ids, values)
    ops : MortarOperators or None
        The local serial result (None when the rank owns no beam element of the group or its
        beam elements reach no solid element).
    beam_elements : (m_local,) int64
        Serial ids of the owned beam elements.
    solid_elements : (n_local,) int64
        Serial ids of the solid elements they reach (the local solid mesh's elements).
    beams, solid : BeamMesh, SolidMesh or None
        The local meshes ``ops`` was assembled on (None with ``ops``).
    beam_nodes, solid_nodes : int64 arrays
        Serial ids of the local meshes' nodes.
    """

    D: tuple
    M: tuple
    kappa: tuple
    ops: object
    beam_elements: np.ndarray
    solid_elements: np.ndarray
    beams: object = None
    solid: object = None
    beam_nodes: np.ndarray = None
    solid_nodes: np.ndarray = None

    def serial_points(self):
        """The local integration points and segments with serial element ids: (point_fields, segments)."""
        if self.ops is None:
            return None, None
        fields = dict(self.ops.point_fields)
        fields["beam_element"] = self.beam_elements[fields["beam_element"]]
        fields["solid_element"] = np.where(fields["solid_element"] >= 0,
                                           self.solid_elements[np.maximum(fields["solid_element"], 0)], -1)
        segments = self.ops.segments.copy()
        segments["beam_element"] = self.beam_elements[segments["beam_element"]]
        segments["solid_element"] = self.solid_elements[segments["solid_element"]]
        return fields, segments


def _triplets(A):
    A = A.tocoo()
    return A.row.astype(np.int64), A.col.astype(np.int64), A.data


def local_operators(solid, beams, partition, numbering, rank, group=0, integration="segment", n_gauss=6,
                    lm="line2", search_points=6):
    """Run the serial mortar pipeline on what ``rank`` owns of beam group ``group`` (see the module
    docstring) and map its rows and columns to the rank-major numbering.

    Returns
    -------
    LocalOperators
    """
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    owned = partition.owned_beams(rank, group)
    reach = partition.reach(rank, group)
    if not len(owned) or not len(reach):
        return LocalOperators(empty, empty, empty[1:], None, owned, reach)
    sub_beams, beam_nodes = beam_submesh(beams, owned)
    sub_solid, solid_nodes = solid_submesh(solid, reach)
    ops = assemble_mortar(sub_beams, sub_solid, integration=integration, n_gauss=n_gauss, lm=lm,
                          search_points=search_points)
    lm_new = numbering.lm[group].new_of_old[serial_lm_nodes(sub_beams, beam_nodes, owned, beams.n_nodes, lm)]
    per_node = beams.n_centreline_dofs // beams.n_nodes
    r, c, v = _triplets(ops.D)
    D = (3 * lm_new[r // 3] + r % 3, per_node * numbering.beams[group].new_of_old[beam_nodes[c // per_node]]
         + c % per_node, v)
    r, c, v = _triplets(ops.M)
    M = (3 * lm_new[r // 3] + r % 3, 3 * numbering.solid.new_of_old[solid_nodes[c // 3]] + c % 3, v)
    return LocalOperators(D, M, (lm_new, ops.kappa), ops, owned, reach, sub_beams, sub_solid, beam_nodes, solid_nodes)


def serial_lm_nodes(sub_beams, beam_nodes, owned, n_nodes, lm):
    """Serial LM node of every LM node of the multiplier type ``lm`` on a rank's beam sub-mesh
    (:func:`beam_submesh` of the elements ``owned``, its nodes ``beam_nodes``; ``n_nodes``: the
    group's): beam nodes by their serial id, interior ones by their element."""
    lm_type = multiplier_type(lm)
    n_lm_local = lm_numbering(sub_beams, lm_type)[1]
    lm_serial = np.empty(n_lm_local, dtype=np.int64)
    lm_serial[:sub_beams.n_nodes] = beam_nodes
    n_int = lm_type.n_interior
    if n_int:
        lm_serial[sub_beams.n_nodes:] = (n_nodes + n_int * owned[:, None] + np.arange(n_int)[None, :]).ravel()
    return lm_serial


@dataclass
class DistributedOperators:
    """D, M (PETSc ``MPIAIJ``) and κ (PETSc ``MPI`` vector) of one beam group, rank-major numbering.

    Attributes
    ----------
    D : petsc4py.PETSc.Mat, (3 n_lm, n_beam_centreline_dofs)
    M : petsc4py.PETSc.Mat, (3 n_lm, 3 n_solid_nodes)
    kappa : petsc4py.PETSc.Vec, (n_lm,)
    local : LocalOperators
        This rank's part before the assembly.
    """

    D: object
    M: object
    kappa: object
    local: LocalOperators

    def gathered(self):
        """(D, M, κ) as scipy CSR matrices and an array on every rank (for checks and output; not
        for large models)."""
        return gather_matrix(self.D), gather_matrix(self.M), gather_vector(self.kappa)


def assemble_distributed(solid, beams, partition, numbering, group=0, comm=None, **options):
    """D, M and κ of beam group ``group`` assembled over the ranks of ``comm`` (see the module docstring).

    Parameters
    ----------
    solid : SolidMesh
    beams : BeamMesh
        The group's beams (every rank holds the meshes; each assembles only what it owns).
    partition : Partition
        With ``n_parts`` equal to the size of ``comm``.
    numbering : Numbering
    comm : petsc4py.PETSc.Comm, optional
        Default ``PETSc.COMM_WORLD``.
    **options
        ``integration``, ``n_gauss``, ``lm``, ``search_points`` of :func:`~mortar1d3d.assemble_mortar`.

    Returns
    -------
    DistributedOperators
    """
    PETSc = petsc()
    comm = PETSc.COMM_WORLD if comm is None else comm
    rank, size = comm.getRank(), comm.getSize()
    if partition.n_parts != size:
        raise ValueError(f"the partition has {partition.n_parts} parts for {size} ranks")
    loc = local_operators(solid, beams, partition, numbering, rank, group, **options)
    lm_num, beam_num, solid_num = numbering.lm[group], numbering.beams[group], numbering.solid
    per_node = beams.n_centreline_dofs // beams.n_nodes
    rows = 3 * lm_num.count(rank), 3 * lm_num.n
    D = coo_matrix(comm, *loc.D, rows, (per_node * beam_num.count(rank), per_node * beam_num.n))
    M = coo_matrix(comm, *loc.M, rows, (3 * solid_num.count(rank), 3 * solid_num.n))
    kappa = summed_vector(comm, *loc.kappa, (lm_num.count(rank), lm_num.n))
    return DistributedOperators(D, M, kappa, loc)


def renumbered(A, row_map, col_map, shape):
    """Serial scipy matrix ``A`` with rows and columns moved to new ids (``row_map[old]``, ``col_map[old]``)."""
    A = A.tocoo()
    return sp.csr_matrix((A.data, (row_map[A.row], col_map[A.col])), shape=shape)
