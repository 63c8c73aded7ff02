"""The wedge (prism) family: elements on the prism ξ1, ξ2 >= 0, ξ1 + ξ2 <= 1, ζ ∈ [-1, 1] (wedge6).

What every wedge shares lives here: the five faces (two triangles, ζ = ∓1, and three
quadrilaterals, all affine in parameter space like every family's: ``ξ = origin + u a + v b``
with an outward normal), the inside test, how a unit cube of a structured mesh is filled (two
wedges over the triangles of the cube's bottom square), and the cells of the validity check
(sub-prisms: a sub-triangle of the red refinement times a sub-interval, on which det J, a
polynomial of total degree p in (ξ1, ξ2) and of degree q in ζ, has a product Bernstein form).
"""
from functools import lru_cache
from math import comb, factorial

import numpy as np

from ..._config import njit
from ..descriptor import ElementFamily
from .face_shapes import QUADRILATERAL, TRIANGLE

#: the corners of the prism in VTK order: the bottom triangle (ζ = -1), then the top one (ζ = +1)
CORNERS = np.array([[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=np.float64)


@njit
def outside_distance(xi):
    """Distance of ``xi`` outside the prism (<= 0 inside), face-wise max."""
    return max(-xi[0], -xi[1], xi[0] + xi[1] - 1.0, abs(xi[2]) - 1.0)


@njit
def box_meets(m0, m1, m2, r, tol):
    """Whether the box |ξ - m|∞ <= r meets the prism grown by ``tol``: the triangle's test (lowest
    corner above -tol on each axis, smallest coordinate sum not above 1 + tol) and the interval's."""
    if m0 + r < -tol or m1 + r < -tol or abs(m2) - r > 1.0 + tol:
        return False
    return max(m0 - r, -tol) + max(m1 - r, -tol) <= 1.0 + tol


def cube_split():
    """(2, 6, 3) corner offsets of the two wedges filling the unit cube, det J > 0.

    The bottom square is cut along its diagonal from (0, 0) to (1, 1), the same in every cube, so
    neighbours conform (the quadrilateral faces on the cube's sides are whole); each triangle is
    counter-clockwise seen from +z and extruded along z.
    """
    bottom = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], dtype=np.int64)
    out = np.zeros((2, 6, 3), dtype=np.int64)
    out[:, :3, :2] = out[:, 3:, :2] = bottom
    out[:, 3:, 2] = 1
    return out


def _triangle_index(p):
    return [(i, j, p - i - j) for i in range(p + 1) for j in range(p + 1 - i)]


class PrismCells:
    """Cells of the validity check on the prism: sub-prisms ``(triangle (n, 3, 2), lower (n,), upper (n,))``.

    det J of a wedge lies in P_p(ξ1, ξ2) ⊗ P_q(ζ); on a sub-prism (a triangle times an interval) it
    has the product Bernstein form (triangle Bernstein basis of degree p times the 1D one of degree
    q). Children: the 4 sub-triangles of the red refinement times the 2 halves of the interval,
    sampled afresh.
    """

    n_children = 8

    @staticmethod
    def jacobian_degree(monomials):
        """(p, q): total degree of det J in (ξ1, ξ2) and degree in ζ.

        Column j of J, ∂x/∂ξ_j, has the degrees max(α1 + α2 - [j < 2]) and max(α3 - [j == 2]) over
        the monomials that ξ_j does not kill; det J takes one factor from each column.
        """
        exps = monomials
        p = q = 0
        for j in range(3):
            alive = exps[exps[:, j] > 0]
            if len(alive):
                p += int((alive[:, 0] + alive[:, 1]).max()) - (j < 2)
                q += int(alive[:, 2].max()) - (j == 2)
        return p, q

    @staticmethod
    @lru_cache(maxsize=None)
    def lattice(degrees):
        """Lattice points ((p+1)(p+2)/2 (q+1), 4) ``(λ0, λ1, λ2, t)`` (barycentric on the triangle,
        t ∈ [0, 1] on the interval; t fastest) and the matrix from values there to Bernstein
        coefficients (Kronecker product of the triangle's and the interval's)."""
        p, q = degrees
        if p == 0:
            lam, tri = np.full((1, 3), 1.0 / 3.0), np.ones((1, 1))
        else:
            index = np.array(_triangle_index(p))
            lam = index / p
            tri = np.array([[factorial(p) / np.prod([factorial(int(a)) for a in alpha]) * np.prod(row ** alpha)
                             for alpha in index] for row in lam])
        t = np.linspace(0.0, 1.0, q + 1) if q > 0 else np.array([0.5])
        line = np.array([[comb(q, j) * x ** j * (1 - x) ** (q - j) for j in range(q + 1)] for x in t])
        points = np.column_stack([np.repeat(lam, len(t), axis=0), np.tile(t, len(lam))])
        return points, np.kron(np.linalg.inv(tri), np.linalg.inv(line))

    @classmethod
    def corner_rows(cls, degrees):
        """Rows of the lattice at the cell's six vertices (where a Bernstein coefficient equals the value)."""
        points, _ = cls.lattice(degrees)
        vertex = points[:, :3].max(axis=1) == 1.0 if degrees[0] > 0 else np.ones(len(points), bool)
        end = (points[:, 3] == 0.0) | (points[:, 3] == 1.0) if degrees[1] > 0 else np.ones(len(points), bool)
        return np.flatnonzero(vertex & end)

    @staticmethod
    def whole(n):
        """n copies of the whole domain."""
        return (np.broadcast_to(CORNERS[:3, :2], (n, 3, 2)).copy(), np.full(n, -1.0), np.full(n, 1.0))

    @staticmethod
    def points(cells, lattice_points):
        """Parameter points (n_cells, n_samples, 3) of the lattice in every cell."""
        triangle, lower, upper = cells
        xy = np.einsum("sv,cvi->csi", lattice_points[:, :3], triangle)
        z = lower[:, None] + lattice_points[None, :, 3] * (upper - lower)[:, None]
        return np.concatenate([xy, z[..., None]], axis=2)

    @staticmethod
    def take(cells, index):
        """The cells at ``index`` (an integer array or a mask)."""
        return tuple(c[index] for c in cells)

    @staticmethod
    def children(cells):
        """The 8 children of every cell (4 sub-triangles × 2 half-intervals), child-major."""
        v, lower, upper = cells
        m = {(i, j): 0.5 * (v[:, i] + v[:, j]) for i in range(3) for j in range(i + 1, 3)}
        triangles = [(v[:, 0], m[0, 1], m[0, 2]), (m[0, 1], v[:, 1], m[1, 2]),
                     (m[0, 2], m[1, 2], v[:, 2]), (m[1, 2], m[0, 2], m[0, 1])]
        mid = 0.5 * (lower + upper)
        out_v, out_lo, out_hi = [], [], []
        for lo, hi in ((lower, mid), (mid, upper)):
            for t in triangles:
                out_v.append(np.stack(t, axis=1))
                out_lo.append(lo)
                out_hi.append(hi)
        return np.concatenate(out_v), np.concatenate(out_lo), np.concatenate(out_hi)


WEDGE = ElementFamily(
    name="wedge", code=2,
    # rows: origin, a, b, outward normal (the triangles on u, v >= 0, u + v <= 1, the quadrilaterals
    # on [-1, 1]², centred on the face)
    faces=np.array([
        [[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, 0, -1]],               # ζ = -1
        [[0, 0, +1], [1, 0, 0], [0, 1, 0], [0, 0, +1]],               # ζ = +1
        [[0.5, 0, 0], [0.5, 0, 0], [0, 0, 1], [0, -1, 0]],            # ξ2 = 0
        [[0.5, 0.5, 0], [-0.5, 0.5, 0], [0, 0, 1], [1, 1, 0]],        # ξ1 + ξ2 = 1
        [[0, 0.5, 0], [0, 0.5, 0], [0, 0, 1], [-1, 0, 0]],            # ξ1 = 0
    ], dtype=np.float64),
    face_nodes=((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (0, 2, 5, 3)),
    face_shapes=(TRIANGLE, TRIANGLE, QUADRILATERAL, QUADRILATERAL, QUADRILATERAL),
    corners=CORNERS, centre=np.array([1.0 / 3.0, 1.0 / 3.0, 0.0]), outside_distance=outside_distance,
    box_meets=box_meets, cells=PrismCells(), cube_split=cube_split(),
)
