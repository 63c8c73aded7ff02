"""Newton projection of points into solid elements: find ξ with x(ξ) = p.

Coordinates passed to these kernels are *local*: element nodes and points minus the element's
origin (its first node), so that round-off is relative to the element size h, not to the
distance from the global origin (design.md §2: tolerances relative to the element size).
"""
import numpy as np

from .._config import NEWTON_MAX_ITERATIONS, NEWTON_RESIDUAL_TOL, njit
from ..elements.solid import dispatch as solid
from .linalg import norm3, solve3

CONVERGED = 0
FAILED = 1
#: outcome of a projection, as stored per point
INSIDE, OUTSIDE, NOT_CONVERGED = 0, 1, 2

_MAX_PARAMETER = 1e3      # |ξ| beyond this: the point is far outside; stop early
_BACKTRACKS = 8


@njit
def map_point(code, X, xi, N, x):
    """x = Σ_a N_a(ξ) X_a for element type ``code`` with local nodes ``X`` (n, 3)."""
    solid.shape(code, xi, N)
    n = solid.n_nodes(code)
    x[0] = x[1] = x[2] = 0.0
    for a in range(n):
        for i in range(3):
            x[i] += N[a] * X[a, i]


@njit
def jacobian(code, X, xi, dN, J):
    """J[i, k] = ∂x_i/∂ξ_k."""
    solid.deriv(code, xi, dN)
    n = solid.n_nodes(code)
    for i in range(3):
        for k in range(3):
            s = 0.0
            for a in range(n):
                s += X[a, i] * dN[a, k]
            J[i, k] = s


@njit
def project_point(code, X, p, h, xi, N, dN):
    """Newton iteration for x(ξ) = p with backtracking line search on |x(ξ) - p|.

    ``xi`` holds the start value on entry and the result on exit. Converged when
    |x(ξ) - p| <= 1e-12 h. Returns CONVERGED or FAILED (singular Jacobian, no decrease,
    parameters running away, or 20 iterations).
    """
    tol = NEWTON_RESIDUAL_TOL * h
    x = np.empty(3)
    r = np.empty(3)
    d = np.empty(3)
    trial = np.empty(3)
    J = np.empty((3, 3))
    map_point(code, X, xi, N, x)
    for i in range(3):
        r[i] = p[i] - x[i]
    rn = norm3(r)
    for _ in range(NEWTON_MAX_ITERATIONS):
        if rn <= tol:
            return CONVERGED
        jacobian(code, X, xi, dN, J)
        if solve3(J, r, d) == 0.0:
            return FAILED
        step = 1.0
        accepted = False
        for _b in range(_BACKTRACKS):
            for i in range(3):
                trial[i] = xi[i] + step * d[i]
            map_point(code, X, trial, N, x)
            for i in range(3):
                r[i] = p[i] - x[i]
            rt = norm3(r)
            if rt < rn or rt <= tol:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            # no decrease along the Newton direction: at round-off level this is convergence
            return CONVERGED if rn <= 1e3 * tol else FAILED
        xi[0], xi[1], xi[2] = trial[0], trial[1], trial[2]
        rn = rt
        if abs(xi[0]) > _MAX_PARAMETER or abs(xi[1]) > _MAX_PARAMETER or abs(xi[2]) > _MAX_PARAMETER:
            return FAILED
    return CONVERGED if rn <= tol else FAILED


@njit
def load_element(points, conn, element, code, origin, X):
    """Copy the local (origin-relative) node coordinates of ``element`` into ``X``."""
    n = solid.n_nodes(code)
    for a in range(n):
        node = conn[element, a]
        for i in range(3):
            X[a, i] = points[node, i] - origin[element, i]


@njit
def locate(code, X, p, h, tol, xi, N, dN):
    """Project ``p`` from the element centre; INSIDE, OUTSIDE or NOT_CONVERGED."""
    solid.centre(code, xi)
    if project_point(code, X, p, h, xi, N, dN) != CONVERGED:
        return NOT_CONVERGED
    if solid.is_inside(code, xi, tol):
        return INSIDE
    return OUTSIDE
