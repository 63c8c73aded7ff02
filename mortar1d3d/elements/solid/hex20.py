"""20-node serendipity hexahedron (meshio ``hexahedron20``, VTK_QUADRATIC_HEXAHEDRON).

Corners 0-7 as in ``hex8``; mid-edge nodes 8-19 on the edges
(0,1) (1,2) (2,3) (3,0) (4,5) (5,6) (6,7) (7,4) (0,4) (1,5) (2,6) (3,7).
"""
import numpy as np

from ..._config import njit
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import HEXAHEDRON, QUADRATIC_NODES, triquadratic_bernstein_matrix

REFERENCE_NODES = QUADRATIC_NODES[:20].copy()


@njit
def shape(xi, N):
    """Write the 20 shape function values at ``xi`` (3,) into ``N`` (20,)."""
    for a in range(20):
        p = REFERENCE_NODES[a]
        if a < 8:
            N[a] = 0.125 * ((1.0 + p[0] * xi[0]) * (1.0 + p[1] * xi[1]) * (1.0 + p[2] * xi[2])
                            * (p[0] * xi[0] + p[1] * xi[1] + p[2] * xi[2] - 2.0))
        else:
            f = 0.25
            for i in range(3):
                if p[i] == 0.0:
                    f *= 1.0 - xi[i] * xi[i]
                else:
                    f *= 1.0 + p[i] * xi[i]
            N[a] = f


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (20, 3)."""
    for a in range(20):
        p = REFERENCE_NODES[a]
        if a < 8:
            f0 = 1.0 + p[0] * xi[0]
            f1 = 1.0 + p[1] * xi[1]
            f2 = 1.0 + p[2] * xi[2]
            s = p[0] * xi[0] + p[1] * xi[1] + p[2] * xi[2] - 2.0
            dN[a, 0] = 0.125 * p[0] * f1 * f2 * (s + f0)
            dN[a, 1] = 0.125 * p[1] * f0 * f2 * (s + f1)
            dN[a, 2] = 0.125 * p[2] * f0 * f1 * (s + f2)
        else:
            g = np.empty(3)
            dg = np.empty(3)
            for i in range(3):
                if p[i] == 0.0:
                    g[i] = 1.0 - xi[i] * xi[i]
                    dg[i] = -2.0 * xi[i]
                else:
                    g[i] = 1.0 + p[i] * xi[i]
                    dg[i] = p[i]
            dN[a, 0] = 0.25 * dg[0] * g[1] * g[2]
            dN[a, 1] = 0.25 * g[0] * dg[1] * g[2]
            dN[a, 2] = 0.25 * g[0] * g[1] * dg[2]


def _bounding_matrix():
    # The serendipity space lies inside the triquadratic one: interpolate the hex20 map at the
    # 27 lattice nodes, then take the triquadratic Bernstein control points (a convex-hull bound).
    values = np.empty((27, 20))
    for a in range(27):
        shape.py_func(QUADRATIC_NODES[a], values[a])
    return triquadratic_bernstein_matrix() @ values


DESCRIPTOR = SolidElementType(
    name="hexahedron20", code=1, n_nodes=20, degree=2, family_type=HEXAHEDRON,
    reference_nodes=REFERENCE_NODES, bounding_matrix=_bounding_matrix(),
    # serendipity: exponents up to 2 with at most one of them equal to 2
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3) if (i, j, k).count(2) <= 1],
    quadrature=hexahedron_rule(3),
)
