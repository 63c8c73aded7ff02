"""Newton projection of points into solid elements: find ξ with x(ξ) = p.

Coordinates passed to these kernels are *local*: element nodes and points minus the element's
origin (its first node), so that round-off is relative to the element size h, not to the
distance from the global origin (docs/conventions.md §2: tolerances relative to the element size).
All buffers come from the caller; nothing here allocates.
"""
import numpy as np
from numba import types

from .._borrowed import borrowed
from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, PARAMETER_TOL, njit, njit_inline
from .._parallel import in_parallel
from .._schedule import claim, new_claims, workers
from .._unlinked import unlinked
from ..elements.beam import MAX_FUNCTIONS
from ..elements.solid import dispatch as solid
from ..elements.solid import hex8, hex27, nurbs27, tet10
from .linalg import inverse3, norm3, solve3
from .search import in_hull
from .rational import (centre_curvature_bound, centre_point, degree_sums, normalise_coefficients,
                       rational_coefficients, rational_curvature_bound, uniform_weights)

CONVERGED = 0
FAILED = 1
#: outcome of locating a point in an element, as stored per integration point
INSIDE, OUTSIDE, NOT_CONVERGED = 0, 1, 2
#: ``only`` of :func:`first_containing` that tests every candidate: an int64, not the literal -1, so that
#: the calls with and without a given element share one compiled version (a literal argument is
#: a signature of its own: a second compilation of the function and of every caller's copy of it)
ANY_CANDIDATE = np.int64(-1)

_MAX_PARAMETER = 1e3      # |ξ| beyond this: the point is far outside; stop early
_BACKTRACKS = 8
#: |x(ξ) - p| below this times h is round-off of the map itself (a few ulps of local coordinates)
_ROUND_OFF = 4 * 2.220446049250313e-16


#: the codes of the trilinear hexahedron, of the quadratic hexahedron and tetrahedron and of the
#: rational triquadratic Bézier hexahedron, whose map and Jacobian skip the registry's dispatch (the
#: common cases of the Newton path): hex8 with the same shape functions and sums over a fixed node
#: count (the same bits); hex27, tet10 and nurbs27 with contractions of their nodes that never form the
#: shape functions (``map_nodes``, ``jacobian_nodes`` of their modules: equal to round-off)
_HEX8 = hex8.DESCRIPTOR.code
_HEX27 = hex27.DESCRIPTOR.code
_TET10 = tet10.DESCRIPTOR.code
_NURBS27 = nurbs27.DESCRIPTOR.code


@njit_inline
def _node_sum(X, N, n):
    """Σ_a N_a X_a over the first ``n`` nodes (inlined: a constant ``n`` gives a fixed loop)."""
    x0 = x1 = x2 = 0.0
    for a in range(n):
        x0 += N[a] * X[a, 0]
        x1 += N[a] * X[a, 1]
        x2 += N[a] * X[a, 2]
    return x0, x1, x2


@njit_inline
def map_point(code, X, xi, N):
    """x(ξ) = Σ_a N_a(ξ) X_a for element type ``code`` with local nodes ``X``; returns (x0, x1, x2).

    Rational types take their node weights from ``X[:, 3]`` (``N`` then holds R_a, except for nurbs27,
    whose map never forms it). Inlined into its callers with the trilinear hexahedron's case written
    out (no call, so no reference counting of the three array arguments per evaluation); every other
    type goes on in :func:`_map_other`."""
    if code == _HEX8:
        hex8.shape(xi, N)
        return _node_sum(X, N, 8)
    return _map_other_call(code, X, xi, N)


@njit
def _map_other(code, X, xi, N):
    """:func:`map_point` of every type but hex8."""
    if code == _HEX27:
        return hex27.map_nodes(X, xi)
    if code == _TET10:
        return tet10.map_nodes(X, xi)
    if code == _NURBS27:
        return nurbs27.map_nodes(X, xi)
    if solid.RATIONAL[code]:
        solid.rational_shape(code, xi, X, N)
    else:
        solid.shape(code, xi, N)
    return _node_sum(X, N, solid.n_nodes(code))


#: called through a symbol (see mortar1d3d._unlinked): every function that evaluates the map holds a
#: declaration, not the other types' shape functions, which LLVM would otherwise optimise again in
#: each of them and in each of their callers; lazily: compiled at its first call, so never for a
#: scene of hex8 elements only
_map_other_call = unlinked(_map_other, returns=types.UniTuple(types.float64, 3))


@njit_inline
def _gradient_sum(X, dN, n):
    """Σ_a X_a ⊗ ∇N_a over the first ``n`` nodes as a 9-tuple, row by row (inlined as :func:`_node_sum`)."""
    j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
    for a in range(n):
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


@njit_inline
def jacobian(code, X, xi, N, dN):
    """J[i, k] = ∂x_i/∂ξ_k as a 9-tuple, row by row. ``N`` is scratch: a rational type but nurbs27 leaves
    R_a(ξ) there (the others do not touch it). Inlined as :func:`map_point`; the other types go on in
    :func:`_jacobian_other`."""
    if code == _HEX8:
        hex8.deriv(xi, dN)
        return _gradient_sum(X, dN, 8)
    return _jacobian_other_call(code, X, xi, N, dN)


@njit
def _jacobian_other(code, X, xi, N, dN):
    """:func:`jacobian` of every type but hex8."""
    if code == _HEX27:
        return hex27.jacobian_nodes(X, xi)
    if code == _TET10:
        return tet10.jacobian_nodes(X, xi)
    if code == _NURBS27:
        return nurbs27.jacobian_nodes(X, xi)
    if solid.RATIONAL[code]:
        solid.rational_deriv(code, xi, X, N, dN)
    else:
        solid.deriv(code, xi, dN)
    return _gradient_sum(X, dN, solid.n_nodes(code))


#: called through a symbol, lazily, as :func:`_map_other`
_jacobian_other_call = unlinked(_jacobian_other, returns=types.UniTuple(types.float64, 9))


@njit
def _map_jacobian_other(code, X, xi, N, dN):
    """x(ξ) and J at one ξ as a 12-tuple (x0, x1, x2, then J row by row), every type but hex8: the values of
    :func:`_map_other` and :func:`_jacobian_other` (the same bits) in one call, for the Newton iterations
    that need both at a point. hex27 shares the contractions of the two (``hex27.map_jacobian_nodes``:
    x costs nine products more than J alone); the others evaluate them one after the other."""
    if code == _HEX27:
        return hex27.map_jacobian_nodes(X, xi)
    if code == _TET10:
        x0, x1, x2 = tet10.map_nodes(X, xi)
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = tet10.jacobian_nodes(X, xi)
    elif code == _NURBS27:
        x0, x1, x2 = nurbs27.map_nodes(X, xi)
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = nurbs27.jacobian_nodes(X, xi)
    else:
        x0, x1, x2 = _map_other(code, X, xi, N)
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = _jacobian_other(code, X, xi, N, dN)
    return x0, x1, x2, j00, j01, j02, j10, j11, j12, j20, j21, j22


#: called through a symbol, lazily, as :func:`_map_other`
_map_jacobian_other_call = unlinked(_map_jacobian_other, returns=types.UniTuple(types.float64, 12))
#: a Newton iterate whose residual |x(ξ) - p| exceeds this times h is not expected to be the last: from
#: it, the types but hex8 evaluate the map at the next iterate together with the Jacobian there
#: (:func:`_map_jacobian_other`), which the step after it needs (quadratic convergence: the residual
#: after a step from r is about r²/h, above the tolerance 1e-12 h while r > 1e-6 h). A wrong guess costs
#: one evaluation, never a bit: the values are those of the separate calls
_PAIRED_ABOVE = 1e-6


@njit
def project_point(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """Newton iteration for x(ξ) = p with a backtracking line search on |x(ξ) - p|.

    ``xi`` (3,) holds the start value on entry and the result on exit; ``trial`` (3,) is
    scratch, and on CONVERGED it holds the residual p - x(ξ) of the result (for
    :func:`polish_residual`, which then needs no evaluation of the map). Converged when
    |x(ξ) - p| <= 1e-12 h. Returns CONVERGED or FAILED (singular Jacobian, no decrease,
    parameters running away, or 20 iterations).

    The trilinear hexahedron's iteration is compiled here, after one test of ``code``: below it
    LLVM knows the type and drops the tests of every evaluation of the map and the Jacobian. Every
    other type's iteration is one call through a symbol to :func:`_project_other` (the same
    iteration, one version for all of them, compiled when a scene first projects into an element
    that is not a hex8).
    """
    if code != _HEX8:
        return _project_other_call(code, X, p0, p1, p2, h, xi, trial, N, dN)
    return _newton(code, X, p0, p1, p2, h, xi, trial, N, dN)


@njit
def _project_other(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """:func:`project_point` of every type but hex8."""
    return _newton(code, X, p0, p1, p2, h, xi, trial, N, dN)


#: lazily through a symbol (see mortar1d3d._unlinked): a scene of hex8 elements never compiles it
_project_other_call = unlinked(_project_other, returns=types.int64)


@njit_inline
def _newton(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """The iteration of :func:`project_point` (inlined into it and into :func:`_project_other`).

    hex8 evaluates the map at each iterate and the Jacobian at the top of each step. Every other type
    (``paired``, a constant after the test of :func:`project_point`) gets both from one call at the
    start and at each iterate expected to need a further step (see ``_PAIRED_ABOVE``); the iteration
    and its values are the same."""
    tol = NEWTON_RESIDUAL_TOL * h
    paired = code != _HEX8
    fresh = paired      # whether (j00 ... j22) is the Jacobian at xi
    if paired:
        x0, x1, x2, j00, j01, j02, j10, j11, j12, j20, j21, j22 = _map_jacobian_other_call(code, X, xi, N, dN)
    else:
        x0, x1, x2 = map_point(code, X, xi, N)
        j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
    r0, r1, r2 = p0 - x0, p1 - x1, p2 - x2
    rn = norm3(r0, r1, r2)
    status = FAILED
    for _ in range(NEWTON_MAX_ITERATIONS):
        if rn <= tol:
            status = CONVERGED
            break
        if not fresh:
            j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xi, N, dN)
        det, d0, d1, d2 = solve3(j00, j01, j02, j10, j11, j12, j20, j21, j22, r0, r1, r2)
        if det == 0.0:
            return FAILED
        fresh = paired and rn > _PAIRED_ABOVE * h
        step = 1.0
        rt = rn
        accepted = False
        for _b in range(_BACKTRACKS):
            trial[0] = xi[0] + step * d0
            trial[1] = xi[1] + step * d1
            trial[2] = xi[2] + step * d2
            if fresh:
                x0, x1, x2, j00, j01, j02, j10, j11, j12, j20, j21, j22 = _map_jacobian_other_call(code, X, trial,
                                                                                                   N, dN)
            else:
                x0, x1, x2 = map_point(code, X, trial, N)
            t0, t1, t2 = p0 - x0, p1 - x1, p2 - x2
            rt = norm3(t0, t1, t2)
            if rt < rn or rt <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            # no decrease along the Newton direction: at round-off level this is convergence
            if not rn <= 1e3 * tol:
                return FAILED
            status = CONVERGED
            break
        xi[0], xi[1], xi[2] = trial[0], trial[1], trial[2]
        r0, r1, r2 = t0, t1, t2
        rn = rt
        if abs(xi[0]) > _MAX_PARAMETER or abs(xi[1]) > _MAX_PARAMETER or abs(xi[2]) > _MAX_PARAMETER:
            return FAILED
    else:
        if rn <= tol:
            status = CONVERGED
    trial[0], trial[1], trial[2] = r0, r1, r2
    return status


@njit_inline
def load_element(points, conn, element, code, origin, X):
    """Copy the local (origin-relative) node coordinates of ``element`` into ``X``; a rational element's
    node weights (column 3 of ``points``, :attr:`mortar1d3d.mesh.SolidMesh.kernel_points`) into ``X[:, 3]``.
    Inlined: the loops that call it per element or point would pass four arrays per call."""
    for a in range(solid.n_nodes(code)):
        node = conn[element, a]
        X[a, 0] = points[node, 0] - origin[element, 0]
        X[a, 1] = points[node, 1] - origin[element, 1]
        X[a, 2] = points[node, 2] - origin[element, 2]
    if solid.RATIONAL[code] and points.shape[1] > 3 and X.shape[1] > 3:
        for a in range(solid.n_nodes(code)):
            X[a, 3] = points[conn[element, a], 3]


@njit
def injectivity_bound(code, a, L, radius):
    """ρ >= sup ‖L J(ξ) - I‖∞ over the box |ξ - ξ_c|∞ <= ``radius``, for L = J(ξ_c)⁻¹.

    L J(ξ) - I = Σ_{|α| >= 2} (L a_α) ∇(y^α)ᵀ (the linear monomials give J(ξ_c)), and on the box
    Σ_j |∂_j y^α| <= |α| radius^(|α|-1). If ρ < 1, then |L (x(ξ) - x(ζ)) - (ξ - ζ)|∞ <= ρ |ξ - ζ|∞
    for any two points of the box: the map is one-to-one there.
    """
    rho = 0.0
    for i in range(3):
        row = 0.0
        for q in range(solid.N_CURVED[code]):
            k, degree = solid.CURVED_MONOMIALS[code, q], solid.CURVED_DEGREE[code, q]
            b = L[i, 0] * a[k, 0] + L[i, 1] * a[k, 1] + L[i, 2] * a[k, 2]
            row += degree * radius ** (degree - 1) * abs(b)
        rho = max(rho, row)
    return rho


@njit
def curvature_bound(code, a, radius):
    """K >= max_i Σ_{j,k} |∂²x_i/∂ξ_j∂ξ_k| over the box |ξ - ξ_c|∞ <= ``radius``.

    Then ‖J(ξ) - J(ζ)‖∞ <= K |ξ - ζ|∞ there (Σ_{j,k} |∂_j ∂_k y^α| <= |α| (|α| - 1) radius^(|α|-2)).
    """
    K = 0.0
    for i in range(3):
        row = 0.0
        for q in range(solid.N_CURVED[code]):
            k, degree = solid.CURVED_MONOMIALS[code, q], solid.CURVED_DEGREE[code, q]
            row += degree * (degree - 1) * radius ** (degree - 2) * abs(a[k, i])
        K = max(K, row)
    return K


#: enlargements δ (max norm, parameter units) of the element about its centre tried for the
#: one-to-one certificate of :func:`linear_maps`, largest first
_CERTIFIED_MARGINS = (1.0, 0.5, 0.25, 0.125)


@njit
def certified_margin(code, X, L, a):
    """Largest δ of ``_CERTIFIED_MARGINS`` for which the element's map is provably one-to-one on the
    box |ξ - ξ_c|∞ <= R + δ (R: the element's radius about its centre); -1 if none.

    ``L`` (3, 3) is J(ξ_c)⁻¹; ``a`` receives the monomial coefficients (scratch). A rational
    element: ‖L J(ξ) - I‖∞ <= K_z |ξ - ξ_c|∞ with K_z the curvature bound of z = L (x - x_c)
    (:func:`.rational.normalise_coefficients`, :func:`.rational.centre_curvature_bound`: the bound of
    :func:`.rational.rational_curvature_bound` about the centre, summed by degree).
    """
    if solid.RATIONAL[code]:
        return _rational_margin_call(code, X, L, a)
    solid.monomial_coefficients(code, X, a)
    for delta in _CERTIFIED_MARGINS:
        if injectivity_bound(code, a, L, solid.RADIUS[code] + delta) < 1.0:
            return delta
    return -1.0


#: computed once per element, on the rare calls that need it: through a symbol, not compiled into every
#: kernel that inlines locate_point (see mortar1d3d._unlinked); lazily: compiled when a scene first meets a
#: Newton solution outside a curved element (never for a mesh of affine elements)
_certified_margin_call = unlinked(certified_margin, returns=types.float64)
#: ``table[s, 4, 1]`` of an element whose certificate :func:`linear_maps` left to its first use (see
#: :func:`certified_outside`)
PENDING_CERTIFICATE = -2.0


@njit
def _rational_margin(code, X, L, a):
    """:func:`certified_margin` of a rational type."""
    rational_coefficients(code, X, a)
    x0, x1, x2 = centre_point(code, a)
    normalise_coefficients(code, a, L, x0, x1, x2, a)
    sums = degree_sums(code, a)
    for delta in _CERTIFIED_MARGINS:
        reach = solid.RADIUS[code] + delta
        if centre_curvature_bound(sums, reach) * reach < 1.0:
            return delta
    return -1.0


#: lazily through a symbol (once per element): compiled when a scene first has a rational element
_rational_margin_call = unlinked(_rational_margin, returns=types.float64)


@njit
def certified_outside(code, table, s, xi, X, a):
    """Whether a solution ξ of x(ξ) = p outside element s proves that p lies outside it.

    True when ξ lies in the box on which the map is one-to-one (:func:`certified_margin`, stored
    in ``table[s, 4, 1]``): that box contains the element, and p has no other preimage in it.
    Only a few elements ever meet such a ξ, so :func:`linear_maps` leaves the margin pending and the
    first call that needs it computes it (``X``: the element's local nodes, ``a``: scratch of
    :func:`search_buffers`) and stores it. Workers that meet the same element at once compute and
    store the same value (a function of ``X`` and of the table's row), so the answer never depends
    on which of them stored it. A ξ beyond the largest margin's box needs no certificate: False.
    """
    margin = table[s, 4, 1]
    if margin == PENDING_CERTIFICATE:
        if not _in_certified_box(code, xi, _CERTIFIED_MARGINS[0]):
            return False
        margin = _certified_margin_call(code, X, table[s, :3], a)
        table[s, 4, 1] = margin
    return margin >= 0.0 and _in_certified_box(code, xi, margin)


@njit_inline
def _in_certified_box(code, xi, margin):
    """Whether ξ lies in the box |ξ - ξ_c|∞ <= R + ``margin`` (R: the element's radius about its centre)."""
    limit = solid.RADIUS[code] + margin
    return (abs(xi[0] - solid.CENTRE[code, 0]) <= limit and abs(xi[1] - solid.CENTRE[code, 1]) <= limit
            and abs(xi[2] - solid.CENTRE[code, 2]) <= limit)


#: boxes of the subdivision search are halved at most this often (2^-16 of the element: far below
#: what any valid element needs, see :func:`search_inside`)
_SEARCH_DEPTH = 16
#: fixed-point iterations of the search in a box where the map is a contraction (factor <= 1/2)
_CHORD_ITERATIONS = 64


@njit
def search_buffers():
    """Scratch of :func:`search_inside`: monomial coefficients (MAX_NODES, 4: a rational map's numerator
    and denominator) and the box stack."""
    return np.empty((solid.MAX_NODES, 4)), np.empty((8 * _SEARCH_DEPTH + 8, 4))


@njit
def search_inside(code, X, p0, p1, p2, h, tol, a, stack, xi, trial, N, dN):
    """Find ξ with x(ξ) = p and outside_distance(ξ) <= ``tol``, or prove that there is none.

    A point inside a curved element can have further preimages outside it (the extended map folds);
    Newton may converge to one of those. This search cannot miss the one inside. It covers the
    element's parameter box (plus ``tol``) with boxes C = {|ξ - m|∞ <= r}. With L = J(m)⁻¹ and K
    bounding the second derivatives (:func:`curvature_bound`), ρ = ‖L‖∞ K r bounds
    ‖L (J(ξ) - J(m))‖∞ on C, so a preimage in C implies |L (p - x(m))|∞ <= (1 + ρ) r: boxes that fail
    this are discarded. When 2ρ <= 1/2, the fixed-point map ξ ↦ ξ + L (p - x(ξ)) contracts by 1/2
    on the doubled box and converges from m to the only preimage there, if any; otherwise the box
    is halved in every direction. A valid element (det J > 0) has ‖L‖ bounded, so boxes become
    small enough long before ``_SEARCH_DEPTH``.

    Returns INSIDE (``xi`` holds the preimage, polished), OUTSIDE (proved: no preimage with
    outside_distance <= tol) or NOT_CONVERGED (a box reached the depth limit undecided: a singular
    Jacobian inside the element). Rational elements bound ρ by the curvature of z = L (x - x(m))
    (:func:`.rational.normalise_coefficients`, :func:`.rational.rational_curvature_bound`).
    """
    rational = solid.RATIONAL[code]
    b = a
    L = a               # polynomial types use neither b nor L: no allocation on their path
    if rational:
        rational_coefficients(code, X, a)
        b = np.empty((solid.MAX_NODES, 4))        # the coefficients of z = L (x - x(m)) per box
        L = np.empty((3, 3))
    else:
        solid.monomial_coefficients(code, X, a)
    c0, c1, c2 = solid.CENTRE[code, 0], solid.CENTRE[code, 1], solid.CENTRE[code, 2]
    lo = solid.PARAMETER_BOX[code, 0]
    hi = solid.PARAMETER_BOX[code, 1]
    r0 = 0.0
    for i in range(3):
        r0 = max(r0, 0.5 * (hi[i] - lo[i]) + tol)
    if not r0 > 0.0:
        return OUTSIDE
    stack[0, 0] = 0.5 * (lo[0] + hi[0])
    stack[0, 1] = 0.5 * (lo[1] + hi[1])
    stack[0, 2] = 0.5 * (lo[2] + hi[2])
    stack[0, 3] = r0
    top = 1
    undecided = False
    r_min = r0 * 0.5 ** _SEARCH_DEPTH
    while top > 0:
        top -= 1
        m0, m1, m2, r = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
        if not solid.box_meets(code, m0, m1, m2, r, tol):
            continue
        trial[0], trial[1], trial[2] = m0, m1, m2
        x0, x1, x2 = map_point(code, X, trial, N)
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, trial, N, dN)
        det = j00 * (j11 * j22 - j12 * j21) - j01 * (j10 * j22 - j12 * j20) + j02 * (j10 * j21 - j11 * j20)
        split = True
        if det > 0.0:
            inv = 1.0 / det
            l00, l01, l02 = inv * (j11 * j22 - j12 * j21), inv * (j02 * j21 - j01 * j22), inv * (j01 * j12 - j02 * j11)
            l10, l11, l12 = inv * (j12 * j20 - j10 * j22), inv * (j00 * j22 - j02 * j20), inv * (j02 * j10 - j00 * j12)
            l20, l21, l22 = inv * (j10 * j21 - j11 * j20), inv * (j01 * j20 - j00 * j21), inv * (j00 * j11 - j01 * j10)
            norm_l = max(abs(l00) + abs(l01) + abs(l02), abs(l10) + abs(l11) + abs(l12), abs(l20) + abs(l21) + abs(l22))
            reach = max(abs(m0 - c0), abs(m1 - c1), abs(m2 - c2)) + 2.0 * r      # the doubled box about ξ_c
            if rational:
                # ‖L (J(ξ) - J(m))‖∞ <= K_z r on C, K_z bounding z = L (x - x(m)) on the doubled box
                L[0, 0], L[0, 1], L[0, 2] = l00, l01, l02
                L[1, 0], L[1, 1], L[1, 2] = l10, l11, l12
                L[2, 0], L[2, 1], L[2, 2] = l20, l21, l22
                normalise_coefficients(code, a, L, x0, x1, x2, b)
                rho = rational_curvature_bound(code, b, m0, m1, m2, 2.0 * r) * r
            else:
                rho = norm_l * curvature_bound(code, a, reach) * r
            e0, e1, e2 = p0 - x0, p1 - x1, p2 - x2
            d0 = l00 * e0 + l01 * e1 + l02 * e2
            d1 = l10 * e0 + l11 * e1 + l12 * e2
            d2 = l20 * e0 + l21 * e1 + l22 * e2
            # no preimage in C (a hair of slack for the round-off of x(m) and L)
            if max(abs(d0), abs(d1), abs(d2)) > (1.0 + rho) * r * (1.0 + 1e-9) + 1e-14:
                continue
            if 2.0 * rho <= 0.5:
                split = False
                # the steps shrink by 1/2 or faster until round-off stops them; leaving the doubled
                # box means there is no preimage in C
                y0, y1, y2 = m0 + d0, m1 + d1, m2 + d2
                step = max(abs(d0), abs(d1), abs(d2))
                within = True
                for _ in range(_CHORD_ITERATIONS):
                    if max(abs(y0 - m0), abs(y1 - m1), abs(y2 - m2)) > 2.0 * r:
                        within = False
                        break
                    trial[0], trial[1], trial[2] = y0, y1, y2
                    x0, x1, x2 = map_point(code, X, trial, N)
                    e0, e1, e2 = p0 - x0, p1 - x1, p2 - x2
                    d0 = l00 * e0 + l01 * e1 + l02 * e2
                    d1 = l10 * e0 + l11 * e1 + l12 * e2
                    d2 = l20 * e0 + l21 * e1 + l22 * e2
                    last = step
                    step = max(abs(d0), abs(d1), abs(d2))
                    if step >= last:
                        break
                    y0, y1, y2 = y0 + d0, y1 + d1, y2 + d2
                if within:
                    xi[0], xi[1], xi[2] = y0, y1, y2
                    x0, x1, x2 = map_point(code, X, xi, N)
                    if norm3(p0 - x0, p1 - x1, p2 - x2) <= NEWTON_RESIDUAL_TOL * h:
                        polish(code, X, p0, p1, p2, h, xi, trial, N, dN)
                        if solid.outside_distance(code, xi) <= tol:
                            return INSIDE
        if split:
            if r <= r_min:
                undecided = True
                continue
            # children, the one holding the linear estimate m + d last (searched first)
            half = 0.5 * r
            first = top
            for child in range(8):
                stack[top, 0] = m0 + (half if child & 1 else -half)
                stack[top, 1] = m1 + (half if child & 2 else -half)
                stack[top, 2] = m2 + (half if child & 4 else -half)
                stack[top, 3] = half
                top += 1
            if det > 0.0:
                best = first + (1 if d0 > 0.0 else 0) + (2 if d1 > 0.0 else 0) + (4 if d2 > 0.0 else 0)
                for i in range(4):
                    v = stack[best, i]
                    stack[best, i] = stack[top - 1, i]
                    stack[top - 1, i] = v
    return NOT_CONVERGED if undecided else OUTSIDE


#: solutions this close to the element's boundary (parameter units) are polished before the inside test
_NEAR_BOUNDARY = 1e-6


@njit_inline
def locate_point(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack):
    """INSIDE, OUTSIDE or NOT_CONVERGED of the local point p in the non-affine element s (nodes ``X``).

    Newton from the linearised estimate (from the centre if that fails). A solution inside is
    final; one outside is final when the element's one-to-one certificate covers it
    (:func:`certified_outside`). Otherwise p may still have a preimage inside (a curved element
    folds beyond its faces, and Newton found another branch): :func:`search_inside` decides.
    On INSIDE or OUTSIDE ``xi`` holds a solution of x(ξ) = p and ``trial`` its residual p - x(ξ)
    (for :func:`polish_residual`); NOT_CONVERGED: no solution known (and none inside the element
    unless the search was undecided).

    This function holds only the common case (Newton converges from the linearised estimate, away
    from the element's faces) and is inlined into the loops that call it, which saves the reference
    counting of eight array arguments per call; every other case continues in :func:`locate_rare`,
    a call of its own.
    """
    converged = (linear_parameters(code, table, s, p0, p1, p2, xi)
                 and project_point(code, X, p0, p1, p2, h, xi, trial, N, dN) == CONVERGED)
    if converged and not abs(solid.outside_distance(code, xi)) <= _NEAR_BOUNDARY:
        if solid.is_inside(code, xi, tol):
            return INSIDE
        if certified_outside(code, table, s, xi, X, a):
            return OUTSIDE
    return _locate_rare_call(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack, converged)


@njit
def locate_rare(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack, converged):
    """:func:`locate_point` from where its common case stops: Newton did not converge from the
    linearised estimate (``converged`` False; restart from the centre), or its solution lies
    within ``_NEAR_BOUNDARY`` of a face (polished before the inside test), or outside the
    certified box (the subdivision search decides). On INSIDE or OUTSIDE ``trial`` holds the
    residual p - x(ξ), as after the common case (one evaluation of the map, on this rare path only)."""
    status = _locate_rare(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack, converged, True)
    if status != NOT_CONVERGED:
        store_residual(code, X, p0, p1, p2, xi, trial, N)
    return status


#: called through a symbol, not compiled into every loop that inlines locate_point (see mortar1d3d._unlinked),
#: and lazily: compiled when a point first needs it
_locate_rare_call = unlinked(locate_rare, returns=types.int64)


@njit
def locate_outside(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack):
    """:func:`locate_point` of a point known to lie outside the element, beyond a plane of its hull
    (:func:`.search.in_hull` False): the same Newton solves and the same ξ, without the subdivision
    search, which could only prove again that p has no preimage within ``tol`` of the element (the
    hull's margin lies far beyond what ``tol`` reaches). OUTSIDE (``xi`` a solution outside) or
    NOT_CONVERGED; ``trial`` is left as scratch, not as the residual."""
    converged = (linear_parameters(code, table, s, p0, p1, p2, xi)
                 and project_point(code, X, p0, p1, p2, h, xi, trial, N, dN) == CONVERGED)
    return _locate_rare(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack, converged, False)


@njit
def _locate_rare(code, X, p0, p1, p2, h, tol, table, s, xi, trial, N, dN, a, stack, converged, search):
    if not converged:
        solid.centre(code, xi)
        converged = project_point(code, X, p0, p1, p2, h, xi, trial, N, dN) == CONVERGED
    if converged:
        if abs(solid.outside_distance(code, xi)) <= _NEAR_BOUNDARY:
            # the inside test near a face is decided to round-off, not to the Newton tolerance
            polish(code, X, p0, p1, p2, h, xi, trial, N, dN)
        if solid.is_inside(code, xi, tol):
            return INSIDE
        if certified_outside(code, table, s, xi, X, a):
            return OUTSIDE
    o0, o1, o2 = xi[0], xi[1], xi[2]
    if search and _search_inside_call(code, X, p0, p1, p2, h, tol, a, stack, xi, trial, N, dN) == INSIDE:
        return INSIDE
    if converged:
        xi[0], xi[1], xi[2] = o0, o1, o2
        return OUTSIDE
    return NOT_CONVERGED


#: lazily through a symbol: :func:`locate_outside` (search False) never calls it
_search_inside_call = unlinked(search_inside, returns=types.int64)


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
    store_residual(code, X, p0, p1, p2, xi, trial, N)
    polish_residual(code, X, p0, p1, p2, h, xi, trial, N, dN)


@njit
def store_residual(code, X, p0, p1, p2, xi, trial, N):
    """Write the residual p - x(ξ) into ``trial`` (the form :func:`polish_residual` takes it in)."""
    x0, x1, x2 = map_point(code, X, xi, N)
    trial[0], trial[1], trial[2] = p0 - x0, p1 - x1, p2 - x2


@njit_inline
def polish_residual(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """:func:`polish` with the residual p - x(ξ) already in ``trial`` (as :func:`project_point` and
    :func:`locate_point` leave it): the same step, one evaluation of the map fewer.

    Inlined into its callers (the integration points' chunks call it once per point): a call would
    pass its five arrays and five scalars per point; inlined, the element-based points stage on the
    distorted hex8 cube executes 0.953 of the kernel instructions (benchmarks/README.md, "The hex8
    points stage in instructions"). The same operations, so the same bits. Types but hex8 as in
    :func:`project_point`: one call to :func:`_polish_other`."""
    if code != _HEX8:
        _polish_other_call(code, X, p0, p1, p2, h, xi, trial, N, dN)
        return
    _polish_step(code, X, p0, p1, p2, h, xi, trial, N, dN)


@njit
def _polish_other(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """:func:`polish_residual` of every type but hex8."""
    _polish_step(code, X, p0, p1, p2, h, xi, trial, N, dN)


#: lazily through a symbol, as :func:`_project_other`
_polish_other_call = unlinked(_polish_other, returns=types.none)


@njit_inline
def _polish_step(code, X, p0, p1, p2, h, xi, trial, N, dN):
    """The step of :func:`polish_residual`."""
    r0, r1, r2 = trial[0], trial[1], trial[2]
    if norm3(r0, r1, r2) <= _ROUND_OFF * h:
        return      # already at round-off (affine elements after one Newton step): nothing to gain
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xi, N, dN)
    det, d0, d1, d2 = solve3(j00, j01, j02, j10, j11, j12, j20, j21, j22, r0, r1, r2)
    if det == 0.0:
        return
    trial[0], trial[1], trial[2] = xi[0] + d0, xi[1] + d1, xi[2] + d2
    x0, x1, x2 = map_point(code, X, trial, N)
    if norm3(p0 - x0, p1 - x1, p2 - x2) < norm3(r0, r1, r2):
        xi[0], xi[1], xi[2] = trial[0], trial[1], trial[2]


@njit
def first_containing(r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, hull, codes, conn, points,
                     solid_origin, solid_h, linear, tol, X, xi, trial, N, dN, a, stack, only):
    """Lowest-index candidate of beam element ``e`` containing the point r (beam-local frame).

    Candidates are ``pair_solid[p0:p1]`` (ascending); returns -1 if none contains the point.
    With ``only`` >= 0, tests just that element. On success ``xi`` holds the point's ξ.
    Before a non-affine element's Newton projection the point must lie in its box and, for a type
    with hull planes (``HULL_TEST``; not hex8), in its ``hull`` (:func:`.search.in_hull`): points outside either are farther from the element than
    any inside test accepts, so these tests change no result, only how many projections run.
    This is the ownership rule of both integrations (docs/conventions.md §1-§2): a point on a face,
    edge or node shared by several elements belongs to the lowest-index one. Affine elements
    are located with their inverse map (``linear``, :func:`linear_maps`), the others by
    :func:`locate_point` (``a``, ``stack``: :func:`search_buffers`), which finds a point inside a
    curved element whatever branch Newton takes; ``X`` is left holding the nodes of the last
    element tested.
    """
    return first_containing_inline(r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, hull, codes,
                                   conn, points, solid_origin, solid_h, linear, tol, X, xi, trial, N, dN, a,
                                   stack, only)


@njit_inline
def first_containing_inline(r0, r1, r2, e, pair_solid, p0, p1, beam_origin, solid_boxes, hull, codes, conn,
                            points, solid_origin, solid_h, linear, tol, X, xi, trial, N, dN, a, stack, only):
    """:func:`first_containing`, inlined into the element-based points loop, which calls it once per
    point: as a call it passes seventeen arrays and eight scalars each time."""
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
            if solid.is_inside(code, xi, tol):
                return s
        elif not solid.HULL_TEST[code] or in_hull(hull, s, x0, x1, x2):
            load_element(points, conn, s, code, solid_origin, X)
            if locate_point(code, X, x0, x1, x2, solid_h[s], tol, linear, s, xi, trial, N, dN, a, stack) == INSIDE:
                return s
    return -1


#: elements whose map is affine to this (relative) accuracy are located with their inverse map,
#: without Newton: exact to round-off, as a polished Newton projection would be
EXACT_AFFINE_TOL = 64 * 2.220446049250313e-16


@njit
def affine_inverse(code, X, h, rel_tol, Ainv):
    """Whether element ``code`` with local nodes ``X`` (node 0 at the origin) is affine; its inverse map.

    Affine means x(ξ) = A (ξ - ξ_0) for every node to ``rel_tol · h`` (tet4 always; a hex8
    that is a parallelepiped; quadratic elements with straight edges and centred mid-nodes).
    On success ``Ainv`` (3, 3) holds A⁻¹, so ξ(x) = ξ_0 + A⁻¹ x exactly (no Newton needed).
    A rational element is affine only with equal weights (then it is its polynomial Bernstein map).
    """
    if solid.RATIONAL[code] and not uniform_weights(code, X):
        return False
    axes = solid.AXIS_NODES[code]
    span = solid.AXIS_SPAN[code]
    a00 = X[axes[0], 0] / span[0]
    a10 = X[axes[0], 1] / span[0]
    a20 = X[axes[0], 2] / span[0]
    a01 = X[axes[1], 0] / span[1]
    a11 = X[axes[1], 1] / span[1]
    a21 = X[axes[1], 2] / span[1]
    a02 = X[axes[2], 0] / span[2]
    a12 = X[axes[2], 1] / span[2]
    a22 = X[axes[2], 2] / span[2]
    ref = solid.REFERENCE_NODES[code]
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
        xi[i] = solid.REFERENCE_NODES[code, 0, i] + Ainv[i, 0] * x0 + Ainv[i, 1] * x1 + Ainv[i, 2] * x2


#: called once per element through a symbol, not compiled into linear_maps' parallel body and kernel
#: again (see mortar1d3d._unlinked)
_affine_inverse_call = unlinked(affine_inverse)


@njit
def linear_maps(points, conn, codes, solid_origin, solid_h, table, workers):
    """The inverse of every element's map linearised at its parameter centre, for locating points.

    ``table[s]`` (5, 3): rows 0-2 the inverse L of the Jacobian at the centre ξ_c, row 3 the
    position x_c = x(ξ_c) (local to node 0), row 4 ``[kind, 0, 0]``: kind 1 for elements affine to
    round-off (every tet4, parallelepiped hex8, straight-edged quadratic elements; L is then
    the exact inverse map and ``ξ = ξ_c + L (x - x_c)`` needs no Newton), 0 for the others (a
    Newton start close to the answer), NaN where the Jacobian at the centre is singular. Row 4,
    column 1 of a curved element: ``PENDING_CERTIFICATE``, until the first Newton solution outside
    the element that needs it replaces it with the margin δ of the element's one-to-one certificate
    (:func:`certified_margin`; -1 if none), with which such a solution proves a point outside
    (:func:`certified_outside`). Few elements ever need it, and it cost more than the rest of the
    row together.
    """
    claims = new_claims(conn.shape[0], workers)
    _linear_maps_workers(workers, claims, points, conn, codes, solid_origin, solid_h, table)


@njit
def _linear_maps_worker(worker, claims, points, conn, codes, solid_origin, solid_h, table):
    n = conn.shape[0]
    X = np.empty((solid.MAX_NODES, 4))
    N = np.empty(solid.MAX_NODES)
    dN = np.empty((solid.MAX_NODES, 3))
    xc = np.empty(3)
    begin, stop = claim(claims, n, worker)
    while begin < stop:
        _linear_maps_chunk(begin, stop, points, conn, codes, solid_origin, solid_h, table, X, N, dN, xc)
        begin, stop = claim(claims, n, worker)


@njit_inline
def _linear_maps_chunk(begin, stop, points, conn, codes, solid_origin, solid_h, table, X, N, dN, xc):
    # the caller holds every array for this call: the calls per element pass them without reference
    # counting (see mortar1d3d._borrowed)
    points, conn, codes, solid_origin, solid_h, table, X, N, dN, xc = borrowed(points, conn, codes, solid_origin,
                                                                               solid_h, table, X, N, dN, xc)
    for s in range(begin, stop):
        code = codes[s]
        load_element(points, conn, s, code, solid_origin, X)
        solid.centre(code, xc)
        table[s, 3, 0], table[s, 3, 1], table[s, 3, 2] = map_point(code, X, xc, N)
        table[s, 4, 1] = table[s, 4, 2] = 0.0
        if _affine_inverse_call(code, X, solid_h[s], EXACT_AFFINE_TOL, table[s, :3]):
            table[s, 4, 0] = 1.0
            continue
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(code, X, xc, N, dN)
        if inverse3(j00, j01, j02, j10, j11, j12, j20, j21, j22, table[s, :3]) > 0.0:
            table[s, 4, 0] = 0.0
            table[s, 4, 1] = PENDING_CERTIFICATE
        else:
            table[s, :, :] = np.nan


#: the kernel's workers run on the package's one parallel loop (see mortar1d3d._parallel); the worker, compiled
#: on its own and called through a symbol, inlines its loop body (``njit_inline``), which is optimised once
_linear_maps_workers = in_parallel(_linear_maps_worker)


@njit
def point_buffers():
    """Work buffers of the kernels that follow beam points into solid elements (one set per worker).

    ``X`` (element nodes; column 3: a rational element's weights), ``N``, ``dN`` (shape functions and
    derivatives), ``H``, ``dH`` (beam functions and derivatives), ``xi`` (parameters), ``trial``
    (Newton trial point).
    """
    return (np.empty((solid.MAX_NODES, 4)), np.empty(solid.MAX_NODES), np.empty((solid.MAX_NODES, 3)),
            np.empty(MAX_FUNCTIONS), np.empty(MAX_FUNCTIONS), np.empty(3), np.empty(3))


@njit
def is_affine(table, s):
    """Whether element s is located exactly by its linear map (see :func:`linear_maps`)."""
    return table[s, 4, 0] == 1.0


#: a linearised start farther out than this (max norm, parameter units) is not used: Newton
#: starts at the centre instead
_START_LIMIT = 4.0


@njit_inline
def linear_image(code, table, s, x0, x1, x2):
    """ζ = ξ_c + L (x - x_c) of element s (x local to node 0) as a 3-tuple, with no limit (the element
    must have a linearisation: ``table[s, 4, 0] >= 0``)."""
    d0 = x0 - table[s, 3, 0]
    d1 = x1 - table[s, 3, 1]
    d2 = x2 - table[s, 3, 2]
    return (solid.CENTRE[code, 0] + table[s, 0, 0] * d0 + table[s, 0, 1] * d1 + table[s, 0, 2] * d2,
            solid.CENTRE[code, 1] + table[s, 1, 0] * d0 + table[s, 1, 1] * d1 + table[s, 1, 2] * d2,
            solid.CENTRE[code, 2] + table[s, 2, 0] * d0 + table[s, 2, 1] * d1 + table[s, 2, 2] * d2)


@njit
def linear_parameters(code, table, s, x0, x1, x2, xi):
    """ξ = ξ_c + L (x - x_c) of element s (x local to node 0): exact where affine, else a start.

    Returns False (``xi`` unchanged) where the element has no linearisation or the estimate
    lies beyond ``_START_LIMIT``.
    """
    if not table[s, 4, 0] >= 0.0:
        return False
    y0, y1, y2 = linear_image(code, table, s, x0, x1, x2)
    if table[s, 4, 0] == 0.0 and max(abs(y0), abs(y1), abs(y2)) > _START_LIMIT:
        return False
    xi[0], xi[1], xi[2] = y0, y1, y2
    return True


@njit
def _project_points_kernel(points, conn, codes, solid_origin, solid_h, linear, x, elements, tol, xi, status,
                           workers):
    """ξ and INSIDE / OUTSIDE / NOT_CONVERGED of each point ``x[i]`` in element ``elements[i]``."""
    n = x.shape[0]
    claims = new_claims(n, workers)
    _project_points_kernel_workers(workers, claims, points, conn, codes, solid_origin, solid_h, linear, x, elements,
                                   tol, xi, status)


@njit
def _project_points_kernel_worker(worker, claims, points, conn, codes, solid_origin, solid_h, linear, x, elements,
                                  tol, xi, status):
    n = x.shape[0]
    X, N, dN, _, _, _, trial = point_buffers()
    a, stack = search_buffers()
    begin, stop = claim(claims, n, worker)
    while begin < stop:
        for i in range(begin, stop):
            s = elements[i]
            code = codes[s]
            x0 = x[i, 0] - solid_origin[s, 0]
            x1 = x[i, 1] - solid_origin[s, 1]
            x2 = x[i, 2] - solid_origin[s, 2]
            if is_affine(linear, s):
                linear_parameters(code, linear, s, x0, x1, x2, xi[i])
                status[i] = INSIDE if solid.is_inside(code, xi[i], tol) else OUTSIDE
                continue
            load_element(points, conn, s, code, solid_origin, X)
            status[i] = locate_point(code, X, x0, x1, x2, solid_h[s], tol, linear, s, xi[i], trial, N, dN, a,
                                     stack)
            if status[i] == NOT_CONVERGED:
                xi[i, 0] = xi[i, 1] = xi[i, 2] = np.nan
            else:
                polish_residual(code, X, x0, x1, x2, solid_h[s], xi[i], trial, N, dN)
        begin, stop = claim(claims, n, worker)


_project_points_kernel_workers = in_parallel(_project_points_kernel_worker)


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
        ``OUTSIDE`` (1): the point lies outside the element; ξ is a solution of x(ξ) = p
        outside it (the map extended beyond the element);
        ``NOT_CONVERGED`` (2): the point lies outside the element and no solution of x(ξ) = p
        was found (far outside a curved element, where the extended map folds or runs away).

    Notes
    -----
    The location used by :func:`mortar1d3d.assemble_mortar`: affine elements (every tet4,
    parallelepiped hex8, straight-edged quadratic elements) use their exact inverse map. The
    others run Newton on x(ξ) - p with a backtracking line search, converged when
    ``|x(ξ) - p| <= 1e-12 h`` (h: the element's size), at most 20 iterations, from the element's map
    linearised at its centre (else from the centre). A curved element's extended map can fold,
    so a point inside may have further solutions outside, and Newton may find one of those.
    A solution outside therefore counts only where the map is proved one-to-one (a bound on its
    second derivatives); elsewhere a subdivision search with the same bound either finds the
    solution inside or proves there is none. A point inside a valid element (det J > 0
    throughout) is always found inside.
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
    linear_maps(solid.kernel_points, solid.connectivity, solid.element_codes, solid_origin, solid_h, linear, workers())
    xi = np.zeros((len(x), 3))
    status = np.empty(len(x), dtype=np.int64)
    _project_points_kernel(solid.kernel_points, solid.connectivity, solid.element_codes, solid_origin, solid_h, linear, x,
                           elements, PARAMETER_TOL, xi, status, workers())
    return xi, status
