"""Segmentation: cut every beam element into pieces that each lie inside one solid element.

Two stages, both parallel over independent items with pre-sized output slots:

1. ``_pair_crossings`` (per candidate pair): sample the beam element at ``search_points``
   parameters and project the samples into the solid element (ξ and dξ/dη = J⁻¹ r').
   For every face, the signed parameter distance g(η) = n·(ξ(η) - o) is modelled on each
   sample interval by the cubic Hermite interpolant of g and dg/dη; the face Newton starts
   at every sign change of that cubic, and at its minimum when it comes close to zero
   (a touch, or a leave-and-re-enter between two samples that linear interpolation would
   miss; not at a sample next to a sign change of the samples, whose crossing that interval's
   own start finds). Accepted crossings have η in the beam element and ξ on the face (tolerance
   1e-9). Pairs are not searched where the beam element's box misses every face's box, or where
   the element's linearised map proves that it reaches no face (:func:`_faces_in_linear_reach`);
   sample intervals where it proves that, and the samples that bound only such intervals, are
   skipped (:func:`_live_intervals`).
2. ``_tile`` (per beam element): the crossings of all its pairs plus η = ±1, sorted and merged
   within 1e-9, cut the element into intervals; each interval's midpoint goes to the *lowest
   index* candidate element containing it (so a piece on a shared face, edge or node is counted
   once); neighbouring intervals with the same owner are merged. Intervals whose midpoint lies
   in no element are outside the solid and are not coupled.

Both stages and the tiling check ask whether a point lies in an element; a bound on how far each
element's linearised map may be from its map (:func:`linear_errors`, once per call) answers most
of these questions without a Newton projection: for a beam element with every point, or a point
deep inside or far outside an element (:func:`_faces_in_linear_reach`, :func:`_linear_side`).

By construction the segments of a beam element never overlap, and together with the uncoupled
intervals they tile [-1, 1] exactly.

The stages are :func:`pair_crossings` and :func:`tile` (``integration="auto"`` finds most
crossings in closed form and shares the second stage); :func:`segment` runs both on every beam
element of a kernel context (:mod:`~mortar1d3d.geometry.context`) and flags the beam elements
whose pieces fail :func:`check_tiling`; :func:`resegment` cuts such beam elements again (more
search points, or bisection of the owner along η), for the one fallback loop of
:func:`mortar1d3d.integration.points.checked_segment_points`.
"""
import numpy as np
from numba import types

from .._borrowed import borrowed
from .._config import MERGE_TOL, PARAMETER_TOL, SEGMENT_OWNER_TOL, TOUCH_TOL, njit
from .._memory import carve
from .._parallel import in_parallel
from .._unlinked import unlinked
from .._schedule import claim, new_claims, workers
from ..elements.solid import dispatch as solid
from .beam import beam_point, beams_affine
from .intersection import face_coordinates, intersect_face
from .linalg import norm3, solve3
from .rational import linearisation_error
from .projection import (ANY_CANDIDATE, CONVERGED, NOT_CONVERGED, certified_outside, first_containing,
                         in_box, is_affine, jacobian, linear_image, linear_parameters, load_element, locate_outside,
                         locate_point, point_buffers, project_point, search_buffers)
from .search import in_hull

_NEAR_FACE = 0.1     # min |g| of the cubic model below this fraction of its variation: try a touch there
_SCAN = 8            # points per sample interval at which the cubic model of g is scanned
_REACH_MARGIN = 1e-6  # faces whose box misses a beam element's box by more than this (relative): no crossing
#: why a pair was not searched (``unsearched`` of :func:`pair_crossings`): searched; the beam element's box
#: misses every face's box (:func:`_faces_in_reach`); the element's linearised map proves that it reaches
#: no face (:func:`_faces_in_linear_reach`)
SEARCHED, BOX_MISS, LINEAR_MISS = 0, 1, 2


@njit
def crossings_capacity(search_points):
    """Most crossings one pair reports (in the second pass of :func:`pair_crossings`; further ones are dropped)."""
    return 4 * search_points * solid.MAX_FACES


#: crossings stored per pair on the first pass; pairs with more (a beam element weaving in and
#: out of one element, or one crossing found from several starts) are searched again with room
#: for ``crossings_capacity``. Keeps the table small: most of it is never written, but every
#: page of it would be touched (and faulted in) row by row.
_FIRST_CAPACITY = 16


@njit
def _record(eta, face, out_eta, out_face, p, count, overflow):
    """Store a crossing (NaN: none) of face ``face`` in row p; flag the pair when its row is full."""
    if np.isnan(eta):
        return count
    if count < out_eta.shape[1]:
        out_eta[p, count] = eta
        out_face[p, count] = face
        return count + 1
    overflow[p] = True
    return count


def pair_crossings(ctx, pair_beam, pair_solid, search_points, errors=None):
    """The first stage: face crossings of the given pairs (``pair_beam`` indexes the beam elements of ``ctx``).

    Returns ``crossing_eta`` (n_pairs, width), ``crossing_face`` (n_pairs, width: the face of the
    solid element each crossing lies on), ``crossing_count`` (n_pairs,) and ``unsearched`` (n_pairs,)
    int8: ``SEARCHED`` (0), or why the beam element reaches no face of the solid element
    (``BOX_MISS``: its box misses every face's box; ``LINEAR_MISS``: the element's linearised map
    proves it, :func:`_faces_in_linear_reach`), so that it lies entirely inside or outside. ``errors``:
    :func:`linear_errors` of ``ctx`` (computed here if not given).
    """
    if errors is None:
        errors = linear_errors(ctx)
    n = len(pair_solid)
    # a straight beam element in an affine solid element has face functions linear in η: their roots
    # are the sign changes between samples, with no touch or double crossing to look for
    straight = beams_affine(ctx.beam_code, ctx.Q, ctx.lengths)
    args = (ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h, ctx.linear, errors, ctx.hull,
            ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin, ctx.beam_boxes, straight, search_points)
    full = crossings_capacity(search_points)
    width = min(_FIRST_CAPACITY, full)
    crossing_eta, crossing_face, crossing_count, unsearched, overflow = carve(
        ((n, width), np.float64), ((n, width), np.int64), (n, np.int64), (n, np.int8), (n, np.bool_))
    crossing_count[:] = 0
    _pair_crossings(pair_beam, pair_solid, *args, crossing_eta, crossing_face, crossing_count, unsearched, overflow,
                    workers())
    again = np.flatnonzero(overflow)
    if len(again) and crossing_eta.shape[1] < full:
        more_eta = np.empty((len(again), full))
        more_face = np.empty((len(again), full), dtype=np.int64)
        more_count = np.zeros(len(again), dtype=np.int64)
        _pair_crossings(pair_beam[again], pair_solid[again], *args, more_eta, more_face, more_count,
                        np.empty(len(again), dtype=np.int8), np.empty(len(again), dtype=np.bool_), workers())
        width = int(more_count.max())
        wide = np.empty((n, max(width, crossing_eta.shape[1])))
        wide_face = np.empty((n, max(width, crossing_eta.shape[1])), dtype=np.int64)
        wide[:, : crossing_eta.shape[1]] = crossing_eta
        wide_face[:, : crossing_eta.shape[1]] = crossing_face
        wide[again, :width] = more_eta[:, :width]
        wide_face[again, :width] = more_face[:, :width]
        crossing_eta, crossing_face = wide, wide_face
        crossing_count[again] = more_count
    return crossing_eta, crossing_face, crossing_count, unsearched


@njit
def _try_crossing(code, X, h, beam_code, Qe, length, s0, s1, s2, face, eta0, xs0, xs1, xs2,
                  z, xi, N, dN, H, dH):
    """Run the face Newton from (η0, ξ0); the crossing's η, or NaN if none in element and face."""
    tol = PARAMETER_TOL
    u, v = face_coordinates(face, xs0, xs1, xs2)
    z[0], z[1], z[2] = eta0, u, v
    if intersect_face(code, X, h, beam_code, Qe, length, s0, s1, s2, face, z, xi, N, dN, H, dH) != CONVERGED:
        return np.nan
    if z[0] < -1.0 - tol or z[0] > 1.0 + tol or not solid.is_inside(code, xi, tol):
        return np.nan
    return min(max(z[0], -1.0), 1.0)


@njit
def _try_between(code, X, h, beam_code, Qe, length, s0, s1, s2, face, eta_s, xi_s, k, t, z, xi, N, dN, H, dH):
    """``_try_crossing`` from the point at fraction t of sample interval k (linear start values)."""
    return _try_crossing(code, X, h, beam_code, Qe, length, s0, s1, s2, face,
                         eta_s[k] + t * (eta_s[k + 1] - eta_s[k]),
                         xi_s[k, 0] + t * (xi_s[k + 1, 0] - xi_s[k, 0]),
                         xi_s[k, 1] + t * (xi_s[k + 1, 1] - xi_s[k, 1]),
                         xi_s[k, 2] + t * (xi_s[k + 1, 2] - xi_s[k, 2]), z, xi, N, dN, H, dH)


@njit
def _hermite_g(g0, g1, d0, d1, t):
    """Cubic Hermite model of the face distance on a sample interval (t in [0, 1], d scaled by h)."""
    t2 = t * t
    t3 = t2 * t
    return ((2 * t3 - 3 * t2 + 1) * g0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * g1 + (t3 - t2) * d1)


@njit
def _deflated_roots(g1, d0, d1):
    """Roots (two values, -1 if none) of q(t) = g(t) / t for the cubic model with g(0) = 0.

    g(t) = t [(t² - 2t + 1) d0 + (3t - 2t²) g1 + (t² - t) d1] (``_hermite_g`` with g0 = 0).
    """
    a = d0 - 2.0 * g1 + d1
    b = -2.0 * d0 + 3.0 * g1 - d1
    c = d0
    if a == 0.0:
        return (-c / b if b != 0.0 else -1.0), -1.0
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return -1.0, -1.0
    root = disc ** 0.5
    return (-b - root) / (2.0 * a), (-b + root) / (2.0 * a)


@njit
def _faces_in_reach(code, X, h, box, origin, C, reach):
    """Which faces of an element (local nodes ``X``) a beam element's box (global) reaches; False if none.

    A crossing lies on a face and on the beam element, hence in the hull of the face's control
    points and in the beam's box: a face whose control-point box misses the beam's box has no
    crossing. The boxes are compared with a margin (``_REACH_MARGIN`` of both sizes plus
    round-off of the coordinates) far above the tolerances with which crossings are accepted,
    so skipping such faces changes no result. No face in reach: the beam element lies entirely
    inside or entirely outside the element.
    """
    solid.control_points(code, X, C)
    big = 0.0
    size = 0.0
    for i in range(3):
        big = max(big, abs(origin[i]), abs(box[0, i]), abs(box[1, i]))
        size += (box[1, i] - box[0, i]) ** 2
    pad = _REACH_MARGIN * (h + size ** 0.5) + 16 * 2.220446049250313e-16 * big
    any_face = False
    for f in range(solid.faces(code).shape[0]):
        reach[f] = True
        for i in range(3):
            lo = hi = C[solid.FACE_CONTROL[code, f, 0], i]
            for k in range(1, solid.N_FACE_CONTROL[code, f]):
                v = C[solid.FACE_CONTROL[code, f, k], i]
                lo = min(lo, v)
                hi = max(hi, v)
            if hi < box[0, i] - origin[i] - pad or lo > box[1, i] - origin[i] + pad:
                reach[f] = False
                break
        any_face = any_face or reach[f]
    return any_face


#: the Bernstein bound of :func:`_linear_error` holds on the element scaled about its centre by 1 + this: for
#: every ξ within 1e-4 of the element in units of the centre's distance to each face (tet10: up to 2.5e-5
#: outside the simplex, hex: 1e-4 outside the cube), far beyond ``_REACH_MARGIN`` and the tolerances of the
#: inside tests the bound stands in for (1e-11 owners, 1e-9 crossings, 1e-6 tiling-check probes)
_BERNSTEIN_GROWTH = 1e-4


@njit
def _linear_error(code, X, s, linear, a, out):
    """ε of element s (local nodes ``X``; ``a``: scratch of :func:`.projection.search_buffers`) into ``out``
    (3,): how far the linearised parameters ζ of a point of the element may lie from its ξ, per component
    (see :func:`_faces_in_linear_reach`); NaN for an element without a linearisation (or a rational one whose
    weight function has no positive lower bound, :func:`_rational_linear_error`).

    With y = ξ - ξ_c, a polynomial map is x(ξ) = x_c + J_c y + Σ_q a_q y^α_q over its monomials of degree
    >= 2, so ζ(x) = ξ_c + L (x - x_c) (``linear``: L = J_c⁻¹) of the point x(ξ) differs from ξ by the
    remainder r(ξ) = Σ_q (L a_q) y^α_q. A type with ``bernstein_error`` bounds it by its Bernstein
    coefficients (:func:`_bernstein_error`), the others by ε_i = Σ_q |(L a_q)_i| R^|α_q| for |y|∞ <= R
    (the element's radius, grown by ``_REACH_MARGIN``: also for ξ within that much outside the element).
    """
    if not linear[s, 4, 0] >= 0.0:
        out[0] = out[1] = out[2] = np.nan
        return
    if solid.RATIONAL[code]:
        _rational_linear_error(code, X, s, linear, a, out)
        return
    solid.monomial_coefficients(code, X, a)
    for q in range(solid.N_CURVED[code]):
        k = solid.CURVED_MONOMIALS[code, q]
        a[k, 0], a[k, 1], a[k, 2] = (linear[s, 0, 0] * a[k, 0] + linear[s, 0, 1] * a[k, 1] + linear[s, 0, 2] * a[k, 2],
                                     linear[s, 1, 0] * a[k, 0] + linear[s, 1, 1] * a[k, 1] + linear[s, 1, 2] * a[k, 2],
                                     linear[s, 2, 0] * a[k, 0] + linear[s, 2, 1] * a[k, 1] + linear[s, 2, 2] * a[k, 2])
    if solid.N_BERNSTEIN[code] > 0:
        _bernstein_error(code, a, out)
    else:
        _monomial_error(code, a, solid.RADIUS[code] * (1.0 + _REACH_MARGIN), 0.0, out)


@njit
def _monomial_error(code, a, outer, inner, out):
    """out_i = Σ_q |a_q,i| (outer^|α_q| - inner^|α_q|) over the monomials of degree >= 2 (``a``: the remainder's
    coefficients L a_q): a bound on |r_i(ξ_c + y)| for |y|∞ <= outer, or, with inner > 0, on how much more
    it may reach there than where |y|∞ <= inner, at the same y / inner scaled."""
    e0 = e1 = e2 = 0.0
    for q in range(solid.N_CURVED[code]):
        k = solid.CURVED_MONOMIALS[code, q]
        scale = outer ** solid.CURVED_DEGREE[code, q] - inner ** solid.CURVED_DEGREE[code, q]
        e0 += abs(a[k, 0]) * scale
        e1 += abs(a[k, 1]) * scale
        e2 += abs(a[k, 2]) * scale
    out[0], out[1], out[2] = e0, e1, e2


@njit
def _bernstein_error(code, a, out):
    """A bound on the remainder r (coefficients L a_q in ``a``) of a type with ``bernstein_error`` over the
    element grown by ``_BERNSTEIN_GROWTH`` about its centre, into ``out``.

    On the element, each component of r lies between the least and greatest of its Bernstein coefficients
    (``BERNSTEIN_MONOMIALS`` times the coefficients). A point of the grown element is ξ_c + g y with ξ_c + y
    in the element (g = 1 + ``_BERNSTEIN_GROWTH``, |y|∞ <= R, the element's radius), where r differs from
    r(ξ_c + y) by Σ_q (L a_q)(g^|α_q| - 1) y^α_q: at most Σ_q |(L a_q)_i| ((g R)^|α_q| - R^|α_q|)
    (:func:`_monomial_error`), added to the largest coefficient's magnitude.
    """
    radius = solid.RADIUS[code]
    _monomial_error(code, a, radius * (1.0 + _BERNSTEIN_GROWTH), radius, out)
    b0 = b1 = b2 = 0.0
    for c in range(solid.N_BERNSTEIN[code]):
        v0 = v1 = v2 = 0.0
        for q in range(solid.N_CURVED[code]):
            t = solid.BERNSTEIN_MONOMIALS[code, c, q]
            k = solid.CURVED_MONOMIALS[code, q]
            v0 += t * a[k, 0]
            v1 += t * a[k, 1]
            v2 += t * a[k, 2]
        b0 = max(b0, abs(v0))
        b1 = max(b1, abs(v1))
        b2 = max(b2, abs(v2))
    out[0] += b0
    out[1] += b1
    out[2] += b2


@njit
def _rational_linear_error(code, X, s, linear, a, out):
    """:func:`_linear_error` of a rational element: :func:`.rational.linearisation_error` on the same region (the
    element grown by ``_REACH_MARGIN``), compiled when a scene first has a rational element."""
    _linearisation_error_call(code, X, linear[s, :3], linear[s, 3, 0], linear[s, 3, 1], linear[s, 3, 2],
                              solid.RADIUS[code] * (1.0 + _REACH_MARGIN), a, out)


#: lazily through a symbol: compiled when a scene first has a rational element
_linearisation_error_call = unlinked(linearisation_error, returns=types.float64)


@njit
def _linear_errors(elements, codes, conn, points, solid_origin, linear, errors):
    # serial: a few hundred nanoseconds per element, where a parallel kernel would cost its compile time
    X, _, _, _, _, _, _ = point_buffers()
    a, _ = search_buffers()
    for i in range(elements.shape[0]):
        s = elements[i]
        load_element(points, conn, s, codes[s], solid_origin, X)
        _linear_error(codes[s], X, s, linear, a, errors[s])


def linear_errors(ctx):
    """(n_solid, 3): :func:`_linear_error` of every candidate element of ``ctx`` (NaN: no bound, or not a
    candidate), computed once per call for the crossing search, the tiling and its check."""
    errors = np.full((len(ctx.codes), 3), np.nan)
    used = np.zeros(len(ctx.codes), dtype=np.bool_)
    used[ctx.pair_solid] = True
    _linear_errors(np.flatnonzero(used), ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.linear, errors)
    return errors


@njit
def _slack(face, errors, s, pad):
    """Σ_i |n_i| ε_i + pad: how far from face ``face``'s plane the linearised image of a point of element s may
    lie when the point's ξ is on it (``errors``: :func:`linear_errors`)."""
    return abs(face[3, 0]) * errors[s, 0] + abs(face[3, 1]) * errors[s, 1] + abs(face[3, 2]) * errors[s, 2] + pad


@njit
def _faces_in_linear_reach(code, h, s, linear, errors, beam_code, Qe, length, s0, s1, s2, Y, H, dH, reach):
    """Clear ``reach[f]`` of the faces that the element's linearised map proves the beam element cannot
    cross; False if no face is left (the beam element lies entirely inside or entirely outside).

    The linearised parameters ζ of a point of the element lie within ε_i (``errors[s]``, see
    :func:`_linear_error`) of its ξ in component i. ζ is affine in x, so the ζ of the beam element's
    centreline lie in the convex hull of the ζ of its Bézier control points (every centreline is a cubic at
    most: its end points and end tangents). A point of face f has n·(ξ - o) = 0, so its ζ lies within
    Σ_i |n_i| ε_i of the face's plane, and a point of the element has n·(ξ - o) <= 0: if all control
    points lie farther than that on the inner side of a face's plane, the beam cannot reach the
    face; farther on its outer side, it cannot reach the element at all. The margin (``_REACH_MARGIN``
    scaled by the sizes in parameter units, the element's by its size ``h``) lies far above the
    tolerances with which crossings are accepted (their ξ within 1e-9 of the element, η within 1e-9 of [-1, 1],
    the residual within 1e-9 h), so clearing such faces changes no crossing found. Elements without a bound (ε NaN: no
    linearisation, or a rational one whose weight function has no positive lower bound) keep their ``reach``
    unchanged.
    """
    if not errors[s, 0] >= 0.0:
        return True
    # Bézier control points of the centreline (η in [-1, 1]: dr/dt = 2 dr/dη for t in [0, 1]), as ζ
    spread = 0.0
    for end in range(2):
        r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Qe, length, s0, s1, s2, 2.0 * end - 1.0, H, dH)
        sign = (2.0 - 4.0 * end) / 3.0
        Y[3 * end, 0], Y[3 * end, 1], Y[3 * end, 2] = linear_image(code, linear, s, r0, r1, r2)
        Y[1 + end, 0], Y[1 + end, 1], Y[1 + end, 2] = linear_image(code, linear, s, r0 + sign * d0, r1 + sign * d1,
                                                                   r2 + sign * d2)
    for c in range(1, 4):
        for i in range(3):
            spread = max(spread, abs(Y[c, i] - Y[0, i]))
    pad = _reach_pad(linear, s, spread, h)
    faces = solid.faces(code)
    any_face = False
    for f in range(faces.shape[0]):
        face = faces[f]
        slack = _slack(face, errors, s, pad)
        lo = np.inf
        hi = -np.inf
        for c in range(4):
            g = _face_side(face, Y[c])
            lo = min(lo, g)
            hi = max(hi, g)
        if lo > slack:
            # beyond this face's plane: outside the element, no face reached
            for k in range(faces.shape[0]):
                reach[k] = False
            return False
        if hi < -slack:
            reach[f] = False
        any_face = any_face or reach[f]
    return any_face


@njit
def _interval_pad(linear, s, zs, eta_s, h):
    """``_REACH_MARGIN`` scaled by the size of the samples' linearised images ``zs`` and of the element (h)."""
    S = eta_s.shape[0]
    spread = 0.0
    for i in range(3):
        for k in range(S):
            spread = max(spread, abs(zs[k, i] - zs[0, i]) + (eta_s[S - 1] - eta_s[0]) * abs(zs[k, 3 + i]))
    return _reach_pad(linear, s, spread, h)


@njit
def _reach_pad(linear, s, spread, h):
    """``_REACH_MARGIN`` scaled by ``spread`` (the extent of the linearised images, parameter units) and by
    the element's size h in parameter units."""
    size = 0.0
    for i in range(3):
        size = max(size, abs(linear[s, i, 0]) + abs(linear[s, i, 1]) + abs(linear[s, i, 2]))
    return _REACH_MARGIN * (1.0 + spread + size * h)


@njit
def _live_intervals(code, s, h, linear, errors, eta_s, rs, reach, zs, live, need):
    """Which sample intervals of a searched pair may hold a crossing of which face: ``live[k, f]`` for
    interval k (η_k to η_k+1) and face f, ``need[k]``: sample k bounds a live interval. False if none is live.

    ``rs[k]``: the centreline's point and tangent dr/dη at sample k (local to the element's origin). The
    centreline is a cubic at most, so on each interval its linearised image ζ (affine in x) lies in the
    hull of four Bézier control points, from ζ and dζ/dη = L r' at the interval's ends; as for the whole
    beam element (:func:`_faces_in_linear_reach`, the same bound and margins), a face whose plane all four
    miss by more than Σ_i |n_i| ε_i has no crossing there, and none has where they lie that far beyond
    one face's plane. Elements without a bound (ε NaN) and affine ones (whose samples
    cost no Newton) keep every interval of a face in ``reach``.
    """
    S = eta_s.shape[0]
    faces = solid.faces(code)
    bounded = linear[s, 4, 0] == 0.0 and errors[s, 0] >= 0.0
    for k in range(S):
        need[k] = not bounded
        if bounded:
            zs[k, 0], zs[k, 1], zs[k, 2] = linear_image(code, linear, s, rs[k, 0], rs[k, 1], rs[k, 2])
            for i in range(3):
                zs[k, 3 + i] = linear[s, i, 0] * rs[k, 3] + linear[s, i, 1] * rs[k, 4] + linear[s, i, 2] * rs[k, 5]
    if not bounded:
        for k in range(S - 1):
            for f in range(faces.shape[0]):
                live[k, f] = reach[f]
        return True
    pad = _interval_pad(linear, s, zs, eta_s, h)
    any_live = False
    for k in range(S - 1):
        third = (eta_s[k + 1] - eta_s[k]) / 3.0
        outside = False
        for f in range(faces.shape[0]):
            live[k, f] = False
        for f in range(faces.shape[0]):
            face = faces[f]
            slack = _slack(face, errors, s, pad)
            lo = np.inf
            hi = -np.inf
            for c in range(4):
                g = _control_value(face, zs, k, c, third)
                lo = min(lo, g)
                hi = max(hi, g)
            if lo > slack:
                outside = True
                break
            live[k, f] = reach[f] and hi >= -slack
        if outside:
            for f in range(faces.shape[0]):
                live[k, f] = False
        for f in range(faces.shape[0]):
            if live[k, f]:
                need[k] = need[k + 1] = True
                any_live = True
    return any_live


#: a sample of a lone live interval moves towards the part that may meet the element (:func:`_clip_samples`)
#: when its linearised image lies farther than this beyond a face plane (parameter units: the element is 2
#: wide) and the part leaves out more than ``_CLIP_SHARE`` of the interval at its end
_CLIP_FAR = 1.0
_CLIP_SHARE = 0.25
#: how far beyond the part that may meet the element a moved sample lies (share of that part, and of the interval)
_CLIP_MARGIN = 0.05


@njit
def _control_value(face, zs, k, c, third):
    """Face ``face``'s plane function at Bézier control point c (0 to 3) of the linearised images ``zs`` on
    sample interval k (``third``: a third of its length in η)."""
    end = k + c // 2
    t = third if c == 1 else -third if c == 2 else 0.0
    v = 0.0
    for i in range(3):
        v += face[3, i] * (zs[end, i] + t * zs[end, 3 + i] - face[0, i])
    return v


@njit
def _clip_samples(code, s, h, linear, errors, eta_s, rs, zs, live, beam_code, Qe, length, s0, s1, s2, H, dH):
    """Move the samples of a lone live interval (:func:`_live_intervals`) to where the beam element may meet
    element s, so that their projections start near the element.

    Every point of the element has its linearised image ζ within ε of the reference cube (``errors[s]``): on
    sample interval k, the beam can meet the element only where the Bézier model of ζ (``zs``, the same four
    control points as :func:`_live_intervals`) lies behind every face plane within Σ_i |n_i| ε_i + pad. By
    the convex hull property that part lies in [t_lo, t_hi] of the interval (t in [0, 1]), the span of the
    control polygon below that level, for every face. A crossing cannot lie outside it. A sample that
    bounds no other live interval and lies farther than ``_CLIP_FAR`` beyond a face plane moves to just
    beyond its end of [t_lo, t_hi] (``_CLIP_MARGIN``) if that leaves out more than ``_CLIP_SHARE`` of the
    interval. A long beam element cutting a corner of a small curved element otherwise has its samples far
    outside, where Newton on the element's map follows branches folded far from the element and the cubic
    model of a face function between them misses a crossing (found by the corner-cut fuzz test: a hex20
    curved by half its validity limit, a piece 3e-10 long in η).
    """
    if not (linear[s, 4, 0] == 0.0 and errors[s, 0] >= 0.0):
        return
    S = eta_s.shape[0]
    faces = solid.faces(code)
    pad = -1.0
    for k in range(S - 1):
        if not _any_live(live, k, faces.shape[0]):
            continue
        # only a far sample that bounds no other live interval moves
        left = (k == 0 or not _any_live(live, k - 1, faces.shape[0])) and _beyond(faces, zs, k) > _CLIP_FAR
        right = (k + 2 == S or not _any_live(live, k + 1, faces.shape[0])) and _beyond(faces, zs, k + 1) > _CLIP_FAR
        if not (left or right):
            continue
        if pad < 0.0:
            pad = _interval_pad(linear, s, zs, eta_s, h)
        third = (eta_s[k + 1] - eta_s[k]) / 3.0
        t_lo = 0.0
        t_hi = 1.0
        for f in range(faces.shape[0]):
            face = faces[f]
            slack = _slack(face, errors, s, pad)
            b0 = _control_value(face, zs, k, 0, third) - slack
            b1 = _control_value(face, zs, k, 1, third) - slack
            b2 = _control_value(face, zs, k, 2, third) - slack
            b3 = _control_value(face, zs, k, 3, third) - slack
            lo = 2.0
            hi = -1.0
            for c in range(4):
                bc = b0 if c == 0 else b1 if c == 1 else b2 if c == 2 else b3
                if bc <= 0.0:
                    lo = min(lo, c / 3.0)
                    hi = max(hi, c / 3.0)
                for d in range(c + 1, 4):
                    bd = b1 if d == 1 else b2 if d == 2 else b3
                    if (bc <= 0.0) != (bd <= 0.0):
                        t = (c + (d - c) * bc / (bc - bd)) / 3.0
                        lo = min(lo, t)
                        hi = max(hi, t)
            t_lo = max(t_lo, lo)
            t_hi = min(t_hi, hi)
        if t_hi < t_lo:
            continue
        margin = _CLIP_MARGIN * max(t_hi - t_lo, 1e-3)
        step = eta_s[k + 1] - eta_s[k]
        a = eta_s[k]
        if left and t_lo - margin > _CLIP_SHARE:
            eta_s[k] = a + (t_lo - margin) * step
            rs[k, 0], rs[k, 1], rs[k, 2], rs[k, 3], rs[k, 4], rs[k, 5] = beam_point(beam_code, Qe, length, s0, s1, s2,
                                                                                 eta_s[k], H, dH)
        if right and t_hi + margin < 1.0 - _CLIP_SHARE:
            eta_s[k + 1] = a + (t_hi + margin) * step
            rs[k + 1, 0], rs[k + 1, 1], rs[k + 1, 2], rs[k + 1, 3], rs[k + 1, 4], rs[k + 1, 5] = beam_point(
                beam_code, Qe, length, s0, s1, s2, eta_s[k + 1], H, dH)


@njit
def _any_live(live, k, n_faces):
    """Whether sample interval k is live for some face."""
    for f in range(n_faces):
        if live[k, f]:
            return True
    return False


@njit
def _beyond(faces, zs, k):
    """How far beyond the farthest face plane the linearised image of sample k lies (negative: inside)."""
    out = -np.inf
    for f in range(faces.shape[0]):
        out = max(out, _face_side(faces[f], zs[k]))
    return out


#: how much deeper than its error bound the linearised image of a point must lie behind (or beyond) the face
#: planes for :func:`_linear_side` to decide (parameter units): far above every tolerance of the inside tests
#: it stands in for (1e-11 for owners, 1e-9 for crossings, 1e-6 for the tiling check's probes)
_SIDE_MARGIN = 1e-5


@njit
def _linear_side(code, s, linear, errors, x0, x1, x2, pad):
    """Where element s's linearised map puts the point x (local to the element's origin), for certain:
    -1 inside, 1 outside, 0 undecided (also for affine elements, located exactly anyway, and for those
    without an error bound, ``errors`` NaN).

    The linearised parameters ζ of x lie within ε (``errors[s]``, :func:`_linear_error`) of the ξ of any
    preimage of x in the element (or within ``_REACH_MARGIN`` of it). Beyond a face plane by more than
    Σ_i |n_i| ε_i + ``pad``: x has no preimage there, it lies outside. Behind every face plane by more
    than that: the map ξ ↦ ζ(x(ξ)) = ξ + δ(ξ), |δ_i| <= ε_i, moves no point of the element's boundary
    across ζ(x) on the way from the identity (t δ, t from 0 to 1), so its degree at ζ(x) stays 1 and x
    has a preimage in the element, deeper than ``pad`` behind every face: it lies inside for every
    inside test of the library (tolerances up to ``pad``), whichever branch Newton would have found.
    """
    if linear[s, 4, 0] == 1.0 or not errors[s, 0] >= 0.0:
        return 0
    z0, z1, z2 = linear_image(code, linear, s, x0, x1, x2)
    faces = solid.faces(code)
    inside = True
    for f in range(faces.shape[0]):
        face = faces[f]
        slack = _slack(face, errors, s, pad)
        g = face[3, 0] * (z0 - face[0, 0]) + face[3, 1] * (z1 - face[0, 1]) + face[3, 2] * (z2 - face[0, 2])
        if g > slack:
            return 1
        if g >= -slack:
            inside = False
    return -1 if inside else 0


@njit
def _contains(r0, r1, r2, e, p, pair_solid, beam_origin, solid_boxes, hull, codes, conn, points, solid_origin, solid_h,
              linear, errors, tol, pad, X, xi, trial, N, dN, a, stack):
    """(contains, decided): whether candidate pair p's element contains the point r (beam element e's frame)
    to ``tol`` (``first_containing``'s test on that element: the same answer), and whether
    :func:`_linear_side` decided it without a projection (then ``xi`` is not set)."""
    s = pair_solid[p]
    if not in_box(solid_boxes[s], r0 + beam_origin[e, 0], r1 + beam_origin[e, 1], r2 + beam_origin[e, 2]):
        return False, True
    side = _linear_side(codes[s], s, linear, errors, r0 + (beam_origin[e, 0] - solid_origin[s, 0]),
                        r1 + (beam_origin[e, 1] - solid_origin[s, 1]), r2 + (beam_origin[e, 2] - solid_origin[s, 2]),
                        pad)
    if side != 0:
        return side < 0, True
    found = first_containing(r0, r1, r2, e, pair_solid, p, p + 1, beam_origin, solid_boxes, hull, codes, conn, points,
                             solid_origin, solid_h, linear, tol, X, xi, trial, N, dN, a, stack, ANY_CANDIDATE)
    return found >= 0, False


@njit
def _pair_crossings(pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h, linear, errors, hull,
                    beam_code, Q, lengths, beam_origin, beam_boxes, straight, search_points, out_eta, out_face,
                    out_count, unsearched, overflow, workers):
    n_pairs = pair_beam.shape[0]
    claims = new_claims(n_pairs, workers)
    _pair_crossings_workers(workers, claims, pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h,
                            linear, errors, hull, beam_code, Q, lengths, beam_origin, beam_boxes, straight,
                            search_points, out_eta, out_face, out_count, unsearched, overflow)


@njit
def _pair_crossings_worker(worker, claims, pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h, linear,
                           errors, hull, beam_code, Q, lengths, beam_origin, beam_boxes, straight, search_points, out_eta,
                           out_face, out_count, unsearched, overflow):
    n_pairs = pair_beam.shape[0]
    S = search_points
    C = np.empty((solid.MAX_CONTROL, 3))
    reach = np.empty(solid.MAX_FACES, dtype=np.bool_)
    X, N, dN, H, dH, xi, trial = point_buffers()
    a, stack = search_buffers()
    z = np.empty(3)
    start = np.empty(3)
    eta_s = np.empty(S)
    xi_s = np.empty((S, 3))
    dxi_s = np.empty((S, 3))
    ok = np.empty(S, dtype=np.bool_)
    g = np.empty(S)
    dg = np.empty(S)
    rs = np.empty((S, 6))
    zs = np.empty((S, 6))
    live = np.empty((S, solid.MAX_FACES), dtype=np.bool_)
    need = np.empty(S, dtype=np.bool_)
    begin, stop = claim(claims, n_pairs, worker)
    while begin < stop:
        _pair_crossings_chunk_call(begin, stop, pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h,
                                   linear, errors, hull, beam_code, Q, lengths, beam_origin, beam_boxes, straight,
                                   out_eta, out_face, out_count, unsearched, overflow, X, xi, S, C, reach, eta_s, H, dH,
                                   start, ok, trial, N, dN, a, stack, xi_s, dxi_s, g, dg, z, rs, zs, live, need)
        begin, stop = claim(claims, n_pairs, worker)


_pair_crossings_workers = in_parallel(_pair_crossings_worker)


@njit
def _pair_crossings_chunk(begin, stop, pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h, linear,
                          errors, hull, beam_code, Q, lengths, beam_origin, beam_boxes, straight, out_eta, out_face,
                          out_count, unsearched, overflow, X, xi, S, C, reach, eta_s, H, dH, start, ok, trial, N, dN, a,
                          stack, xi_s, dxi_s, g, dg, z, rs, zs, live, need):
    # the caller holds every array for this call: the calls below pass them without reference
    # counting (see mortar1d3d._borrowed)
    (pair_beam, pair_solid, codes, conn, points, solid_origin, solid_h, linear, errors, hull, Q, lengths, beam_origin,
        beam_boxes, straight, out_eta, out_face, out_count, unsearched, overflow, X, xi, S, C, reach, eta_s, H, dH,
        start, ok, trial, N, dN, a, stack, xi_s, dxi_s, g, dg, z, rs, zs, live, need) = borrowed(pair_beam, pair_solid,
        codes, conn, points, solid_origin, solid_h, linear, errors, hull, Q, lengths, beam_origin, beam_boxes,
        straight, out_eta, out_face, out_count, unsearched, overflow, X, xi, S, C, reach, eta_s, H, dH, start, ok,
        trial, N, dN, a, stack, xi_s, dxi_s, g, dg, z, rs, zs, live, need)
    for p in range(begin, stop):
        e = pair_beam[p]
        s = pair_solid[p]
        code = codes[s]
        h = solid_h[s]
        Qe = Q[e]
        load_element(points, conn, s, code, solid_origin, X)
        overflow[p] = False
        unsearched[p] = BOX_MISS
        out_count[p] = 0
        if not _faces_in_reach(code, X, h, beam_boxes[e], solid_origin[s], C, reach):
            continue
        s0 = beam_origin[e, 0] - solid_origin[s, 0]
        s1 = beam_origin[e, 1] - solid_origin[s, 1]
        s2 = beam_origin[e, 2] - solid_origin[s, 2]
        unsearched[p] = LINEAR_MISS
        if not _faces_in_linear_reach(code, h, s, linear, errors, beam_code, Qe, lengths[e], s0, s1, s2, C, H, dH,
                                      reach):
            continue
        for k in range(S):
            eta_s[k] = -1.0 + 2.0 * k / (S - 1)
            rs[k, 0], rs[k, 1], rs[k, 2], rs[k, 3], rs[k, 4], rs[k, 5] = beam_point(beam_code, Qe, lengths[e], s0, s1,
                                                                                 s2, eta_s[k], H, dH)
        # the sample intervals the linearised map cannot rule out, and the samples that bound them
        if not _live_intervals(code, s, h, linear, errors, eta_s, rs, reach, zs, live, need):
            continue
        _clip_samples(code, s, h, linear, errors, eta_s, rs, zs, live, beam_code, Qe, lengths[e], s0, s1, s2, H,
                      dH)
        unsearched[p] = SEARCHED
        # samples along the beam element: ξ(η) and dξ/dη = J⁻¹ r'(η) (warm-started Newton)
        solid.centre(code, xi)
        affine = is_affine(linear, s)
        for k in range(S):
            ok[k] = False
            if not need[k]:
                continue
            r0, r1, r2, d0, d1, d2 = rs[k, 0], rs[k, 1], rs[k, 2], rs[k, 3], rs[k, 4], rs[k, 5]
            if affine:
                # ξ(η) and dξ/dη = A⁻¹ r' directly
                ok[k] = True
                linear_parameters(code, linear, s, r0, r1, r2, xi_s[k])
                for i in range(3):
                    dxi_s[k, i] = linear[s, i, 0] * d0 + linear[s, i, 1] * d1 + linear[s, i, 2] * d2
                continue
            if k == 0 or not need[k - 1]:
                # the first sample, or the first after samples not needed: the linearised estimate
                solid.centre(code, xi)
                linear_parameters(code, linear, s, r0, r1, r2, xi)
            elif ok[k - 1]:
                # the previous sample's tangent predicts this one: ξ + dξ/dη Δη (after a failed
                # sample, xi holds the centre)
                for i in range(3):
                    xi[i] = xi_s[k - 1, i] + dxi_s[k - 1, i] * (eta_s[k] - eta_s[k - 1])
            start[0], start[1], start[2] = xi[0], xi[1], xi[2]
            ok[k] = project_point(code, X, r0, r1, r2, h, xi, trial, N, dN) == CONVERGED
            # a sample beyond a hull plane has no preimage inside: a converged warm start is its
            # answer (the branch the samples follow, solved once), certificate or not; the plane is
            # tested first, so that only samples near the element need its certificate
            if not (ok[k] and (solid.is_inside(code, xi, PARAMETER_TOL)
                               or (solid.HULL_TEST[code] and not in_hull(hull, s, r0, r1, r2))
                               or certified_outside(code, linear, s, xi, X, a))):
                # the warm start may have followed a branch of the map folded outside a
                # curved element: locate the sample for certain. Without a converged warm start, a
                # sample beyond a hull plane gets the Newton solves of locate_point without its
                # subdivision search
                start[0], start[1], start[2] = xi[0], xi[1], xi[2]
                if in_hull(hull, s, r0, r1, r2):
                    status = locate_point(code, X, r0, r1, r2, h, PARAMETER_TOL, linear, s, xi, trial, N, dN,
                                          a, stack)
                else:
                    status = locate_outside(code, X, r0, r1, r2, h, PARAMETER_TOL, linear, s, xi, trial, N, dN,
                                            a, stack)
                ok[k] = status != NOT_CONVERGED
                if not ok[k]:
                    xi[0], xi[1], xi[2] = start[0], start[1], start[2]
            if ok[k]:
                xi_s[k, 0], xi_s[k, 1], xi_s[k, 2] = xi[0], xi[1], xi[2]
                j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xi, N, dN)
                det, dxi_s[k, 0], dxi_s[k, 1], dxi_s[k, 2] = solve3(j00, j01, j02, j10, j11, j12, j20, j21,
                                                                   j22, d0, d1, d2)
            else:
                xi_s[k, 0], xi_s[k, 1], xi_s[k, 2] = start[0], start[1], start[2]
                dxi_s[k] = 0.0
                solid.centre(code, xi)
        faces = solid.faces(code)
        line = affine and straight[e]
        count = np.int64(0)     # not the literal 0: _record would compile for it as well
        for f in range(faces.shape[0]):
            if not reach[f]:
                continue
            face = faces[f]
            for k in range(S):
                if not need[k]:
                    continue
                g[k] = (face[3, 0] * (xi_s[k, 0] - face[0, 0]) + face[3, 1] * (xi_s[k, 1] - face[0, 1])
                        + face[3, 2] * (xi_s[k, 2] - face[0, 2]))
                dg[k] = face[3, 0] * dxi_s[k, 0] + face[3, 1] * dxi_s[k, 1] + face[3, 2] * dxi_s[k, 2]
            for k in range(S):
                if need[k] and not ok[k]:
                    # the projection failed here: start on the face centre
                    for i in range(3):      # element by element: an array assignment compiles Numba's
                        start[i] = solid.FACE_CENTROIDS[code, f, i]   # shape-mismatch message
                    eta = _try_crossing(code, X, h, beam_code, Qe, lengths[e], s0, s1, s2, face, eta_s[k],
                                        start[0], start[1], start[2], z, xi, N, dN, H, dH)
                    count = _record(eta, f, out_eta, out_face, p, count, overflow)
            for k in range(S - 1):
                if not (live[k, f] and ok[k] and ok[k + 1]):
                    continue
                step = eta_s[k + 1] - eta_s[k]
                g0, g1 = g[k], g[k + 1]
                d0, d1 = dg[k] * step, dg[k + 1] * step
                # cheap reject: the cubic stays clearly on one side of the face
                if min(g0, g1) > 0.5 * (abs(d0) + abs(d1)) or max(g0, g1) < -0.5 * (abs(d0) + abs(d1)):
                    continue
                # scan the cubic model: start Newton at each sign change and at a near touch
                prev = g0
                best = abs(g0)
                best_t = 0.0
                for i in range(1, _SCAN + 1):
                    t = i / _SCAN
                    cur = _hermite_g(g0, g1, d0, d1, t)
                    t_start = -1.0
                    if prev * cur <= 0.0 and not (prev == 0.0 and i > 1):
                        step = prev / (prev - cur) if prev != cur else 0.5
                        t_start = t - 1.0 / _SCAN + (1.0 / _SCAN) * step
                    if abs(cur) < best:
                        best = abs(cur)
                        best_t = t
                    prev = cur
                    if t_start < 0.0:
                        continue
                    eta = _try_between(code, X, h, beam_code, Qe, lengths[e], s0, s1, s2, face, eta_s, xi_s, k,
                                       t_start, z, xi, N, dN, H, dH)
                    count = _record(eta, f, out_eta, out_face, p, count, overflow)
                if line:
                    # g is linear in η: a sign change is its only root, and it cannot touch the
                    # face or cross it twice (the searches below found each crossing again)
                    continue
                # a sample on the face: the scan starts Newton there and finds that point again;
                # a crossing soon after it (leaving at a corner and coming back) is a root of
                # the cubic divided by its known root (found by make fuzz, see test_hard_cases)
                for end in range(2):
                    if abs(g1 if end else g0) > PARAMETER_TOL:
                        continue
                    if end:
                        r_a, r_b = _deflated_roots(g0, -d1, -d0)
                        r_a, r_b = 1.0 - r_a, 1.0 - r_b
                    else:
                        r_a, r_b = _deflated_roots(g1, d0, d1)
                    for t_start in (r_a, r_b):
                        if not 0.0 < t_start < 1.0:
                            continue
                        eta = _try_between(code, X, h, beam_code, Qe, lengths[e], s0, s1, s2, face, eta_s, xi_s,
                                           k, t_start, z, xi, N, dN, H, dH)
                        count = _record(eta, f, out_eta, out_face, p, count, overflow)
                # nearest the face at a sample, beyond which the next interval changes sign: the
                # model approaches the face monotonically, and the crossing lies in that interval,
                # whose scan starts Newton at its sign change
                at_crossing = ((best_t == 1.0 and k + 2 < S and ok[k + 2] and g[k + 1] * g[k + 2] <= 0.0)
                               or (best_t == 0.0 and k > 0 and ok[k - 1] and g[k - 1] * g[k] <= 0.0))
                if best < _NEAR_FACE * (abs(d0) + abs(d1) + abs(g1 - g0)) and g0 * g1 > 0.0 and not at_crossing:
                    # close to the face without a sign change: a touch or a missed double crossing.
                    # Newton converges to one of two close roots; the other lies about as far on
                    # the other side of the extremum of g: start there too (a dip through the
                    # face shorter than a sample interval has both ends found). A root outside
                    # the sample interval is no end of a dip within it: it is a crossing of a
                    # neighbouring interval (found by that interval's own search), and its
                    # mirror would only find it again
                    eta = _try_between(code, X, h, beam_code, Qe, lengths[e], s0, s1, s2, face, eta_s, xi_s, k,
                                       best_t, z, xi, N, dN, H, dH)
                    count = _record(eta, f, out_eta, out_face, p, count, overflow)
                    if eta_s[k] <= eta <= eta_s[k + 1]:
                        t_mirror = 2.0 * best_t - (eta - eta_s[k]) / (eta_s[k + 1] - eta_s[k])
                        if 0.0 < t_mirror < 1.0:
                            eta = _try_between(code, X, h, beam_code, Qe, lengths[e], s0, s1, s2, face, eta_s,
                                               xi_s, k, t_mirror, z, xi, N, dN, H, dH)
                            count = _record(eta, f, out_eta, out_face, p, count, overflow)
        out_count[p] = count


#: the loop body of :func:`_pair_crossings` (per claimed chunk), optimised once: called through a symbol
_pair_crossings_chunk_call = unlinked(_pair_crossings_chunk)


@njit
def _insertion_sort(a, n):
    for i in range(1, n):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@njit
def _next_crossing(crossing_eta, crossing_face, crossing_count, p, q, tol):
    """η of the next crossing of the same face after crossing q of pair p (farther than ``tol``); inf if none."""
    f = crossing_face[p, q]
    after = np.inf
    if f < 0:
        return after
    for k in range(crossing_count[p]):
        eta = crossing_eta[p, k]
        if crossing_face[p, k] == f and crossing_eta[p, q] + tol < eta < after:
            after = eta
    return after


@njit
def _face_zone(crossing_eta, crossing_face, crossing_count, p, a, b, tol):
    """The face of pair p's element whose consecutive crossings η1 <= a and η2 >= b enclose [a, b]
    (to ``tol``): between them the beam stays on one side of that face. -1 if none."""
    for q in range(crossing_count[p]):
        if crossing_face[p, q] >= 0 and crossing_eta[p, q] <= a + tol:
            if b - tol <= _next_crossing(crossing_eta, crossing_face, crossing_count, p, q, tol) < np.inf:
                return crossing_face[p, q]
    return -1


@njit
def _face_side(face, xi):
    """n·(ξ - o) of a face (origin, a, b, normal rows): > 0 beyond it."""
    return face[3, 0] * (xi[0] - face[0, 0]) + face[3, 1] * (xi[1] - face[0, 1]) + face[3, 2] * (xi[2] - face[0, 2])


@njit
def _beyond_bounding_faces(code, crossing_eta, crossing_face, crossing_count, p, a, b, tol, xi):
    """How far ξ lies beyond the faces of pair p's element that bound the piece [a, b]: the faces crossed
    within ``tol`` of its ends, and the face whose consecutive crossings enclose it (-inf if none)."""
    faces = solid.faces(code)
    beyond = -np.inf
    f = _face_zone(crossing_eta, crossing_face, crossing_count, p, a, b, tol)
    if f >= 0:
        beyond = _face_side(faces[f], xi)
    for q in range(crossing_count[p]):
        if crossing_face[p, q] >= 0 and (abs(crossing_eta[p, q] - a) <= tol or abs(crossing_eta[p, q] - b) <= tol):
            beyond = max(beyond, _face_side(faces[crossing_face[p, q]], xi))
    return beyond


@njit
def _face_condition(e, s, f, eta, codes, conn, points, solid_origin, solid_h, linear, beam_code, Q, lengths,
                    beam_origin, X, xi, trial, N, dN, H, dH, a, stack):
    """g = n·(ξ - o) of face f of element s at the centreline point r(η) (> 0: beyond the face); NaN if
    r(η) cannot be located in s. Leaves ξ in ``xi``."""
    code = codes[s]
    r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], beam_origin[e, 0] - solid_origin[s, 0],
                                     beam_origin[e, 1] - solid_origin[s, 1], beam_origin[e, 2] - solid_origin[s, 2],
                                     eta, H, dH)
    if is_affine(linear, s):
        linear_parameters(code, linear, s, r0, r1, r2, xi)
    else:
        load_element(points, conn, s, code, solid_origin, X)
        if locate_point(code, X, r0, r1, r2, solid_h[s], PARAMETER_TOL, linear, s, xi, trial, N, dN, a,
                        stack) == NOT_CONVERGED:
            return np.nan
    return _face_side(solid.faces(code)[f], xi)


@njit
def _merge_distance(beam_code, Qe, length, eta, h, H, dH):
    """Cuts closer than this in η are one point: ``MERGE_TOL`` h along the centreline at η."""
    _, _, _, d0, d1, d2 = beam_point(beam_code, Qe, length, 0.0, 0.0, 0.0, eta, H, dH)
    return MERGE_TOL * h / max(norm3(d0, d1, d2), 1e-300)


@njit
def _tile(pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes, conn, points, solid_origin,
          solid_h, solid_boxes, hull, linear, errors, beam_code, Q, lengths, beam_origin, seg_offsets, seg_solid,
          seg_start, seg_end, seg_count, workers):
    n_beam = pair_offsets.shape[0] - 1
    claims = new_claims(n_beam, workers)
    _tile_workers(workers, claims, pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes,
                  conn, points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q, lengths,
                  beam_origin, seg_offsets, seg_solid, seg_start, seg_end, seg_count)


@njit
def _tile_worker(worker, claims, pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes, conn,
                 points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q, lengths,
                 beam_origin, seg_offsets, seg_solid, seg_start, seg_end, seg_count):
    n_beam = pair_offsets.shape[0] - 1
    X, N, dN, H, dH, xi, trial = point_buffers()
    a, stack = search_buffers()
    cuts = np.empty(64)
    reach = np.empty(64)
    touch = np.empty(64, dtype=np.bool_)
    owners = np.empty(64, dtype=np.int64)
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _tile_chunk_call(begin, stop, pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes,
                         conn, points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q,
                         lengths, beam_origin, seg_offsets, seg_solid, seg_start, seg_end, seg_count, cuts, reach, H, dH,
                         touch, owners, X, xi, trial, N, dN, a, stack)
        begin, stop = claim(claims, n_beam, worker)


_tile_workers = in_parallel(_tile_worker)


@njit
def _tile_chunk(begin, stop, pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes, conn,
                points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q, lengths, beam_origin,
                seg_offsets, seg_solid, seg_start, seg_end, seg_count, cuts, reach, H, dH, touch, owners, X, xi, trial,
                N, dN, a, stack):
    # the caller holds every array for this call: the calls below pass them without reference
    # counting (see mortar1d3d._borrowed)
    (pair_offsets, pair_solid, crossing_eta, crossing_face, crossing_count, codes, conn, points, solid_origin,
        solid_h, solid_boxes, hull, linear, errors, Q, lengths, beam_origin, seg_offsets, seg_solid, seg_start, seg_end,
        seg_count, cuts, reach, H, dH, touch, owners, X, xi, trial, N, dN, a, stack) = borrowed(pair_offsets,
        pair_solid, crossing_eta, crossing_face, crossing_count, codes, conn, points, solid_origin, solid_h,
        solid_boxes, hull, linear, errors, Q, lengths, beam_origin, seg_offsets, seg_solid, seg_start, seg_end,
        seg_count, cuts, reach, H, dH, touch, owners, X, xi, trial, N, dN, a, stack)
    for e in range(begin, stop):
        p0 = pair_offsets[e]
        p1 = pair_offsets[e + 1]
        m = 0
        h = np.inf
        big = max(abs(beam_origin[e, 0]), abs(beam_origin[e, 1]), abs(beam_origin[e, 2]))
        for p in range(p0, p1):
            m += crossing_count[p]
            h = min(h, solid_h[pair_solid[p]])
        # far from the origin the coordinates themselves carry round-off (about eps |x|; in
        # parameter units relative to h): a beam meant to lie in a face is off it by that much
        round_off = 2.220446049250313e-16 * big / h
        owner_tol = SEGMENT_OWNER_TOL + 8.0 * round_off
        touch_tol = TOUCH_TOL + 64.0 * round_off
        pad = _SIDE_MARGIN + 64.0 * round_off
        if m + 2 > cuts.shape[0]:
            cuts = np.empty(2 * (m + 2))
            reach = np.empty(2 * (m + 2))
            touch = np.empty(2 * (m + 2), dtype=np.bool_)
            owners = np.empty(2 * (m + 2), dtype=np.int64)
        # breakpoints: -1, the crossings (sorted; physically coincident ones merged), +1
        m = np.int64(0)     # not the literal 0: _insertion_sort would compile for it as well
        for p in range(p0, p1):
            for q in range(crossing_count[p]):
                cuts[1 + m] = crossing_eta[p, q]
                m += 1
        _insertion_sort(cuts[1:], m)
        cuts[0] = -1.0
        reach[0] = _merge_distance(beam_code, Q[e], lengths[e], -1.0, h, H, dH)
        n_pts = 1
        for q in range(1, m + 1):
            tol = _merge_distance(beam_code, Q[e], lengths[e], cuts[q], h, H, dH)
            if cuts[q] > cuts[n_pts - 1] + max(tol, reach[n_pts - 1]) and cuts[q] < 1.0 - tol:
                cuts[n_pts] = cuts[q]
                reach[n_pts] = tol
                n_pts += 1
        cuts[n_pts] = 1.0
        reach[n_pts] = _merge_distance(beam_code, Q[e], lengths[e], 1.0, h, H, dH)
        n_pts += 1

        # a tangential touch: two consecutive crossings of the same face of one candidate with
        # the centreline on that face between them (the face condition vanishes there and,
        # both ends being roots, so does its derivative: a double root, which Newton
        # resolves only to about sqrt(round-off), into several close cuts). Every interval
        # between them is a touch.
        for iv in range(n_pts - 1):
            touch[iv] = False
        for p in range(p0, p1):
            for q in range(crossing_count[p]):
                eta1 = crossing_eta[p, q]
                eta2 = _next_crossing(crossing_eta, crossing_face, crossing_count, p, q, reach[0])
                if eta2 == np.inf:
                    continue
                g = _face_condition(e, pair_solid[p], crossing_face[p, q], 0.5 * (eta1 + eta2), codes, conn,
                                    points, solid_origin, solid_h, linear, beam_code, Q, lengths, beam_origin,
                                    X, xi, trial, N, dN, H, dH, a, stack)
                if not abs(g) <= touch_tol:
                    continue
                for iv in range(n_pts - 1):
                    if cuts[iv] >= eta1 - 2.0 * reach[iv] and cuts[iv + 1] <= eta2 + 2.0 * reach[iv + 1]:
                        touch[iv] = True

        # owner of every interval: the lowest-index candidate containing its midpoint
        for iv in range(n_pts - 1):
            owners[iv] = -1
            mid = 0.5 * (cuts[iv] + cuts[iv + 1])
            r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, mid, H, dH)
            for p in range(p0, p1):
                inside, decided = _contains(r0, r1, r2, e, p, pair_solid, beam_origin, solid_boxes, hull, codes, conn,
                                            points, solid_origin, solid_h, linear, errors, owner_tol, pad, X, xi,
                                            trial, N, dN, a, stack)
                if not inside:
                    continue
                # a piece bounded by crossings of the owner's faces lies on the owner's side of
                # those faces only if the face conditions say so at its midpoint, not within the
                # inside tolerance: a piece that leaves through a face and comes back through it,
                # or a beam that passes an edge or a corner just outside, crossing the faces'
                # planes beyond the faces (within the crossings' tolerance). A midpoint the
                # linearised map puts inside lies deeper than ``pad`` behind every face: no test
                if decided or _beyond_bounding_faces(codes[pair_solid[p]], crossing_eta, crossing_face, crossing_count,
                                                     p, cuts[iv], cuts[iv + 1], 2.0 * max(reach[iv], reach[iv + 1]),
                                                     xi) <= touch_tol:
                    owners[iv] = pair_solid[p]
                    break
        # a run of touches stays on the side the beam is on: it joins a neighbouring piece whose
        # owner contains it, or is not coupled (a touch from outside). A beam element that
        # lies in a face from end to end has no such neighbour: its pieces are owned as usual.
        iv = 0
        while iv < n_pts - 1:
            if not touch[iv]:
                iv += 1
                continue
            last = iv
            while last + 1 < n_pts - 1 and touch[last + 1]:
                last += 1
            if iv == 0 and last == n_pts - 2:
                break
            before = owners[iv - 1] if iv > 0 else -1
            after = owners[last + 1] if last + 1 < n_pts - 1 else -1
            for k in range(iv, last + 1):
                owners[k] = -1
                mid = 0.5 * (cuts[k] + cuts[k + 1])
                r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, mid, H, dH)
                for neighbour in (before, after):
                    if neighbour >= 0 and first_containing(
                            r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, hull, codes, conn,
                            points, solid_origin, solid_h, linear, owner_tol, X, xi, trial, N, dN, a, stack,
                            neighbour) == neighbour:
                        owners[k] = neighbour
                        break
            iv = last + 1

        base = seg_offsets[e]
        n_seg = 0
        for iv in range(n_pts - 1):
            owner = owners[iv]
            if owner < 0:
                continue
            a_eta = cuts[iv]
            b_eta = cuts[iv + 1]
            if n_seg > 0 and seg_solid[base + n_seg - 1] == owner and seg_end[base + n_seg - 1] == a_eta:
                seg_end[base + n_seg - 1] = b_eta
            else:
                seg_solid[base + n_seg] = owner
                seg_start[base + n_seg] = a_eta
                seg_end[base + n_seg] = b_eta
                n_seg += 1
        seg_count[e] = n_seg


#: the loop body of :func:`_tile` (per claimed chunk), optimised once: called through a symbol
_tile_chunk_call = unlinked(_tile_chunk)


_GAP_PROBES = 7


@njit
def _check_tiling(seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets, pair_solid, codes, conn,
                  points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q, lengths, beam_origin,
                  certain, bad, workers):
    """Flag beam elements whose pieces do not tile their embedded part.

    Probes every segment at 1/4 and 3/4 (its midpoint chose the owner): each probe must lie in
    the owner (to 1e-6, the integration points' tolerance). Probes every uncoupled gap at
    ``_GAP_PROBES`` equidistant points: none may lie clearly (1e-6) inside a candidate element
    (cheap: most probes of a gap fall outside every candidate's box). A failure means a
    missed face crossing: the pieces would put integration points outside their element, or
    leave an embedded part uncoupled.

    Not probed: beam elements that reach no face of any candidate (``certain``) and lie in one
    element as a single piece [-1, 1]: without a crossing, the element containing the midpoint
    contains all of it.
    """
    n_beam = pair_offsets.shape[0] - 1
    claims = new_claims(n_beam, workers)
    _check_tiling_workers(workers, claims, seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets,
                          pair_solid, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
                          errors, beam_code, Q, lengths, beam_origin, certain, bad)


@njit
def _check_tiling_worker(worker, claims, seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets,
                         pair_solid, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
                         errors, beam_code, Q, lengths, beam_origin, certain, bad):
    n_beam = pair_offsets.shape[0] - 1
    loose = 1e3 * PARAMETER_TOL
    X, N, dN, H, dH, xi, trial = point_buffers()
    a_buf, stack = search_buffers()
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        _check_tiling_chunk_call(begin, stop, seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets,
                                 pair_solid, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
                                 errors, beam_code, Q, lengths, beam_origin, certain, bad, H, dH, loose, X, xi, trial,
                                 N, dN, a_buf, stack)
        begin, stop = claim(claims, n_beam, worker)


_check_tiling_workers = in_parallel(_check_tiling_worker)


@njit
def _check_tiling_chunk(begin, stop, seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets, pair_solid,
                        codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear, errors, beam_code, Q,
                        lengths, beam_origin, certain, bad, H, dH, loose, X, xi, trial, N, dN, a_buf, stack):
    # the caller holds every array for this call: the calls below pass them without reference
    # counting (see mortar1d3d._borrowed)
    (seg_offsets, seg_solid, seg_start, seg_end, seg_count, pair_offsets, pair_solid, codes, conn, points,
        solid_origin, solid_h, solid_boxes, hull, linear, errors, Q, lengths, beam_origin, certain, bad, H, dH, X,
        xi, trial, N, dN, a_buf, stack) = borrowed(seg_offsets, seg_solid, seg_start, seg_end, seg_count,
        pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear, errors, Q,
        lengths, beam_origin, certain, bad, H, dH, X, xi, trial, N, dN, a_buf, stack)
    for e in range(begin, stop):
        p0 = pair_offsets[e]
        p1 = pair_offsets[e + 1]
        base = seg_offsets[e]
        if certain[e] and seg_count[e] == 1 and seg_start[base] == -1.0 and seg_end[base] == 1.0:
            bad[e] = False
            continue
        # coordinates far from the origin carry round-off (see _tile_chunk)
        h = np.inf
        for p in range(p0, p1):
            h = min(h, solid_h[pair_solid[p]])
        pad = _SIDE_MARGIN + 64.0 * 2.220446049250313e-16 * max(abs(beam_origin[e, 0]), abs(beam_origin[e, 1]),
                                                                abs(beam_origin[e, 2])) / h
        failed = False
        gap_start = -1.0
        for q in range(seg_count[e] + 1):
            last = q == seg_count[e]
            a = 1.0 if last else seg_start[base + q]
            if a - gap_start > PARAMETER_TOL:
                for k in range(1, _GAP_PROBES + 1):
                    eta = gap_start + k * (a - gap_start) / (_GAP_PROBES + 1)
                    r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, eta, H, dH)
                    for p in range(p0, p1):
                        if _contains(r0, r1, r2, e, p, pair_solid, beam_origin, solid_boxes, hull, codes, conn, points,
                                     solid_origin, solid_h, linear, errors, -loose, pad, X, xi, trial, N, dN, a_buf,
                                     stack)[0]:
                            failed = True
                            break
            if last or failed:
                break
            b = seg_end[base + q]
            owner = seg_solid[base + q]
            p = p0
            while p < p1 and pair_solid[p] != owner:
                p += 1
            if p == p1:
                # not a candidate of this beam element
                failed = True
                break
            for k in (1, 3):
                eta = a + 0.25 * k * (b - a)
                r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, eta, H, dH)
                if not _contains(r0, r1, r2, e, p, pair_solid, beam_origin, solid_boxes, hull, codes, conn, points,
                                 solid_origin, solid_h, linear, errors, loose, pad, X, xi, trial, N, dN, a_buf,
                                 stack)[0]:
                    failed = True
            if failed:
                break
            gap_start = b
        bad[e] = failed


#: the loop body of :func:`_check_tiling` (per claimed chunk), optimised once: called through a symbol
_check_tiling_chunk_call = unlinked(_check_tiling_chunk)


@njit
def _owner(eta, e, pair_solid, p0, p1, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
           beam_code, Q, lengths, beam_origin, X, xi, trial, N, dN, H, dH, a, stack):
    """Lowest-index candidate containing r(η) to ``_SHARP`` (round-off: the owner changes where the
    centreline crosses a face, so the bisected cuts land on the faces)."""
    r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, eta, H, dH)
    return first_containing(r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, hull, codes, conn, points,
                            solid_origin, solid_h, linear, _SHARP, X, xi, trial, N, dN, a, stack, ANY_CANDIDATE)


_SHARP = TOUCH_TOL


@njit
def _bisection_cuts(pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
                    beam_code, Q, lengths, beam_origin, n_samples, out_eta, out_count, workers):
    """Cuts of each beam element where the owner (lowest-index element containing r(η)) changes.

    The fallback that does not rely on face intersections: the owner is sampled at
    ``n_samples`` equidistant η; every change is bisected to 1e-13 in η, and again from the
    cut while the owner just after it still differs from the next sample's (several changes
    between two samples, e.g. across a sliver). Pieces shorter than the sampling that start
    and end in the same owner are not seen.
    """
    n_beam = pair_offsets.shape[0] - 1
    claims = new_claims(n_beam, workers)
    _bisection_cuts_workers(workers, claims, pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h,
                            solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, n_samples, out_eta,
                            out_count)


@njit
def _bisection_cuts_worker(worker, claims, pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h,
                           solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, n_samples, out_eta,
                           out_count):
    n_beam = pair_offsets.shape[0] - 1
    cap = out_eta.shape[1]
    X, N, dN, H, dH, xi, trial = point_buffers()
    a, stack = search_buffers()
    begin, stop = claim(claims, n_beam, worker)
    while begin < stop:
        for e in range(begin, stop):
            p0 = pair_offsets[e]
            p1 = pair_offsets[e + 1]
            count = 0
            previous = -2
            eta_previous = -1.0
            for k in range(n_samples):
                eta = -1.0 + 2.0 * k / (n_samples - 1)
                owner = _owner(eta, e, pair_solid, p0, p1, codes, conn, points, solid_origin, solid_h, solid_boxes,
                               hull, linear, beam_code, Q, lengths, beam_origin, X, xi, trial, N, dN, H, dH, a,
                               stack)
                lo = eta_previous
                current = previous
                while k > 0 and current != owner and count < cap:
                    hi = eta
                    while hi - lo > 1e-13:
                        mid = 0.5 * (lo + hi)
                        if _owner(mid, e, pair_solid, p0, p1, codes, conn, points, solid_origin, solid_h,
                                  solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, X, xi, trial, N,
                                  dN, H, dH, a, stack) == current:
                            lo = mid
                        else:
                            hi = mid
                    out_eta[e, count] = 0.5 * (lo + hi)
                    count += 1
                    current = _owner(hi, e, pair_solid, p0, p1, codes, conn, points, solid_origin, solid_h,
                                     solid_boxes, hull, linear, beam_code, Q, lengths, beam_origin, X, xi, trial,
                                     N, dN, H, dH, a, stack)
                    lo = hi
                previous = owner
                eta_previous = eta
            out_count[e] = count
        begin, stop = claim(claims, n_beam, worker)


_bisection_cuts_workers = in_parallel(_bisection_cuts_worker)


#: search points of the first retry of a beam element whose pieces do not tile
_RETRY_SEARCH_POINTS = 4
#: owner samples along a beam element in the bisection fallback
_BISECTION_SAMPLES = 65


@njit
def _compact_index(offsets, counts):
    out = np.empty(counts.sum(), dtype=np.int64)
    m = 0
    for e in range(counts.shape[0]):
        for q in range(counts[e]):
            out[m] = offsets[e] + q
            m += 1
    return out


def tile(ctx, crossing_eta, crossing_face, crossing_count, errors=None):
    """The second stage: the segments of every beam element of ``ctx`` from the crossings of its pairs.

    Per beam element, its pairs' crossings (rows of the (n_pairs, width) tables, ``crossing_count``
    used; face -1: a cut that is no face crossing) and η = ±1 cut [-1, 1] into intervals; each
    goes to the lowest-index candidate containing its midpoint, neighbours with the same owner
    are merged (see the module docstring). ``errors``: :func:`linear_errors` of ``ctx`` (computed here if not
    given), with which most midpoints are located without a projection (:func:`_linear_side`).

    Returns
    -------
    seg_beam, seg_solid, seg_start, seg_end : (n_segments,) arrays
        Beam element (global index: ``ctx.beam_ids``), owning solid element and η range of every
        segment, ordered by beam element and η.
    seg_count : (m,) int64
        Segments per beam element of ``ctx``.
    """
    pair_offsets = ctx.pair_offsets
    # at most (crossings + 1) intervals per beam element
    cumulative = np.concatenate([[0], np.cumsum(crossing_count)])
    per_beam = cumulative[pair_offsets[1:]] - cumulative[pair_offsets[:-1]] + 1
    seg_offsets = np.concatenate([[0], np.cumsum(per_beam)]).astype(np.int64)
    total = seg_offsets[-1]
    seg_solid = np.empty(total, dtype=np.int64)
    seg_start = np.empty(total)
    seg_end = np.empty(total)
    seg_count = np.zeros(ctx.n_beam, dtype=np.int64)
    if errors is None:
        errors = linear_errors(ctx)
    _tile(pair_offsets, ctx.pair_solid, crossing_eta, crossing_face, crossing_count, ctx.codes, ctx.conn, ctx.points,
          ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.hull, ctx.linear, errors, ctx.beam_code, ctx.Q,
          ctx.lengths, ctx.beam_origin, seg_offsets, seg_solid, seg_start, seg_end, seg_count, workers())
    keep = _compact_index(seg_offsets, seg_count)
    return np.repeat(ctx.beam_ids, seg_count), seg_solid[keep], seg_start[keep], seg_end[keep], seg_count


def check_tiling(ctx, seg_solid, seg_start, seg_end, seg_count, certain, errors=None):
    """(m,) bool: the beam elements of ``ctx`` whose segments (of :func:`tile`) fail the tiling check.

    ``certain`` (m,) bool: beam elements that reach no face of any candidate (not probed when
    they are one piece [-1, 1], see ``_check_tiling``). ``errors``: :func:`linear_errors` of ``ctx``
    (computed here if not given), with which most probes are located without a projection.
    """
    if errors is None:
        errors = linear_errors(ctx)
    seg_offsets = np.concatenate([[0], np.cumsum(seg_count)]).astype(np.int64)
    bad = np.zeros(ctx.n_beam, dtype=np.bool_)
    _check_tiling(seg_offsets, seg_solid, seg_start, seg_end, seg_count, ctx.pair_offsets, ctx.pair_solid, ctx.codes,
                  ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h, ctx.solid_boxes, ctx.hull, ctx.linear, errors,
                  ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin, certain, bad, workers())
    return bad


def _bisected(ctx):
    """Both stages with the owner changes found by bisection as cuts: (seg_beam, ..., seg_end, bad).

    The cuts are stored as the crossings (face -1) of each beam element's first pair.
    """
    n = ctx.n_beam
    cap = 4 * _BISECTION_SAMPLES
    cuts = np.empty((n, cap))
    count = np.zeros(n, dtype=np.int64)
    _bisection_cuts(ctx.pair_offsets, ctx.pair_solid, ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h,
                    ctx.solid_boxes, ctx.hull, ctx.linear, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin,
                    _BISECTION_SAMPLES, cuts, count, workers())
    crossing_eta = np.zeros((len(ctx.pair_solid), cap))
    crossing_face = np.full((len(ctx.pair_solid), cap), -1, dtype=np.int64)     # not a face crossing
    crossing_count = np.zeros(len(ctx.pair_solid), dtype=np.int64)
    has_pairs = np.diff(ctx.pair_offsets) > 0
    first = ctx.pair_offsets[:-1][has_pairs]
    crossing_eta[first] = cuts[has_pairs]
    crossing_count[first] = count[has_pairs]
    errors = linear_errors(ctx)
    *segments, seg_count = tile(ctx, crossing_eta, crossing_face, crossing_count, errors)
    # every beam element is probed: without face crossings no element is known to be one piece
    return (*segments, check_tiling(ctx, *segments[1:], seg_count, np.zeros(n, dtype=np.bool_), errors))


def segment(ctx, search_points, diagnostics=None):
    """Segments of all beam elements of ``ctx``, and which of them fail the tiling check.

    Returns (beam_element, solid_element, eta_start, eta_end, bad): the segments of :func:`tile`
    and ``bad`` (m,) bool from :func:`check_tiling`. A beam element that fails is to be segmented
    again (:func:`resegment`); :func:`mortar1d3d.integration.points.checked_segment_points` does
    that, for these and for the beam elements whose integration points miss their owner.
    ``diagnostics`` (a dict), if given, receives ``face_crossings``, ``pairs_out_of_reach``
    (candidate pairs whose beam element's box misses every face's box: not searched),
    ``pairs_out_of_linear_reach`` (further pairs not searched: the solid element's linearised map
    proves that the beam element reaches none of its faces) and ``beam_elements_out_of_reach`` (beam
    elements all of whose pairs are either).
    """
    errors = linear_errors(ctx)
    crossing_eta, crossing_face, crossing_count, unsearched = pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid,
                                                                             search_points, errors)
    reaching = np.concatenate([[0], np.cumsum(unsearched == SEARCHED)])
    certain = reaching[ctx.pair_offsets[1:]] == reaching[ctx.pair_offsets[:-1]]
    *segments, seg_count = tile(ctx, crossing_eta, crossing_face, crossing_count, errors)
    bad = check_tiling(ctx, *segments[1:], seg_count, certain, errors)
    if diagnostics is not None:
        diagnostics["face_crossings"] = int(crossing_count.sum())
        diagnostics["pairs_out_of_reach"] = int(np.count_nonzero(unsearched == BOX_MISS))
        diagnostics["pairs_out_of_linear_reach"] = int(np.count_nonzero(unsearched == LINEAR_MISS))
        diagnostics["beam_elements_out_of_reach"] = int(certain.sum())
    return (*segments, bad)


def resegment(ctx, elements, search_points, bisection=False):
    """Segment the beam elements ``elements`` (sorted indices) of ``ctx`` again: the fallback of :func:`segment`.

    With ``4 * search_points`` search points, or (``bisection=True``) by bisection of the owner
    along η, which does not rely on the face intersections at all. Returns (beam_element,
    solid_element, eta_start, eta_end, bad), ``bad`` (len(elements),) from the tiling check.
    """
    sub = ctx.beam_subset(np.asarray(elements, dtype=np.int64))
    if bisection:
        return _bisected(sub)
    return segment(sub, min(64, _RETRY_SEARCH_POINTS * search_points))
