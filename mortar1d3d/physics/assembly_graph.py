"""Where element contributions go, and in which order: the CSR pattern and the block colouring.

Parallel assembly without races, bit-identical for any number of threads: the elements are cut
into blocks of ``block`` (64 in :class:`~mortar1d3d.physics.solid.SolidModel`) consecutive
elements, and the blocks are greedily coloured once (no two blocks of a colour share a node).
Colours are processed in order, the blocks of one colour in parallel, the elements of a block in
order, each adding its element vector and matrix directly into ``f_int`` and the CSR data of its
nodes' rows. Every entry thus receives its contributions in the same order whatever the thread
count. Blocks rather than single elements keep the writes local: consecutive elements share
nodes, so the matrix rows they touch stay in cache (colouring single elements made each colour
sweep the whole matrix). Locality thus follows the element numbering (mesh generators number
elements locally).

The CSR pattern (node graph expanded to 3×3 blocks, three DOFs per node) and, per element, the
column slot of every node pair in the block row are computed once per mesh by
:func:`assembly_graph`.
"""
from typing import NamedTuple

import numpy as np

from .._config import njit
from ..elements.solid.dispatch import N_NODES


class AssemblyGraph(NamedTuple):
    """The arrays of :func:`assembly_graph` (all int64 unless noted).

    node_ptr, neighbours : CSR of the sorted neighbour nodes (incl. itself) of every node
    slot_ptr, slots : per element, ``slots[slot_ptr[e] + a*n + b]`` (int32) = position of node b
        in the sorted neighbour list of node a
    indptr, indices : scalar CSR pattern, row ``3v+i`` holds ``3m+k`` for neighbours m, k < 3
    colour_ptr, colour_blocks : blocks (elements ``k*block`` to ``(k+1)*block - 1``) grouped by
        colour, ascending within a colour; blocks of one colour share no node
    """

    node_ptr: np.ndarray
    neighbours: np.ndarray
    slot_ptr: np.ndarray
    slots: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    colour_ptr: np.ndarray
    colour_blocks: np.ndarray


def assembly_graph(connectivity, codes, n_nodes, block):
    """CSR pattern, per-element slots and block colouring of a mesh (module docstring).

    Parameters
    ----------
    connectivity : (n_elements, m) int64, C-contiguous, m >= the nodes of every element (padded with -1)
    codes : (n_elements,) int64
        Element type codes (:data:`~mortar1d3d.elements.solid.dispatch.N_NODES` gives the nodes).
    n_nodes : int
    block : int
        Consecutive elements per coloured block, >= 1.

    Returns
    -------
    AssemblyGraph
    """
    el_ptr, node_elements = _node_elements(connectivity, codes, n_nodes)
    pattern = _pattern_kernel(connectivity, codes, n_nodes, el_ptr, node_elements)
    return AssemblyGraph(*pattern, *_colour_kernel(connectivity, codes, el_ptr, node_elements, block))


@njit
def _node_elements(connectivity, codes, n_nodes):
    """CSR node -> elements: ``node_elements[el_ptr[v]:el_ptr[v + 1]]``, ascending."""
    n_el = codes.shape[0]
    count = np.zeros(n_nodes + 1, dtype=np.int64)
    for e in range(n_el):
        for a in range(N_NODES[codes[e]]):
            count[connectivity[e, a] + 1] += 1
    el_ptr = np.cumsum(count)
    fill = el_ptr[:-1].copy()
    node_elements = np.empty(el_ptr[-1], dtype=np.int64)
    for e in range(n_el):
        for a in range(N_NODES[codes[e]]):
            v = connectivity[e, a]
            node_elements[fill[v]] = e
            fill[v] += 1
    return el_ptr, node_elements


@njit
def _pattern_kernel(connectivity, codes, n_nodes, el_ptr, node_elements):
    """Neighbour lists, per-element slots and the scalar CSR pattern (see :class:`AssemblyGraph`)."""
    n_el = codes.shape[0]
    # neighbour nodes: count, then fill and sort (short lists: insertion sort)
    stamp = np.full(n_nodes, -1, dtype=np.int64)
    degree = np.zeros(n_nodes + 1, dtype=np.int64)
    for v in range(n_nodes):
        for t in range(el_ptr[v], el_ptr[v + 1]):
            e = node_elements[t]
            for a in range(N_NODES[codes[e]]):
                m = connectivity[e, a]
                if stamp[m] != v:
                    stamp[m] = v
                    degree[v + 1] += 1
    node_ptr = np.cumsum(degree)
    neighbours = np.empty(node_ptr[-1], dtype=np.int64)
    stamp[:] = -1
    for v in range(n_nodes):
        k = node_ptr[v]
        for t in range(el_ptr[v], el_ptr[v + 1]):
            e = node_elements[t]
            for a in range(N_NODES[codes[e]]):
                m = connectivity[e, a]
                if stamp[m] != v:
                    stamp[m] = v
                    neighbours[k] = m
                    k += 1
        lo = node_ptr[v]
        for i in range(lo + 1, k):
            x = neighbours[i]
            j = i - 1
            while j >= lo and neighbours[j] > x:
                neighbours[j + 1] = neighbours[j]
                j -= 1
            neighbours[j + 1] = x
    # per element slots (binary search in the sorted neighbour lists)
    slot_ptr = np.zeros(n_el + 1, dtype=np.int64)
    for e in range(n_el):
        n = N_NODES[codes[e]]
        slot_ptr[e + 1] = slot_ptr[e] + n * n
    slots = np.empty(slot_ptr[-1], dtype=np.int32)
    for e in range(n_el):
        n = N_NODES[codes[e]]
        for a in range(n):
            v = connectivity[e, a]
            lo0 = node_ptr[v]
            for b in range(n):
                slots[slot_ptr[e] + a * n + b] = sorted_position(neighbours, lo0, node_ptr[v + 1],
                                                                 connectivity[e, b]) - lo0
    # scalar CSR pattern: the block row of node v expanded to rows 3v, 3v+1, 3v+2
    indptr = np.empty(3 * n_nodes + 1, dtype=np.int64)
    indptr[0] = 0
    indices = np.empty(9 * node_ptr[-1], dtype=np.int64)
    for v in range(n_nodes):
        deg = node_ptr[v + 1] - node_ptr[v]
        for i in range(3):
            start = 9 * node_ptr[v] + 3 * i * deg
            indptr[3 * v + i + 1] = start + 3 * deg
            for s in range(deg):
                for k in range(3):
                    indices[start + 3 * s + k] = 3 * neighbours[node_ptr[v] + s] + k
    return node_ptr, neighbours, slot_ptr, slots, indptr, indices


@njit
def _colour_kernel(connectivity, codes, el_ptr, node_elements, block):
    """Greedy colouring of blocks of ``block`` consecutive elements (see :class:`AssemblyGraph`)."""
    n_el = codes.shape[0]
    # greedy colouring of blocks of `block` consecutive elements: the smallest colour that no
    # earlier block sharing a node has
    n_blocks = (n_el + block - 1) // block
    colour = np.full(n_blocks, -1, dtype=np.int64)
    forbidden = np.full(n_blocks + 1, -1, dtype=np.int64)
    n_colours = 0
    for k in range(n_blocks):
        for e in range(k * block, min(n_el, (k + 1) * block)):
            for a in range(N_NODES[codes[e]]):
                v = connectivity[e, a]
                for t in range(el_ptr[v], el_ptr[v + 1]):
                    other = node_elements[t] // block
                    if other != k and colour[other] >= 0:
                        forbidden[colour[other]] = k
        c = 0
        while forbidden[c] == k:
            c += 1
        colour[k] = c
        if c + 1 > n_colours:
            n_colours = c + 1
    colour_count = np.zeros(n_colours + 1, dtype=np.int64)
    for k in range(n_blocks):
        colour_count[colour[k] + 1] += 1
    colour_ptr = np.cumsum(colour_count)
    fill = colour_ptr[:-1].copy()
    colour_blocks = np.empty(n_blocks, dtype=np.int64)
    for k in range(n_blocks):
        colour_blocks[fill[colour[k]]] = k
        fill[colour[k]] += 1
    return colour_ptr, colour_blocks


@njit
def sorted_position(values, first, last, target):
    """Position of ``target`` in the ascending ``values[first:last]`` (binary search), -1 if absent."""
    lo, hi = first, last
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] < target:
            lo = mid + 1
        else:
            hi = mid
    if lo < last and values[lo] == target:
        return lo
    return -1


@njit
def pattern_positions(indptr, indices, block_indptr, block_indices, row_map, col_map, positions):
    """Where each entry of a sparse block lies in a larger CSR pattern that contains it.

    Entry k of the block (CSR arrays ``block_indptr``, ``block_indices``; local row i, column j)
    is entry (``row_map[i]``, ``col_map[j]``) of the pattern (``indptr``, ``indices``, sorted
    columns in every row); its position in the pattern's data is written to ``positions[k]`` by
    binary search in that row. Returns the number of block entries not found (0 when the pattern
    contains the block; their positions are -1).
    """
    missing = 0
    for i in range(block_indptr.shape[0] - 1):
        row = row_map[i]
        first, last = indptr[row], indptr[row + 1]
        for k in range(block_indptr[i], block_indptr[i + 1]):
            positions[k] = sorted_position(indices, first, last, col_map[block_indices[k]])
            if positions[k] < 0:
                missing += 1
    return missing


@njit
def add_at_positions(data, positions, values):
    """``data[positions[k]] += values[k]`` for every k in order (repeated positions sum in entry order)."""
    for k in range(positions.shape[0]):
        data[positions[k]] += values[k]


@njit
def subtract_at_positions(data, positions, values, scale):
    """``data[positions[k]] -= scale * values[k]`` for every k in order (a load's tangent term)."""
    for k in range(positions.shape[0]):
        data[positions[k]] -= scale * values[k]


@njit
def has_zero(data):
    """Whether any entry of ``data`` equals zero (stops at the first; no temporary array)."""
    for k in range(data.shape[0]):
        if data[k] == 0.0:
            return True
    return False
