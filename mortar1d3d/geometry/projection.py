"""Newton projection of points into solid elements: find ξ with x(ξ) = p.

Coordinates passed to these kernels are *local*: element nodes and points minus the element's
origin (its first node), so that round-off is relative to the element size h, not to the
distance from the global origin (design.md §2: tolerances relative to the element size).
All buffers come from the caller; nothing here allocates.
"""
from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, njit
from ..elements.solid import dispatch as solid
from .linalg import norm3, solve3

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
           solid_h, tol, X, xi, trial, N, dN, only):
    """Lowest-index candidate of beam element ``e`` containing the point r (beam-local frame).

    Candidates are ``pair_solid[p0:p1]`` (ascending); returns -1 if none contains the point.
    With ``only`` >= 0, tests just that element. On success ``xi`` holds the point's ξ.
    This is the ownership rule of both integrations (design.md §1-§2): a point on a face,
    edge or node shared by several elements belongs to the lowest-index one.
    """
    for p in range(p0, p1):
        s = pair_solid[p]
        if only >= 0 and s != only:
            continue
        if not in_box(solid_boxes[s], r0 + beam_origin[e, 0], r1 + beam_origin[e, 1], r2 + beam_origin[e, 2]):
            continue
        code = codes[s]
        load_element(points, conn, s, code, solid_origin, X)
        if locate(code, X, r0 + (beam_origin[e, 0] - solid_origin[s, 0]),
                  r1 + (beam_origin[e, 1] - solid_origin[s, 1]),
                  r2 + (beam_origin[e, 2] - solid_origin[s, 2]),
                  solid_h[s], tol, xi, trial, N, dN) == INSIDE:
            return s
    return -1
