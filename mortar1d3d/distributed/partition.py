"""Partition: solid and beam elements to ranks, each beam element with the solid elements it can reach.

The coupling of a beam element touches every solid element its bounding box overlaps (the
candidate pairs of :func:`~mortar1d3d.geometry.search.find_candidate_pairs`): its mortar block M
has columns at their nodes. A partition that puts a beam element on another rank than those solid
elements sends its M entries across ranks at every assembly, so beams and solid are partitioned
together, on one graph:

* a vertex per solid element and per beam element (of every beam group);
* an edge between two solid elements that share a node, between two beam elements of one group
  that share a node, and between a beam element and every solid element whose box overlaps its box.

``method = "metis"`` cuts this graph with METIS (pymetis); ``"geometric"`` cuts the solid elements
into slabs of equal count along the longest axis of their centres and gives each beam element to
the part that owns most of its candidate solid elements (ties: the lowest part). Both are
deterministic. Each rank then holds its owned elements plus one ghost layer of solid elements
(:meth:`Partition.ghost_solid`): the elements sharing a node with an owned one and the candidate
solid elements of its owned beam elements.
"""
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..geometry.search import beam_frames, find_candidate_pairs, solid_frames

METHODS = ("metis", "geometric")


def candidate_pairs(solid, beams):
    """Candidate (beam element, solid element) pairs of one beam mesh as CSR: ``offsets`` (m + 1,),
    ``solids`` (n_pairs,) ascending per beam element (the library's broad phase)."""
    return find_candidate_pairs(beam_frames(beams)[2], solid_frames(solid)[0])


def _incidence(elements, n_nodes):
    """(n_elements, n_nodes) 0/1 CSR: element e uses node a (padding -1 ignored)."""
    elements = np.asarray(elements)
    rows = np.repeat(np.arange(len(elements)), elements.shape[1])
    cols = elements.ravel()
    keep = cols >= 0
    return sp.csr_matrix((np.ones(keep.sum()), (rows[keep], cols[keep])), shape=(len(elements), n_nodes))


def _node_neighbours(elements, n_nodes):
    """Adjacency (CSR, no diagonal) of elements that share at least one node."""
    E = _incidence(elements, n_nodes)
    A = (E @ E.T).tocsr()
    A.setdiag(0)
    A.eliminate_zeros()
    return A


@dataclass
class Partition:
    """Owner rank of every solid element and every beam element.

    Attributes
    ----------
    n_parts : int
    solid_part : (n_solid_elements,) int64
    beam_part : list of (m_g,) int64
        One array per beam group (group order).
    pairs : list of (offsets, solids)
        The candidate pairs of each beam group (:func:`candidate_pairs`).
    method : str
        ``"metis"``, ``"geometric"`` or ``"given"``.
    stats : dict
        Measured quality: ``cut_pairs`` (candidate pairs whose two elements live on different
        ranks: the M blocks assembled off-rank), ``cut_solid_edges`` (node-sharing solid
        element pairs on different ranks), ``ghost_solid`` (ghost elements summed over the
        ranks), ``solid_per_part`` and ``beam_per_part`` (owned counts).
    """

    n_parts: int
    solid_part: np.ndarray
    beam_part: list
    pairs: list
    method: str
    stats: dict = field(default_factory=dict)
    _solid_neighbours: object = None

    def owned_solid(self, rank):
        """Ascending ids of the solid elements of ``rank``."""
        return np.flatnonzero(self.solid_part == rank)

    def owned_beams(self, rank, group=0):
        """Ascending ids of the beam elements of ``group`` owned by ``rank``."""
        return np.flatnonzero(self.beam_part[group] == rank)

    def reach(self, rank, group=0):
        """Ascending ids of the solid elements that the owned beam elements of ``group`` can reach
        (their candidate solid elements): what the rank's mortar assembly needs."""
        offsets, solids = self.pairs[group]
        mine = self.owned_beams(rank, group)
        if not len(mine):
            return np.zeros(0, dtype=np.int64)
        starts, stops = offsets[mine], offsets[mine + 1]
        pick = np.concatenate([solids[a:b] for a, b in zip(starts, stops)]) if len(mine) else np.zeros(0, np.int64)
        return np.unique(pick).astype(np.int64)

    def ghost_solid(self, rank):
        """Ascending ids of the ghost solid elements of ``rank``: not owned, and sharing a node with an
        owned solid element or reached by an owned beam element (one layer)."""
        owned = self.solid_part == rank
        near = np.zeros(len(self.solid_part), dtype=bool)
        A = self._solid_neighbours
        if owned.any():
            near[np.unique(A[np.flatnonzero(owned)].indices)] = True
        for g in range(len(self.beam_part)):
            near[self.reach(rank, g)] = True
        return np.flatnonzero(near & ~owned)

    def _measure(self):
        rows, cols = self._solid_neighbours.nonzero()
        cut_solid = int(np.count_nonzero(self.solid_part[rows] != self.solid_part[cols]) // 2)
        cut_pairs = 0
        for (offsets, solids), part in zip(self.pairs, self.beam_part):
            beam_of_pair = np.repeat(np.arange(len(part)), np.diff(offsets))
            cut_pairs += int(np.count_nonzero(part[beam_of_pair] != self.solid_part[solids]))
        self.stats = {
            "cut_pairs": cut_pairs, "cut_solid_edges": cut_solid,
            "ghost_solid": int(sum(len(self.ghost_solid(r)) for r in range(self.n_parts))),
            "solid_per_part": np.bincount(self.solid_part, minlength=self.n_parts).tolist(),
            "beam_per_part": (sum(np.bincount(p, minlength=self.n_parts) for p in self.beam_part)
                              if self.beam_part else np.zeros(self.n_parts, np.int64)).tolist()}


def _check_parts(parts, n, n_parts, path):
    parts = np.asarray(parts)
    if parts.shape != (n,) or not np.issubdtype(parts.dtype, np.integer):
        raise ValueError(f"{path}: expected {n} integer ranks, got an array of shape {parts.shape} and dtype {parts.dtype}")
    bad = np.flatnonzero((parts < 0) | (parts >= n_parts))
    if bad.size:
        raise ValueError(f"{path}: ranks must be in [0, {n_parts}), not at elements {bad[:5].tolist()}")
    return parts.astype(np.int64)


def partition(solid, beam_meshes=(), n_parts=1, method="metis", *, solid_part=None, beam_part=None):
    """Owner ranks of the solid and beam elements (see the module docstring).

    Parameters
    ----------
    solid : SolidMesh
    beam_meshes : sequence of BeamMesh
        One per beam group.
    n_parts : int
        Number of ranks (>= 1). Parts may come out empty (more ranks than elements): that works.
    method : {"metis", "geometric"}
    solid_part, beam_part : arrays, optional
        A given partition instead (method ``"given"``): ranks per solid element and, per group,
        per beam element. Any assignment is accepted, also one that leaves ranks empty.

    Returns
    -------
    Partition
    """
    if isinstance(n_parts, bool) or not isinstance(n_parts, (int, np.integer)) or n_parts < 1:
        raise ValueError(f"n_parts must be an integer >= 1, got {n_parts!r}")
    beam_meshes = list(beam_meshes)
    pairs = [candidate_pairs(solid, b) for b in beam_meshes]
    neighbours = _node_neighbours(solid.connectivity, solid.n_nodes)
    if solid_part is not None or beam_part is not None:
        if solid_part is None or beam_part is None or len(beam_part) != len(beam_meshes):
            raise ValueError("a given partition needs solid_part and one beam_part array per beam group")
        sp_ = _check_parts(solid_part, solid.n_elements, n_parts, "solid_part")
        bp = [_check_parts(p, b.n_elements, n_parts, f"beam_part[{g}]") for g, (p, b) in
              enumerate(zip(beam_part, beam_meshes))]
        method = "given"
    elif method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    elif n_parts == 1:
        sp_, bp = np.zeros(solid.n_elements, np.int64), [np.zeros(b.n_elements, np.int64) for b in beam_meshes]
    elif method == "metis":
        sp_, bp = _metis(solid, beam_meshes, pairs, neighbours, n_parts)
    else:
        sp_, bp = _geometric(solid, beam_meshes, pairs, n_parts)
    out = Partition(n_parts=int(n_parts), solid_part=sp_, beam_part=bp, pairs=pairs, method=method,
                    _solid_neighbours=neighbours)
    out._measure()
    return out


def _metis(solid, beam_meshes, pairs, neighbours, n_parts):
    """METIS on the combined graph: solid elements first, then the beam elements group by group."""
    from ._require import require
    pymetis = require("pymetis")
    n_s = solid.n_elements
    blocks_rows, blocks_cols = [neighbours.nonzero()[0]], [neighbours.nonzero()[1]]
    start = n_s
    for beams, (offsets, solids) in zip(beam_meshes, pairs):
        bb = _node_neighbours(beams.elements, beams.n_nodes)
        r, c = bb.nonzero()
        blocks_rows.append(r + start)
        blocks_cols.append(c + start)
        beam_of_pair = np.repeat(np.arange(beams.n_elements), np.diff(offsets)) + start
        blocks_rows += [beam_of_pair, solids]
        blocks_cols += [solids, beam_of_pair]
        start += beams.n_elements
    rows, cols = np.concatenate(blocks_rows), np.concatenate(blocks_cols)
    A = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(start, start))
    A.sum_duplicates()
    A.sort_indices()
    xadj, adjncy = A.indptr.astype(np.int64), A.indices.astype(np.int64)
    if hasattr(pymetis, "CSRAdjacency"):
        result = pymetis.part_graph(int(n_parts), pymetis.CSRAdjacency(xadj, adjncy))
    else:
        result = pymetis.part_graph(int(n_parts), xadj=xadj, adjncy=adjncy)
    part = np.asarray(result[1], dtype=np.int64)
    out, start = [], n_s
    for beams in beam_meshes:
        out.append(part[start:start + beams.n_elements].copy())
        start += beams.n_elements
    return part[:n_s].copy(), out


def _geometric(solid, beam_meshes, pairs, n_parts):
    """Slabs of equal solid-element count along the longest axis; beams follow their candidates."""
    conn = solid.connectivity
    used = conn >= 0
    centre = (solid.points[np.where(used, conn, 0)] * used[..., None]).sum(axis=1) / used.sum(axis=1)[:, None]
    axis = int(np.argmax(np.ptp(centre, axis=0)))
    order = np.lexsort((np.arange(len(centre)), centre[:, axis]))
    solid_part = np.empty(len(centre), np.int64)
    solid_part[order] = (np.arange(len(centre)) * n_parts) // len(centre)
    out = []
    for beams, (offsets, solids) in zip(beam_meshes, pairs):
        part = np.zeros(beams.n_elements, np.int64)
        for e in range(beams.n_elements):
            cand = solids[offsets[e]:offsets[e + 1]]
            if len(cand):
                part[e] = int(np.argmax(np.bincount(solid_part[cand], minlength=n_parts)))
            elif e:
                part[e] = part[e - 1]          # outside the solid: stay with the previous element
        out.append(part)
    return solid_part, out
