"""Two-node Lagrange line (meshio ``line``) on η ∈ [-1, 1]: nodes at -1, +1.

Coefficients per element: r1, r2; 3 centreline DOFs per node. ``length`` is unused (the
functions do not depend on it) and kept for one signature across centreline types.
"""
from ..._config import njit, njit_inline
from ..descriptor import BeamElementType


@njit
def shape(eta, length, H):
    H[0] = 0.5 * (1.0 - eta)
    H[1] = 0.5 * (1.0 + eta)


@njit
def deriv(eta, length, dH):
    dH[0] = -0.5
    dH[1] = 0.5


@njit
def deriv2(eta, length, ddH):
    ddH[0] = 0.0
    ddH[1] = 0.0


@njit_inline
def coefficients(positions, tangents, nodes, origin, Qe):
    """Coefficients (r1, r2) of element ``nodes`` into ``Qe`` (4, 3), minus ``origin``; rows 2, 3 zero."""
    for i in range(3):
        Qe[0, i] = positions[nodes[0], i] - origin[i]
        Qe[1, i] = positions[nodes[1], i] - origin[i]
        Qe[2, i] = 0.0
        Qe[3, i] = 0.0


@njit_inline
def control_points(Qe, length, ctrl):
    """Bézier control points of coefficients ``Qe``: the two nodes; returns 2."""
    for i in range(3):
        ctrl[0, i] = Qe[0, i]
        ctrl[1, i] = Qe[1, i]
    return 2


DESCRIPTOR = BeamElementType("line", code=1, n_nodes=2, n_functions=2, dofs_per_node=3,
                             function_node=(0, 1), function_offset=(0, 0), degree=1)
