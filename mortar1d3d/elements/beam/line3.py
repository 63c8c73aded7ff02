"""Three-node Lagrange line (meshio ``line3``) on η ∈ [-1, 1]: ends at -1, +1, then the middle at 0.

Coefficients per element: r1, r2, r_mid; 3 centreline DOFs per node. ``length`` is unused.
"""
from ..._config import njit, njit_inline
from ..descriptor import BeamElementType


@njit
def shape(eta, length, H):
    H[0] = 0.5 * eta * (eta - 1.0)
    H[1] = 0.5 * eta * (eta + 1.0)
    H[2] = 1.0 - eta * eta


@njit
def deriv(eta, length, dH):
    dH[0] = eta - 0.5
    dH[1] = eta + 0.5
    dH[2] = -2.0 * eta


@njit
def deriv2(eta, length, ddH):
    ddH[0] = 1.0
    ddH[1] = 1.0
    ddH[2] = -2.0


@njit_inline
def coefficients(positions, tangents, nodes, origin, Qe):
    """Coefficients (r1, r2, r_mid) of element ``nodes`` into ``Qe`` (4, 3), minus ``origin``; row 3 zero."""
    for i in range(3):
        Qe[0, i] = positions[nodes[0], i] - origin[i]
        Qe[1, i] = positions[nodes[1], i] - origin[i]
        Qe[2, i] = positions[nodes[2], i] - origin[i]
        Qe[3, i] = 0.0


@njit_inline
def control_points(Qe, length, ctrl):
    """Bézier control points r1, 2 r_mid - (r1 + r2)/2, r2 of coefficients ``Qe``; returns 3."""
    for i in range(3):
        ctrl[0, i] = Qe[0, i]
        ctrl[1, i] = 2.0 * Qe[2, i] - 0.5 * (Qe[0, i] + Qe[1, i])
        ctrl[2, i] = Qe[1, i]
    return 3


DESCRIPTOR = BeamElementType("line3", code=2, n_nodes=3, n_functions=3, dofs_per_node=3,
                             function_node=(0, 1, 2), function_offset=(0, 0, 0), degree=2)
