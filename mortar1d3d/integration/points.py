"""Integration points of the coupling integrals.

Both rules produce the same record per point: beam element, solid element, η, ξ (the solid
parameter coordinates of r(η), Newton projection in the reference configuration), the weight
``w_g · (η_b - η_a)/2 · |r'(η_g)|`` (so that Σ weight = coupled arc length) and the outcome of
the projection. Only the set of points differs (design.md §1):

- segment-based: ``n_gauss`` points on every segment [η_a, η_b], in its owning element;
- element-based: ``n_gauss`` points on the whole beam element, each given to the lowest-index
  candidate element that contains it; points inside no element are not coupled;
- auto (:func:`auto_segments`): the segments of segment-based integration, found without the
  crossing search where possible (closed form for straight beams in affine elements; a Bézier
  certificate for curved beam elements inside one affine element, which keep the element-based
  points), and per segment the minimal exact Gauss rule where the integrand is a polynomial.
"""
import numpy as np
from numba import prange

from .._config import PARAMETER_TOL, njit, njit_parallel
from .._memory import carve
from .._schedule import claim, new_claims, workers
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from ..geometry.beam import beam_point
from ..geometry.linalg import norm3
from ..geometry.projection import (CONVERGED, INSIDE, NOT_CONVERGED, OUTSIDE, affine_inverse, affine_parameters,
                                   first_containing, is_affine, linear_parameters, load_element, locate_point,
                                   point_buffers, polish, project_point, search_buffers)
from ..geometry.segmentation import pair_crossings, resegment, tile
from ..quadrature import gauss_legendre, gauss_tables

#: point outcome codes (as stored in ``status``)
POINT_INSIDE, POINT_OUTSIDE, POINT_NOT_CONVERGED, POINT_UNCOUPLED = INSIDE, OUTSIDE, NOT_CONVERGED, 3


@njit_parallel
def _segment_points(seg_beam, seg_solid, seg_start, seg_end, seg_points, gx, gw, codes, conn, points,
                    solid_origin, solid_h, linear, beam_code, Q, lengths, beam_origin,
                    eta, xi, weight, position, status, workers):
    # segment g gets the n-point rule (n = seg_points[g+1] - seg_points[g]) stored in row n of gx, gw
    n_seg = seg_beam.shape[0]
    loose = 1e3 * PARAMETER_TOL
    claims = new_claims(n_seg, workers)
    for worker in prange(workers):
        X, N, dN, H, dH, x, trial = point_buffers()
        a, stack = search_buffers()
        begin, stop = claim(claims, n_seg, worker)
        while begin < stop:
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
                    r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Q[e], lengths[e], s0, s1, s2, eta[k], H, dH)
                    weight[k] = gw[n_gauss, q] * half * norm3(d0, d1, d2)
                    position[k, 0] = r0 + solid_origin[s, 0]
                    position[k, 1] = r1 + solid_origin[s, 1]
                    position[k, 2] = r2 + solid_origin[s, 2]
                    if affine:
                        linear_parameters(code, linear, s, r0, r1, r2, x)
                        xi[k] = x
                        status[k] = INSIDE if solid.is_inside(code, x, loose) else OUTSIDE
                        continue
                    # warm start from the previous point of the segment (the first from the
                    # linearised estimate); if that does not end inside, locate the point for
                    # certain (a curved element's map folds outside it: Newton may take that branch)
                    if q == 0:
                        linear_parameters(code, linear, s, r0, r1, r2, x)
                    if not (project_point(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN) == CONVERGED
                            and solid.is_inside(code, x, loose)):
                        status[k] = locate_point(code, X, r0, r1, r2, solid_h[s], loose, linear, s, x, trial, N, dN,
                                                 a, stack)
                        if status[k] == NOT_CONVERGED:
                            solid.centre(code, x)
                            xi[k] = x
                            continue
                    polish(code, X, r0, r1, r2, solid_h[s], x, trial, N, dN)
                    xi[k] = x
                    # a segment lies in its element: a point clearly outside means a missed
                    # crossing; it is reported, not hidden
                    status[k] = INSIDE if solid.is_inside(code, x, loose) else OUTSIDE
            begin, stop = claim(claims, n_seg, worker)


@njit_parallel
def _element_points(pair_offsets, pair_solid, gx, gw, codes, conn, points, solid_origin, solid_h,
                    solid_boxes, linear, beam_code, Q, lengths, beam_origin,
                    beam, owner, eta, xi, weight, position, status, workers):
    n_gauss = gx.shape[0]
    n_beam = pair_offsets.shape[0] - 1
    tol = PARAMETER_TOL
    claims = new_claims(n_beam, workers)
    for worker in prange(workers):
        X, N, dN, H, dH, x, trial = point_buffers()
        a, stack = search_buffers()
        begin, stop = claim(claims, n_beam, worker)
        while begin < stop:
            for e in range(begin, stop):
                for q in range(n_gauss):
                    k = e * n_gauss + q
                    beam[k] = e
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
                                         solid_boxes, codes, conn, points, solid_origin, solid_h, linear, tol, X, x,
                                         trial, N, dN, a, stack, -1)
                    if s >= 0:
                        if not is_affine(linear, s):
                            # X still holds the owner's nodes (it was the last element tested)
                            polish(codes[s], X, r0 + (beam_origin[e, 0] - solid_origin[s, 0]),
                                   r1 + (beam_origin[e, 1] - solid_origin[s, 1]),
                                   r2 + (beam_origin[e, 2] - solid_origin[s, 2]), solid_h[s], x, trial, N, dN)
                        owner[k] = s
                        status[k] = POINT_INSIDE
                        xi[k] = x
            begin, stop = claim(claims, n_beam, worker)


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
    gx, gw = gauss_legendre(n_gauss)
    n_beam = len(ctx.pair_offsets) - 1
    n = n_beam * n_gauss
    beam, owner, eta, weight, xi, position, status = carve(
        (n, np.int64), (n, np.int64), (n, np.float64), (n, np.float64), ((n, 3), np.float64), ((n, 3), np.float64),
        (n, np.int64))
    xi[:] = 0.0                 # points no element owns keep ξ = 0
    _element_points(ctx.pair_offsets, ctx.pair_solid, gx, gw, ctx.codes, ctx.conn, ctx.points,
                    ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.linear, ctx.beam_code, ctx.Q, ctx.lengths,
                    ctx.beam_origin, beam, owner, eta, xi, weight, position, status, workers())
    return beam, owner, eta, xi, weight, position, status


# ------------------------------------------------------------------------------------------------
# integration="auto": cut only the beam elements that cross faces; exact rules where polynomial
# ------------------------------------------------------------------------------------------------

#: a map counts as affine when its nonlinear part is below AFFINE_TOL times the element size
AFFINE_TOL = 1e-12
#: a curved beam element is certified inside an affine solid element when all its Bézier control
#: points lie this far (parameter units) inside; far above PARAMETER_TOL, so no neighbour can
#: claim any of its points under the ownership rule
CERTIFY_MARGIN = 1e3 * PARAMETER_TOL
#: degree along a straight line of the solid shape functions N(ξ(η)) when ξ(η) is affine in η, per
#: element code (hex8 trilinear: 3, hex20 serendipity: 4, hex27 triquadratic: 6, tet4: 1, tet10: 2)
LINE_DEGREE = solid.LINE_DEGREE
#: polynomial degree of the centreline functions per beam code (hermite, line, line3)
BEAM_DEGREE = np.array([3, 1, 2], dtype=np.int64)
#: pair outcome of the auto classification
PAIR_DONE, PAIR_NUMERIC = 0, 1


@njit
def beam_is_affine(beam_code, Qe, length):
    """Whether the centreline r(η) of one beam element is affine in η (to ``AFFINE_TOL · L``).

    Hermite: r(η) - affine = (1 - η²)/8 [η (2c - L (t1 + t2)) + L (t1 - t2)] with c = r2 - r1,
    so it is affine iff t1 = t2 = c / L. Lagrange line: always; line3: iff the middle node is the
    chord's midpoint. Then |r'| is constant and every coupling integrand is a polynomial in an
    affine solid element.
    """
    tol = AFFINE_TOL * length
    dev = 0.0
    if beam_code == 0:
        for i in range(3):
            c = Qe[2, i] - Qe[0, i]
            dev = max(dev, abs(2.0 * c - length * (Qe[1, i] + Qe[3, i])) + length * abs(Qe[1, i] - Qe[3, i]))
        dev *= 0.125
    elif beam_code == 2:
        for i in range(3):
            dev = max(dev, abs(Qe[2, i] - 0.5 * (Qe[0, i] + Qe[1, i])))
    return dev <= tol


@njit
def _control_points(beam_code, Qe, length, ctrl):
    """Bézier control points of a beam element (local frame); their number. The curve lies in their hull."""
    if beam_code == 0:
        for i in range(3):
            ctrl[0, i] = Qe[0, i]
            ctrl[1, i] = Qe[0, i] + length / 3.0 * Qe[1, i]
            ctrl[2, i] = Qe[2, i] - length / 3.0 * Qe[3, i]
            ctrl[3, i] = Qe[2, i]
        return 4
    if beam_code == 1:
        ctrl[0] = Qe[0]
        ctrl[1] = Qe[1]
        return 2
    for i in range(3):
        ctrl[0, i] = Qe[0, i]
        ctrl[1, i] = 2.0 * Qe[2, i] - 0.5 * (Qe[0, i] + Qe[1, i])
        ctrl[2, i] = Qe[1, i]
    return 3


@njit_parallel
def _auto_crossings(pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h, beam_code, Q, lengths,
                    beam_origin, crossing_eta, crossing_face, crossing_count, pair_state, beam_affine, beam_inside,
                    workers):
    """Face crossings of every candidate pair where they can be had without a search.

    Per beam element e and candidate solid element s (both frames local, see projection):

    - affine s, affine beam: ξ(η) = α + β η is a line; its entry and exit η through the faces
      ``n·(ξ - o) = 0`` are computed in closed form (the crossings the numeric search would find);
    - affine s, curved beam: if every Bézier control point maps ``CERTIFY_MARGIN`` inside s, the
      whole element is inside s (convex hull; affine maps keep it), so no pair of e has a crossing;
    - otherwise the pair is marked ``PAIR_NUMERIC`` for the segmentation's crossing search.
    """
    n_beam = pair_offsets.shape[0] - 1
    tol = PARAMETER_TOL
    claims = new_claims(n_beam, workers)
    for worker in prange(workers):
        X = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        Ainv = np.empty((3, 3))
        ctrl = np.empty((4, 3))
        alpha = np.empty(3)
        beta = np.empty(3)
        xi = np.empty(3)
        begin, stop = claim(claims, n_beam, worker)
        while begin < stop:
            for e in range(begin, stop):
                Qe = Q[e]
                straight = beam_is_affine(beam_code, Qe, lengths[e])
                beam_affine[e] = straight
                # the line r(η) = p + q η (straight) or the control polygon (curved), beam-local frame
                p0, p1, p2, q0, q1, q2 = beam_point(beam_code, Qe, lengths[e], 0.0, 0.0, 0.0, 0.0, H, dH)
                n_ctrl = 0 if straight else _control_points(beam_code, Qe, lengths[e], ctrl)
                inside = -1
                for p in range(pair_offsets[e], pair_offsets[e + 1]):
                    s = pair_solid[p]
                    code = codes[s]
                    crossing_count[p] = 0
                    pair_state[p] = PAIR_NUMERIC
                    load_element(points, conn, s, code, solid_origin, X)
                    if not affine_inverse(code, X, solid_h[s], AFFINE_TOL, Ainv):
                        continue
                    s0 = beam_origin[e, 0] - solid_origin[s, 0]
                    s1 = beam_origin[e, 1] - solid_origin[s, 1]
                    s2 = beam_origin[e, 2] - solid_origin[s, 2]
                    if not straight:
                        certified = True
                        for k in range(n_ctrl):
                            affine_parameters(code, Ainv, ctrl[k, 0] + s0, ctrl[k, 1] + s1, ctrl[k, 2] + s2, xi)
                            if solid.outside_distance(code, xi) > -CERTIFY_MARGIN:
                                certified = False
                                break
                        if certified:
                            inside = s
                            break
                        continue
                    pair_state[p] = PAIR_DONE
                    affine_parameters(code, Ainv, p0 + s0, p1 + s1, p2 + s2, alpha)
                    for i in range(3):
                        beta[i] = Ainv[i, 0] * q0 + Ainv[i, 1] * q1 + Ainv[i, 2] * q2
                    # clip the line against the half-spaces n·(ξ - o) <= 0 of the faces
                    eta_in = -np.inf
                    eta_out = np.inf
                    face_in = face_out = -1
                    empty = False
                    faces = solid.faces(code)
                    for f in range(faces.shape[0]):
                        g0 = 0.0
                        g1 = 0.0
                        for i in range(3):
                            g0 += faces[f, 3, i] * (alpha[i] - faces[f, 0, i])
                            g1 += faces[f, 3, i] * beta[i]
                        if g1 == 0.0:
                            if g0 > 0.0:
                                empty = True
                        elif g1 > 0.0:
                            if -g0 / g1 < eta_out:
                                eta_out = -g0 / g1
                                face_out = f
                        elif -g0 / g1 > eta_in:
                            eta_in = -g0 / g1
                            face_in = f
                    if empty:
                        continue
                    # entry and exit are crossings when they lie on the element (inside test with the
                    # tolerance, as for a numeric crossing) and on the beam element
                    n = 0
                    for k in range(2):
                        t = eta_in if k == 0 else eta_out
                        if not (-1.0 - tol <= t <= 1.0 + tol):
                            continue
                        for i in range(3):
                            xi[i] = alpha[i] + beta[i] * t
                        if solid.is_inside(code, xi, tol):
                            crossing_eta[p, n] = min(max(t, -1.0), 1.0)
                            crossing_face[p, n] = face_in if k == 0 else face_out
                            n += 1
                    crossing_count[p] = n
                beam_inside[e] = inside
                if inside >= 0:
                    for p in range(pair_offsets[e], pair_offsets[e + 1]):
                        crossing_count[p] = 0
                        pair_state[p] = PAIR_DONE
            begin, stop = claim(claims, n_beam, worker)


@njit
def exact_gauss_count(beam_code, solid_code, n_phi):
    """Gauss points that integrate Φ·H, Φ·N and Φ exactly on a straight beam in an affine element.

    Degrees in η: Φ_j ``n_phi - 1``, H_k ``BEAM_DEGREE``, N_a(ξ(η)) ``LINE_DEGREE`` (ξ affine in η),
    |r'| constant; an n-point Gauss rule is exact to degree 2n - 1. The one formula: the kernel
    ``_auto_gauss_counts`` calls it, and it can be called from Python.
    """
    degree = n_phi - 1 + max(BEAM_DEGREE[beam_code], LINE_DEGREE[solid_code])
    return degree // 2 + 1


@njit_parallel
def _auto_gauss_counts(seg_beam, seg_solid, codes, conn, points, solid_origin, solid_h, beam_affine, beam_code,
                       n_phi, n_gauss, counts, exact, workers):
    """Gauss points per segment: the minimal exact rule where the integrand is a polynomial, else n_gauss."""
    n_seg = seg_beam.shape[0]
    claims = new_claims(n_seg, workers)
    for worker in prange(workers):
        X = np.empty((solid.MAX_NODES, 3))
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


def auto_segments(ctx, search_points, n_gauss, n_phi):
    """Segments and Gauss counts of ``integration="auto"``.

    Beam elements certified to lie inside one solid element keep one segment [-1, 1] (the points
    of element-based integration); the others are cut at their face crossings, computed in closed
    form for straight beams in affine elements and by the segmentation's crossing search
    otherwise. Every segment then gets the minimal exact Gauss rule where the integrand is a
    polynomial (straight beam, affine element), else ``n_gauss`` points.

    Returns
    -------
    seg_beam, seg_solid, seg_start, seg_end, counts : (n_segments,) arrays
        Beam element, owning solid element, η range and Gauss points of every segment.
    info : dict
        Counts for the diagnostics: face crossings, numeric pairs, beam elements left uncut.
    """
    pair_offsets, pair_solid = ctx.pair_offsets, ctx.pair_solid
    n_beam = len(pair_offsets) - 1
    n_pairs = len(pair_solid)
    closed = np.empty((n_pairs, 2))
    closed_face = np.empty((n_pairs, 2), dtype=np.int64)
    count = np.zeros(n_pairs, dtype=np.int64)
    state = np.empty(n_pairs, dtype=np.int64)
    beam_affine = np.empty(n_beam, dtype=np.bool_)
    beam_inside = np.empty(n_beam, dtype=np.int64)
    _auto_crossings(pair_offsets, pair_solid, ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h,
                    ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin, closed, closed_face, count, state, beam_affine,
                    beam_inside, workers())
    numeric = np.flatnonzero(state == PAIR_NUMERIC)
    crossing_eta, crossing_face = closed, closed_face
    if len(numeric):
        found, found_face, found_count, _ = pair_crossings(ctx, ctx.pair_beam()[numeric], pair_solid[numeric],
                                                           search_points)
        width = max(2, int(found_count.max()))
        crossing_eta = np.empty((n_pairs, width))
        crossing_face = np.empty((n_pairs, width), dtype=np.int64)
        crossing_eta[:, :2] = closed
        crossing_face[:, :2] = closed_face
        crossing_eta[numeric, :width] = found[:, :width]
        crossing_face[numeric, :width] = found_face[:, :width]
        count[numeric] = found_count
    seg_beam, seg_solid, seg_start, seg_end, per_beam = tile(ctx, crossing_eta, crossing_face, count)
    counts = np.empty(len(seg_beam), dtype=np.int64)
    exact = np.empty(len(seg_beam), dtype=np.bool_)
    _auto_gauss_counts(seg_beam, seg_solid, ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h,
                       beam_affine, ctx.beam_code, n_phi, n_gauss, counts, exact, workers())
    whole = (per_beam == 1)[seg_beam] & (seg_start == -1.0) & (seg_end == 1.0)
    info = {"face_crossings": int(count.sum()), "numeric_pairs": int(len(numeric)),
            "certified_inside": int(np.count_nonzero(beam_inside >= 0)),
            "beam_elements_uncut": int(np.count_nonzero(whole)),
            "exact_rule_segments": int(np.count_nonzero(exact))}
    return seg_beam, seg_solid, seg_start, seg_end, counts, info
