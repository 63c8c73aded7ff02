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
    quadrature=tetrahedron_rule(4),
)
