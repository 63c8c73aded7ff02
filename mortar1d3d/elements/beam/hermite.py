"""Cubic Hermite centreline on η ∈ [-1, 1]: positions and unit tangents at the two end nodes.

``r(η) = H1 r1 + H2 t1 + H3 r2 + H4 t2`` with unit tangents t and the element length L
entering H2, H4, so that dr/dη = L/2 · t at the nodes:

    H1 = (2 - 3η + η³)/4        H2 = L/8 (1 - η - η² + η³)
    H3 = (2 + 3η - η³)/4        H4 = L/8 (-1 - η + η² + η³)

L is the arc length of the curve it defines (see :func:`mortar1d3d.mesh.hermite_lengths`).
Coefficients per element: r1, t1, r2, t2; 6 centreline DOFs per node ``[r, t]``.
"""
from ..._config import njit, njit_inline
from ..descriptor import BeamElementType


@njit
def shape(eta, length, H):
    e2 = eta * eta
    e3 = e2 * eta
    H[0] = 0.25 * (2.0 - 3.0 * eta + e3)
    H[1] = 0.125 * length * (1.0 - eta - e2 + e3)
    H[2] = 0.25 * (2.0 + 3.0 * eta - e3)
    H[3] = 0.125 * length * (-1.0 - eta + e2 + e3)


@njit
def deriv(eta, length, dH):
    e2 = eta * eta
    dH[0] = 0.75 * (e2 - 1.0)
    dH[1] = 0.125 * length * (-1.0 - 2.0 * eta + 3.0 * e2)
    dH[2] = 0.75 * (1.0 - e2)
    dH[3] = 0.125 * length * (-1.0 + 2.0 * eta + 3.0 * e2)


@njit
def deriv2(eta, length, ddH):
    ddH[0] = 1.5 * eta
    ddH[1] = 0.125 * length * (-2.0 + 6.0 * eta)
    ddH[2] = -1.5 * eta
    ddH[3] = 0.125 * length * (2.0 + 6.0 * eta)


@njit_inline
def coefficients(positions, tangents, nodes, origin, Qe):
    """Coefficients (r1, t1, r2, t2) of element ``nodes`` into ``Qe`` (4, 3), positions minus ``origin``."""
    n0, n1 = nodes[0], nodes[1]
    for i in range(3):
        Qe[0, i] = positions[n0, i] - origin[i]
        Qe[1, i] = tangents[n0, i]
        Qe[2, i] = positions[n1, i] - origin[i]
        Qe[3, i] = tangents[n1, i]


@njit_inline
def control_points(Qe, length, ctrl):
    """Bézier control points r1, r1 + L/3 t1, r2 - L/3 t2, r2 of coefficients ``Qe`` into ``ctrl``; returns 4."""
    for i in range(3):
        ctrl[0, i] = Qe[0, i]
        ctrl[1, i] = Qe[0, i] + length / 3.0 * Qe[1, i]
        ctrl[2, i] = Qe[2, i] - length / 3.0 * Qe[3, i]
        ctrl[3, i] = Qe[2, i]
    return 4


DESCRIPTOR = BeamElementType("hermite", code=0, n_nodes=2, n_functions=4, dofs_per_node=6,
                             function_node=(0, 0, 1, 1), function_offset=(0, 3, 0, 3), degree=3)
