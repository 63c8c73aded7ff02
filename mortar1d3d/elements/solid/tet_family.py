"""The tetrahedral family: elements on the unit simplex ξ_i >= 0, Σξ_i <= 1 (tet4, tet10).

What every tetrahedron shares lives here: the four faces (affine in parameter space, as for every
family: ``ξ = origin + u a + v b`` with an outward normal), the inside test,
how a unit cube of a structured mesh is filled (the six tetrahedra of the Kuhn split), and the cells
of the validity check (sub-simplices from red refinement, on which det J is sampled afresh).
"""
from functools import lru_cache
from math import factorial

import numpy as np

from ..._config import njit
from ..descriptor import ElementFamily
from .face_shapes import TRIANGLE

#: the vertices of the unit simplex in VTK order
CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)


@njit
def outside_distance(xi):
    """Distance of ``xi`` outside the unit simplex (<= 0 inside), face-wise max."""
    return max(-xi[0], -xi[1], -xi[2], xi[0] + xi[1] + xi[2] - 1.0)


@njit
def box_meets(m0, m1, m2, r, tol):
    """Whether the box |ξ - m|∞ <= r meets the simplex grown by ``tol`` (its lowest corner on each
    axis above -tol, and the smallest coordinate sum over the box not above 1 + tol)."""
    if m0 + r < -tol or m1 + r < -tol or m2 + r < -tol:
        return False
    return max(m0 - r, -tol) + max(m1 - r, -tol) + max(m2 - r, -tol) <= 1.0 + tol


def kuhn_split():
    """(6, 4, 3) corner offsets of the Kuhn (Freudenthal) split of the unit cube, det J > 0.

    Tet π walks from (0,0,0) to (1,1,1) along the axes in the order of the permutation π; every
    cube uses the same split, so the face diagonals (all from the (0,0) to the (1,1) corner of
    the face) match between neighbours and the mesh is conforming. det[v1-v0, v2-v0, v3-v0] is
    the sign of π: odd permutations swap their last two vertices.
    """
    perms = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
    eye = np.eye(3, dtype=np.int64)
    steps = eye[perms]                                                          # (6, 3 steps, 3)
    offsets = np.concatenate([np.zeros((6, 1, 3), np.int64), np.cumsum(steps, axis=1)], axis=1)
    offsets[3:, [2, 3]] = offsets[3:, [3, 2]]                                   # the odd permutations
    return offsets


class SimplexCells:
    """Cells of the validity check on the unit simplex: sub-simplices given by their vertices (n, 4, 3).

    A polynomial of total degree p (P_p) has a Bernstein–Bézier form on every simplex; children come
    from red refinement (8 per cell) and are sampled afresh.
    """

    n_children = 8

    @staticmethod
    def jacobian_degree(monomials):
        """Total degree of det J (det J ∈ P_p): three columns of degree (max total degree - 1)."""
        return 3 * max(int(monomials.sum(axis=1).max()) - 1, 0)

    @staticmethod
    @lru_cache(maxsize=None)
    def lattice(p):
        """Barycentric lattice points ((p+1)(p+2)(p+3)/6, 4) of P_p and the matrix from values there
        to Bernstein coefficients."""
        if p == 0:
            return np.full((1, 4), 0.25), np.ones((1, 1))
        index = np.array([(i, j, k, p - i - j - k) for i in range(p + 1) for j in range(p + 1 - i)
                          for k in range(p + 1 - i - j)])
        lam = index / p
        basis = np.array([[factorial(p) / np.prod([factorial(int(a)) for a in alpha]) * np.prod(lam_row ** alpha)
                           for alpha in index] for lam_row in lam])
        return lam, np.linalg.inv(basis)

    @classmethod
    def corner_rows(cls, p):
        """Rows of the lattice at the cell's vertices (where a Bernstein coefficient equals the value)."""
        lam, _ = cls.lattice(p)
        return np.flatnonzero(lam.max(axis=1) == 1.0) if len(lam) > 1 else np.array([0])

    @staticmethod
    def whole(n):
        """n copies of the whole domain."""
        return np.broadcast_to(CORNERS, (n, 4, 3)).copy()

    @staticmethod
    def points(cells, lattice_points):
        """Parameter points (n_cells, n_samples, 3) of the barycentric lattice in every cell."""
        return np.einsum("sv,cvi->csi", lattice_points, cells)

    @staticmethod
    def take(cells, index):
        return cells[index]

    @staticmethod
    def children(cells):
        """The 8 children of every cell by red refinement, child-major."""
        v = cells
        m = {(i, j): 0.5 * (v[:, i] + v[:, j]) for i in range(4) for j in range(i + 1, 4)}
        children = [(v[:, 0], m[0, 1], m[0, 2], m[0, 3]), (m[0, 1], v[:, 1], m[1, 2], m[1, 3]),
                    (m[0, 2], m[1, 2], v[:, 2], m[2, 3]), (m[0, 3], m[1, 3], m[2, 3], v[:, 3]),
                    (m[0, 1], m[0, 2], m[0, 3], m[1, 3]), (m[0, 1], m[0, 2], m[1, 2], m[1, 3]),
                    (m[0, 2], m[0, 3], m[1, 3], m[2, 3]), (m[0, 2], m[1, 2], m[1, 3], m[2, 3])]
        return np.concatenate([np.stack(c, axis=1) for c in children])


TETRAHEDRON = ElementFamily(
    name="tet", code=1,
    faces=np.array([
        [[0, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]],    # ξ1 = 0
        [[0, 0, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]],    # ξ2 = 0
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1]],    # ξ3 = 0
        [[1, 0, 0], [-1, 1, 0], [-1, 0, 1], [1, 1, 1]],   # ξ1 + ξ2 + ξ3 = 1
    ], dtype=np.float64),
    face_nodes=((0, 2, 3), (0, 1, 3), (0, 1, 2), (1, 2, 3)),
    corners=CORNERS, centre=np.full(3, 0.25), outside_distance=outside_distance, box_meets=box_meets,
    face_shapes=(TRIANGLE,) * 4, cells=SimplexCells(), cube_split=kuhn_split(),
)
