"""The hexahedral family: elements on the box [-1, 1]^3 (hex8, hex20, hex27).

What every hexahedron shares lives here: the six faces (affine in parameter space, so the
intersection kernels treat every face alike: ``ξ = origin + u a + v b`` with an outward normal),
the inside test, how a unit cube of a structured mesh is filled (one element),
and the cells of the validity check (sub-boxes, whose Bernstein coefficients of det J are
subdivided exactly by de Casteljau's rule). Also the 3 × 3 × 3 node lattice of the quadratic
hexahedra (hex20 takes the serendipity subset of hex27's nodes).
"""
from functools import lru_cache
from math import comb

import numpy as np

from ..._config import njit
from ..descriptor import ElementFamily
from .face_shapes import QUADRILATERAL

#: the corners of [-1, 1]^3 in VTK order
CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=np.float64)


@njit
def outside_distance(xi):
    """Distance of ``xi`` outside [-1, 1]^3 in the max norm (<= 0 inside)."""
    return max(abs(xi[0]), abs(xi[1]), abs(xi[2])) - 1.0


@njit
def box_meets(m0, m1, m2, r, tol):
    """Whether the box |ξ - m|∞ <= r meets the domain: always, for the boxes of the point search
    (they subdivide the domain itself)."""
    return True


@lru_cache(maxsize=None)
def _halves_1d(p):
    """Bernstein coefficients of a degree-p polynomial on [0, 1/2] and on [1/2, 1] from those on [0, 1]
    (de Casteljau at 1/2): the lower and the upper (p+1, p+1) matrix."""
    lower = np.array([[comb(i, j) * 0.5 ** i if j <= i else 0.0 for j in range(p + 1)] for i in range(p + 1)])
    upper = np.array([[comb(p - i, j - i) * 0.5 ** (p - i) if j >= i else 0.0 for j in range(p + 1)]
                      for i in range(p + 1)])
    return lower, upper


class BoxCells:
    """Cells of the validity check on [-1, 1]^3: sub-boxes ``(lower (n, 3), upper (n, 3))``.

    A polynomial of degree p in each direction (Q_p) has a tensor-product Bernstein form on every
    box; its coefficients on the 8 half-boxes follow from those on the box by de Casteljau's rule,
    so refinement needs no new samples (:meth:`child_coefficients`).
    """

    n_children = 8

    @staticmethod
    def jacobian_degree(monomials):
        """Degree of det J per direction (det J ∈ Q_p) for shape functions spanned by ``monomials``.

        Column j of J, ∂x/∂ξ_j, has in ξ_i the degree max(α_i - [i == j]) over the monomials that
        ξ_j does not kill; det J takes one factor from each column.
        """
        exps = monomials
        return max(sum(int(max(exps[exps[:, j] > 0, i] - (i == j), default=0)) for j in range(3))
                   for i in range(3))

    @staticmethod
    @lru_cache(maxsize=None)
    def lattice(p):
        """Lattice points t ∈ [0, 1]^3 ((p+1)^3, 3) of Q_p and the matrix from values there to Bernstein
        coefficients (tensor product of the 1D inverse)."""
        t = np.linspace(0.0, 1.0, p + 1) if p > 0 else np.array([0.5])
        k = np.arange(p + 1)
        basis = np.array([[comb(p, j) * x ** j * (1 - x) ** (p - j) for j in k] for x in t])
        inverse = np.linalg.inv(basis)
        grid = np.stack(np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
        return grid, np.kron(np.kron(inverse, inverse), inverse)

    @staticmethod
    def corner_rows(p):
        """Rows of the lattice at the box corners (where a Bernstein coefficient equals the value)."""
        n = p + 1
        return [i * n * n + j * n + k for i in (0, p) for j in (0, p) for k in (0, p)]

    @staticmethod
    def whole(n):
        """n copies of the whole domain."""
        return np.full((n, 3), -1.0), np.full((n, 3), 1.0)

    @staticmethod
    def points(cells, lattice_points):
        """Parameter points (n_cells, n_samples, 3) of the lattice in every cell."""
        lower, upper = cells
        return lower[:, None, :] + lattice_points[None, :, :] * (upper - lower)[:, None, :]

    @staticmethod
    def take(cells, index):
        return cells[0][index], cells[1][index]

    @staticmethod
    def children(cells):
        """The 8 halves of every box (child k: upper half of axis i if bit i of k), child-major."""
        lower, upper = cells
        mid = 0.5 * (lower + upper)
        lo, hi = [], []
        for corner in range(8):
            pick = np.array([(corner >> i) & 1 for i in range(3)], dtype=bool)
            lo.append(np.where(pick, mid, lower))
            hi.append(np.where(pick, upper, mid))
        return np.concatenate(lo), np.concatenate(hi)

    @staticmethod
    def child_coefficients(coefficients, p):
        """Bernstein coefficients ((8 n), (p+1)^3) on the 8 halves of n boxes, in :meth:`children`'s
        order, one axis at a time."""
        n = len(coefficients)
        c = coefficients.reshape(n, p + 1, p + 1, p + 1)
        lower, upper = _halves_1d(p)
        children = []
        for child in range(8):
            a, b, d = (upper if (child >> i) & 1 else lower for i in range(3))
            children.append(np.einsum("ai,bj,ck,nijk->nabc", a, b, d, c, optimize=True).reshape(n, -1))
        return np.concatenate(children)


HEXAHEDRON = ElementFamily(
    name="hex", code=0,
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
    corners=CORNERS, centre=np.zeros(3), outside_distance=outside_distance, box_meets=box_meets,
    face_shapes=(QUADRILATERAL,) * 6,
    cells=BoxCells(),
    # a unit cube of a structured mesh is one hexahedron (corner offsets in lattice units)
    cube_split=((CORNERS[None] + 1) // 2).astype(np.int64),
)

# the quadratic hexahedra: VTK order of the 27 lattice nodes (hex20 uses the first 20)
QUADRATIC_NODES = np.array([
    [-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
    [0, -1, -1], [1, 0, -1], [0, 1, -1], [-1, 0, -1],
    [0, -1, 1], [1, 0, 1], [0, 1, 1], [-1, 0, 1],
    [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
    [-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1],
    [0, 0, 0],
], dtype=np.float64)
#: lattice index (0, 1, 2) <-> coordinate (-1, 0, +1) of every node of QUADRATIC_NODES, per direction
QUADRATIC_LATTICE = (QUADRATIC_NODES + 1).astype(np.int64)
#: the node at lattice position (i, j, k) (3, 3, 3): the inverse of QUADRATIC_LATTICE
QUADRATIC_LATTICE_NODE = np.empty((3, 3, 3), dtype=np.int64)
QUADRATIC_LATTICE_NODE[QUADRATIC_LATTICE[:, 0], QUADRATIC_LATTICE[:, 1], QUADRATIC_LATTICE[:, 2]] = np.arange(27)


@njit
def lattice_values(lattice, v, N):
    """N_a = v[0, l0] v[1, l1] v[2, l2] for every node a with lattice index ``lattice[a]`` (n, 3), from the
    1D functions per direction ``v`` (3, p+1): the tensor products of hex27 and of the rational Bézier
    hexahedra (one compiled kernel for all of them)."""
    for a in range(lattice.shape[0]):
        N[a] = v[0, lattice[a, 0]] * v[1, lattice[a, 1]] * v[2, lattice[a, 2]]


@njit
def lattice_gradients(lattice, v, dv, dN):
    """∂N_a/∂ξ_i (n, 3) of the tensor products of :func:`lattice_values`, with the 1D derivatives ``dv``."""
    for a in range(lattice.shape[0]):
        l0, l1, l2 = lattice[a, 0], lattice[a, 1], lattice[a, 2]
        dN[a, 0] = dv[0, l0] * v[1, l1] * v[2, l2]
        dN[a, 1] = v[0, l0] * dv[1, l1] * v[2, l2]
        dN[a, 2] = v[0, l0] * v[1, l1] * dv[2, l2]


def quadratic_bernstein_1d():
    """Map values at (-1, 0, +1) of a 1D quadratic to its Bernstein control points."""
    return np.array([[1.0, 0.0, 0.0], [-0.5, 2.0, -0.5], [0.0, 0.0, 1.0]])


def triquadratic_bernstein_matrix():
    """(27, 27): Bernstein control points of a triquadratic map from its values at the lattice nodes
    (tensor product of the 1D conversion, nodes in QUADRATIC_NODES order)."""
    C = quadratic_bernstein_1d()
    L = QUADRATIC_LATTICE
    T = np.empty((27, 27))
    for a in range(27):
        for b in range(27):
            T[a, b] = C[L[a, 0], L[b, 0]] * C[L[a, 1], L[b, 1]] * C[L[a, 2], L[b, 2]]
    return T
