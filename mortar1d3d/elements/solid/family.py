"""The element families: hexahedra on [-1, 1]^3 and tetrahedra on the unit simplex.

A family fixes what all its element types share: the parameter domain, its faces (affine in
parameter space for both families, so the intersection kernels treat every face the same way:
``ξ = origin + u a + v b`` with an outward normal ``n``), the inside test and the face quadrature.
The hexahedral family also holds the 3 × 3 × 3 lattice of the quadratic hexahedra (hex20 is the
serendipity subset of hex27's nodes).
"""
import numpy as np

from ..._config import njit
from ...quadrature import quadrilateral_rule, triangle_rule
from ..descriptor import ElementFamily


@njit
def hex_outside_distance(xi):
    """Distance of ``xi`` outside [-1, 1]^3 in the max norm (<= 0 inside)."""
    return max(abs(xi[0]), abs(xi[1]), abs(xi[2])) - 1.0


@njit
def tet_outside_distance(xi):
    """Distance of ``xi`` outside the unit simplex (<= 0 inside), face-wise max."""
    return max(-xi[0], -xi[1], -xi[2], xi[0] + xi[1] + xi[2] - 1.0)


HEXAHEDRON = ElementFamily(
    name="hex", code=0, domain="box",
    # rows: origin, a, b, outward normal
    faces=np.array([
        [[-1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]],   # ξ = -1
        [[+1, 0, 0], [0, 1, 0], [0, 0, 1], [+1, 0, 0]],   # ξ = +1
        [[0, -1, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]],   # η = -1
        [[0, +1, 0], [1, 0, 0], [0, 0, 1], [0, +1, 0]],   # η = +1
        [[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, 0, -1]],   # ζ = -1
        [[0, 0, +1], [1, 0, 0], [0, 1, 0], [0, 0, +1]],   # ζ = +1
    ], dtype=np.float64),
    face_nodes=((0, 3, 7, 4), (1, 2, 6, 5), (0, 1, 5, 4), (3, 2, 6, 7), (0, 1, 2, 3), (4, 5, 6, 7)),
    centre=np.zeros(3), outside_distance=hex_outside_distance, face_rule=quadrilateral_rule,
)

TETRAHEDRON = ElementFamily(
    name="tet", code=1, domain="simplex",
    faces=np.array([
        [[0, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]],    # ξ1 = 0
        [[0, 0, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]],    # ξ2 = 0
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1]],    # ξ3 = 0
        [[1, 0, 0], [-1, 1, 0], [-1, 0, 1], [1, 1, 1]],   # ξ1 + ξ2 + ξ3 = 1
    ], dtype=np.float64),
    face_nodes=((0, 2, 3), (0, 1, 3), (0, 1, 2), (1, 2, 3)),
    centre=np.full(3, 0.25), outside_distance=tet_outside_distance, face_rule=triangle_rule,
    face_centre=1.0 / 3.0,
)

#: family codes, as the kernels compare them
HEX, TET = HEXAHEDRON.code, TETRAHEDRON.code
#: for code that needs the raw tables
HEX_FACES, TET_FACES = HEXAHEDRON.faces, TETRAHEDRON.faces

# the quadratic hexahedra: VTK order of the 27 lattice nodes (hex20 uses the first 20)
QUADRATIC_HEX_NODES = np.array([
    [-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
    [0, -1, -1], [1, 0, -1], [0, 1, -1], [-1, 0, -1],
    [0, -1, 1], [1, 0, 1], [0, 1, 1], [-1, 0, 1],
    [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
    [-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1],
    [0, 0, 0],
], dtype=np.float64)
#: lattice index (0, 1, 2) <-> coordinate (-1, 0, +1) of every node of QUADRATIC_HEX_NODES, per direction
QUADRATIC_HEX_LATTICE = (QUADRATIC_HEX_NODES + 1).astype(np.int64)


def quadratic_bernstein_1d():
    """Map values at (-1, 0, +1) of a 1D quadratic to its Bernstein control points."""
    return np.array([[1.0, 0.0, 0.0], [-0.5, 2.0, -0.5], [0.0, 0.0, 1.0]])


def triquadratic_bernstein_matrix():
    """(27, 27): Bernstein control points of a triquadratic map from its values at the lattice nodes
    (tensor product of the 1D conversion, nodes in QUADRATIC_HEX_NODES order)."""
    C = quadratic_bernstein_1d()
    L = QUADRATIC_HEX_LATTICE
    T = np.empty((27, 27))
    for a in range(27):
        for b in range(27):
            T[a, b] = C[L[a, 0], L[b, 0]] * C[L[a, 1], L[b, 1]] * C[L[a, 2], L[b, 2]]
    return T
