"""Integration points of the coupling integrals.

Both rules produce the same record per point: beam element, solid element, η, ξ (the solid
parameter coordinates of r(η), Newton projection in the reference configuration), the weight
``w_g · (η_b - η_a)/2 · |r'(η_g)|`` (so that Σ weight = coupled arc length) and the outcome of
the projection. Only the set of points differs (docs/conventions.md §1):

- segment-based: ``n_gauss`` points on every segment [η_a, η_b], in its owning element;
- element-based: ``n_gauss`` points on the whole beam element, each given to the lowest-index
  candidate element that contains it; points inside no element are not coupled;
- element_boundary: element-based, except that the beam elements crossing the solid's boundary
  get the segment-based points on their pieces inside (:func:`boundary_segmented_points`);
- auto: the segments of segment-based integration, found without the crossing search where
  possible (:mod:`~mortar1d3d.geometry.auto_segments`; beam elements certified inside one
  element keep the element-based points), and per segment the minimal exact Gauss rule where
  the integrand is a polynomial (:func:`exact_rule_counts`).
"""
import numpy as np
from numba import types

from .._borrowed import borrowed
from .._config import PARAMETER_TOL, njit
from .._memory import carve
from .._parallel import in_parallel
from .._unlinked import unlinked
from .._schedule import claim, new_claims, workers
from ..elements import beam as beam_elements
from ..elements.solid import dispatch as solid
from ..geometry.beam import AFFINE_TOL
from ..elements.beam import CODES as BEAM_CODES
from ..geometry.beam import beam_point_of
from ..geometry.linalg import norm3
from ..geometry.projection import (ANY_CANDIDATE, CONVERGED, INSIDE, NOT_CONVERGED, OUTSIDE, affine_inverse,
                                   first_containing_inline, is_affine, linear_parameters, load_element, locate_point,
                                   point_buffers, polish_residual, project_point, search_buffers)
from ..geometry.segmentation import resegment, segment
from ..quadrature import gauss_legendre, gauss_tables

#: point outcome codes (as stored in ``status``)
POINT_INSIDE, POINT_OUTSIDE, POINT_NOT_CONVERGED, POINT_UNCOUPLED = INSIDE, OUTSIDE, NOT_CONVERGED, 3


@njit
def _segment_points(seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn, points,
                    solid_origin, solid_h, linear, beam_code, Q, lengths, beam_origin,
                    eta, xi, weight, position, status, workers):
    # segment g gets the n-point rule (n = seg_points[g+1] - seg_points[g]) stored in row n of gx, gw
    claims = new_claims(seg_beam.shape[0], workers)
    _segment_points_workers(workers, claims, seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn,
                            points, solid_origin, solid_h, linear, beam_code, Q, lengths, beam_origin, eta, xi, weight,
                            position, status)


@njit
def _segment_points_worker(worker, claims, seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn,
                           points, solid_origin, solid_h, linear, beam_code, Q, lengths, beam_origin, eta, xi, weight,
                           position, status):
    n_seg = seg_beam.shape[0]
    X, N, dN, H, dH, x, trial = point_buffers()
    a, stack = search_buffers()
    begin, stop = claim(claims, n_seg, worker)
    while begin < stop:
        _segment_points_chunk_call(beam_code, begin, stop, seg_beam, seg_solid, seg_start, seg_end, seg_points,
                                   gx, gw, codes, conn, points, solid_origin, solid_h, linear, Q, lengths,
                                   beam_origin, eta, xi, weight, position, status, X, N, dN, H, dH, x, trial, a,
                                   stack)
        begin, stop = claim(claims, n_seg, worker)


@njit
def _segment_points_chunk(kb, begin, stop, seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw,
                          codes, conn, points, solid_origin, solid_h, linear, Q, lengths, beam_origin, eta,
                          xi, weight, position, status, X, N, dN, H, dH, x, trial, a, stack):
    # segments begin..stop of beam type kb, a literal: compiled per beam type (see search._beam_frames_chunk)
    # the caller holds every array for this call: the calls per point below pass them without
    # reference counting (see mortar1d3d._borrowed)
    (seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn, points, solid_origin, solid_h, linear,
     Q, lengths, beam_origin, eta, xi, weight, position, status, X, N, dN, H, dH, x, trial, a, stack) = borrowed(
        seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn, points, solid_origin, solid_h, linear,
        Q, lengths, beam_origin, eta, xi, weight, position, status, X, N, dN, H, dH, x, trial, a, stack)
    loose = 1e3 * PARAMETER_TOL
    for g in range(begin, stop):
        e = seg_beam[g]
        s = seg_solid[g]
        code = codes[s]
        n_gauss = seg_points[g + 1] - seg_points[g]
        affine = is_affine(linear, s)
        if not affine:
            load_element(points, conn, s, code, solid_origin, X)
        s0 = beam_origin[e, 0] - solid_origin[s, 0]
        s1 = beam_origin[e, 1] - solid_origin[s, 1]
        s2 = beam_origin[e, 2] - solid_origin[s, 2]
        half = 0.5 * (seg_end[g] - seg_start[g])
        mid = 0.5 * (seg_end[g] + seg_start[g])
        solid.centre(code, x)
        for q in range(n_gauss):
            k = seg_points[g] + q
            eta[k] = mid + half * gx[n_gauss, q]
            r0, r1, r2, d0, d1, d2 = beam_point_of(kb, Q[e], lengths[e], s0, s1, s2, eta[k], H, dH)
            weight[k] = gw[n_gauss, q] * half * norm3(d0, d1, d2)
            position[k, 0] = r0 + solid_origin[s, 0]
            position[k, 1] = r1 + solid_origin[s, 1]
            position[k, 2] = r2 + solid_origin[s, 2]
            if affine:
                linear_parameters(code, linear, s, r0, r1, r2, x)
                xi[k, 0], xi[k, 1], xi[k, 2] = x[0], x[1], x[2]
                status[k] = INSIDE if solid.is_inside(code, x, loose) else OUTSIDE
                continue
            # start from the linearised estimate (closer than the previous point: fewer Newton
            # iterations); if that does not end inside, locate the point for certain (a curved
            # element's map folds outside it: Newton may take that branch)
            linear_parameters(code, linear, s, r0, r1, r2, x)
            if not (project_point(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN) == CONVERGED
                    and solid.is_inside(code, x, loose)):
                status[k] = locate_point(code, X, r0, r1, r2, solid_h[s], loose, linear, s, x, trial, N, dN,
                                         a, stack)
                if status[k] == NOT_CONVERGED:
                    solid.centre(code, x)
                    xi[k, 0], xi[k, 1], xi[k, 2] = x[0], x[1], x[2]
                    continue
            # the residual of x is in trial (project_point or locate_point left it there)
            polish_residual(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN)
            xi[k, 0], xi[k, 1], xi[k, 2] = x[0], x[1], x[2]
            # a segment lies in its element: a point clearly outside means a missed
            # crossing; it is reported, not hidden
            status[k] = INSIDE if solid.is_inside(code, x, loose) else OUTSIDE


#: called once per chunk through a symbol, not compiled into the kernel again, and compiled per beam type
#: when a scene first uses it (see mortar1d3d._unlinked)
_segment_points_chunk_call = unlinked(_segment_points_chunk, returns=types.none, cases=BEAM_CODES)
#: the kernels' workers run on the package's one parallel loop (see mortar1d3d._parallel)
_segment_points_workers = in_parallel(_segment_points_worker)


@njit
def _element_points(pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h,
                    solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin,
                    beam, owner, eta, xi, weight, position, status, workers):
    claims = new_claims(pair_offsets.shape[0] - 1, workers)
    _element_points_workers(workers, claims, pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin,
                            solid_h, solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, beam, owner, eta,
                            xi, weight, position, status)


@njit
def _element_points_worker(worker, claims, pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin,
                           solid_h, solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, beam, owner, eta, xi,
                           weight, position, status):
    n_beam = pair_offsets.shape[0] - 1
    X, N, dN, H, dH, x, trial = point_buffers()
    a, stack = search_buffers()
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _element_points_chunk_call(beam_code, begin, stop, pair_offsets, pair_solid, gx, gw, codes, conn,
                                   points, solid_origin, solid_h, solid_boxes, hull, linear, Q, lengths,
                                   beam_origin, beam, owner, eta, xi, weight, position, status, X, N, dN, H, dH,
                                   x, trial, a, stack)
        begin, stop = claim(claims, n_beam, worker)


@njit
def _element_points_chunk(kb, begin, stop, pair_offsets, pair_solid, gx, gw, codes, conn, points,
                          solid_origin, solid_h, solid_boxes, hull, linear, Q, lengths, beam_origin, beam, owner,
                          eta, xi, weight, position, status, X, N, dN, H, dH, x, trial, a, stack):
    # beam elements begin..stop of beam type kb, a literal (see search._beam_frames_chunk)
    # the caller holds every array for this call: the calls per point below pass them without
    # reference counting (see mortar1d3d._borrowed)
    (pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear, Q,
     lengths, beam_origin, beam, owner, eta, xi, weight, position, status, X, N, dN, H, dH, x, trial, a,
     stack) = borrowed(pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h, solid_boxes, hull,
                       linear, Q, lengths, beam_origin, beam, owner, eta, xi, weight, position, status, X, N, dN, H,
                       dH, x, trial, a, stack)
    n_gauss = gx.shape[0]
    tol = PARAMETER_TOL
    for e in range(begin, stop):
        for q in range(n_gauss):
            k = e * n_gauss + q
            beam[k] = e
            eta[k] = gx[q]
            r0, r1, r2, d0, d1, d2 = beam_point_of(kb, Q[e], lengths[e], 0.0, 0.0, 0.0, gx[q], H, dH)
            weight[k] = gw[q] * norm3(d0, d1, d2)
            position[k, 0] = r0 + beam_origin[e, 0]
            position[k, 1] = r1 + beam_origin[e, 1]
            position[k, 2] = r2 + beam_origin[e, 2]
            owner[k] = -1
            status[k] = POINT_UNCOUPLED
            # the lowest-index candidate element containing the point owns it
            s = first_containing_inline(r0, r1, r2, e, pair_solid, pair_offsets[e], pair_offsets[e + 1],
                                        beam_origin, solid_boxes, hull, codes, conn, points, solid_origin, solid_h,
                                        linear, tol, X, x, trial, N, dN, a, stack, ANY_CANDIDATE)
            if s >= 0:
                if not is_affine(linear, s):
                    # X still holds the owner's nodes (it was the last element tested) and
                    # trial the residual of x (see locate_point)
                    polish_residual(codes[s], X, r0 + (beam_origin[e, 0] - solid_origin[s, 0]),
                           r1 + (beam_origin[e, 1] - solid_origin[s, 1]),
                           r2 + (beam_origin[e, 2] - solid_origin[s, 2]), solid_h[s], x, trial, N, dN)
                owner[k] = s
                status[k] = POINT_INSIDE
                xi[k, 0], xi[k, 1], xi[k, 2] = x[0], x[1], x[2]


#: called once per chunk through a symbol, compiled per beam type when first used, as the one above
_element_points_chunk_call = unlinked(_element_points_chunk, returns=types.none, cases=BEAM_CODES)
_element_points_workers = in_parallel(_element_points_worker)


def segment_points(ctx, seg_beam, seg_solid, seg_start, seg_end, n_gauss):
    """Integration points of segment-based integration.

    ``n_gauss``: Gauss points per segment, an int (every segment) or an (n_segments,) int array.
    """
    counts = np.broadcast_to(np.asarray(n_gauss, dtype=np.int64), seg_beam.shape)
    seg_points = np.zeros(len(seg_beam) + 1, dtype=np.int64)
    np.cumsum(counts, out=seg_points[1:])
    gx, gw = gauss_tables(int(counts.max()) if len(counts) else 1)
    n = int(seg_points[-1])
    eta, weight, xi, position, status = carve((n, np.float64), (n, np.float64), ((n, 3), np.float64),
                                              ((n, 3), np.float64), (n, np.int64))
    _segment_points(seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, ctx.codes, ctx.conn, ctx.points,
                    ctx.solid_origin, ctx.solid_h, ctx.linear, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin,
                    eta, xi, weight, position, status, workers())
    return np.repeat(seg_beam, counts), np.repeat(seg_solid, counts), eta, xi, weight, position, status


def _splice(rows, replacement, elements):
    """``rows`` (arrays whose first holds each row's beam element, ascending) with the rows of beam
    ``elements`` replaced by those of ``replacement`` (same layout); every beam element's rows stay
    together and in their order."""
    replaced = np.isin(rows[0], elements)
    parts = [np.concatenate([a[~replaced], b]) for a, b in zip(rows, replacement)]
    order = np.argsort(parts[0], kind="stable")
    return tuple(a[order] for a in parts)


def checked_segment_points(ctx, segments, bad, n_gauss, search_points, diagnostics):
    """Integration points of the segments; beam elements whose pieces fail are segmented again.

    ``segments`` and ``bad`` are those of :func:`~mortar1d3d.geometry.segmentation.segment`: a
    beam element fails when its pieces fail the tiling check (``bad``) or when one of its
    integration points does not lie in (or does not converge in) its owning element (a missed
    face crossing). Such beam elements are segmented again, with more search points and then,
    those still failing, by bisection of the owner
    (:func:`~mortar1d3d.geometry.segmentation.resegment`), and only their points recomputed, so
    that no result is built on such a point when the fallback resolves it. ``diagnostics``
    receives ``segmentation_fallbacks`` (beam elements segmented again),
    ``segmentation_bisections`` (of those, the ones that needed the bisection) and
    ``segmentation_unresolved`` (still failing afterwards).

    Returns the (possibly new) segments and the points of :func:`segment_points`.
    """
    segments = tuple(segments)
    points = segment_points(ctx, *segments, n_gauss)
    failed = bad.copy()
    failed[points[0][points[6] != INSIDE]] = True
    counts = {"segmentation_fallbacks": 0, "segmentation_bisections": 0, "segmentation_unresolved": 0}
    for key, bisection in (("segmentation_fallbacks", False), ("segmentation_bisections", True)):
        elements = np.flatnonzero(failed)
        if not len(elements):
            break
        counts[key] = len(elements)
        *again, still = resegment(ctx, elements, search_points, bisection)
        again_points = segment_points(ctx, *again, n_gauss)
        still |= np.isin(elements, again_points[0][again_points[6] != INSIDE])
        segments = _splice(segments, again, elements)
        points = _splice(points, again_points, elements)
        failed[elements] = still
    else:
        counts["segmentation_unresolved"] = int(np.count_nonzero(failed))
    diagnostics.update(counts)
    return segments, points


def element_points(ctx, n_gauss):
    """Integration points of element-based integration, uncoupled points included (owner -1)."""
    return _points_on_elements(ctx, *gauss_legendre(n_gauss))


def _points_on_elements(ctx, gx, gw):
    """The points ``gx`` (weights ``gw``) of [-1, 1] on every beam element, each in the lowest-index
    candidate element containing it (owner -1 and status POINT_UNCOUPLED where none does)."""
    n_gauss = len(gx)
    n_beam = len(ctx.pair_offsets) - 1
    n = n_beam * n_gauss
    beam, owner, eta, weight, xi, position, status = carve(
        (n, np.int64), (n, np.int64), (n, np.float64), (n, np.float64), ((n, 3), np.float64), ((n, 3), np.float64),
        (n, np.int64))
    xi[:] = 0.0                 # points no element owns keep ξ = 0
    _element_points(ctx.pair_offsets, ctx.pair_solid, gx, gw, ctx.codes, ctx.conn, ctx.points,
                    ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.hull, ctx.linear, ctx.beam_code, ctx.Q,
                    ctx.lengths, ctx.beam_origin, beam, owner, eta, xi, weight, position, status, workers())
    return beam, owner, eta, xi, weight, position, status


def boundary_segmented_points(ctx, n_gauss, search_points, diagnostics):
    """Integration points of ``integration="element_boundary"``: element-based, except on the beam
    elements that cross the solid's boundary, which are segmented.

    A beam element crosses the boundary when one of its ``n_gauss`` Gauss points or one of its two
    ends lies in no solid element. Such an element gets ``n_gauss`` Gauss points on each of its
    pieces inside a solid element (the segments of segment-based integration, with their fallback
    :func:`checked_segment_points`); its part outside the solid is not coupled. Every other beam
    element keeps the element-based points on the whole element. Taking the ends into the test
    makes the points continuous in the beam's position: the segment of an element whose end just
    left the solid is the whole element up to a sliver. ``diagnostics`` receives
    ``boundary_segmented_elements`` and the counts of :func:`checked_segment_points`.
    """
    points = element_points(ctx, n_gauss)
    ends = _points_on_elements(ctx, np.array([-1.0, 1.0]), np.zeros(2))
    crossing = np.union1d(points[0][points[6] == POINT_UNCOUPLED], ends[0][ends[6] == POINT_UNCOUPLED])
    diagnostics["boundary_segmented_elements"] = len(crossing)
    if not len(crossing):
        return points
    *segments, bad_crossing = segment(ctx.beam_subset(crossing), search_points)
    bad = np.zeros(len(ctx.pair_offsets) - 1, dtype=np.bool_)
    bad[crossing] = bad_crossing
    _, crossing_points = checked_segment_points(ctx, segments, bad, n_gauss, search_points, diagnostics)
    return _splice(points, crossing_points, crossing)


# ------------------------------------------------------------------------------------------------
# integration="auto": the minimal exact Gauss rule where the integrand is a polynomial
# ------------------------------------------------------------------------------------------------

#: degree along a straight line of the solid shape functions N(ξ(η)) when ξ(η) is affine in η, per
#: element code (hex8 trilinear: 3, hex20 serendipity: 4, hex27 triquadratic: 6, tet4: 1, tet10: 2)
LINE_DEGREE = solid.LINE_DEGREE
#: polynomial degree of the centreline functions per beam code (from the beam element descriptors)
BEAM_DEGREE = beam_elements.DEGREE


@njit
def exact_gauss_count(beam_code, solid_code, n_phi):
    """Gauss points that integrate Φ·H, Φ·N and Φ exactly on a straight beam in an affine element.

    Degrees in η: Φ_j ``n_phi - 1``, H_k ``BEAM_DEGREE``, N_a(ξ(η)) ``LINE_DEGREE`` (ξ affine in η),
    |r'| constant; an n-point Gauss rule is exact to degree 2n - 1. The one formula: the kernel
    ``_auto_gauss_counts`` calls it, and it can be called from Python.
    """
    degree = n_phi - 1 + max(BEAM_DEGREE[beam_code], LINE_DEGREE[solid_code])
    return degree // 2 + 1


@njit
def _auto_gauss_counts(seg_beam, seg_solid, codes, conn, points, solid_origin, solid_h, beam_affine, beam_code,
                       n_phi, n_gauss, counts, exact, workers):
    """Gauss points per segment: the minimal exact rule where the integrand is a polynomial, else n_gauss."""
    n_seg = seg_beam.shape[0]
    claims = new_claims(n_seg, workers)
    _auto_gauss_counts_workers(workers, claims, seg_beam, seg_solid, codes, conn, points, solid_origin, solid_h,
                               beam_affine, beam_code, n_phi, n_gauss, counts, exact)


@njit
def _auto_gauss_counts_worker(worker, claims, seg_beam, seg_solid, codes, conn, points, solid_origin, solid_h,
                              beam_affine, beam_code, n_phi, n_gauss, counts, exact):
    n_seg = seg_beam.shape[0]
    X = np.empty((solid.MAX_NODES, 4))
    Ainv = np.empty((3, 3))
    begin, stop = claim(claims, n_seg, worker)
    while begin < stop:
        for g in range(begin, stop):
            s = seg_solid[g]
            code = codes[s]
            counts[g] = n_gauss
            exact[g] = False
            if beam_affine[seg_beam[g]]:
                load_element(points, conn, s, code, solid_origin, X)
                if affine_inverse(code, X, solid_h[s], AFFINE_TOL, Ainv):
                    counts[g] = exact_gauss_count(beam_code, code, n_phi)
                    exact[g] = True
        begin, stop = claim(claims, n_seg, worker)


_auto_gauss_counts_workers = in_parallel(_auto_gauss_counts_worker)


def exact_rule_counts(ctx, seg_beam, seg_solid, beam_affine, n_phi, n_gauss):
    """Gauss points per segment of ``integration="auto"``, and how many segments have an exact rule.

    The minimal exact rule (:func:`exact_gauss_count`) where the integrand is a polynomial (a
    straight beam element, ``beam_affine``, in an affine solid element), else ``n_gauss``.
    """
    counts = np.empty(len(seg_beam), dtype=np.int64)
    exact = np.empty(len(seg_beam), dtype=np.bool_)
    _auto_gauss_counts(seg_beam, seg_solid, ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h,
                       beam_affine, ctx.beam_code, n_phi, n_gauss, counts, exact, workers())
    return counts, int(np.count_nonzero(exact))
