"""27-node triquadratic hexahedron (meshio ``hexahedron27``, VTK_TRIQUADRATIC_HEXAHEDRON).

Nodes 0-19 as in ``hex20``; face centres 20-25 on the faces ξ=-1, ξ=+1, η=-1, η=+1,
ζ=-1, ζ=+1; node 26 at the centre. N_a is a tensor product of 1D quadratic Lagrange
polynomials through -1, 0, +1.
"""

from ..._config import njit, njit_inline
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import HEXAHEDRON, QUADRATIC_LATTICE, QUADRATIC_NODES, triquadratic_bernstein_matrix

REFERENCE_NODES = QUADRATIC_NODES


@njit_inline
def _line3(x):
    """The 1D quadratic Lagrange polynomials through -1, 0, +1 at ``x`` and their derivatives (two 3-tuples)."""
    return (0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)), (x - 0.5, -2.0 * x, x + 0.5)


# The tensor products below keep the 1D values in tuples (registers), not in arrays: an array here
# would be a heap allocation per call, and these two kernels run in every Newton step on a hex27.
# The products are those of hex_family.lattice_values / lattice_gradients, in the same order.
@njit
def shape(xi, N):
    """Write the 27 shape function values at ``xi`` (3,) into ``N`` (27,)."""
    u, _ = _line3(xi[0])
    v, _ = _line3(xi[1])
    w, _ = _line3(xi[2])
    for a in range(27):
        N[a] = u[QUADRATIC_LATTICE[a, 0]] * v[QUADRATIC_LATTICE[a, 1]] * w[QUADRATIC_LATTICE[a, 2]]


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    u, du = _line3(xi[0])
    v, dv = _line3(xi[1])
    w, dw = _line3(xi[2])
    for a in range(27):
        l0, l1, l2 = QUADRATIC_LATTICE[a, 0], QUADRATIC_LATTICE[a, 1], QUADRATIC_LATTICE[a, 2]
        dN[a, 0] = du[l0] * v[l1] * w[l2]
        dN[a, 1] = u[l0] * dv[l1] * w[l2]
        dN[a, 2] = u[l0] * v[l1] * dw[l2]


DESCRIPTOR = SolidElementType(
    name="hexahedron27", code=2, n_nodes=27, degree=2, family_type=HEXAHEDRON,
    # Bernstein control points of a triquadratic map: tensor product of the 1D conversion
    reference_nodes=REFERENCE_NODES, bounding_matrix=triquadratic_bernstein_matrix(),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3)],   # triquadratic
    quadrature=hexahedron_rule(3),
)
