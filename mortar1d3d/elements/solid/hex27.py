"""27-node triquadratic hexahedron (meshio ``hexahedron27``, VTK_TRIQUADRATIC_HEXAHEDRON).

Nodes 0-19 as in ``hex20``; face centres 20-25 on the faces ξ=-1, ξ=+1, η=-1, η=+1,
ζ=-1, ζ=+1; node 26 at the centre. N_a is a tensor product of 1D quadratic Lagrange
polynomials through -1, 0, +1.
"""
import numpy as np

from ..._config import njit
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import (HEXAHEDRON, QUADRATIC_LATTICE, QUADRATIC_NODES, lattice_gradients, lattice_values,
                         triquadratic_bernstein_matrix)

REFERENCE_NODES = QUADRATIC_NODES


@njit
def _line3(x, v, dv):
    v[0] = 0.5 * x * (x - 1.0)
    v[1] = 1.0 - x * x
    v[2] = 0.5 * x * (x + 1.0)
    dv[0] = x - 0.5
    dv[1] = -2.0 * x
    dv[2] = x + 0.5


@njit
def shape(xi, N):
    """Write the 27 shape function values at ``xi`` (3,) into ``N`` (27,)."""
    v = np.empty((3, 3))
    dv = np.empty((3, 3))
    for i in range(3):
        _line3(xi[i], v[i], dv[i])
    lattice_values(QUADRATIC_LATTICE, v, N)


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    v = np.empty((3, 3))
    dv = np.empty((3, 3))
    for i in range(3):
        _line3(xi[i], v[i], dv[i])
    lattice_gradients(QUADRATIC_LATTICE, v, dv, dN)


DESCRIPTOR = SolidElementType(
    name="hexahedron27", code=2, n_nodes=27, degree=2, family_type=HEXAHEDRON,
    # Bernstein control points of a triquadratic map: tensor product of the 1D conversion
    reference_nodes=REFERENCE_NODES, bounding_matrix=triquadratic_bernstein_matrix(),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3)],   # triquadratic
    quadrature=hexahedron_rule(3),
)
