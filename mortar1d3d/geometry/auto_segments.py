"""Segments of ``integration="auto"``: face crossings without the search where the geometry allows it.

Per candidate pair (beam element e, solid element s), both frames local (see
:mod:`~mortar1d3d.geometry.projection`):

- affine s, straight e: ξ(η) is a line; its entry and exit through the faces are computed in
  closed form (the crossings the search of :mod:`~mortar1d3d.geometry.segmentation` would find);
- affine s, curved e: if every Bézier control point of e maps well inside s, all of e lies in s
  (convex hull; affine maps keep it) and e is not cut;
- otherwise the pair is left to the segmentation's crossing search.

The segmentation's second stage (:func:`~mortar1d3d.geometry.segmentation.tile`) then makes the
segments from these crossings, exactly as for segment-based integration. Which segments get an
exact Gauss rule is decided with the integration points (:mod:`mortar1d3d.integration.points`).
"""
import numpy as np

from .._config import PARAMETER_TOL, njit
from .._parallel import in_parallel
from .._schedule import claim, new_claims, workers
from ..elements import beam as beam_functions
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from .beam import AFFINE_TOL, beam_is_affine, beam_point
from .projection import affine_inverse, affine_parameters, load_element
from .segmentation import linear_errors, pair_crossings, tile

#: a curved beam element is certified inside an affine solid element when all its Bézier control
#: points lie this far (parameter units) inside; far above PARAMETER_TOL, so no neighbour can
#: claim any of its points under the ownership rule
CERTIFY_MARGIN = 1e3 * PARAMETER_TOL
#: pair outcome of the auto classification
PAIR_DONE, PAIR_NUMERIC = 0, 1


@njit
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
    claims = new_claims(n_beam, workers)
    _auto_crossings_workers(workers, claims, pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h,
                            beam_code, Q, lengths, beam_origin, crossing_eta, crossing_face, crossing_count,
                            pair_state, beam_affine, beam_inside)


@njit
def _auto_crossings_worker(worker, claims, pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h,
                           beam_code, Q, lengths, beam_origin, crossing_eta, crossing_face, crossing_count,
                           pair_state, beam_affine, beam_inside):
    n_beam = pair_offsets.shape[0] - 1
    tol = PARAMETER_TOL
    X = np.empty((solid.MAX_NODES, 4))
    H = np.empty(MAX_FUNCTIONS)
    dH = np.empty(MAX_FUNCTIONS)
    ddH = np.empty(MAX_FUNCTIONS)
    Ainv = np.empty((3, 3))
    ctrl = np.empty((4, 3))
    alpha = np.empty(3)
    beta = np.empty(3)
    xi = np.empty(3)
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        for e in range(begin, stop):
            Qe = Q[e]
            straight = beam_is_affine(beam_code, Qe, lengths[e], ddH)
            beam_affine[e] = straight
            # the line r(η) = p + q η (straight) or the control polygon (curved), beam-local frame
            p0, p1, p2, q0, q1, q2 = beam_point(beam_code, Qe, lengths[e], 0.0, 0.0, 0.0, 0.0, H, dH)
            n_ctrl = 0 if straight else beam_functions.control_points(beam_code, Qe, lengths[e], ctrl)
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


_auto_crossings_workers = in_parallel(_auto_crossings_worker)


def auto_segments(ctx, search_points):
    """Segments of ``integration="auto"``, without the crossing search where the geometry allows it.

    Beam elements certified to lie inside one solid element keep one segment [-1, 1] (the points
    of element-based integration); the others are cut at their face crossings, computed in closed
    form for straight beams in affine elements and by the segmentation's crossing search
    (:func:`~.segmentation.pair_crossings`) otherwise; the segmentation's second stage
    (:func:`~.segmentation.tile`) makes the segments.

    Returns
    -------
    seg_beam, seg_solid, seg_start, seg_end : (n_segments,) arrays
        Beam element, owning solid element and η range of every segment.
    beam_affine : (m,) bool
        Which beam elements are straight (:func:`beam_is_affine`).
    info : dict
        Counts for the diagnostics: face crossings, numeric pairs, beam elements certified inside
        one element, beam elements left uncut.
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
    errors = linear_errors(ctx)     # the element bounds, once for both stages
    if len(numeric):
        found, found_face, found_count, _ = pair_crossings(ctx, ctx.pair_beam()[numeric], pair_solid[numeric],
                                                           search_points, errors)
        width = max(2, int(found_count.max()))
        crossing_eta = np.empty((n_pairs, width))
        crossing_face = np.empty((n_pairs, width), dtype=np.int64)
        crossing_eta[:, :2] = closed
        crossing_face[:, :2] = closed_face
        crossing_eta[numeric, :width] = found[:, :width]
        crossing_face[numeric, :width] = found_face[:, :width]
        count[numeric] = found_count
    seg_beam, seg_solid, seg_start, seg_end, per_beam = tile(ctx, crossing_eta, crossing_face, count, errors)
    whole = (per_beam == 1)[seg_beam] & (seg_start == -1.0) & (seg_end == 1.0)
    info = {"face_crossings": int(count.sum()), "numeric_pairs": int(len(numeric)),
            "certified_inside": int(np.count_nonzero(beam_inside >= 0)),
            "beam_elements_uncut": int(np.count_nonzero(whole))}
    return seg_beam, seg_solid, seg_start, seg_end, beam_affine, info
