"""Integration points of the coupling integrals.

Both rules produce the same record per point: beam element, solid element, η, ξ (the solid
parameter coordinates of r(η), Newton projection in the reference configuration), the weight
``w_g · (η_b - η_a)/2 · |r'(η_g)|`` (so that Σ weight = coupled arc length) and the outcome of
the projection. Only the set of points differs (design.md §1):

- segment-based: ``n_gauss`` points on every segment [η_a, η_b], in its owning element;
- element-based: ``n_gauss`` points on the whole beam element, each given to the lowest-index
  candidate element that contains it; points inside no element are not coupled.
"""
import numpy as np
from numba import prange

from .._config import CHUNK, PARAMETER_TOL, njit_parallel
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from ..geometry.beam import beam_point
from ..geometry.linalg import n_chunks, norm3
from ..geometry.projection import (CONVERGED, INSIDE, NOT_CONVERGED, OUTSIDE, first_containing, load_element,
                                   polish, project_point)
from ..geometry.segmentation import resegment, splice
from .quadrature import gauss_legendre

#: point outcome codes (as stored in ``status``)
POINT_INSIDE, POINT_OUTSIDE, POINT_NOT_CONVERGED, POINT_UNCOUPLED = INSIDE, OUTSIDE, NOT_CONVERGED, 3


@njit_parallel
def _segment_points(seg_beam, seg_solid, seg_start, seg_end, gx, gw, codes, conn, points,
                    solid_origin, solid_h, beam_code, Q, lengths, beam_origin,
                    eta, xi, weight, position, status):
    n_gauss = gx.shape[0]
    n_seg = seg_beam.shape[0]
    loose = 1e3 * PARAMETER_TOL
    for c in prange(n_chunks(n_seg, CHUNK)):
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        x = np.empty(3)
        trial = np.empty(3)
        for g in range(c * CHUNK, min(n_seg, (c + 1) * CHUNK)):
            e = seg_beam[g]
            s = seg_solid[g]
            code = codes[s]
            load_element(points, conn, s, code, solid_origin, X)
            s0 = beam_origin[e, 0] - solid_origin[s, 0]
            s1 = beam_origin[e, 1] - solid_origin[s, 1]
            s2 = beam_origin[e, 2] - solid_origin[s, 2]
            half = 0.5 * (seg_end[g] - seg_start[g])
            mid = 0.5 * (seg_end[g] + seg_start[g])
            solid.centre(code, x)
            for q in range(n_gauss):
                k = g * n_gauss + q
                eta[k] = mid + half * gx[q]
                r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Q[e], lengths[e], s0, s1, s2, eta[k], H, dH)
                weight[k] = gw[q] * half * norm3(d0, d1, d2)
                position[k, 0] = r0 + solid_origin[s, 0]
                position[k, 1] = r1 + solid_origin[s, 1]
                position[k, 2] = r2 + solid_origin[s, 2]
                # warm start from the previous point of the segment; retry from the centre
                if project_point(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN) != CONVERGED:
                    solid.centre(code, x)
                    if project_point(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN) != CONVERGED:
                        status[k] = NOT_CONVERGED
                        solid.centre(code, x)
                        xi[k] = x
                        continue
                polish(code, X, r0, r1, r2, x, trial, N, dN)
                xi[k] = x
                # a segment lies in its element: a point clearly outside means a missed
                # crossing; it is reported, not hidden
                status[k] = INSIDE if solid.is_inside(code, x, loose) else OUTSIDE


@njit_parallel
def _element_points(pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h,
                    solid_boxes, beam_code, Q, lengths, beam_origin,
                    owner, eta, xi, weight, position, status):
    n_gauss = gx.shape[0]
    n_beam = pair_offsets.shape[0] - 1
    tol = PARAMETER_TOL
    for c in prange(n_chunks(n_beam, CHUNK)):
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        x = np.empty(3)
        trial = np.empty(3)
        for e in range(c * CHUNK, min(n_beam, (c + 1) * CHUNK)):
            for q in range(n_gauss):
                k = e * n_gauss + q
                eta[k] = gx[q]
                r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, gx[q], H, dH)
                weight[k] = gw[q] * norm3(d0, d1, d2)
                position[k, 0] = r0 + beam_origin[e, 0]
                position[k, 1] = r1 + beam_origin[e, 1]
                position[k, 2] = r2 + beam_origin[e, 2]
                owner[k] = -1
                status[k] = POINT_UNCOUPLED
                # the lowest-index candidate element containing the point owns it
                s = first_containing(r0, r1, r2, e, pair_solid, pair_offsets[e], pair_offsets[e + 1], beam_origin,
                                     solid_boxes, codes, conn, points, solid_origin, solid_h, tol, X, x, trial, N,
                                     dN, -1)
                if s >= 0:
                    # X still holds the owner's nodes (it was the last element tested)
                    polish(codes[s], X, r0 + (beam_origin[e, 0] - solid_origin[s, 0]),
                           r1 + (beam_origin[e, 1] - solid_origin[s, 1]),
                           r2 + (beam_origin[e, 2] - solid_origin[s, 2]), x, trial, N, dN)
                    owner[k] = s
                    status[k] = POINT_INSIDE
                    xi[k] = x


def segment_points(ctx, seg_beam, seg_solid, seg_start, seg_end, n_gauss):
    """Integration points of segment-based integration (``n_gauss`` per segment)."""
    gx, gw = gauss_legendre_arrays(n_gauss)
    n = len(seg_beam) * n_gauss
    eta, weight = np.empty(n), np.empty(n)
    xi, position = np.empty((n, 3)), np.empty((n, 3))
    status = np.empty(n, dtype=np.int64)
    _segment_points(seg_beam, seg_solid, seg_start, seg_end, gx, gw, ctx.codes, ctx.conn, ctx.points,
                    ctx.solid_origin, ctx.solid_h, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin,
                    eta, xi, weight, position, status)
    return np.repeat(seg_beam, n_gauss), np.repeat(seg_solid, n_gauss), eta, xi, weight, position, status


def checked_segment_points(ctx, segments, n_gauss, search_points, diagnostics):
    """Integration points of the segments; beam elements with a point outside its owner are re-segmented.

    A point of a segment that does not lie in (or does not converge in) its owning element
    means a missed face crossing. Such beam elements are segmented again (more search points,
    then bisection of the owner, :func:`~mortar1d3d.geometry.segmentation.resegment`) and their
    points recomputed, so that no result is built on such a point when the fallback resolves
    it; the counts go to ``diagnostics`` (``segmentation_fallbacks``,
    ``segmentation_bisections``, ``segmentation_unresolved``).

    Returns the (possibly new) segments and the points of :func:`segment_points`.
    """
    points = segment_points(ctx, *segments, n_gauss)
    for bisection in (False, True):
        bad = np.unique(points[0][points[6] != INSIDE])
        if not len(bad):
            break
        key = "segmentation_bisections" if bisection else "segmentation_fallbacks"
        diagnostics[key] = diagnostics.get(key, 0) + len(bad)
        segments = splice(segments, resegment(ctx, bad, search_points, bisection), bad)
        points = segment_points(ctx, *segments, n_gauss)
    else:
        left = len(np.unique(points[0][points[6] != INSIDE]))
        diagnostics["segmentation_unresolved"] = diagnostics.get("segmentation_unresolved", 0) + left
    return segments, points


def element_points(ctx, n_gauss):
    """Integration points of element-based integration, uncoupled points included (owner -1)."""
    gx, gw = gauss_legendre_arrays(n_gauss)
    n_beam = len(ctx.pair_offsets) - 1
    n = n_beam * n_gauss
    owner = np.empty(n, dtype=np.int64)
    eta, weight = np.empty(n), np.empty(n)
    xi, position = np.zeros((n, 3)), np.empty((n, 3))
    status = np.empty(n, dtype=np.int64)
    _element_points(ctx.pair_offsets, ctx.pair_solid, gx, gw, ctx.codes, ctx.conn, ctx.points,
                    ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.beam_code, ctx.Q, ctx.lengths,
                    ctx.beam_origin, owner, eta, xi, weight, position, status)
    return np.repeat(np.arange(n_beam), n_gauss), owner, eta, xi, weight, position, status


def gauss_legendre_arrays(n_gauss):
    x, w = gauss_legendre(n_gauss)
    return np.ascontiguousarray(x), np.ascontiguousarray(w)
