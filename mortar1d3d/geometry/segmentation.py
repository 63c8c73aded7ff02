"""Segmentation: cut every beam element into pieces that each lie inside one solid element.

Two stages, both parallel over independent items with pre-sized output slots:

1. ``_pair_crossings`` (per candidate pair): sample the beam element at ``search_points``
   parameters, project the samples into the solid element and, for every face whose signed
   parameter distance changes sign between neighbouring samples (or comes close to zero), run
   the face-intersection Newton from the interpolated start. Accepted crossings have η in the
   beam element and ξ on the face (tolerance 1e-9).
2. ``_tile`` (per beam element): the crossings of all its pairs plus η = ±1, sorted and merged
   within 1e-9, cut the element into intervals; each interval's midpoint goes to the *lowest
   index* candidate element containing it (so a piece on a shared face, edge or node is counted
   once); neighbouring intervals with the same owner are merged. Intervals whose midpoint lies
   in no element are outside the solid and are not coupled.

By construction the segments of a beam element never overlap, and together with the uncoupled
intervals they tile [-1, 1] exactly.
"""
import numpy as np
from numba import prange

from .._config import PARAMETER_TOL, njit, njit_parallel
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from .beam import beam_point
from .intersection import face_coordinates, intersect_face
from .projection import CONVERGED, INSIDE, load_element, locate, project_point

_NEAR_FACE = 0.3     # |g| below this (parameter units) at a local minimum: try a crossing there


@njit
def _signed_face_distance(face, xi):
    g = 0.0
    for i in range(3):
        g += face[3, i] * (xi[i] - face[0, i])
    return g


@njit
def _shift(beam_origin, e, solid_origin, s, shift):
    for i in range(3):
        shift[i] = beam_origin[e, i] - solid_origin[s, i]


@njit
def _face_centre(code, face, xi):
    """Centroid of a face in parameter space (hex faces: u, v in [-1, 1]; tet: the unit triangle)."""
    c = 0.0 if solid.FAMILY[code] == solid.HEX else 1.0 / 3.0
    for i in range(3):
        xi[i] = face[0, i] + c * (face[1, i] + face[2, i])


@njit
def crossings_capacity(search_points):
    """Most crossings one pair can report (one per face and start)."""
    return 2 * search_points * solid.MAX_FACES


@njit_parallel
def _pair_crossings(pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h,
                    beam_code, Q, lengths, beam_origin, search_points, out_eta, out_count):
    n_pairs = pair_beam.shape[0]
    tol = PARAMETER_TOL
    for p in prange(n_pairs):
        e = pair_beam[p]
        s = pair_solid[p]
        code = codes[s]
        h = solid_h[s]
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        r = np.empty(3)
        dr = np.empty(3)
        shift = np.empty(3)
        xi = np.empty(3)
        z = np.empty(3)
        uv = np.empty(2)
        load_element(points, conn, s, code, solid_origin, X)
        _shift(beam_origin, e, solid_origin, s, shift)
        faces = solid.faces(code)
        n_faces = faces.shape[0]

        # samples along the beam element and their parameter coordinates
        S = search_points
        eta_s = np.empty(S)
        xi_s = np.empty((S, 3))
        ok = np.empty(S, dtype=np.bool_)
        solid.centre(code, xi)
        for k in range(S):
            eta_s[k] = -1.0 + 2.0 * k / (S - 1)
            beam_point(beam_code, Q[e], lengths[e], shift, eta_s[k], H, dH, r, dr)
            start = xi.copy()
            ok[k] = project_point(code, X, r, h, xi, N, dN) == CONVERGED
            if ok[k]:
                xi_s[k] = xi
            else:
                solid.centre(code, xi)
                xi_s[k] = start

        count = 0
        for f in range(n_faces):
            face = faces[f]
            g = np.empty(S)
            for k in range(S):
                g[k] = _signed_face_distance(face, xi_s[k])
            for k in range(S):
                # start candidates: a sign change towards the next sample, a near local minimum
                # of |g|, or a sample whose projection failed
                starts_eta = np.empty(2)
                starts_xi = np.empty((2, 3))
                n_starts = 0
                if not ok[k]:
                    starts_eta[0] = eta_s[k]
                    _face_centre(code, face, starts_xi[0])
                    n_starts = 1
                else:
                    if k + 1 < S and ok[k + 1] and g[k] * g[k + 1] <= 0.0:
                        t = 0.5 if g[k] == g[k + 1] else g[k] / (g[k] - g[k + 1])
                        starts_eta[n_starts] = eta_s[k] + t * (eta_s[k + 1] - eta_s[k])
                        starts_xi[n_starts] = xi_s[k] + t * (xi_s[k + 1] - xi_s[k])
                        n_starts += 1
                    left = abs(g[k - 1]) if k > 0 else np.inf
                    right = abs(g[k + 1]) if k + 1 < S else np.inf
                    if abs(g[k]) < _NEAR_FACE and abs(g[k]) <= left and abs(g[k]) <= right:
                        starts_eta[n_starts] = eta_s[k]
                        starts_xi[n_starts] = xi_s[k]
                        n_starts += 1
                for q in range(n_starts):
                    face_coordinates(face, starts_xi[q], uv)
                    z[0] = starts_eta[q]
                    z[1] = uv[0]
                    z[2] = uv[1]
                    status = intersect_face(code, X, h, beam_code, Q[e], lengths[e], shift, face, z,
                                            xi, N, dN, H, dH)
                    if status != CONVERGED:
                        continue
                    if z[0] < -1.0 - tol or z[0] > 1.0 + tol:
                        continue
                    if not solid.is_inside(code, xi, tol):
                        continue
                    out_eta[p, count] = min(max(z[0], -1.0), 1.0)
                    count += 1
        out_count[p] = count


@njit_parallel
def _tile(pair_offsets, pair_solid, crossing_eta, crossing_count, codes, conn, points, solid_origin,
          solid_h, solid_boxes, beam_code, Q, lengths, beam_origin, seg_offsets, seg_solid,
          seg_start, seg_end, seg_count):
    n_beam = pair_offsets.shape[0] - 1
    tol = PARAMETER_TOL
    for e in prange(n_beam):
        p0 = pair_offsets[e]
        p1 = pair_offsets[e + 1]
        n_cross = 0
        for p in range(p0, p1):
            n_cross += crossing_count[p]
        cuts = np.empty(n_cross + 2)
        m = 0
        for p in range(p0, p1):
            for q in range(crossing_count[p]):
                cuts[m] = crossing_eta[p, q]
                m += 1
        cuts = np.sort(cuts[:m])
        points_eta = np.empty(m + 2)
        points_eta[0] = -1.0
        n_pts = 1
        for q in range(m):
            if cuts[q] > points_eta[n_pts - 1] + tol and cuts[q] < 1.0 - tol:
                points_eta[n_pts] = cuts[q]
                n_pts += 1
        points_eta[n_pts] = 1.0
        n_pts += 1

        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        H = np.empty(MAX_FUNCTIONS)
        dH = np.empty(MAX_FUNCTIONS)
        r = np.empty(3)
        dr = np.empty(3)
        x = np.empty(3)
        shift = np.empty(3)
        xi = np.empty(3)
        base = seg_offsets[e]
        n_seg = 0
        for iv in range(n_pts - 1):
            a = points_eta[iv]
            b = points_eta[iv + 1]
            mid = 0.5 * (a + b)
            owner = -1
            # global position of the midpoint (beam-local frame; the solid shift is added below)
            for i in range(3):
                shift[i] = 0.0
            beam_point(beam_code, Q[e], lengths[e], shift, mid, H, dH, r, dr)
            for p in range(p0, p1):
                s = pair_solid[p]
                inside_box = True
                for i in range(3):
                    xg = r[i] + beam_origin[e, i]
                    if xg < solid_boxes[s, 0, i] or xg > solid_boxes[s, 1, i]:
                        inside_box = False
                if not inside_box:
                    continue
                code = codes[s]
                load_element(points, conn, s, code, solid_origin, X)
                for i in range(3):
                    x[i] = r[i] + (beam_origin[e, i] - solid_origin[s, i])
                if locate(code, X, x, solid_h[s], tol, xi, N, dN) == INSIDE:
                    owner = s
                    break
            if owner < 0:
                continue
            if n_seg > 0 and seg_solid[base + n_seg - 1] == owner and seg_end[base + n_seg - 1] == a:
                seg_end[base + n_seg - 1] = b
            else:
                seg_solid[base + n_seg] = owner
                seg_start[base + n_seg] = a
                seg_end[base + n_seg] = b
                n_seg += 1
        seg_count[e] = n_seg


def segment(ctx, search_points):
    """Segments of all beam elements: (beam_element, solid_element, eta_start, eta_end) arrays.

    ``ctx`` is the prepared kernel input of :mod:`mortar1d3d.mortar.assemble`. Also returns the
    number of face crossings found (a diagnostic).
    """
    pair_offsets, pair_solid = ctx.pair_offsets, ctx.pair_solid
    n_beam = len(pair_offsets) - 1
    pair_beam = np.repeat(np.arange(n_beam), np.diff(pair_offsets))
    cap = crossings_capacity(search_points)
    crossing_eta = np.empty((len(pair_solid), cap))
    crossing_count = np.zeros(len(pair_solid), dtype=np.int64)
    _pair_crossings(pair_beam, pair_solid, ctx.codes, ctx.conn, ctx.points, ctx.solid_origin,
                    ctx.solid_h, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin, search_points,
                    crossing_eta, crossing_count)
    # at most (crossings + 1) intervals per beam element
    cumulative = np.concatenate([[0], np.cumsum(crossing_count)])
    per_beam = cumulative[pair_offsets[1:]] - cumulative[pair_offsets[:-1]] + 1
    seg_offsets = np.concatenate([[0], np.cumsum(per_beam)])
    total = seg_offsets[-1]
    seg_solid = np.empty(total, dtype=np.int64)
    seg_start = np.empty(total)
    seg_end = np.empty(total)
    seg_count = np.zeros(n_beam, dtype=np.int64)
    _tile(pair_offsets, pair_solid, crossing_eta, crossing_count, ctx.codes, ctx.conn, ctx.points,
          ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.beam_code, ctx.Q, ctx.lengths,
          ctx.beam_origin, seg_offsets, seg_solid, seg_start, seg_end, seg_count)
    keep = _compact_index(seg_offsets, seg_count)
    beam_element = np.repeat(np.arange(n_beam), seg_count)
    return beam_element, seg_solid[keep], seg_start[keep], seg_end[keep], int(crossing_count.sum())


@njit
def _compact_index(offsets, counts):
    out = np.empty(counts.sum(), dtype=np.int64)
    m = 0
    for e in range(counts.shape[0]):
        for q in range(counts[e]):
            out[m] = offsets[e] + q
            m += 1
    return out
