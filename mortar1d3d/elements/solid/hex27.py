"""27-node triquadratic hexahedron (meshio ``hexahedron27``, VTK_TRIQUADRATIC_HEXAHEDRON).

Nodes 0-19 as in ``hex20``; face centres 20-25 on the faces ξ=-1, ξ=+1, η=-1, η=+1,
ζ=-1, ζ=+1; node 26 at the centre. N_a is a tensor product of 1D quadratic Lagrange
polynomials through -1, 0, +1.
"""
import numpy as np

from ..._config import njit
from ..descriptor import SolidElementType
from ._family import HEX_CENTRE, HEX_FACE_NODES, HEX_FACES, quadratic_bernstein_1d

REFERENCE_NODES = np.array([
    [-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
    [0, -1, -1], [1, 0, -1], [0, 1, -1], [-1, 0, -1],
    [0, -1, 1], [1, 0, 1], [0, 1, 1], [-1, 0, 1],
    [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
    [-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1],
    [0, 0, 0],
], dtype=np.float64)
# lattice index (0, 1, 2) <-> coordinate (-1, 0, +1) of every node, per direction
_LATTICE = (REFERENCE_NODES + 1).astype(np.int64)


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
    for a in range(27):
        N[a] = v[0, _LATTICE[a, 0]] * v[1, _LATTICE[a, 1]] * v[2, _LATTICE[a, 2]]


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    v = np.empty((3, 3))
    dv = np.empty((3, 3))
    for i in range(3):
        _line3(xi[i], v[i], dv[i])
    for a in range(27):
        l0, l1, l2 = _LATTICE[a, 0], _LATTICE[a, 1], _LATTICE[a, 2]
        dN[a, 0] = dv[0, l0] * v[1, l1] * v[2, l2]
        dN[a, 1] = v[0, l0] * dv[1, l1] * v[2, l2]
        dN[a, 2] = v[0, l0] * v[1, l1] * dv[2, l2]


def _bounding_matrix():
    # Bernstein control points of a triquadratic map: tensor product of the 1D conversion.
    C = quadratic_bernstein_1d()
    T = np.empty((27, 27))
    for a in range(27):
        for b in range(27):
            T[a, b] = (C[_LATTICE[a, 0], _LATTICE[b, 0]] * C[_LATTICE[a, 1], _LATTICE[b, 1]]
                       * C[_LATTICE[a, 2], _LATTICE[b, 2]])
    return T


DESCRIPTOR = SolidElementType(
    name="hexahedron27", code=2, n_nodes=27, degree=2, family="hex",
    reference_nodes=REFERENCE_NODES, centre=HEX_CENTRE, faces=HEX_FACES, face_nodes=HEX_FACE_NODES,
    bounding_matrix=_bounding_matrix(),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3)],   # triquadratic
)
