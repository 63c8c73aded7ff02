r"""6-node linear wedge (prism; meshio ``wedge``, VTK_WEDGE).

::

        5                 ζ
       /|\                |  ξ2
      3---4               | /
      | 2 |               |/
      |/ \|               +----ξ1
      0---1

Parameter space: the prism ξ1, ξ2 >= 0, ξ1 + ξ2 <= 1, ζ ∈ [-1, 1]; nodes 0, 1, 2 at ζ = -1 and
3, 4, 5 at ζ = +1 (the same node order in VTK and gmsh). With the triangle's barycentric
L = (1 - ξ1 - ξ2, ξ1, ξ2): N_a = L_a (1 - ζ)/2 and N_{a+3} = L_a (1 + ζ)/2.
"""
import numpy as np

from ..._config import njit
from ...quadrature import wedge_rule
from ..descriptor import SolidElementType
from .wedge_family import CORNERS, WEDGE

REFERENCE_NODES = CORNERS


@njit
def shape(xi, N):
    """Write the 6 shape function values at ``xi`` (3,) into ``N`` (6,)."""
    lo = 0.5 * (1.0 - xi[2])
    hi = 0.5 * (1.0 + xi[2])
    L0 = 1.0 - xi[0] - xi[1]
    N[0], N[1], N[2] = L0 * lo, xi[0] * lo, xi[1] * lo
    N[3], N[4], N[5] = L0 * hi, xi[0] * hi, xi[1] * hi


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (6, 3)."""
    lo = 0.5 * (1.0 - xi[2])
    hi = 0.5 * (1.0 + xi[2])
    L0 = 1.0 - xi[0] - xi[1]
    dN[0, 0], dN[0, 1], dN[0, 2] = -lo, -lo, -0.5 * L0
    dN[1, 0], dN[1, 1], dN[1, 2] = lo, 0.0, -0.5 * xi[0]
    dN[2, 0], dN[2, 1], dN[2, 2] = 0.0, lo, -0.5 * xi[1]
    dN[3, 0], dN[3, 1], dN[3, 2] = -hi, -hi, 0.5 * L0
    dN[4, 0], dN[4, 1], dN[4, 2] = hi, 0.0, 0.5 * xi[0]
    dN[5, 0], dN[5, 1], dN[5, 2] = 0.0, hi, 0.5 * xi[1]


DESCRIPTOR = SolidElementType(
    name="wedge", code=5, n_nodes=6, degree=1, family_type=WEDGE,
    reference_nodes=REFERENCE_NODES, bounding_matrix=np.eye(6),
    # linear on the triangle times linear in ζ
    monomials=[(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)],
    quadrature=wedge_rule(2, 2),            # 3-point triangle (degree 2) times 2-point Gauss: 6 points
)
