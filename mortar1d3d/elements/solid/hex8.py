"""8-node trilinear hexahedron (meshio ``hexahedron``, VTK_HEXAHEDRON).

::

        7-------6          ζ
       /|      /|          |  η
      4-------5 |          | /
      | 3-----|-2          |/
      |/      |/           +----ξ
      0-------1

Parameter space [-1, 1]^3; node a sits at ``REFERENCE_NODES[a]``.
"""
import numpy as np

from ..._config import njit_inline
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import CORNERS, HEXAHEDRON

REFERENCE_NODES = CORNERS


@njit_inline
def shape(xi, N):
    """Write the 8 shape function values at ``xi`` (3,) into ``N`` (8,)."""
    for a in range(8):
        N[a] = 0.125 * ((1.0 + REFERENCE_NODES[a, 0] * xi[0]) * (1.0 + REFERENCE_NODES[a, 1] * xi[1])
                        * (1.0 + REFERENCE_NODES[a, 2] * xi[2]))


@njit_inline
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (8, 3)."""
    for a in range(8):
        p = REFERENCE_NODES[a]
        fx = 1.0 + p[0] * xi[0]
        fy = 1.0 + p[1] * xi[1]
        fz = 1.0 + p[2] * xi[2]
        dN[a, 0] = 0.125 * p[0] * fy * fz
        dN[a, 1] = 0.125 * fx * p[1] * fz
        dN[a, 2] = 0.125 * fx * fy * p[2]


DESCRIPTOR = SolidElementType(
    name="hexahedron", code=0, n_nodes=8, degree=1, family_type=HEXAHEDRON,
    reference_nodes=REFERENCE_NODES, bounding_matrix=np.eye(8),
    monomials=[(i, j, k) for i in (0, 1) for j in (0, 1) for k in (0, 1)],     # trilinear
    quadrature=hexahedron_rule(2),
    hull_test=False,    # its box is tight enough: the planes cost more than they save (the descriptor's docs)
)
