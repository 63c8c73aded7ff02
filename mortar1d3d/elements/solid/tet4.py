"""4-node linear tetrahedron (meshio ``tetra``, VTK_TETRA).

Parameter space: the unit simplex ξ_i >= 0, ξ1 + ξ2 + ξ3 <= 1; nodes at the origin and the
three unit points: N = (1 - ξ1 - ξ2 - ξ3, ξ1, ξ2, ξ3).
"""
import numpy as np

from ..._config import njit
from ...quadrature import tetrahedron_rule
from ..descriptor import SolidElementType
from .tet_family import CORNERS, TETRAHEDRON

REFERENCE_NODES = CORNERS


@njit
def shape(xi, N):
    """Write the 4 shape function values at ``xi`` (3,) into ``N`` (4,)."""
    N[0] = 1.0 - xi[0] - xi[1] - xi[2]
    N[1] = xi[0]
    N[2] = xi[1]
    N[3] = xi[2]


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i (constant) into ``dN`` (4, 3)."""
    for a in range(4):
        for i in range(3):
            dN[a, i] = 0.0
    for i in range(3):
        dN[0, i] = -1.0
        dN[i + 1, i] = 1.0


DESCRIPTOR = SolidElementType(
    name="tetra", code=3, n_nodes=4, degree=1, family_type=TETRAHEDRON,
    reference_nodes=REFERENCE_NODES, bounding_matrix=np.eye(4),
    monomials=[(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],                  # linear
    quadrature=tetrahedron_rule(1),
)
