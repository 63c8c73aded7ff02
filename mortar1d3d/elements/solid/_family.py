"""Parameter-space geometry shared by all elements of one family (hex: [-1, 1]^3, tet: unit simplex).

Faces are affine in parameter space for both families, which lets the intersection kernels
treat every face the same way: ``ξ = origin + u a + v b`` with an outward normal ``n``.
"""
import numpy as np

from ..._config import njit

HEX, TET = 0, 1

# rows: origin, a, b, outward normal
HEX_FACES = np.array([
    [[-1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]],   # ξ = -1
    [[+1, 0, 0], [0, 1, 0], [0, 0, 1], [+1, 0, 0]],   # ξ = +1
    [[0, -1, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]],   # η = -1
    [[0, +1, 0], [1, 0, 0], [0, 0, 1], [0, +1, 0]],   # η = +1
    [[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, 0, -1]],   # ζ = -1
    [[0, 0, +1], [1, 0, 0], [0, 1, 0], [0, 0, +1]],   # ζ = +1
], dtype=np.float64)
HEX_FACE_NODES = ((0, 3, 7, 4), (1, 2, 6, 5), (0, 1, 5, 4), (3, 2, 6, 7), (0, 1, 2, 3), (4, 5, 6, 7))
HEX_CENTRE = np.zeros(3)

TET_FACES = np.array([
    [[0, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]],    # ξ1 = 0
    [[0, 0, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]],    # ξ2 = 0
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1]],    # ξ3 = 0
    [[1, 0, 0], [-1, 1, 0], [-1, 0, 1], [1, 1, 1]],   # ξ1 + ξ2 + ξ3 = 1
], dtype=np.float64)
TET_FACE_NODES = ((0, 2, 3), (0, 1, 3), (0, 1, 2), (1, 2, 3))
TET_CENTRE = np.full(3, 0.25)


@njit
def hex_outside_distance(xi):
    """Distance of ``xi`` outside [-1, 1]^3 in the max norm (<= 0 inside)."""
    return max(abs(xi[0]), abs(xi[1]), abs(xi[2])) - 1.0


@njit
def tet_outside_distance(xi):
    """Distance of ``xi`` outside the unit simplex (<= 0 inside), face-wise max."""
    return max(-xi[0], -xi[1], -xi[2], xi[0] + xi[1] + xi[2] - 1.0)


def quadratic_bernstein_1d():
    """Map values at (-1, 0, +1) of a 1D quadratic to its Bernstein control points."""
    return np.array([[1.0, 0.0, 0.0], [-0.5, 2.0, -0.5], [0.0, 0.0, 1.0]])
