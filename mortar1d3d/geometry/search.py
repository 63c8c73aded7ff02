"""Broad phase: candidate (beam element, solid element) pairs whose bounding boxes overlap.

Bounding boxes are conservative: the convex hull of the Bézier control points of a beam
element (Hermite: r1, r1 + L/3 t1, r2 - L/3 t2, r2) and of the Bernstein control points of a
solid element (``descriptor.bounding_matrix``) contains the element. Solid boxes are binned in
a uniform grid; each beam box visits only the grid cells it covers, so the cost is
O(n_beam + n_solid) for meshes of comparable element sizes, not O(n_beam · n_solid).

Boxes are loose for elements whose faces are oblique to the axes (the six tetrahedra of a
cube's Kuhn split share one box): :func:`solid_hulls` bounds each element by planes along its
faces as well, and :func:`hull_pairs` drops the pairs those planes separate, the same test
:func:`in_hull` makes per point.
"""
import numpy as np
from numba import types

from .._config import PARAMETER_TOL, njit, njit_inline
from .._borrowed import borrowed
from .._memory import carve
from .._parallel import in_parallel
from .._unlinked import unlinked
from .._schedule import claim, new_claims, workers
from ..elements import beam as beam_functions
from ..elements.beam import CODES as _BEAM_CODES, select as _beam_kernel
from ..elements.solid.dispatch import (FACE_CORNERS, HULL_TEST, MAX_CONTROL, MAX_FACES, MAX_NODES, N_CORNERS,
                                       N_FACE_CORNERS, N_FACES, N_NODES, RATIONAL, control_points)



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


@njit
def _solid_boxes(points, conn, codes, padding, boxes, size, origin, workers):
    claims = new_claims(conn.shape[0], workers)
    _solid_boxes_workers(workers, claims, points, conn, codes, padding, boxes, size, origin)


@njit
def _solid_boxes_worker(worker, claims, points, conn, codes, padding, boxes, size, origin):
    X = np.empty((MAX_NODES, 3))
    C = np.empty((MAX_CONTROL, 3))
    begin, stop = claim(claims, conn.shape[0], worker)
    while begin < stop:
        _solid_boxes_chunk(begin, stop, points, conn, codes, padding, boxes, size, origin, X, C)
        begin, stop = claim(claims, conn.shape[0], worker)


@njit_inline
def _solid_boxes_chunk(begin, stop, points, conn, codes, padding, boxes, size, origin, X, C):
    # the caller holds every array for this call: the calls per element pass them without reference
    # counting (see mortar1d3d._borrowed)
    points, conn, codes, boxes, size, origin, X, C = borrowed(points, conn, codes, boxes, size, origin, X, C)
    for s in range(begin, stop):
        code = codes[s]
        for a in range(N_NODES[code]):
            for i in range(3):
                X[a, i] = points[conn[s, a], i]
        origin[s, 0], origin[s, 1], origin[s, 2] = X[0, 0], X[0, 1], X[0, 2]
        _hull_box(C, control_points(code, X, C), boxes[s])
        size[s] = _finish_box(boxes[s], padding)


#: the kernels' workers run on the package's one parallel loop (see mortar1d3d._parallel); a worker is
#: compiled on its own and called through a symbol, so the loop bodies it inlines (``_X_chunk``,
#: ``njit_inline``: one function compiled instead of a worker and a chunk function) are optimised once
_solid_boxes_workers = in_parallel(_solid_boxes_worker)


@njit
def _beam_frames(positions, tangents, elements, lengths, code, padding, Q, origin, boxes, size, workers):
    # coefficients relative to the first node (the kernels' frame); the box from the Bézier control
    # points of the coefficients in the global frame (the curve lies in their convex hull)
    claims = new_claims(elements.shape[0], workers)
    _beam_frames_workers(workers, claims, positions, tangents, elements, lengths, code, padding, Q, origin, boxes, size)


@njit
def _beam_frames_worker(worker, claims, positions, tangents, elements, lengths, code, padding, Q, origin, boxes, size):
    n_el = elements.shape[0]
    zero = np.zeros(3)
    ctrl = np.empty((beam_functions.MAX_FUNCTIONS, 3))
    global_q = np.empty((beam_functions.MAX_FUNCTIONS, 3))
    begin, stop = claim(claims, n_el, worker)
    while begin < stop:
        _beam_frames_chunk_call(code, begin, stop, positions, tangents, elements, lengths, padding, Q,
                                origin, boxes, size, zero, ctrl, global_q)
        begin, stop = claim(claims, n_el, worker)


@njit
def _beam_frames_chunk(k, begin, stop, positions, tangents, elements, lengths, padding, Q, origin, boxes, size,
                       zero, ctrl, global_q):
    # k, the beam type, is a literal: this function is compiled per type (``cases`` of its call below),
    # each calling its type's kernels directly (inlined), and only for the types a scene uses. The
    # choice is made by the call, not by a literal_unroll loop in the prange body (which would make
    # Numba compile the parallel loop serially).
    for e in range(begin, stop):
        nodes = elements[e]
        for i in range(3):
            origin[e, i] = positions[nodes[0], i]
        _beam_kernel(k, "coefficients")(positions, tangents, nodes, origin[e], Q[e])
        _beam_kernel(k, "coefficients")(positions, tangents, nodes, zero, global_q)
        _hull_box(ctrl, _beam_kernel(k, "control_points")(global_q, lengths[e], ctrl), boxes[e])
        size[e] = _finish_box(boxes[e], padding)


#: called once per chunk through a symbol, not compiled into the kernel again, and compiled per beam type
#: when a scene first uses it (see mortar1d3d._unlinked)
_beam_frames_chunk_call = unlinked(_beam_frames_chunk, returns=types.none, cases=_BEAM_CODES)
_beam_frames_workers = in_parallel(_beam_frames_worker)


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
def _bin_part(part, solid_boxes, lower, inv_cell, dims, n_parts, counts, ids):
    """One pass over the elements of ``part``: count them per cell (``ids`` empty) or place them.

    When placing, ``counts[part, c]`` holds the part's next slot in cell c. A worker of
    :func:`_bin_solids` (one per part, see mortar1d3d._parallel).
    """
    solid_boxes, lower, dims, counts, ids = borrowed(solid_boxes, lower, dims, counts, ids)
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


_bin_parts = in_parallel(_bin_part)


@njit
def _bin_solids(solid_boxes, lower, inv_cell, dims, n_parts):
    """CSR (offsets, ids) of the solid elements whose box covers each grid cell, ids ascending.

    A counting sort in ``n_parts`` contiguous parts of the elements (one histogram each, in
    parallel); parts are laid out in order within each cell, so the result does not depend on
    ``n_parts``.
    """
    n_cells = dims[0] * dims[1] * dims[2]
    counts = np.zeros((n_parts, n_cells), dtype=np.int64)
    _bin_parts(n_parts, solid_boxes, lower, inv_cell, dims, n_parts, counts, np.empty(0, dtype=np.int64))
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
    _bin_parts(n_parts, solid_boxes, lower, inv_cell, dims, n_parts, counts, ids)
    return offsets, ids


@njit_inline
def _overlap(box, boxes, s):
    """Whether ``box`` and ``boxes[s]`` overlap (inlined: no view of the row, no reference counting)."""
    for i in range(3):
        if box[1, i] < boxes[s, 0, i] or boxes[s, 1, i] < box[0, i]:
            return False
    return True


#: candidate lists up to this long are sorted in place by insertion (longer ones by numpy's sort)
_INSERTION_SORT_MAX = 32


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
def _sort_front(out, n):
    """Sort the first ``n`` entries of ``out`` in place (numpy's sort)."""
    out[:n].sort()


#: a candidate list longer than _INSERTION_SORT_MAX is rare (a beam element's box over many solid
#: elements): numpy's sort (about 1 CPU s of a first compile) is compiled when a scene first has one
_sort_front_call = unlinked(_sort_front, returns=types.none)


@njit
def _candidates_of(box, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, lo, hi, out, seen, stamp):
    """Sorted unique solid elements overlapping ``box``, written to the front of ``out``.

    ``out`` must hold :func:`_cell_total` entries. ``seen`` (one entry per solid element) marks the
    elements met so far with ``stamp``, unique to this box (the beam element): an element whose box
    covers several of the grid cells is tested and listed once. Returns the count.
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
                    if seen[s] == stamp:
                        continue
                    seen[s] = stamp
                    if _overlap(box, solid_boxes, s):
                        out[n] = s
                        n += 1
    if n > _INSERTION_SORT_MAX:
        _sort_front_call(out, n)
        return n
    for a in range(1, n):                    # insertion sort: a few candidates per box, no call
        s = out[a]
        b = a
        while b > 0 and out[b - 1] > s:
            out[b] = out[b - 1]
            b -= 1
        out[b] = s
    return n


#: called once per beam element through a symbol, not compiled into _find_pairs' parallel body and
#: kernel again (see mortar1d3d._unlinked)
_candidates_of_call = unlinked(_candidates_of)


@njit
def _find_pairs(beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, workers):
    # one pass of overlap tests: each beam element gets room for every entry of the cells it
    # covers (a cheap bound), finds its sorted unique candidates in place, then the lists are packed
    n_beam = beam_boxes.shape[0]
    bound = np.zeros(n_beam + 1, dtype=np.int64)
    claims = new_claims(n_beam, workers)
    _cell_totals_workers(workers, claims, beam_boxes, cell_offsets, lower, inv_cell, dims, bound)
    room = np.cumsum(bound)
    work = np.empty(room[-1], dtype=np.int64)
    counts = np.zeros(n_beam + 1, dtype=np.int64)
    claims = new_claims(n_beam, workers)
    _candidates_workers(workers, claims, beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, work,
                        room, counts)
    offsets = np.cumsum(counts)
    solids = np.empty(offsets[-1], dtype=np.int64)
    claims = new_claims(n_beam, workers)
    _pack_workers(workers, claims, counts, offsets, room, work, solids)
    return offsets, solids


@njit
def _cell_totals_worker(worker, claims, beam_boxes, cell_offsets, lower, inv_cell, dims, bound):
    n_beam = beam_boxes.shape[0]
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _cell_totals_chunk(begin, stop, beam_boxes, cell_offsets, lower, inv_cell, dims, lo, hi, bound)
        begin, stop = claim(claims, n_beam, worker)


@njit
def _candidates_worker(worker, claims, beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, work,
                       room, counts):
    n_beam = beam_boxes.shape[0]
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    seen = np.full(solid_boxes.shape[0], -1, dtype=np.int64)
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _candidates_chunk(begin, stop, beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims,
                          lo, hi, work, room, counts, seen)
        begin, stop = claim(claims, n_beam, worker)


@njit
def _pack_worker(worker, claims, counts, offsets, room, work, solids):
    n_beam = counts.shape[0] - 1
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _pack_chunk(begin, stop, counts, offsets, room, work, solids)
        begin, stop = claim(claims, n_beam, worker)


@njit_inline
def _cell_totals_chunk(begin, stop, beam_boxes, cell_offsets, lower, inv_cell, dims, lo, hi, bound):
    beam_boxes, cell_offsets, lower, dims, lo, hi, bound = borrowed(beam_boxes, cell_offsets, lower, dims, lo, hi,
                                                                    bound)
    for e in range(begin, stop):
        bound[e + 1] = _cell_total(beam_boxes[e], cell_offsets, lower, inv_cell, dims, lo, hi)


@njit_inline
def _candidates_chunk(begin, stop, beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, inv_cell, dims, lo, hi, work,
                      room, counts, seen):
    # the caller holds every array for this call: the call per beam element passes them without
    # reference counting (see mortar1d3d._borrowed)
    beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, dims, lo, hi, work, room, counts, seen = borrowed(
        beam_boxes, solid_boxes, cell_offsets, cell_ids, lower, dims, lo, hi, work, room, counts, seen)
    for e in range(begin, stop):
        counts[e + 1] = _candidates_of_call(beam_boxes[e], solid_boxes, cell_offsets, cell_ids, lower, inv_cell,
                                            dims, lo, hi, work[room[e]:room[e + 1]], seen, e)


@njit_inline
def _pack_chunk(begin, stop, counts, offsets, room, work, solids):
    for e in range(begin, stop):
        for q in range(counts[e + 1]):
            solids[offsets[e] + q] = work[room[e] + q]


_cell_totals_workers = in_parallel(_cell_totals_worker)
_candidates_workers = in_parallel(_candidates_worker)
_pack_workers = in_parallel(_pack_worker)


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


#: the planes of :func:`hull_planes` lie this far (relative to the element size h) outside the
#: element's control points. A point accepted by an inside test at tolerance τ (parameter units;
#: the loosest in the library is 1e-6, the integration points' check) lies within |∂x/∂ξ| τ of the
#: element, and |∂x/∂ξ| is a few h for a polynomial element (degree × the spread of its control
#: points per parameter unit): the margin is about 1e2-1e3 times that. Rational elements get it
#: times (w_max / w_min)², which bounds how much their weights can stretch the derivatives.
HULL_MARGIN = 1e-3
#: round-off of coordinates shifted between frames, relative to their magnitude (16 ulps): added to
#: every plane's offset and pair test
_SHIFT_ROUND_OFF = 16 * 2.220446049250313e-16
#: beam elements: parameters up to this far (relative, η units) outside [-1, 1] count (crossings
#: are accepted at η within 1e-9 of the element's ends), so their points lie within this fraction
#: of the beam box's diagonal outside the hull of its control points
BEAM_HULL_MARGIN = 1e-6


@njit
def hull_planes(code, X, C, pad, planes):
    """Half-spaces containing an element (local nodes ``X``, column 3 ignored): ``planes`` (MAX_FACES, 4).

    Row f: a unit normal n_f of face f (from the face's corners: the cross product of the
    diagonals of a quadrilateral, of two edges of a triangle, turned away from the corners'
    centroid) and the offset max_k n_f·C_k + ``pad`` over the element's control points C_k
    (``C``: scratch, MAX_CONTROL rows). The element lies in the hull of its control points, so
    in every half-space n_f·x <= offset, whatever the normal: the corners only choose directions
    along which the bound is tight. Rows beyond the element's faces (and faces with a degenerate
    normal) are 0, 0, 0, 0: no bound.
    """
    n_ctrl = control_points(code, X, C)
    m = N_CORNERS[code]
    c0 = c1 = c2 = 0.0
    for a in range(m):
        c0 += X[a, 0]
        c1 += X[a, 1]
        c2 += X[a, 2]
    c0, c1, c2 = c0 / m, c1 / m, c2 / m
    for f in range(MAX_FACES):
        for i in range(4):
            planes[f, i] = 0.0
        k = N_FACE_CORNERS[code, f]
        if f >= N_FACES[code] or k < 3:
            continue
        a, b, c = FACE_CORNERS[code, f, 0], FACE_CORNERS[code, f, 1], FACE_CORNERS[code, f, 2]
        if k == 4:
            d = FACE_CORNERS[code, f, 3]
            u0, u1, u2 = X[c, 0] - X[a, 0], X[c, 1] - X[a, 1], X[c, 2] - X[a, 2]
            v0, v1, v2 = X[d, 0] - X[b, 0], X[d, 1] - X[b, 1], X[d, 2] - X[b, 2]
        else:
            u0, u1, u2 = X[b, 0] - X[a, 0], X[b, 1] - X[a, 1], X[b, 2] - X[a, 2]
            v0, v1, v2 = X[c, 0] - X[a, 0], X[c, 1] - X[a, 1], X[c, 2] - X[a, 2]
        n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
        length = (n0 * n0 + n1 * n1 + n2 * n2) ** 0.5
        if not length > 0.0:
            continue
        f0 = f1 = f2 = 0.0
        for j in range(k):
            q = FACE_CORNERS[code, f, j]
            f0 += X[q, 0]
            f1 += X[q, 1]
            f2 += X[q, 2]
        if n0 * (f0 / k - c0) + n1 * (f1 / k - c1) + n2 * (f2 / k - c2) < 0.0:
            length = -length
        n0, n1, n2 = n0 / length, n1 / length, n2 / length
        top = -np.inf
        for q in range(n_ctrl):
            top = max(top, n0 * C[q, 0] + n1 * C[q, 1] + n2 * C[q, 2])
        planes[f, 0], planes[f, 1], planes[f, 2], planes[f, 3] = n0, n1, n2, top + pad


@njit
def _solid_hulls(points, conn, codes, solid_origin, solid_h, margin, needed, hull, workers):
    claims = new_claims(conn.shape[0], workers)
    _solid_hulls_workers(workers, claims, points, conn, codes, solid_origin, solid_h, margin, needed, hull)


@njit
def _solid_hulls_worker(worker, claims, points, conn, codes, solid_origin, solid_h, margin, needed, hull):
    n = conn.shape[0]
    X = np.empty((MAX_NODES, 3))
    C = np.empty((MAX_CONTROL, 3))
    begin, stop = claim(claims, n, worker)
    while begin < stop:
        _solid_hulls_chunk(begin, stop, points, conn, codes, solid_origin, solid_h, margin, needed, hull, X, C)
        begin, stop = claim(claims, n, worker)


@njit_inline
def _solid_hulls_chunk(begin, stop, points, conn, codes, solid_origin, solid_h, margin, needed, hull, X, C):
    points, conn, codes, solid_origin, solid_h, needed, hull, X, C = borrowed(points, conn, codes, solid_origin,
                                                                             solid_h, needed, hull, X, C)
    for s in range(begin, stop):
        code = codes[s]
        if not (HULL_TEST[code] and needed[s]):
            for f in range(hull.shape[1]):
                for i in range(4):
                    hull[s, f, i] = 0.0     # no bound
            continue
        spread = 1.0
        if RATIONAL[code] and points.shape[1] > 3:
            lo = hi = points[conn[s, 0], 3]
            for a in range(1, N_NODES[code]):
                lo = min(lo, points[conn[s, a], 3])
                hi = max(hi, points[conn[s, a], 3])
            spread = (hi / lo) ** 2
        big = 0.0
        for a in range(N_NODES[code]):
            for i in range(3):
                X[a, i] = points[conn[s, a], i] - solid_origin[s, i]
                big = max(big, abs(points[conn[s, a], i]))
        # round-off of the coordinates far from the origin (the kernels shift points between frames)
        _hull_planes_call(code, X, C, margin * solid_h[s] * spread + _SHIFT_ROUND_OFF * big, hull[s])


_solid_hulls_workers = in_parallel(_solid_hulls_worker)
#: lazily through a symbol (once per element): a mesh of types without hull planes (hex8) never compiles it
_hull_planes_call = unlinked(hull_planes, returns=types.none)


def solid_hulls(points, conn, codes, solid_origin, solid_h, margin=HULL_MARGIN, elements=None):
    """(n_elements, MAX_FACES, 4): the half-spaces of :func:`hull_planes` of every solid element, local to
    its origin, ``margin`` · h outside its control points (``points``: the mesh's ``kernel_points``).

    With ``elements`` (indices, repeats allowed), only those elements get their planes; every other
    row is 0, 0, 0, 0 (no bound, as for a type without planes: a test against it passes). The kernel
    input asks for the elements of its candidate pairs, the only ones any kernel tests against its
    hull: on the benchmark cubes fewer than half of the elements (a fibre bundle does not fill the
    solid), and the planes cost more per element than anything else of the search stage."""
    if not HULL_TEST[codes].any():
        # what the kernel writes for types without hull planes (no bound): a mesh of those (hex8) never
        # compiles it
        return np.zeros((conn.shape[0], MAX_FACES, 4))
    if elements is None:
        needed = np.ones(conn.shape[0], dtype=np.bool_)
    else:
        needed = np.zeros(conn.shape[0], dtype=np.bool_)
        needed[elements] = True
    hull = np.empty((conn.shape[0], MAX_FACES, 4))
    _solid_hulls(points, conn, codes, solid_origin, solid_h, margin, needed, hull, workers())
    return hull


@njit_inline
def in_hull(hull, s, x0, x1, x2):
    """Whether the point x (local to element s's origin) lies in all half-spaces of ``hull[s]``.

    False proves that x is farther than the hull's margin from the element: no inside test
    of the library accepts it (see ``HULL_MARGIN``)."""
    for f in range(hull.shape[1]):
        if hull[s, f, 0] * x0 + hull[s, f, 1] * x1 + hull[s, f, 2] * x2 > hull[s, f, 3]:
            return False
    return True


@njit_inline
def _separated(hull, s, ctrl, n_ctrl, t0, t1, t2, pad):
    """Whether a plane of ``hull[s]`` has all of ``ctrl[:n_ctrl]`` + t beyond it by more than ``pad``."""
    for f in range(hull.shape[1]):
        n0, n1, n2 = hull[s, f, 0], hull[s, f, 1], hull[s, f, 2]
        if n0 == 0.0 and n1 == 0.0 and n2 == 0.0:
            continue
        low = np.inf
        for k in range(n_ctrl):
            low = min(low, n0 * (ctrl[k, 0] + t0) + n1 * (ctrl[k, 1] + t1) + n2 * (ctrl[k, 2] + t2))
        if low > hull[s, f, 3] + pad:
            return True
    return False


@njit
def _hull_pair_counts(pair_offsets, pair_solid, hull, solid_origin, beam_code, Q, lengths, beam_origin, beam_boxes,
                      margin, keep, counts, workers):
    n_beam = pair_offsets.shape[0] - 1
    claims = new_claims(n_beam, workers)
    _hull_pair_counts_workers(workers, claims, pair_offsets, pair_solid, hull, solid_origin, beam_code, Q, lengths,
                              beam_origin, beam_boxes, margin, keep, counts)


@njit
def _hull_pair_counts_worker(worker, claims, pair_offsets, pair_solid, hull, solid_origin, beam_code, Q, lengths,
                             beam_origin, beam_boxes, margin, keep, counts):
    n_beam = pair_offsets.shape[0] - 1
    ctrl = np.empty((beam_functions.MAX_FUNCTIONS, 3))
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        for e in range(begin, stop):
            n_ctrl = beam_functions.control_points(beam_code, Q[e], lengths[e], ctrl)
            size = 0.0
            for i in range(3):
                size += (beam_boxes[e, 1, i] - beam_boxes[e, 0, i]) ** 2
            big = max(abs(beam_origin[e, 0]), abs(beam_origin[e, 1]), abs(beam_origin[e, 2]))
            pad = margin * size ** 0.5 + _SHIFT_ROUND_OFF * big
            n = 0
            for p in range(pair_offsets[e], pair_offsets[e + 1]):
                s = pair_solid[p]
                keep[p] = not _separated(hull, s, ctrl, n_ctrl, beam_origin[e, 0] - solid_origin[s, 0],
                                         beam_origin[e, 1] - solid_origin[s, 1],
                                         beam_origin[e, 2] - solid_origin[s, 2], pad)
                if keep[p]:
                    n += 1
            counts[e + 1] = n
        begin, stop = claim(claims, n_beam, worker)


_hull_pair_counts_workers = in_parallel(_hull_pair_counts_worker)


def hull_pairs(pair_offsets, pair_solid, hull, solid_origin, beam_code, Q, lengths, beam_origin, beam_boxes,
               margin=BEAM_HULL_MARGIN):
    """The candidate pairs (CSR, as :func:`find_candidate_pairs`) without those a plane of the solid
    element's ``hull`` (:func:`solid_hulls`) separates from the beam element's control points.

    A dropped pair has no point of the beam element (η within ``margin`` of [-1, 1], relative to
    the beam box) within the hull's margin of the solid element: no integration point, segment
    or face crossing. Order within each beam element is kept (ascending)."""
    n_beam = len(pair_offsets) - 1
    keep = np.empty(len(pair_solid), dtype=np.bool_)
    counts = np.zeros(n_beam + 1, dtype=np.int64)
    _hull_pair_counts(pair_offsets, pair_solid, hull, solid_origin, beam_code, Q, lengths, beam_origin, beam_boxes,
                      margin, keep, counts, workers())
    return np.cumsum(counts), pair_solid[keep]
