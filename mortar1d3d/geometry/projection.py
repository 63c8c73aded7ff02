"""Newton projection of points into solid elements: find ξ with x(ξ) = p.

Coordinates passed to these kernels are *local*: element nodes and points minus the element's
origin (its first node), so that round-off is relative to the element size h, not to the
distance from the global origin (design.md §2: tolerances relative to the element size).
All buffers come from the caller; nothing here allocates.
"""
import numpy as np
from numba import prange

from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, PARAMETER_TOL, njit, njit_parallel
from .._schedule import claim, new_claims, workers
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from .linalg import inverse3, norm3, solve3

CONVERGED = 0
FAILED = 1
#: outcome of locating a point in an element, as stored per integration point
INSIDE, OUTSIDE, NOT_CONVERGED = 0, 1, 2

_MAX_PARAMETER = 1e3      # |ξ| beyond this: the point is far outside; stop early
_BACKTRACKS = 8
#: |x(ξ) - p| below this times h is round-off of the map itself (a few ulps of local coordinates)
_ROUND_OFF = 4 * 2.220446049250313e-16


@njit
def map_point(code, X, xi, N):
    """x(ξ) = Σ_a N_a(ξ) X_a for element type ``code`` with local nodes ``X``; returns (x0, x1, x2)."""
    solid.shape(code, xi, N)
    x0 = x1 = x2 = 0.0
    for a in range(solid.n_nodes(code)):
        x0 += N[a] * X[a, 0]
        x1 += N[a] * X[a, 1]
        x2 += N[a] * X[a, 2]
    return x0, x1, x2


@njit
def jacobian(code, X, xi, dN):
    """J[i, k] = ∂x_i/∂ξ_k as a 9-tuple, row by row."""
    solid.deriv(code, xi, dN)
    j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
    for a in range(solid.n_nodes(code)):
        x0, x1, x2 = X[a, 0], X[a, 1], X[a, 2]
        d0, d1, d2 = dN[a, 0], dN[a, 1], dN[a, 2]
        j00 += x0 * d0
        j01 += x0 * d1
        j02 += x0 * d2
        j10 += x1 * d0
        j11 += x1 * d1
        j12 += x1 * d2
        j20 += x2 * d0
        j21 += x2 * d1
        j22 += x2 * d2
    return j00, j01, j02, j10, j11, j12, j20, j21, j22


@njit
def project_point(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """Newton iteration for x(ξ) = p with a backtracking line search on |x(ξ) - p|.

    ``xi`` (3,) holds the start value on entry and the result on exit; ``trial`` (3,) is
    scratch. Converged when |x(ξ) - p| <= 1e-12 h. Returns CONVERGED or FAILED (singular
    Jacobian, no decrease, parameters running away, or 20 iterations).
    """
    tol = NEWTON_RESIDUAL_TOL * h
    x0, x1, x2 = map_point(code, X, xi, N)
    r0, r1, r2 = p0 - x0, p1 - x1, p2 - x2
    rn = norm3(r0, r1, r2)
    for _ in range(NEWTON_MAX_ITERATIONS):
        if rn <= tol:
            return CONVERGED
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xi, dN)
        det, d0, d1, d2 = solve3(j00, j01, j02, j10, j11, j12, j20, j21, j22, r0, r1, r2)
        if det == 0.0:
            return FAILED
        step = 1.0
        rt = rn
        accepted = False
        for _b in range(_BACKTRACKS):
            trial[0] = xi[0] + step * d0
            trial[1] = xi[1] + step * d1
            trial[2] = xi[2] + step * d2
            x0, x1, x2 = map_point(code, X, trial, N)
            t0, t1, t2 = p0 - x0, p1 - x1, p2 - x2
            rt = norm3(t0, t1, t2)
            if rt < rn or rt <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            # no decrease along the Newton direction: at round-off level this is convergence
            return CONVERGED if rn <= 1e3 * tol else FAILED
        xi[0], xi[1], xi[2] = trial[0], trial[1], trial[2]
        r0, r1, r2 = t0, t1, t2
        rn = rt
        if abs(xi[0]) > _MAX_PARAMETER or abs(xi[1]) > _MAX_PARAMETER or abs(xi[2]) > _MAX_PARAMETER:
            return FAILED
    return CONVERGED if rn <= tol else FAILED


@njit
def load_element(points, conn, element, code, origin, X):
    """Copy the local (origin-relative) node coordinates of ``element`` into ``X``."""
    for a in range(solid.n_nodes(code)):
        node = conn[element, a]
        X[a, 0] = points[node, 0] - origin[element, 0]
        X[a, 1] = points[node, 1] - origin[element, 1]
        X[a, 2] = points[node, 2] - origin[element, 2]


@njit
def locate(code, X, p0, p1, p2, h, tol, xi, trial, N, dN):
    """Project p from the element centre: INSIDE, OUTSIDE or NOT_CONVERGED; ξ in ``xi``."""
    solid.centre(code, xi)
    if project_point(code, X, p0, p1, p2, h, xi, trial, N, dN) != CONVERGED:
        return NOT_CONVERGED
    if solid.is_inside(code, xi, tol):
        return INSIDE
    return OUTSIDE


@njit
def in_box(box, x0, x1, x2):
    return (box[0, 0] <= x0 <= box[1, 0]) and (box[0, 1] <= x1 <= box[1, 1]) and (box[0, 2] <= x2 <= box[1, 2])


@njit
def polish(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """One more Newton step on a converged projection, kept if it lowers |x(ξ) - p|.

    The convergence test (1e-12 h) decides *whether* a point is found; integration points get
    this extra step so that ξ is exact to round-off (quadratic convergence), which is what the
    certificate ‖D q_B - M X_S‖ measures.
    """
    x0, x1, x2 = map_point(code, X, xi, N)
    r0, r1, r2 = p0 - x0, p1 - x1, p2 - x2
    if norm3(r0, r1, r2) <= _ROUND_OFF * h:
        return      # already at round-off (affine elements after one Newton step): nothing to gain
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xi, dN)
    det, d0, d1, d2 = solve3(j00, j01, j02, j10, j11, j12, j20, j21, j22, r0, r1, r2)
    if det == 0.0:
        return
    trial[0], trial[1], trial[2] = xi[0] + d0, xi[1] + d1, xi[2] + d2
    x0, x1, x2 = map_point(code, X, trial, N)
    if norm3(p0 - x0, p1 - x1, p2 - x2) < norm3(r0, r1, r2):
        xi[0], xi[1], xi[2] = trial[0], trial[1], trial[2]


@njit
def first_containing(r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, codes, conn, points, solid_origin,
                     solid_h, linear, tol, X, xi, trial, N, dN, only):
    """Lowest-index candidate of beam element ``e`` containing the point r (beam-local frame).

    Candidates are ``pair_solid[p0:p1]`` (ascending); returns -1 if none contains the point.
    With ``only`` >= 0, tests just that element. On success ``xi`` holds the point's ξ.
    This is the ownership rule of both integrations (design.md §1-§2): a point on a face,
    edge or node shared by several elements belongs to the lowest-index one. Affine elements
    are located with their inverse map (``linear``, :func:`linear_maps`); for the others a
    Newton projection runs from the linearised estimate (from the centre if there is none or it
    fails) and ``X`` is left holding the nodes of the last element tested.
    """
    for p in range(p0, p1):
        s = pair_solid[p]
        if only >= 0 and s != only:
            continue
        if not in_box(solid_boxes[s], r0 + beam_origin[e, 0], r1 + beam_origin[e, 1], r2 + beam_origin[e, 2]):
            continue
        code = codes[s]
        x0 = r0 + (beam_origin[e, 0] - solid_origin[s, 0])
        x1 = r1 + (beam_origin[e, 1] - solid_origin[s, 1])
        x2 = r2 + (beam_origin[e, 2] - solid_origin[s, 2])
        if is_affine(linear, s):
            linear_parameters(code, linear, s, x0, x1, x2, xi)
        else:
            load_element(points, conn, s, code, solid_origin, X)
            if not (linear_parameters(code, linear, s, x0, x1, x2, xi)
                    and project_point(code, X, x0, x1, x2, solid_h[s], xi, trial, N, dN) == CONVERGED):
                if locate(code, X, x0, x1, x2, solid_h[s], tol, xi, trial, N, dN) == NOT_CONVERGED:
                    continue
        if solid.is_inside(code, xi, tol):
            return s
    return -1


# nodes spanning the parameter axes from node 0 (hex: 1, 3, 4; tet: 1, 2, 3) and their distance
_AXIS_NODES = np.array([[1, 3, 4], [1, 3, 4], [1, 3, 4], [1, 2, 3], [1, 2, 3]], dtype=np.int64)
_AXIS_SPAN = np.array([2.0, 2.0, 2.0, 1.0, 1.0])
_REFERENCE_NODES = np.zeros((len(solid.BY_CODE), solid.MAX_NODES, 3))
for _code, _descriptor in solid.BY_CODE.items():
    _REFERENCE_NODES[_code, : _descriptor.n_nodes] = _descriptor.reference_nodes

#: elements whose map is affine to this (relative) accuracy are located with their inverse map,
#: without Newton: exact to round-off, as a polished Newton projection would be
EXACT_AFFINE_TOL = 64 * 2.220446049250313e-16


@njit
def affine_inverse(code, X, h, rel_tol, Ainv):
    """Whether element ``code`` with local nodes ``X`` (node 0 at the origin) is affine; its inverse map.

    Affine means x(ξ) = A (ξ - ξ_0) for every node to ``rel_tol · h`` (tet4 always; a hex8
    that is a parallelepiped; quadratic elements with straight edges and centred mid-nodes).
    On success ``Ainv`` (3, 3) holds A⁻¹, so ξ(x) = ξ_0 + A⁻¹ x exactly (no Newton needed).
    """
    axes = _AXIS_NODES[code]
    span = _AXIS_SPAN[code]
    a00 = X[axes[0], 0] / span
    a10 = X[axes[0], 1] / span
    a20 = X[axes[0], 2] / span
    a01 = X[axes[1], 0] / span
    a11 = X[axes[1], 1] / span
    a21 = X[axes[1], 2] / span
    a02 = X[axes[2], 0] / span
    a12 = X[axes[2], 1] / span
    a22 = X[axes[2], 2] / span
    ref = _REFERENCE_NODES[code]
    tol = rel_tol * h
    for a in range(solid.n_nodes(code)):
        d0 = ref[a, 0] - ref[0, 0]
        d1 = ref[a, 1] - ref[0, 1]
        d2 = ref[a, 2] - ref[0, 2]
        if (abs(a00 * d0 + a01 * d1 + a02 * d2 - X[a, 0]) > tol or abs(a10 * d0 + a11 * d1 + a12 * d2 - X[a, 1]) > tol
                or abs(a20 * d0 + a21 * d1 + a22 * d2 - X[a, 2]) > tol):
            return False
    # inverted or degenerate: leave it to the general path
    return inverse3(a00, a01, a02, a10, a11, a12, a20, a21, a22, Ainv) > 0.0


@njit
def affine_parameters(code, Ainv, x0, x1, x2, xi):
    """ξ = ξ_0 + A⁻¹ x for an affine element (x local to node 0)."""
    for i in range(3):
        xi[i] = _REFERENCE_NODES[code, 0, i] + Ainv[i, 0] * x0 + Ainv[i, 1] * x1 + Ainv[i, 2] * x2


@njit_parallel
def linear_maps(points, conn, codes, solid_origin, solid_h, table, workers):
    """The inverse of every element's map linearised at its parameter centre, for locating points.

    ``table[s]`` (5, 3): rows 0-2 the inverse L of the Jacobian at the centre ξ_c, row 3 the
    position x_c = x(ξ_c) (local to node 0), row 4 ``[kind, 0, 0]``: kind 1 for elements affine to
    round-off (every tet4, parallelepiped hex8, straight-edged quadratic elements; L is then
    the exact inverse map and ``ξ = ξ_c + L (x - x_c)`` needs no Newton), 0 for the others (a
    Newton start close to the answer), NaN where the Jacobian at the centre is singular.
    """
    n = conn.shape[0]
    claims = new_claims(n, workers)
    for worker in prange(workers):
        X = np.empty((solid.MAX_NODES, 3))
        N = np.empty(solid.MAX_NODES)
        dN = np.empty((solid.MAX_NODES, 3))
        xc = np.empty(3)
        begin, stop = claim(claims, n, worker)
        while begin < stop:
            for s in range(begin, stop):
                code = codes[s]
                load_element(points, conn, s, code, solid_origin, X)
                solid.centre(code, xc)
                table[s, 3, 0], table[s, 3, 1], table[s, 3, 2] = map_point(code, X, xc, N)
                table[s, 4, 1] = table[s, 4, 2] = 0.0
                if affine_inverse(code, X, solid_h[s], EXACT_AFFINE_TOL, table[s, :3]):
                    table[s, 4, 0] = 1.0
                    continue
                j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xc, dN)
                if inverse3(j00, j01, j02, j10, j11, j12, j20, j21, j22, table[s, :3]) > 0.0:
                    table[s, 4, 0] = 0.0
                else:
                    table[s, :, :] = np.nan
            begin, stop = claim(claims, n, worker)


@njit
def point_buffers():
    """Work buffers of the kernels that follow beam points into solid elements (one set per worker).

    ``X`` (element nodes), ``N``, ``dN`` (shape functions and derivatives), ``H``, ``dH`` (beam
    functions and derivatives), ``xi`` (parameters), ``trial`` (Newton trial point).
    """
    return (np.empty((solid.MAX_NODES, 3)), np.empty(solid.MAX_NODES), np.empty((solid.MAX_NODES, 3)),
            np.empty(MAX_FUNCTIONS), np.empty(MAX_FUNCTIONS), np.empty(3), np.empty(3))


@njit
def is_affine(table, s):
    """Whether element s is located exactly by its linear map (see :func:`linear_maps`)."""
    return table[s, 4, 0] == 1.0


#: a linearised start farther out than this (max norm, parameter units) is not used: Newton
#: starts at the centre instead
_START_LIMIT = 4.0


@njit
def linear_parameters(code, table, s, x0, x1, x2, xi):
    """ξ = ξ_c + L (x - x_c) of element s (x local to node 0): exact where affine, else a start.

    Returns False (``xi`` unchanged) where the element has no linearisation or the estimate
    lies beyond ``_START_LIMIT``.
    """
    if not table[s, 4, 0] >= 0.0:
        return False
    d0 = x0 - table[s, 3, 0]
    d1 = x1 - table[s, 3, 1]
    d2 = x2 - table[s, 3, 2]
    c = 0.0 if solid.FAMILY[code] == solid.HEX else 0.25
    y0 = c + table[s, 0, 0] * d0 + table[s, 0, 1] * d1 + table[s, 0, 2] * d2
    y1 = c + table[s, 1, 0] * d0 + table[s, 1, 1] * d1 + table[s, 1, 2] * d2
    y2 = c + table[s, 2, 0] * d0 + table[s, 2, 1] * d1 + table[s, 2, 2] * d2
    if table[s, 4, 0] == 0.0 and max(abs(y0), abs(y1), abs(y2)) > _START_LIMIT:
        return False
    xi[0], xi[1], xi[2] = y0, y1, y2
    return True


@njit_parallel
def _project_points_kernel(points, conn, codes, solid_origin, solid_h, linear, x, elements, tol, xi, status,
                           workers):
    """ξ and INSIDE / OUTSIDE / NOT_CONVERGED of each point ``x[i]`` in element ``elements[i]``."""
    n = x.shape[0]
    claims = new_claims(n, workers)
    for worker in prange(workers):
        X, N, dN, _, _, _, trial = point_buffers()
        begin, stop = claim(claims, n, worker)
        while begin < stop:
            for i in range(begin, stop):
                s = elements[i]
                code = codes[s]
                x0 = x[i, 0] - solid_origin[s, 0]
                x1 = x[i, 1] - solid_origin[s, 1]
                x2 = x[i, 2] - solid_origin[s, 2]
                # the steps of first_containing for one given element, written out: a helper
                # shared by both (numba inline="always") made the element-based assembly about
                # 10 % slower (pinned to one CPU, 37.6-40.3 ms -> 42.3-44.9 ms per call)
                found = True
                if is_affine(linear, s):
                    linear_parameters(code, linear, s, x0, x1, x2, xi[i])
                else:
                    load_element(points, conn, s, code, solid_origin, X)
                    if not (linear_parameters(code, linear, s, x0, x1, x2, xi[i])
                            and project_point(code, X, x0, x1, x2, solid_h[s], xi[i], trial, N, dN) == CONVERGED):
                        found = locate(code, X, x0, x1, x2, solid_h[s], tol, xi[i], trial, N, dN) != NOT_CONVERGED
                    if found:
                        polish(code, X, x0, x1, x2, solid_h[s], xi[i], trial, N, dN)
                if not found:
                    status[i] = NOT_CONVERGED
                    xi[i, 0] = xi[i, 1] = xi[i, 2] = np.nan
                elif solid.is_inside(code, xi[i], tol):
                    status[i] = INSIDE
                else:
                    status[i] = OUTSIDE
            begin, stop = claim(claims, n, worker)


def project_points(solid, points, elements):
    """Parameter coordinates ξ of ``points`` in the solid elements ``elements``: x(ξ) = p.

    Parameters
    ----------
    solid : SolidMesh
    points : (n, 3) array_like of float
        Points in the solid mesh's coordinates.
    elements : int or (n,) array_like of int
        The element each point is projected into (one element for all points, or one each).

    Returns
    -------
    xi : (n, 3) float64
        Parameter coordinates (hexahedra: [-1, 1]³; tetrahedra: the unit simplex); NaN where
        the projection did not converge.
    status : (n,) int64
        ``INSIDE`` (0): converged, ξ in the element up to the parameter tolerance 1e-9;
        ``OUTSIDE`` (1): converged, ξ outside the element (x(ξ) = p still holds);
        ``NOT_CONVERGED`` (2): Newton failed (the point lies far outside a curved element,
        where the map extended beyond its element folds or runs away).

    Notes
    -----
    The projection used by :func:`mortar1d3d.assemble_mortar` (design.md §2): Newton on
    x(ξ) - p with a backtracking line search, converged when |x(ξ) - p| <= 1e-12 h (h: the
    element's size), at most 20 iterations, started from the element map linearised at its
    centre and, failing that, from the centre; affine elements (every tet4, parallelepiped hex8,
    straight-edged quadratic elements) use their exact inverse map instead.
    """
    from ..errors import MeshError, format_ids
    from ..mesh import SolidMesh, _as_points
    from .search import solid_frames

    if not isinstance(solid, SolidMesh):
        raise TypeError(f"solid must be a SolidMesh, got {type(solid).__name__}")
    x = _as_points(points, "points")
    try:
        elements = np.asarray(elements)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"elements: expected integers ({exc})") from None
    if elements.dtype.kind not in "iu":
        raise MeshError(f"elements: expected integer element ids, got dtype {elements.dtype}")
    elements = np.ascontiguousarray(np.broadcast_to(elements, (len(x),)) if elements.ndim == 0 else elements,
                                    dtype=np.int64)
    if elements.shape != (len(x),):
        raise MeshError(f"elements: expected one element id or {len(x)} of them, got shape {elements.shape}")
    bad = np.flatnonzero((elements < 0) | (elements >= solid.n_elements))
    if bad.size:
        raise MeshError(f"elements: ids out of range [0, {solid.n_elements}) at points {format_ids(bad)}")
    _, solid_h, solid_origin = solid_frames(solid)
    linear = np.empty((solid.n_elements, 5, 3))
    linear_maps(solid.points, solid.connectivity, solid.element_codes, solid_origin, solid_h, linear, workers())
    xi = np.zeros((len(x), 3))
    status = np.empty(len(x), dtype=np.int64)
    _project_points_kernel(solid.points, solid.connectivity, solid.element_codes, solid_origin, solid_h, linear, x,
                           elements, PARAMETER_TOL, xi, status, workers())
    return xi, status
