"""Intersection of a beam centreline with a face of a solid element.

Every face of the supported elements is affine in parameter space, ``ξ = o + u a + v b``, so the
intersection is one 3×3 Newton problem in z = (η, u, v):

    F(z) = x(o + u a + v b) - r(η) = 0,   ∂F/∂z = [-r'(η), J a, J b].
"""
import numpy as np
from numba import types

from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, njit, njit_inline
from .._unlinked import unlinked
from .beam import beam_point
from .linalg import norm3, solve3
from .projection import _HEX8, CONVERGED, FAILED, _map_jacobian_other_call, jacobian, map_point

#: step halvings of the line search. A beam that enters a face at a grazing angle (tangent to it
#: a little outside) makes the Jacobian nearly singular near the tangency: the Newton step then
#: overshoots the crossing by a factor ~ 1/sqrt(distance) and only ~2^-10 of it lowers |F| (found
#: by make fuzz: with 8 halvings the entry 6e-4 into the element was never found, see
#: test_hard_cases.test_grazing_entry_from_outside). 2^-30 covers distances down to round-off.
_BACKTRACKS = 30
_MAX_ETA = 10.0     # Newton wandering this far beyond the beam element: no crossing there
_POLISH_STEP = 1e-11        # parameter step below which a converged crossing is final
_POLISH_ITERATIONS = 40     # linear convergence at a tangential touch halves the error per step


@njit
def face_coordinates(face, xi0, xi1, xi2):
    """Least-squares (u, v) of the point of the face plane nearest to ξ (parameter space)."""
    a = face[1]
    b = face[2]
    aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    d0, d1, d2 = xi0 - face[0, 0], xi1 - face[0, 1], xi2 - face[0, 2]
    ra = a[0] * d0 + a[1] * d1 + a[2] * d2
    rb = b[0] * d0 + b[1] * d1 + b[2] * d2
    det = aa * bb - ab * ab
    return (bb * ra - ab * rb) / det, (aa * rb - ab * ra) / det


@njit
def _residual(solid_code, X, beam_code, Q, length, s0, s1, s2, face, eta, u, v, xi, N, H, dH):
    """F at (η, u, v); sets ξ. Returns (|F|, F0, F1, F2, dr0, dr1, dr2)."""
    for i in range(3):
        xi[i] = face[0, i] + u * face[1, i] + v * face[2, i]
    x0, x1, x2 = map_point(solid_code, X, xi, N)
    r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Q, length, s0, s1, s2, eta, H, dH)
    f0, f1, f2 = x0 - r0, x1 - r1, x2 - r2
    return norm3(f0, f1, f2), f0, f1, f2, d0, d1, d2


@njit_inline
def _residual_jacobian(solid_code, X, beam_code, Q, length, s0, s1, s2, face, eta, u, v, xi, N, dN, H, dH):
    """:func:`_residual` of a type but hex8 and the solid's Jacobian at the same ξ (one call,
    :func:`~mortar1d3d.geometry.projection._map_jacobian_other`): its 7 values, then J row by row."""
    for i in range(3):
        xi[i] = face[0, i] + u * face[1, i] + v * face[2, i]
    x0, x1, x2, j00, j01, j02, j10, j11, j12, j20, j21, j22 = _map_jacobian_other_call(solid_code, X, xi, N, dN)
    r0, r1, r2, d0, d1, d2 = beam_point(beam_code, Q, length, s0, s1, s2, eta, H, dH)
    f0, f1, f2 = x0 - r0, x1 - r1, x2 - r2
    return (norm3(f0, f1, f2), f0, f1, f2, d0, d1, d2, j00, j01, j02, j10, j11, j12, j20, j21, j22)


@njit
def intersect_face(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH):
    """Newton on F(η, u, v) = 0 from the start ``z`` = (η, u, v); result in ``z`` and ``xi``.

    Returns CONVERGED (|F| <= 1e-12 h within 20 iterations) or FAILED. The caller decides
    whether η lies in the beam element and ξ on the face.

    Once |F| is below the tolerance the iteration goes on until the step is below 1e-11:
    one extra step for a transversal crossing (quadratic convergence), more for a beam that
    touches the face tangentially (a double root, linear convergence), where the residual
    test alone leaves η off by O(√tol) and two spurious crossings on either side of the touch.

    The trilinear hexahedron's iteration is compiled here, every other type's is one call to
    :func:`_intersect_other`, as in :func:`~mortar1d3d.geometry.projection.project_point`.
    """
    if solid_code != _HEX8:
        return _intersect_other_call(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH)
    return _face_newton(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH)


@njit
def _intersect_other(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH):
    """:func:`intersect_face` of every solid type but hex8."""
    return _face_newton(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH)


#: lazily through a symbol (see mortar1d3d._unlinked): a scene of hex8 elements never compiles it
_intersect_other_call = unlinked(_intersect_other, returns=types.int64)


@njit_inline
def _face_newton(solid_code, X, h, beam_code, Q, length, s0, s1, s2, face, z, xi, N, dN, H, dH):
    """The iteration of :func:`intersect_face` (inlined into it and into :func:`_intersect_other`).

    Every type but hex8 (``paired``, a constant after the test of :func:`intersect_face`) gets the
    solid's Jacobian with the residual at the start and at each trial whose step exceeds
    ``_POLISH_STEP`` (:func:`_residual_jacobian`): an accepted one needs a further step. The same
    iteration and values as hex8's, which evaluates the Jacobian at the top of each step."""
    tol = NEWTON_RESIDUAL_TOL * h
    paired = solid_code != _HEX8
    fresh = paired      # whether (j00 ... j22) is the solid's Jacobian at xi
    if paired:
        fn, f0, f1, f2, d0, d1, d2, j00, j01, j02, j10, j11, j12, j20, j21, j22 = _residual_jacobian(
            solid_code, X, beam_code, Q, length, s0, s1, s2, face, z[0], z[1], z[2], xi, N, dN, H, dH)
    else:
        fn, f0, f1, f2, d0, d1, d2 = _residual(solid_code, X, beam_code, Q, length, s0, s1, s2, face,
                                               z[0], z[1], z[2], xi, N, H, dH)
        j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
    last_step = np.inf
    for it in range(NEWTON_MAX_ITERATIONS + _POLISH_ITERATIONS):
        converged = fn <= tol
        if converged and last_step <= _POLISH_STEP:
            return CONVERGED
        if not converged and it >= NEWTON_MAX_ITERATIONS:
            return FAILED
        if not fresh:
            j00, j01, j02, j10, j11, j12, j20, j21, j22 = jacobian(solid_code, X, xi, N, dN)
        a, b = face[1], face[2]
        det, s_eta, s_u, s_v = solve3(
            -d0, j00 * a[0] + j01 * a[1] + j02 * a[2], j00 * b[0] + j01 * b[1] + j02 * b[2],
            -d1, j10 * a[0] + j11 * a[1] + j12 * a[2], j10 * b[0] + j11 * b[1] + j12 * b[2],
            -d2, j20 * a[0] + j21 * a[1] + j22 * a[2], j20 * b[0] + j21 * b[1] + j22 * b[2],
            -f0, -f1, -f2)
        if det == 0.0:
            return CONVERGED if converged else FAILED
        full = max(abs(s_eta), abs(s_u), abs(s_v))
        step = 1.0
        accepted = False
        for _b in range(_BACKTRACKS):
            e_t = z[0] + step * s_eta
            u_t = z[1] + step * s_u
            v_t = z[2] + step * s_v
            fresh = paired and step * full > _POLISH_STEP
            if fresh:
                ft, g0, g1, g2, c0, c1, c2, j00, j01, j02, j10, j11, j12, j20, j21, j22 = _residual_jacobian(
                    solid_code, X, beam_code, Q, length, s0, s1, s2, face, e_t, u_t, v_t, xi, N, dN, H, dH)
            else:
                ft, g0, g1, g2, c0, c1, c2 = _residual(solid_code, X, beam_code, Q, length, s0, s1, s2, face,
                                                       e_t, u_t, v_t, xi, N, H, dH)
            if ft < fn or ft <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            _residual(solid_code, X, beam_code, Q, length, s0, s1, s2, face, z[0], z[1], z[2], xi, N, H, dH)
            return CONVERGED if fn <= 1e3 * tol else FAILED
        last_step = step * full
        z[0], z[1], z[2] = e_t, u_t, v_t
        fn, f0, f1, f2, d0, d1, d2 = ft, g0, g1, g2, c0, c1, c2
        if abs(z[0]) > _MAX_ETA:
            return FAILED
    return CONVERGED if fn <= tol else FAILED
