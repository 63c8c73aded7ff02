"""Broad phase: candidate (beam element, solid element) pairs whose bounding boxes overlap.

Bounding boxes are conservative: the convex hull of the Bézier control points of a beam
element (Hermite: r1, r1 + L/3 t1, r2 - L/3 t2, r2) and of the Bernstein control points of a
solid element (``descriptor.bounding_matrix``) contains the element. Solid boxes are binned in
a uniform grid; each beam box visits only the grid cells it covers, so the cost is
O(n_beam + n_solid) for meshes of comparable element sizes, not O(n_beam · n_solid).
"""
import numpy as np
from numba import literal_unroll, prange

from .._config import PARAMETER_TOL, njit, njit_parallel, njit_inline
from .._memory import carve
from .._schedule import claim, new_claims, workers
from ..elements import beam as beam_functions
from ..elements.beam import CODES as _BEAM_CODES, select as _beam_kernel
from ..elements.solid.dispatch import MAX_CONTROL, MAX_NODES, N_NODES, control_points



def solid_bounding_boxes(solid, padding=PARAMETER_TOL):
    """(n_elements, 2, 3) boxes [min, max] of the solid elements, padded by ``padding``·h.

    Returns the boxes and the element sizes h (box diagonals before padding).
    """
    return solid_frames(solid, padding)[:2]


def solid_frames(solid, padding=PARAMETER_TOL):
    """:func:`solid_bounding_boxes` and each element's origin (its first node), in one pass."""
    boxes = np.empty((solid.n_elements, 2, 3))
    size = np.empty(solid.n_elements)
    origin = np.empty((solid.n_elements, 3))
    _solid_boxes(solid.points, solid.connectivity, solid.element_codes, padding, boxes, size, origin, workers())
    return boxes, size, origin


def beam_bounding_boxes(beams, padding=PARAMETER_TOL):
    """(n_elements, 2, 3) padded boxes of the beam elements, and their sizes."""
    return beam_frames(beams, padding)[2:]


def beam_frames(beams, padding=PARAMETER_TOL):
    """What the kernels need of the beam elements, in one pass.

    Returns ``Q`` (m, 4, 3): the coefficients of ``r(η) = Σ H_k q_k`` relative to the element's
    origin (its first node; tangents unchanged, unused rows zero), ``origin`` (m, 3), and the
    padded boxes (m, 2, 3) and sizes (m,) of :func:`beam_bounding_boxes`.
    """
    m = beams.n_elements
    Q, origin, boxes, size = carve(((m, 4, 3), np.float64), ((m, 3), np.float64), ((m, 2, 3), np.float64),
                                   (m, np.float64))
    tangents = beams.tangents if beams.tangents is not None else np.zeros((0, 3))
    _beam_frames(beams.positions, tangents, beams.elements, beams.lengths, beams.element_type.code, padding,
                 Q, origin, boxes, size, workers())
    return Q, origin, boxes, size


@njit_inline
def _hull_box(points, n, box):
    """The box (2, 3) of the first ``n`` rows of ``points``: a curve or element inside their convex hull
    is inside it."""
    for i in range(3):
        lo = hi = points[0, i]
        for k in range(1, n):
            lo = min(lo, points[k, i])
            hi = max(hi, points[k, i])
        box[0, i] = lo
        box[1, i] = hi


@njit
def _finish_box(box, padding):
    """Pad by ``padding`` times the diagonal plus a few ulps of the coordinates; return the diagonal."""
    size = 0.0
    big = 0.0
    for i in range(3):
        size += (box[1, i] - box[0, i]) ** 2
        big = max(big, abs(box[0, i]), abs(box[1, i]))
    size = size ** 0.5
    pad = padding * size + 8 * 2.220446049250313e-16 * big
    for i in range(3):
        box[0, i] -= pad
        box[1, i] += pad
    return size


@njit_parallel
def _solid_boxes(points, conn, codes, padding, boxes, size, origin, workers):
    claims = new_claims(conn.shape[0], workers)
    for worker in prange(workers):
        X = np.empty((MAX_NODES, 3))
        C = np.empty((MAX_CONTROL, 3))
        begin, stop = claim(claims, conn.shape[0], worker)
        while begin < stop:
            for s in range(begin, stop):
                code = codes[s]
                for a in range(N_NODES[code]):
                    for i in range(3):
                        X[a, i] = points[conn[s, a], i]
                origin[s, 0], origin[s, 1], origin[s, 2] = X[0, 0], X[0, 1], X[0, 2]
                _hull_box(C, control_points(code, X, C), boxes[s])
                size[s] = _finish_box(boxes[s], padding)
            begin, stop = claim(claims, conn.shape[0], worker)


@njit_parallel
def _beam_frames(positions, tangents, elements, lengths, code, padding, Q, origin, boxes, size, workers):
    # coefficients relative to the first node (the kernels' frame); the box from the Bézier control
    # points of the coefficients in the global frame (the curve lies in their convex hull)
    n_el = elements.shape[0]
    claims = new_claims(n_el, workers)
    for worker in prange(workers):
        zero = np.zeros(3)
        ctrl = np.empty((beam_functions.MAX_FUNCTIONS, 3))
        global_q = np.empty((beam_functions.MAX_FUNCTIONS, 3))
        begin, stop = claim(claims, n_el, worker)
        while begin < stop:
            _beam_frames_chunk(code, begin, stop, positions, tangents, elements, lengths, padding, Q, origin,
                               boxes, size, zero, ctrl, global_q)
            begin, stop = claim(claims, n_el, worker)


@njit
def _beam_frames_chunk(code, begin, stop, positions, tangents, elements, lengths, padding, Q, origin, boxes, size,
                       zero, ctrl, global_q):
    # the beam type chosen once per claimed chunk, not per element: the loop below then calls its
    # kernels directly (inlined). The choice stays out of the prange body, where a literal_unroll loop
    # would make Numba compile the parallel loop serially.
    for k in literal_unroll(_BEAM_CODES):
        if k == code:
            for e in range(begin, stop):
                nodes = elements[e]
                for i in range(3):
                    origin[e, i] = positions[nodes[0], i]
                _beam_kernel(k, "coefficients")(positions, tangents, nodes, origin[e], Q[e])
                _beam_kernel(k, "coefficients")(positions, tangents, nodes, zero, global_q)
                _hull_box(ctrl, _beam_kernel(k, "control_points")(global_q, lengths[e], ctrl), boxes[e])
                size[e] = _finish_box(boxes[e], padding)


@njit
def _cell_range(box, lower, inv_cell, dims, lo, hi):
    """Grid cells covered by ``box``; False if the box misses the grid.

    Cell coordinates are clamped in floating point before the conversion to integers, so
    boxes far outside (or huge) neither overflow nor miss the cells they touch; a box that
    touches the grid's upper face gets the last cell.
    """
    for i in range(3):
        a = (box[0, i] - lower[i]) * inv_cell
        b = (box[1, i] - lower[i]) * inv_cell
        if b < 0.0 or a > dims[i] or not (a <= b):
            return False
        lo[i] = int(np.floor(min(max(a, 0.0), dims[i] - 1.0)))
        hi[i] = int(np.floor(min(max(b, 0.0), dims[i] - 1.0)))
    return True


@njit
def _bin_part(solid_boxes, lower, inv_cell, dims, part, n_parts, counts, ids):
    """One pass over the elements of ``part``: count them per cell (``ids`` empty) or place them.

    When placing, ``counts[part, c]`` holds the part's next slot in cell c.
    """
    n_solid = solid_boxes.shape[0]
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    for s in range(part * n_solid // n_parts, (part + 1) * n_solid // n_parts):
        if _cell_range(solid_boxes[s], lower, inv_cell, dims, lo, hi):
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for k in range(lo[2], hi[2] + 1):
                        c = (i * dims[1] + j) * dims[2] + k
                        if ids.shape[0]:
                            ids[counts[part, c]] = s
                        counts[part, c] += 1


@njit_parallel
def _bin_solids(solid_boxes, lower, inv_cell, dims, n_parts):
    """CSR (offsets, ids) of the solid elements whose box covers each grid cell, ids ascending.

    A counting sort in ``n_parts`` contiguous parts of the elements (one histogram each, in
    parallel); parts are laid out in order within each cell, so the result does not depend on
    ``n_parts``.
    """
    n_cells = dims[0] * dims[1] * dims[2]
    counts = np.zeros((n_parts, n_cells), dtype=np.int64)
    for part in prange(n_parts):
        _bin_part(solid_boxes, lower, inv_cell, dims, part, n_parts, counts, np.empty(0, dtype=np.int64))
    offsets = np.empty(n_cells + 1, dtype=np.int64)
    total = 0
    for c in range(n_cells):           # counts become each part's first slot in cell c
        offsets[c] = total
        for part in range(n_parts):
            n = counts[part, c]
            counts[part, c] = total
            total += n
    offsets[n_cells] = total
    ids = np.empty(total, dtype=np.int64)
    for part in prange(n_parts):
        _bin_part(solid_boxes, lower, inv_cell, dims, part, n_parts, counts, ids)
    return offsets, ids


@njit
def _overlap(a, b):
    for i in range(3):
        if a[1, i] < b[0, i] or b[1, i] < a[0, i]:
            return False
    return True


@njit
def _cell_total(box, cell_offsets, lower, inv_cell, dims, lo, hi):
    """Number of (cell, solid) entries in the cells ``box`` covers: a bound on its candidates."""
    if not _cell_range(box, lower, inv_cell, dims, lo, hi):
        return 0
    total = 0
    for i in range(lo[0], hi[0] + 1):
        for j in range(lo[1], hi[1] + 1):
            for k in range(lo[2], hi[2] + 1):
                c = (i * dims[1] + j) * dims[2] + k
                total += cell_offsets[c + 1] - cell_offsets[c]
    return total


@njit
def _candidates_of(box, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, lo, hi, out):
    """Sorted unique solid elements overlapping ``box``, written to the front of ``out``.

    ``out`` must hold :func:`_cell_total` entries (it is the work space too). Returns the count.
    """
    if not _cell_range(box, lower, inv_cell, dims, lo, hi):
        return 0
    n = 0
    for i in range(lo[0], hi[0] + 1):
        for j in range(lo[1], hi[1] + 1):
            for k in range(lo[2], hi[2] + 1):
                c = (i * dims[1] + j) * dims[2] + k
                for q in range(cell_offsets[c], cell_offsets[c + 1]):
                    s = cell_ids[q]
                    if _overlap(box, solid_boxes[s]):
                        out[n] = s
                        n += 1
    out[:n].sort()
    m = 0
    for q in range(n):
        if q == 0 or out[q] != out[m - 1]:
            out[m] = out[q]
            m += 1
    return m


@njit_parallel
def _find_pairs(beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, workers):
    # one pass of overlap tests: each beam element gets room for every entry of the cells it
    # covers (a cheap bound), finds its sorted unique candidates in place, then the lists are packed
    n_beam = beam_boxes.shape[0]
    bound = np.zeros(n_beam + 1, dtype=np.int64)
    claims = new_claims(n_beam, workers)
    for worker in prange(workers):
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        begin, stop = claim(claims, n_beam, worker)
        while begin < stop:
            for e in range(begin, stop):
                bound[e + 1] = _cell_total(beam_boxes[e], cell_offsets, lower, inv_cell, dims, lo, hi)
            begin, stop = claim(claims, n_beam, worker)
    room = np.cumsum(bound)
    work = np.empty(room[-1], dtype=np.int64)
    counts = np.zeros(n_beam + 1, dtype=np.int64)
    claims = new_claims(n_beam, workers)
    for worker in prange(workers):
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        begin, stop = claim(claims, n_beam, worker)
        while begin < stop:
            for e in range(begin, stop):
                counts[e + 1] = _candidates_of(beam_boxes[e], solid_boxes, cell_offsets, cell_ids, lower, inv_cell,
                                               dims, lo, hi, work[room[e]:room[e + 1]])
            begin, stop = claim(claims, n_beam, worker)
    offsets = np.cumsum(counts)
    solids = np.empty(offsets[-1], dtype=np.int64)
    claims = new_claims(n_beam, workers)
    for worker in prange(workers):
        begin, stop = claim(claims, n_beam, worker)
        while begin < stop:
            for e in range(begin, stop):
                for q in range(counts[e + 1]):
                    solids[offsets[e] + q] = work[room[e] + q]
            begin, stop = claim(claims, n_beam, worker)
    return offsets, solids


@njit
def _grid_extent(boxes, lower, upper, sizes):
    """Bounds of all boxes and the largest extent of each (one pass)."""
    lower[:] = np.inf
    upper[:] = -np.inf
    for s in range(boxes.shape[0]):
        size = 0.0
        for i in range(3):
            lower[i] = min(lower[i], boxes[s, 0, i])
            upper[i] = max(upper[i], boxes[s, 1, i])
            size = max(size, boxes[s, 1, i] - boxes[s, 0, i])
        sizes[s] = size


def find_candidate_pairs(beam_boxes, solid_boxes):
    """Candidate pairs as CSR over beam elements: ``offsets`` (n_beam + 1,), ``solids`` (n_pairs,).

    The solid elements of each beam element are sorted ascending (the ownership rules rely on
    it). Exactly the pairs whose boxes overlap are returned (tests compare with brute force).
    """
    lower = np.empty(3)
    upper = np.empty(3)
    sizes = np.empty(len(solid_boxes))
    _grid_extent(solid_boxes, lower, upper, sizes)
    extent = np.maximum(upper - lower, 1e-300)
    cell = max(float(np.median(sizes)), float(extent.max()) / 256.0)
    # keep the grid at most a few cells per element
    while np.prod(np.ceil(extent / cell)) > 8 * len(solid_boxes) + 64:
        cell *= 1.25
    dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
    # one part per thread, at most 4 (each part holds a count per grid cell)
    offsets_c, ids = _bin_solids(solid_boxes, lower, 1.0 / cell, dims, min(4, workers()))
    return _find_pairs(beam_boxes, solid_boxes, offsets_c, ids, lower, 1.0 / cell, dims, workers())
