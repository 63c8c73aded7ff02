"""Intersection of a beam centreline with a face of a solid element.

Every face of the supported elements is affine in parameter space, ``ξ = o + u a + v b``, so the
intersection is one 3×3 Newton problem in (η, u, v):

    F(η, u, v) = x(o + u a + v b) - r(η) = 0,   ∂F/∂(η, u, v) = [-r'(η), J a, J b].
"""
import numpy as np

from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, njit
from .beam import beam_point
from .linalg import norm3, solve3
from .projection import CONVERGED, FAILED, jacobian, map_point

_BACKTRACKS = 8


@njit
def face_coordinates(face, xi, uv):
    """Least-squares (u, v) of the point of the face plane nearest to ``xi`` (parameter space)."""
    a = face[1]
    b = face[2]
    aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    ra = 0.0
    rb = 0.0
    for i in range(3):
        ra += a[i] * (xi[i] - face[0, i])
        rb += b[i] * (xi[i] - face[0, i])
    det = aa * bb - ab * ab
    uv[0] = (bb * ra - ab * rb) / det
    uv[1] = (aa * rb - ab * ra) / det


@njit
def _residual(solid_code, X, beam_code, Q, length, shift, face, z, xi, N, H, dH, x, r, dr, F):
    """F = x(ξ(u, v)) - r(η) at z = (η, u, v); also sets ξ, r, dr. Returns |F|."""
    for i in range(3):
        xi[i] = face[0, i] + z[1] * face[1, i] + z[2] * face[2, i]
    map_point(solid_code, X, xi, N, x)
    beam_point(beam_code, Q, length, shift, z[0], H, dH, r, dr)
    for i in range(3):
        F[i] = x[i] - r[i]
    return norm3(F)


@njit
def intersect_face(solid_code, X, h, beam_code, Q, length, shift, face, z, xi, N, dN, H, dH):
    """Newton on F(η, u, v) = 0 from the start ``z`` = (η, u, v); result in ``z`` and ``xi``.

    Returns CONVERGED (|F| <= 1e-12 h) or FAILED. The caller decides whether η and ξ lie in
    the beam element and in the face.
    """
    tol = NEWTON_RESIDUAL_TOL * h
    x = np.empty(3)
    r = np.empty(3)
    dr = np.empty(3)
    F = np.empty(3)
    d = np.empty(3)
    trial = np.empty(3)
    J = np.empty((3, 3))
    A = np.empty((3, 3))

    fn = _residual(solid_code, X, beam_code, Q, length, shift, face, z, xi, N, H, dH, x, r, dr, F)
    for _ in range(NEWTON_MAX_ITERATIONS):
        if fn <= tol:
            return CONVERGED
        jacobian(solid_code, X, xi, dN, J)
        for i in range(3):
            A[i, 0] = -dr[i]
            A[i, 1] = J[i, 0] * face[1, 0] + J[i, 1] * face[1, 1] + J[i, 2] * face[1, 2]
            A[i, 2] = J[i, 0] * face[2, 0] + J[i, 1] * face[2, 1] + J[i, 2] * face[2, 2]
            F[i] = -F[i]
        if solve3(A, F, d) == 0.0:
            return FAILED
        step = 1.0
        accepted = False
        for _b in range(_BACKTRACKS):
            for i in range(3):
                trial[i] = z[i] + step * d[i]
            ft = _residual(solid_code, X, beam_code, Q, length, shift, face, trial, xi, N, H, dH, x, r, dr, F)
            if ft < fn or ft <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            _residual(solid_code, X, beam_code, Q, length, shift, face, z, xi, N, H, dH, x, r, dr, F)
            return CONVERGED if fn <= 1e3 * tol else FAILED
        z[0], z[1], z[2] = trial[0], trial[1], trial[2]
        fn = ft
        if abs(z[0]) > 10.0:
            return FAILED      # far beyond the beam element: no crossing there
    return CONVERGED if fn <= tol else FAILED
