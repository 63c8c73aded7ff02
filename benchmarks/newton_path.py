"""Where a call on a curved or distorted solid spends its time: the Newton path profiled (issue 22, item 1).

    .venv/bin/python benchmarks/newton_path.py [--scene hex8|hex27|tet10|nurbs27] [--n 20] [--fibres 1000]
                                               [--distort 0.1] [--repeats 5] [--package CHECKOUT]
                                           [--helices 40]

Scenes (n_gauss 4, search_points 6, 1 thread, as ``make bench``): ``hex8`` is the distorted benchmark
cube (``fibre_cube(n, fibres, 20)``, interior nodes moved by up to ``--distort`` cells,
``generate.distort`` seed 1); ``hex27`` and ``tet10`` the same cube of n³ cells as quadratic
elements, moved the same way (curved edges: no element is affine); ``nurbs27`` the NURBS pipe of
``nurbs_throughput.py`` with its helices (another geometry: compare its points per second, not its
counts; ``--helices`` other than its 40 sizes the call, to see what part of its cost does not grow
with the points: ``targets.py`` always runs 40).

Printed:

1. **Times** per stage (median of ``--repeats`` calls of ``ops.timings``) and integration points per
   second, element- and segment-based, and the segmentation's parts timed alone on the same context
   (median of the repeats): the crossing search (``pair_crossings``), the tiling (``tile``), its check
   (``check_tiling``) and the points of the segments (``segment_points``).
2. **Counts**, from a counting copy of the kernels' decisions (this script's kernels, built from the
   library's own Newton step, inside tests and locators; the library's kernels hold no counters):
   candidate pairs per beam element, the box pairs before the hull planes and how many solid elements they
   hold (a type with hull planes), the one-to-one certificates the library's kernels computed
   (element- and segment-based: a checkout that computes them on first use), element-based
   candidates tested per point (box test passed,
   and how many of those a hull plane rejects before Newton), Newton projections and iterations, points that needed the rare path (restart from the centre,
   face polish, subdivision search); for the segments: Newton iterations of the warm-started
   integration points and their fallbacks; for the crossing search: pairs searched, sample
   projections per searched pair (those the checkout's search needs) and their iterations, face-Newton
   starts, their steps and residual evaluations (a counted copy of the face Newton), and crossings found;
   for a checkout with the linearised map's point test, how many of the segments' midpoints and
   tiling-check probes it decides in their owners.

An iteration is one Newton step (Jacobian, solve, residual at the new point), counted as full steps
from the kernel's start value (see :func:`newton_counted`); a projection that starts at the answer
has 0 iterations and one residual evaluation.
"""
import argparse
import sys
import time

import numpy as np

from _record import record
from throughput import _package_root

# the package must be imported from the chosen checkout before anything imports it
sys.path.insert(0, str(_package_root(None)))

import numba  # noqa: E402

import mortar1d3d as m13  # noqa: E402
from mortar1d3d._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, PARAMETER_TOL, njit  # noqa: E402
from mortar1d3d.elements.solid import dispatch as solid  # noqa: E402
from mortar1d3d.geometry import projection as pr  # noqa: E402
from mortar1d3d.geometry.beam import beam_point, beams_affine  # noqa: E402
from mortar1d3d.geometry.intersection import face_coordinates  # noqa: E402
from mortar1d3d.geometry.intersection import _residual as face_residual  # noqa: E402
from mortar1d3d.geometry.intersection import _BACKTRACKS as FACE_BACKTRACKS  # noqa: E402
from mortar1d3d.geometry.intersection import _MAX_ETA as FACE_MAX_ETA  # noqa: E402
from mortar1d3d.geometry.intersection import _POLISH_ITERATIONS as FACE_POLISH_ITERATIONS  # noqa: E402
from mortar1d3d.geometry.intersection import _POLISH_STEP as FACE_POLISH_STEP  # noqa: E402
from mortar1d3d.geometry.context import KernelInput  # noqa: E402
from mortar1d3d.geometry.linalg import norm3, solve3  # noqa: E402
from mortar1d3d.geometry import segmentation as sg  # noqa: E402
from mortar1d3d.integration.points import element_points, segment_points  # noqa: E402
from mortar1d3d.quadrature import gauss_legendre  # noqa: E402

N_GAUSS = 4
SEARCH_POINTS = 6
#: a checkout whose linear maps leave the one-to-one certificates to their first use marks them so
PENDING = getattr(pr, "PENDING_CERTIFICATE", None)

#: whether the checkout's crossing search skips a touch start at a sample next to a sign change
TOUCH_SKIPS_CROSSINGS = "at_crossing" in open(sg.__file__).read()

if hasattr(sg, "_live_intervals"):
    live_intervals = sg._live_intervals
else:
    @njit
    def live_intervals(code, s, h, linear, errors, eta_s, rs, reach, zs, live, need):
        """An older checkout: every sample is projected, every interval of a face in reach searched."""
        for k in range(eta_s.shape[0]):
            need[k] = True
            for f in range(solid.MAX_FACES):
                live[k, f] = f < solid.faces(code).shape[0] and reach[f]
        return True

if hasattr(sg, "_clip_samples"):
    clip_samples = sg._clip_samples
else:
    @njit
    def clip_samples(code, s, h, linear, errors, eta_s, rs, zs, live, beam_code, Qe, length, s0, s1, s2, H, dH):
        """An older checkout: the samples stay where they are."""
        return

if hasattr(sg, "linear_errors"):
    @njit
    def faces_in_linear_reach(code, X, h, s, linear, errors, beam_code, Qe, length, s0, s1, s2, a, Y, H, dH, reach):
        """The library's linear-reach test, its error bounds ``errors`` computed once per element."""
        return sg._faces_in_linear_reach(code, h, s, linear, errors, beam_code, Qe, length, s0, s1, s2, Y, H, dH,
                                         reach)
elif hasattr(sg, "_faces_in_linear_reach"):
    @njit
    def faces_in_linear_reach(code, X, h, s, linear, errors, beam_code, Qe, length, s0, s1, s2, a, Y, H, dH, reach):
        """An older checkout's linear-reach test (its error bounds computed for every pair)."""
        return sg._faces_in_linear_reach(code, X, h, s, linear, beam_code, Qe, length, s0, s1, s2, a, Y, H, dH, reach)
else:
    @njit
    def faces_in_linear_reach(code, X, h, s, linear, errors, beam_code, Qe, length, s0, s1, s2, a, Y, H, dH, reach):
        """An older checkout: only the boxes decide which pairs are searched."""
        return True

if PENDING is not None:
    certified_outside = pr.certified_outside
else:
    @njit
    def certified_outside(code, linear, s, xi, X, a):
        """An older checkout's certificate test (the margins computed beforehand, for every element)."""
        return pr.certified_outside(code, linear, s, xi)


def scene(name, n, fibres, amplitude, n_helices=40):
    """(beams, solid) of the named scene (see the module docstring)."""
    if name == "nurbs27":
        sys.path.insert(0, str(_package_root(None) / "benchmarks"))
        from nurbs_throughput import helices, meshes
        return helices(n_helices), meshes((2, 24, 8))[0]
    beams, cube = m13.generate.fibre_cube(n, fibres, 20)
    element = {"hex8": "hexahedron", "hex27": "hexahedron27", "tet10": "tetra10"}[name]
    if element != "hexahedron":
        cube = m13.generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (n, n, n), element=element)
    return beams, m13.generate.distort(cube, amplitude, seed=1) if amplitude else cube


@njit
def newton_counted(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """(converged, iterations) of the library's Newton projection (:func:`projection.project_point`) of p
    from the start ``xi``, which receives its result. The iterations are counted on a copy by
    repeating the library's full Newton step (:func:`projection.polish_residual`) from the same start
    until the residual is at the tolerance (1e-12 h), at most 20 steps: project_point's count
    whenever its line search takes full steps."""
    start = xi.copy()
    converged = pr.project_point(code, X, p0, p1, p2, h, xi, trial, N, dN) == pr.CONVERGED
    tol = NEWTON_RESIDUAL_TOL * h
    pr.store_residual(code, X, p0, p1, p2, start, trial, N)
    iterations = 0
    while norm3(trial[0], trial[1], trial[2]) > tol and iterations < NEWTON_MAX_ITERATIONS:
        before = start.copy()
        pr.polish_residual(code, X, p0, p1, p2, h, start, trial, N, dN)
        iterations += 1
        if start[0] == before[0] and start[1] == before[1] and start[2] == before[2]:
            break           # a full step that does not lower the residual: project_point would cut it
        pr.store_residual(code, X, p0, p1, p2, start, trial, N)
    return converged, iterations


@njit
def in_hull(hull, s, x0, x1, x2):
    """The library's hull test (:func:`mortar1d3d.geometry.search.in_hull`), here so that a checkout
    without it can be counted (its context has no planes: the counts then see none)."""
    for f in range(hull.shape[1]):
        if hull[s, f, 0] * x0 + hull[s, f, 1] * x1 + hull[s, f, 2] * x2 > hull[s, f, 3]:
            return False
    return True


@njit
def element_counts(ctx_pairs, pair_solid, gx, codes, conn, points, solid_origin, solid_h, solid_boxes, hull, linear,
                   beam_code, Q, lengths, beam_origin, out):
    """Element-based location, counted: out = [points, box tests passed, Newton projections, Newton
    iterations, rare paths, owners found, affine locations, hull tests failed]."""
    X, N, dN, H, dH, xi, trial = pr.point_buffers()
    a, stack = pr.search_buffers()
    for e in range(ctx_pairs.shape[0] - 1):
        for q in range(gx.shape[0]):
            out[0] += 1
            r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], 0.0, 0.0, 0.0, gx[q], H, dH)
            for p in range(ctx_pairs[e], ctx_pairs[e + 1]):
                s = pair_solid[p]
                if not pr.in_box(solid_boxes[s], r0 + beam_origin[e, 0], r1 + beam_origin[e, 1],
                                 r2 + beam_origin[e, 2]):
                    continue
                out[1] += 1
                code = codes[s]
                x0 = r0 + (beam_origin[e, 0] - solid_origin[s, 0])
                x1 = r1 + (beam_origin[e, 1] - solid_origin[s, 1])
                x2 = r2 + (beam_origin[e, 2] - solid_origin[s, 2])
                if pr.is_affine(linear, s):
                    out[6] += 1
                    pr.linear_parameters(code, linear, s, x0, x1, x2, xi)
                    if solid.is_inside(code, xi, PARAMETER_TOL):
                        out[5] += 1
                        break
                    continue
                if not in_hull(hull, s, x0, x1, x2):
                    out[7] += 1
                    continue
                pr.load_element(points, conn, s, code, solid_origin, X)
                out[2] += 1
                converged = False
                if pr.linear_parameters(code, linear, s, x0, x1, x2, xi):
                    converged, its = newton_counted(code, X, x0, x1, x2, solid_h[s], xi, trial, N, dN)
                    out[3] += its
                if converged and not abs(solid.outside_distance(code, xi)) <= 1e-6:
                    if solid.is_inside(code, xi, PARAMETER_TOL):
                        out[5] += 1
                        break
                    if certified_outside(code, linear, s, xi, X, a):
                        continue
                out[4] += 1
                if pr.locate_rare(code, X, x0, x1, x2, solid_h[s], PARAMETER_TOL, linear, s, xi, trial, N, dN, a,
                                  stack, converged) == pr.INSIDE:
                    out[5] += 1
                    break


@njit
def segment_point_counts(seg_beam, seg_solid, seg_start, seg_end, gx, codes, conn, points, solid_origin, solid_h,
                         linear, beam_code, Q, lengths, beam_origin, out):
    """The segments' integration points, counted: out = [points, Newton iterations (warm start),
    fallbacks to the locator, affine points]."""
    X, N, dN, H, dH, xi, trial = pr.point_buffers()
    a, stack = pr.search_buffers()
    loose = 1e3 * PARAMETER_TOL
    for g in range(seg_beam.shape[0]):
        e, s = seg_beam[g], seg_solid[g]
        code = codes[s]
        affine = pr.is_affine(linear, s)
        pr.load_element(points, conn, s, code, solid_origin, X)
        s0, s1, s2 = (beam_origin[e, 0] - solid_origin[s, 0], beam_origin[e, 1] - solid_origin[s, 1],
                      beam_origin[e, 2] - solid_origin[s, 2])
        half, mid = 0.5 * (seg_end[g] - seg_start[g]), 0.5 * (seg_end[g] + seg_start[g])
        solid.centre(code, xi)
        for q in range(gx.shape[0]):
            out[0] += 1
            if affine:
                out[3] += 1
                continue
            r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], s0, s1, s2, mid + half * gx[q], H, dH)
            pr.linear_parameters(code, linear, s, r0, r1, r2, xi)
            converged, its = newton_counted(code, X, r0, r1, r2, solid_h[s], xi, trial, N, dN)
            out[1] += its
            if not (converged and solid.is_inside(code, xi, loose)):
                out[2] += 1
                if pr.locate_point(code, X, r0, r1, r2, solid_h[s], loose, linear, s, xi, trial, N, dN, a,
                                   stack) == pr.NOT_CONVERGED:
                    solid.centre(code, xi)


@njit
def face_newton_counted(code, X, h, beam_code, Qe, length, s0, s1, s2, face, eta0, xs0, xs1, xs2, z, xi, N, dN, H, dH,
                        out):
    """The crossing search's face Newton (:func:`mortar1d3d.geometry.intersection.intersect_face`, then
    the acceptance of ``segmentation._try_crossing``) from (η0, ξ0), counted: out[9] += Newton steps
    (Jacobian and solve), out[10] += residual evaluations (the start's and every line-search trial's),
    out[11] += 1 if no crossing was accepted. A copy of the library's iteration with counters (the
    library's kernels hold none): the same steps, the same result. Returns the crossing's η or NaN."""
    z[0] = eta0
    z[1], z[2] = face_coordinates(face, xs0, xs1, xs2)
    tol = NEWTON_RESIDUAL_TOL * h
    fn, f0, f1, f2, d0, d1, d2 = face_residual(code, X, beam_code, Qe, length, s0, s1, s2, face, z[0], z[1], z[2],
                                               xi, N, H, dH)
    out[10] += 1
    status = -1
    last_step = np.inf
    for it in range(NEWTON_MAX_ITERATIONS + FACE_POLISH_ITERATIONS):
        converged = fn <= tol
        if converged and last_step <= FACE_POLISH_STEP:
            status = 1
            break
        if not converged and it >= NEWTON_MAX_ITERATIONS:
            status = 0
            break
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = pr.jacobian(code, X, xi, N, dN)
        out[9] += 1
        a, b = face[1], face[2]
        det, s_eta, s_u, s_v = solve3(
            -d0, j00 * a[0] + j01 * a[1] + j02 * a[2], j00 * b[0] + j01 * b[1] + j02 * b[2],
            -d1, j10 * a[0] + j11 * a[1] + j12 * a[2], j10 * b[0] + j11 * b[1] + j12 * b[2],
            -d2, j20 * a[0] + j21 * a[1] + j22 * a[2], j20 * b[0] + j21 * b[1] + j22 * b[2],
            -f0, -f1, -f2)
        if det == 0.0:
            status = 1 if converged else 0
            break
        step = 1.0
        accepted = False
        for _b in range(FACE_BACKTRACKS):
            e_t = z[0] + step * s_eta
            u_t = z[1] + step * s_u
            v_t = z[2] + step * s_v
            ft, g0, g1, g2, c0, c1, c2 = face_residual(code, X, beam_code, Qe, length, s0, s1, s2, face, e_t, u_t,
                                                       v_t, xi, N, H, dH)
            out[10] += 1
            if ft < fn or ft <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            face_residual(code, X, beam_code, Qe, length, s0, s1, s2, face, z[0], z[1], z[2], xi, N, H, dH)
            out[10] += 1
            status = 1 if fn <= 1e3 * tol else 0
            break
        last_step = step * max(abs(s_eta), abs(s_u), abs(s_v))
        z[0], z[1], z[2] = e_t, u_t, v_t
        fn, f0, f1, f2, d0, d1, d2 = ft, g0, g1, g2, c0, c1, c2
        if abs(z[0]) > FACE_MAX_ETA:
            status = 0
            break
    if status < 0:
        status = 1 if fn <= tol else 0
    if (status == 0 or z[0] < -1.0 - PARAMETER_TOL or z[0] > 1.0 + PARAMETER_TOL
            or not solid.is_inside(code, xi, PARAMETER_TOL)):
        out[11] += 1
        return np.nan
    return min(max(z[0], -1.0), 1.0)


@njit
def face_newton_between(code, X, h, beam_code, Qe, length, s0, s1, s2, face, eta_s, xi_s, k, t, z, xi, N, dN, H, dH,
                        out):
    """:func:`face_newton_counted` from the point at fraction t of sample interval k (the library's linear
    start values, ``segmentation._try_between``)."""
    return face_newton_counted(code, X, h, beam_code, Qe, length, s0, s1, s2, face,
                               eta_s[k] + t * (eta_s[k + 1] - eta_s[k]),
                               xi_s[k, 0] + t * (xi_s[k + 1, 0] - xi_s[k, 0]),
                               xi_s[k, 1] + t * (xi_s[k + 1, 1] - xi_s[k, 1]),
                               xi_s[k, 2] + t * (xi_s[k + 1, 2] - xi_s[k, 2]), z, xi, N, dN, H, dH, out)


@njit
def crossing_counts(pair_offsets, pair_solid, codes, conn, points, solid_origin, solid_h, linear, errors, hull,
                    beam_code, Q, lengths, beam_origin, beam_boxes, straight, S, out):
    """The crossing search's samples and face Newton, counted: out = [pairs, pairs searched (a face in reach),
    sample projections, their Newton iterations, sample fallbacks, face-Newton starts at sign changes of the
    cubic model, touch starts, fallbacks beyond a hull plane (no subdivision search), pairs whose boxes meet
    but whose beam element the linearised map proves to reach no face (not searched: on the whole element,
    or on each sample interval, ``segmentation._live_intervals``), face-Newton steps,
    face-Newton residual evaluations, face-Newton starts that found no crossing, mirror starts after a touch].
    The face Newton runs from the library's starts (:func:`face_newton_counted`); starts from the deflated
    cubic (a sample exactly on a face) and at a failed sample are not made (both rare, none on these scenes)."""
    C = np.empty((solid.MAX_CONTROL, 3))
    reach = np.empty(solid.MAX_FACES, dtype=np.bool_)
    X, N, dN, H, dH, xi, trial = pr.point_buffers()
    a, stack = pr.search_buffers()
    eta_s = np.empty(S)
    xi_s = np.empty((S, 3))
    dxi_s = np.empty((S, 3))
    z = np.empty(3)
    rs = np.empty((S, 6))
    zs = np.empty((S, 6))
    live = np.empty((S, solid.MAX_FACES), dtype=np.bool_)
    need = np.empty(S, dtype=np.bool_)
    for e in range(pair_offsets.shape[0] - 1):
        for p in range(pair_offsets[e], pair_offsets[e + 1]):
            out[0] += 1
            s = pair_solid[p]
            code = codes[s]
            h = solid_h[s]
            pr.load_element(points, conn, s, code, solid_origin, X)
            if not sg._faces_in_reach(code, X, h, beam_boxes[e], solid_origin[s], C, reach):
                continue
            s0, s1, s2 = (beam_origin[e, 0] - solid_origin[s, 0], beam_origin[e, 1] - solid_origin[s, 1],
                          beam_origin[e, 2] - solid_origin[s, 2])
            if not faces_in_linear_reach(code, X, h, s, linear, errors, beam_code, Q[e], lengths[e], s0, s1, s2, a, C,
                                         H, dH, reach):
                out[8] += 1
                continue
            for k in range(S):
                eta_s[k] = -1.0 + 2.0 * k / (S - 1)
                rs[k, 0], rs[k, 1], rs[k, 2], rs[k, 3], rs[k, 4], rs[k, 5] = beam_point(beam_code, Q[e], lengths[e],
                                                                                     s0, s1, s2, eta_s[k], H, dH)
            if not live_intervals(code, s, h, linear, errors, eta_s, rs, reach, zs, live, need):
                out[8] += 1
                continue
            clip_samples(code, s, h, linear, errors, eta_s, rs, zs, live, beam_code, Q[e], lengths[e], s0, s1, s2, H, dH)
            out[1] += 1
            solid.centre(code, xi)
            for k in range(S):
                if not need[k]:
                    continue
                r0, r1, r2, d0, d1, d2 = rs[k, 0], rs[k, 1], rs[k, 2], rs[k, 3], rs[k, 4], rs[k, 5]
                if pr.is_affine(linear, s):
                    pr.linear_parameters(code, linear, s, r0, r1, r2, xi_s[k])
                    for i in range(3):
                        dxi_s[k, i] = linear[s, i, 0] * d0 + linear[s, i, 1] * d1 + linear[s, i, 2] * d2
                    continue
                if k == 0 or not need[k - 1]:
                    solid.centre(code, xi)
                    pr.linear_parameters(code, linear, s, r0, r1, r2, xi)
                else:
                    for i in range(3):
                        xi[i] = xi_s[k - 1, i] + dxi_s[k - 1, i] * (eta_s[k] - eta_s[k - 1])
                out[2] += 1
                converged, its = newton_counted(code, X, r0, r1, r2, h, xi, trial, N, dN)
                out[3] += its
                if not (converged and (solid.is_inside(code, xi, PARAMETER_TOL)
                                       or certified_outside(code, linear, s, xi, X, a))):
                    out[4] += 1
                    beyond = not in_hull(hull, s, r0, r1, r2)
                    out[7] += beyond
                    # beyond a hull plane the library keeps a converged warm start (as here) and
                    # otherwise skips the subdivision search (the same ξ as locate_point)
                    if not (beyond and converged):
                        pr.locate_point(code, X, r0, r1, r2, h, PARAMETER_TOL, linear, s, xi, trial, N, dN, a,
                                        stack)
                xi_s[k] = xi
                j00, j01, j02, j10, j11, j12, j20, j21, j22 = pr.jacobian(code, X, xi, N, dN)
                _, dxi_s[k, 0], dxi_s[k, 1], dxi_s[k, 2] = solve3(j00, j01, j02, j10, j11, j12, j20, j21, j22,
                                                                  d0, d1, d2)
            faces = solid.faces(code)
            line = pr.is_affine(linear, s) and straight[e]
            for f in range(faces.shape[0]):
                if not reach[f]:
                    continue
                face = faces[f]
                for k in range(S - 1):
                    if not live[k, f]:
                        continue
                    step = eta_s[k + 1] - eta_s[k]
                    g0 = sg._face_side(face, xi_s[k])
                    g1 = sg._face_side(face, xi_s[k + 1])
                    dg0 = (face[3, 0] * dxi_s[k, 0] + face[3, 1] * dxi_s[k, 1] + face[3, 2] * dxi_s[k, 2]) * step
                    dg1 = (face[3, 0] * dxi_s[k + 1, 0] + face[3, 1] * dxi_s[k + 1, 1]
                           + face[3, 2] * dxi_s[k + 1, 2]) * step
                    if min(g0, g1) > 0.5 * (abs(dg0) + abs(dg1)) or max(g0, g1) < -0.5 * (abs(dg0) + abs(dg1)):
                        continue
                    prev = g0
                    best = abs(g0)
                    best_t = 0.0
                    for i in range(1, sg._SCAN + 1):
                        t = i / sg._SCAN
                        cur = sg._hermite_g(g0, g1, dg0, dg1, t)
                        t_start = -1.0
                        if prev * cur <= 0.0 and not (prev == 0.0 and i > 1):
                            out[5] += 1
                            t_start = t - 1.0 / sg._SCAN + (1.0 / sg._SCAN) * (prev / (prev - cur) if prev != cur
                                                                                else 0.5)
                        if abs(cur) < best:
                            best = abs(cur)
                            best_t = t
                        prev = cur
                        if t_start >= 0.0:
                            face_newton_between(code, X, h, beam_code, Q[e], lengths[e], s0, s1, s2, face, eta_s,
                                                xi_s, k, t_start, z, xi, N, dN, H, dH, out)
                    if line:
                        continue
                    # the library's touch start skips a sample next to a sign change of the samples
                    # (where its kernel has this test; an older checkout starts there, and mirrors every touch)
                    near = TOUCH_SKIPS_CROSSINGS and (
                        (best_t == 1.0 and k + 2 < S and need[k + 2] and g1 * sg._face_side(face, xi_s[k + 2]) <= 0.0)
                        or (best_t == 0.0 and k > 0 and need[k - 1] and g0 * sg._face_side(face, xi_s[k - 1]) <= 0.0))
                    if best < sg._NEAR_FACE * (abs(dg0) + abs(dg1) + abs(g1 - g0)) and g0 * g1 > 0.0 and not near:
                        out[6] += 1
                        eta = face_newton_between(code, X, h, beam_code, Q[e], lengths[e], s0, s1, s2, face, eta_s,
                                                  xi_s, k, best_t, z, xi, N, dN, H, dH, out)
                        if eta_s[k] <= eta <= eta_s[k + 1] or (not TOUCH_SKIPS_CROSSINGS and not np.isnan(eta)):
                            t_mirror = 2.0 * best_t - (eta - eta_s[k]) / (eta_s[k + 1] - eta_s[k])
                            if 0.0 < t_mirror < 1.0:
                                out[12] += 1
                                face_newton_between(code, X, h, beam_code, Q[e], lengths[e], s0, s1, s2, face,
                                                    eta_s, xi_s, k, t_mirror, z, xi, N, dN, H, dH, out)


if hasattr(sg, "_linear_side"):
    @njit
    def decided_points(seg_beam, seg_solid, seg_start, seg_end, codes, linear, errors, solid_origin, beam_code, Q,
                       lengths, beam_origin, out):
        """The segments' midpoints and the tiling check's probes (1/4, 3/4) that the library's linearised map
        decides in the segment's owner (``segmentation._linear_side``, with its margin): out = [points, inside,
        outside] (the tiling's intervals are these segments and the uncoupled gaps)."""
        _, _, _, H, dH, _, _ = pr.point_buffers()
        for g in range(seg_beam.shape[0]):
            e, s = seg_beam[g], seg_solid[g]
            for q in range(1, 4):
                eta = seg_start[g] + 0.25 * q * (seg_end[g] - seg_start[g])
                r0, r1, r2, _, _, _ = beam_point(beam_code, Q[e], lengths[e], beam_origin[e, 0] - solid_origin[s, 0],
                                                 beam_origin[e, 1] - solid_origin[s, 1],
                                                 beam_origin[e, 2] - solid_origin[s, 2], eta, H, dH)
                side = sg._linear_side(codes[s], s, linear, errors, r0, r1, r2, sg._SIDE_MARGIN)
                out[0] += 1
                out[1] += side < 0
                out[2] += side > 0


def _median_timings(calls):
    keys = calls[0].keys()
    return {k: float(np.median([c[k] for c in calls])) for k in keys}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="hex8", choices=("hex8", "hex27", "tet10", "nurbs27"))
    parser.add_argument("--n", type=int, default=20)
    parser.add_argument("--fibres", type=int, default=1000)
    parser.add_argument("--distort", type=float, default=0.1, metavar="A")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--package", help="checkout whose package is measured (default: this one)")
    parser.add_argument("--no-counts", action="store_true", help="times only")
    parser.add_argument("--helices", type=int, default=40, help="helices of the nurbs27 scene (default 40)")
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    beams, solid_mesh = scene(args.scene, args.n, args.fibres, args.distort, args.helices)
    print(f"package {m13.__file__.rsplit('/', 2)[0]}; scene {args.scene}: {solid_mesh.n_elements} solid elements, "
          f"{beams.n_elements} beam elements, n_gauss {N_GAUSS}, 1 thread, median of {args.repeats} calls")

    rates = {}
    for integration in ("element", "segment"):
        m13.assemble_mortar(beams, solid_mesh, integration=integration, n_gauss=N_GAUSS)      # compile, warm
        calls = []
        for _ in range(args.repeats):
            ops = m13.assemble_mortar(beams, solid_mesh, integration=integration, n_gauss=N_GAUSS)
            calls.append(ops.timings)
        t = _median_timings(calls)
        rates[integration] = ops.n_integration_points / t["total"]
        stages = "  ".join(f"{k} {1e3 * v:.1f}" for k, v in t.items())
        print(f"{integration}-based: {ops.n_integration_points} points, {rates[integration]:.3g} points/s; "
              f"stages [ms]: {stages}")
        print(f"  diagnostics: {ops.diagnostics}")
    record("newton_path", scene=args.scene, element_gp_per_s=rates["element"],
           segment_gp_per_s=rates["segment"])

    ctx = KernelInput(beams, solid_mesh)
    crossing = sg.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, SEARCH_POINTS)
    reaching = np.concatenate([[0], np.cumsum(crossing[3] == 0)])      # searched (bool or int8 status)
    certain = reaching[ctx.pair_offsets[1:]] == reaching[ctx.pair_offsets[:-1]]
    tiled = sg.tile(ctx, *crossing[:3])
    parts = {
        "pair_crossings": lambda: sg.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, SEARCH_POINTS),
        "tile": lambda: sg.tile(ctx, *crossing[:3]),
        "check_tiling": lambda: sg.check_tiling(ctx, *tiled[1:4], tiled[4], certain),
        "segment_points": lambda: segment_points(ctx, *tiled[:4], N_GAUSS),
    }
    times = {}
    for name, call in parts.items():
        call()
        runs = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            call()
            runs.append(time.perf_counter() - t0)
        times[name] = np.median(runs)
    print("segmentation's parts alone [ms]: " + "  ".join(f"{k} {1e3 * v:.1f}" for k, v in times.items()))
    if args.no_counts:
        return rates

    pairs = np.diff(ctx.pair_offsets)
    print(f"candidate pairs per beam element: mean {pairs.mean():.2f}, max {pairs.max()}")
    if solid.HULL_TEST[ctx.codes].any():
        from mortar1d3d.geometry.search import find_candidate_pairs
        boxed = find_candidate_pairs(ctx.beam_boxes, ctx.solid_boxes)[1]
        print(f"box pairs before the hull planes: {len(boxed)}, their solid elements (those that need planes) "
              f"{len(np.unique(boxed))} of {len(ctx.codes)}")
    if PENDING is not None:
        # the library's own kernels, on contexts of their own: the element-based points, and the segmentation's
        # parts above (ctx); a certificate is computed once, where a decision needs it
        ctx_element = KernelInput(beams, solid_mesh)
        element_points(ctx_element, N_GAUSS)
        curved = ctx.linear[:, 4, 0] == 0.0
        print(f"one-to-one certificates computed, of {curved.sum()} curved elements: element-based "
              f"{(ctx_element.linear[curved, 4, 1] != PENDING).sum()}, segment-based "
              f"{(ctx.linear[curved, 4, 1] != PENDING).sum()}")
    gx, _ = gauss_legendre(N_GAUSS)
    args_ctx = (ctx.codes, ctx.conn, ctx.points, ctx.solid_origin, ctx.solid_h)
    out = np.zeros(8, dtype=np.int64)
    hull = getattr(ctx, "hull", np.zeros((len(ctx.codes), 1, 4)))       # a checkout without planes: none
    element_counts(ctx.pair_offsets, ctx.pair_solid, gx, *args_ctx, ctx.solid_boxes, hull, ctx.linear, ctx.beam_code,
                   ctx.Q, ctx.lengths, ctx.beam_origin, out)
    n = out[0]
    print(f"element-based, per point: box tests passed {out[1] / n:.3f}, hull tests failed {out[7] / n:.3f}, "
          f"Newton projections {out[2] / n:.3f}, "
          f"affine locations {out[6] / n:.3f}; Newton iterations per projection {out[3] / max(out[2], 1):.3f}; "
          f"rare path (restart, face polish, subdivision) {out[4]} of {out[2]} projections; owned {out[5]} of {n}")
    out = np.zeros(4, dtype=np.int64)
    segment_point_counts(*tiled[:4], gx, *args_ctx, ctx.linear, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin,
                         out)
    print(f"segment-based points: {out[0]} ({len(tiled[0])} segments, {len(tiled[0]) / len(pairs):.2f} per beam "
          f"element); Newton iterations per point {out[1] / max(out[0] - out[3], 1):.3f} (warm start), fallbacks "
          f"{out[2]}, affine {out[3]}")
    out = np.zeros(13, dtype=np.int64)
    errors = sg.linear_errors(ctx) if hasattr(sg, "linear_errors") else np.zeros((1, 3))
    crossing_counts(ctx.pair_offsets, ctx.pair_solid, *args_ctx, ctx.linear, errors, hull, ctx.beam_code, ctx.Q,
                    ctx.lengths, ctx.beam_origin, ctx.beam_boxes, beams_affine(ctx.beam_code, ctx.Q, ctx.lengths),
                    SEARCH_POINTS, out)
    found = int(crossing[2].sum())
    print(f"crossing search: {out[0]} pairs, {out[1]} searched ({out[1] / len(pairs):.2f} per beam element), "
          f"{out[8]} more not searched (the linearised map proves that they reach no face); "
          f"per searched pair: {out[2] / max(out[1], 1):.2f} sample projections "
          f"({out[3] / max(out[2], 1):.3f} Newton iterations each, {out[4]} fallbacks in all, {out[7]} of them "
          f"beyond a hull plane: the warm start kept if it converged, else no subdivision search), face-Newton starts "
          f"{out[5] / max(out[1], 1):.3f} at sign changes + {out[6] / max(out[1], 1):.3f} at touches ({out[5]} + {out[6]} "
          f"in all), crossings found {found / max(out[1], 1):.3f} ({found} in all)")
    if hasattr(sg, "_linear_side"):
        decided = np.zeros(3, dtype=np.int64)
        decided_points(tiled[0], *tiled[1:4], ctx.codes, ctx.linear, errors, ctx.solid_origin, ctx.beam_code, ctx.Q,
                       ctx.lengths, ctx.beam_origin, decided)
        print(f"segments' midpoints and tiling-check probes in their owner: {decided[0]}, decided by the "
              f"linearised map {decided[1]} inside, {decided[2]} outside (the others projected)")
    starts = out[5] + out[6] + out[12]
    print(f"face Newton: {starts} solves (sign changes, touches and {out[12]} mirrors), {out[9] / max(starts, 1):.2f} "
          f"steps and {out[10] / max(starts, 1):.2f} residual evaluations each, {out[11]} found no crossing")
    return rates


if __name__ == "__main__":
    main()
