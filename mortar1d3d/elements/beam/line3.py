"""Three-node Lagrange line (meshio ``line3``) on η ∈ [-1, 1]: ends at -1, +1, then the middle at 0.

Coefficients per element: r1, r2, r_mid; 3 centreline DOFs per node. ``length`` is unused.
"""
from ..._config import njit
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


DESCRIPTOR = BeamElementType("line3", code=2, n_nodes=3, n_functions=3, dofs_per_node=3,
                             function_node=(0, 1, 2), function_offset=(0, 0, 0), degree=2)
