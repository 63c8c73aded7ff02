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

from .._config import PARAMETER_TOL, njit_parallel
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from ..geometry.beam import beam_point
from ..geometry.linalg import norm3
from ..geometry.projection import CONVERGED, INSIDE, NOT_CONVERGED, OUTSIDE, load_element, locate, project_point

#: point outcome codes (as stored in ``status``)
POINT_INSIDE, POINT_OUTSIDE, POINT_NOT_CONVERGED, POINT_UNCOUPLED = INSIDE, OUTSIDE, NOT_CONVERGED, 3


@njit_parallel
def _segment_points(seg_beam, seg_solid, seg_start, seg_end, gx, gw, codes, conn, points,
                    solid_origin, solid_h, beam_code, Q, lengths, beam_origin,
                    eta, xi, weight, position, status):
    n_gauss = gx.shape[0]
    tol = PARAMETER_TOL
    for g in prange(seg_beam.shape[0]):
        e = seg_beam[g]
        s = seg_solid[g]
        code = codes[s]
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        r = np.empty(3)
        dr = np.empty(3)
        shift = np.empty(3)
        x = np.empty(3)
        load_element(points, conn, s, code, solid_origin, X)
        for i in range(3):
            shift[i] = beam_origin[e, i] - solid_origin[s, i]
        half = 0.5 * (seg_end[g] - seg_start[g])
        mid = 0.5 * (seg_end[g] + seg_start[g])
        solid.centre(code, x)
        for q in range(n_gauss):
            k = g * n_gauss + q
            eta[k] = mid + half * gx[q]
            beam_point(beam_code, Q[e], lengths[e], shift, eta[k], H, dH, r, dr)
            weight[k] = gw[q] * half * norm3(dr)
            for i in range(3):
                position[k, i] = r[i] + solid_origin[s, i]
            # warm start from the previous point of the segment (same element, nearby)
            if project_point(code, X, r, solid_h[s], x, N, dN) != CONVERGED:
                solid.centre(code, x)
                if project_point(code, X, r, solid_h[s], x, N, dN) != CONVERGED:
                    status[k] = NOT_CONVERGED
                    solid.centre(code, x)
                    xi[k] = x
                    continue
            xi[k] = x
            # a segment lies in its element: a point outside by more than the tolerance
            # means a crossing was missed; it is reported, not hidden
            status[k] = INSIDE if solid.is_inside(code, x, 1e3 * tol) else OUTSIDE


@njit_parallel
def _element_points(pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h,
                    solid_boxes, beam_code, Q, lengths, beam_origin,
                    owner, eta, xi, weight, position, status):
    n_gauss = gx.shape[0]
    tol = PARAMETER_TOL
    for e in prange(pair_offsets.shape[0] - 1):
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        r = np.empty(3)
        dr = np.empty(3)
        zero = np.zeros(3)
        x = np.empty(3)
        xl = np.empty(3)
        for q in range(n_gauss):
            k = e * n_gauss + q
            eta[k] = gx[q]
            beam_point(beam_code, Q[e], lengths[e], zero, gx[q], H, dH, r, dr)
            weight[k] = gw[q] * norm3(dr)
            for i in range(3):
                position[k, i] = r[i] + beam_origin[e, i]
            owner[k] = -1
            status[k] = POINT_UNCOUPLED
            for p in range(pair_offsets[e], pair_offsets[e + 1]):
                s = pair_solid[p]
                inside_box = True
                for i in range(3):
                    if position[k, i] < solid_boxes[s, 0, i] or position[k, i] > solid_boxes[s, 1, i]:
                        inside_box = False
                if not inside_box:
                    continue
                code = codes[s]
                load_element(points, conn, s, code, solid_origin, X)
                for i in range(3):
                    xl[i] = r[i] + (beam_origin[e, i] - solid_origin[s, i])
                if locate(code, X, xl, solid_h[s], tol, x, N, dN) == INSIDE:
                    owner[k] = s
                    status[k] = POINT_INSIDE
                    xi[k] = x
                    break


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
    from .quadrature import gauss_legendre
    x, w = gauss_legendre(n_gauss)
    return np.ascontiguousarray(x), np.ascontiguousarray(w)
