"""10-node quadratic tetrahedron (meshio ``tetra10``, VTK_QUADRATIC_TETRA).

Corners 0-3 as in ``tet4``; mid-edge nodes 4-9 on the edges (0,1) (1,2) (0,2) (0,3) (1,3) (2,3).
With barycentric L = (1 - Σξ, ξ1, ξ2, ξ3): corners L_i (2 L_i - 1), edges 4 L_i L_j.
"""
import numpy as np

from ..._config import njit, njit_inline
from ...quadrature import tetrahedron_rule
from ..descriptor import SolidElementType
from .tet_family import CORNERS as _CORNERS, TETRAHEDRON

EDGES = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]], dtype=np.int64)
REFERENCE_NODES = np.vstack([_CORNERS, 0.5 * (_CORNERS[EDGES[:, 0]] + _CORNERS[EDGES[:, 1]])])
# ∂L_i/∂ξ_k
_DL = np.array([[-1, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)


@njit_inline
def _barycentric(xi):
    """L = (1 - Σξ, ξ1, ξ2, ξ3) as a 4-tuple (registers: no array allocated per call)."""
    return 1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]


@njit
def shape(xi, N):
    """Write the 10 shape function values at ``xi`` (3,) into ``N`` (10,)."""
    L = _barycentric(xi)
    for a in range(4):
        N[a] = L[a] * (2.0 * L[a] - 1.0)
    for e in range(6):
        N[4 + e] = 4.0 * L[EDGES[e, 0]] * L[EDGES[e, 1]]


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (10, 3)."""
    L = _barycentric(xi)
    for k in range(3):
        for a in range(4):
            dN[a, k] = (4.0 * L[a] - 1.0) * _DL[a, k]
        for e in range(6):
            i, j = EDGES[e, 0], EDGES[e, 1]
            dN[4 + e, k] = 4.0 * (_DL[i, k] * L[j] + L[i] * _DL[j, k])


# The map and its Jacobian on the Newton path without forming the 10 shape functions, written out
# for the edge numbering above: x = Σ_i L_i (2 L_i - 1) X_i + 4 Σ_(i,j) L_i L_j X_ij, and with
# G_i = ∂x/∂L_i = (4 L_i - 1) X_i + 4 Σ_(j≠i) L_j X_ij the columns of J are ∂x/∂ξ_k = G_(k+1) - G_0
# (∂L_0/∂ξ_k = -1, ∂L_(k+1)/∂ξ_k = 1). Sums associated differently from Σ_a N_a X_a: the results
# differ from shape() / deriv() and a node sum by round-off (tests/test_elements.py).
@njit_inline
def map_nodes(X, xi):
    """x(ξ) = Σ_a N_a(ξ) X_a for nodes ``X`` (10, ≥3) as (x0, x1, x2)."""
    l0, l1, l2, l3 = _barycentric(xi)
    c0, c1, c2, c3 = l0 * (2.0 * l0 - 1.0), l1 * (2.0 * l1 - 1.0), l2 * (2.0 * l2 - 1.0), l3 * (2.0 * l3 - 1.0)
    e4, e5, e6 = 4.0 * l0 * l1, 4.0 * l1 * l2, 4.0 * l0 * l2
    e7, e8, e9 = 4.0 * l0 * l3, 4.0 * l1 * l3, 4.0 * l2 * l3
    x0 = (c0 * X[0, 0] + c1 * X[1, 0] + c2 * X[2, 0] + c3 * X[3, 0] + e4 * X[4, 0] + e5 * X[5, 0] + e6 * X[6, 0]
          + e7 * X[7, 0] + e8 * X[8, 0] + e9 * X[9, 0])
    x1 = (c0 * X[0, 1] + c1 * X[1, 1] + c2 * X[2, 1] + c3 * X[3, 1] + e4 * X[4, 1] + e5 * X[5, 1] + e6 * X[6, 1]
          + e7 * X[7, 1] + e8 * X[8, 1] + e9 * X[9, 1])
    x2 = (c0 * X[0, 2] + c1 * X[1, 2] + c2 * X[2, 2] + c3 * X[3, 2] + e4 * X[4, 2] + e5 * X[5, 2] + e6 * X[6, 2]
          + e7 * X[7, 2] + e8 * X[8, 2] + e9 * X[9, 2])
    return x0, x1, x2


@njit_inline
def _dx_dl(X, m, l0, l1, l2, l3):
    """(G_0, G_1, G_2, G_3) of coordinate ``m``: G_i = ∂x_m/∂L_i."""
    f0, f1, f2, f3 = 4.0 * l0, 4.0 * l1, 4.0 * l2, 4.0 * l3
    g0 = (f0 - 1.0) * X[0, m] + f1 * X[4, m] + f2 * X[6, m] + f3 * X[7, m]
    g1 = (f1 - 1.0) * X[1, m] + f0 * X[4, m] + f2 * X[5, m] + f3 * X[8, m]
    g2 = (f2 - 1.0) * X[2, m] + f0 * X[6, m] + f1 * X[5, m] + f3 * X[9, m]
    g3 = (f3 - 1.0) * X[3, m] + f0 * X[7, m] + f1 * X[8, m] + f2 * X[9, m]
    return g0, g1, g2, g3


@njit_inline
def jacobian_nodes(X, xi):
    """J[m, k] = ∂x_m/∂ξ_k at ``xi`` for nodes ``X`` (10, ≥3) as a 9-tuple, row by row."""
    l0, l1, l2, l3 = _barycentric(xi)
    a0, a1, a2, a3 = _dx_dl(X, 0, l0, l1, l2, l3)
    b0, b1, b2, b3 = _dx_dl(X, 1, l0, l1, l2, l3)
    c0, c1, c2, c3 = _dx_dl(X, 2, l0, l1, l2, l3)
    return a1 - a0, a2 - a0, a3 - a0, b1 - b0, b2 - b0, b3 - b0, c1 - c0, c2 - c0, c3 - c0


def _bounding_matrix():
    # Bernstein control points: corners stay, an edge's is 2 x_mid - (x_i + x_j) / 2.
    T = np.eye(10)
    for e, (i, j) in enumerate(EDGES):
        T[4 + e, 4 + e] = 2.0
        T[4 + e, i] = T[4 + e, j] = -0.5
    return T


DESCRIPTOR = SolidElementType(
    name="tetra10", code=4, n_nodes=10, degree=2, family_type=TETRAHEDRON,
    reference_nodes=REFERENCE_NODES, bounding_matrix=_bounding_matrix(),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3) if i + j + k <= 2],   # quadratic
    quadrature=tetrahedron_rule(4), bernstein_error=True,
)
