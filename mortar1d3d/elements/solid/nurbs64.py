"""Rational tricubic Bézier hexahedron: one span of a cubic NURBS volume after Bézier extraction.

The 64 nodes are the span's Bézier control points at the lattice positions ξ = -1, -1/3, 1/3, 1 per
direction, each with a weight w_a > 0: the 8 corners in VTK order, then the other 56 lattice points
in C order of their lattice index (:func:`.bezier_hex.bezier_nodes`). The element's functions are
R_a = w_a B_a / W with B_a the tricubic Bernstein polynomials on [-1, 1]³; everything but the node
order and the two kernels below is shared with the other degrees in :mod:`.bezier_hex`.

Volume rule: 4 × 4 × 4 Gauss points (exact for the tricubic polynomial part of a stiffness
integrand on an affine span; no rule is exact for rational functions).
"""
import numpy as np

from ..._config import njit
from ...quadrature import hexahedron_rule
from . import bezier_hex
from .bezier_hex import bernstein, rational_descriptor
from .hex_family import lattice_gradients, lattice_values

DEGREE = 3
REFERENCE_NODES = bezier_hex.bezier_nodes(DEGREE)
#: lattice index (0 … 3) per direction of every node
LATTICE = bezier_hex.lattice_indices(REFERENCE_NODES, DEGREE)
#: B_a at the reference nodes (64, 64): row = node; maps Bernstein coefficients to nodal values
NODE_VALUES = bezier_hex.node_values(DEGREE, REFERENCE_NODES)


@njit
def shape(xi, N):
    """The 64 tricubic Bernstein polynomials B_a at ``xi`` (3,) into ``N`` (64,)."""
    v = np.empty((3, 4))
    dv = np.empty((3, 4))
    for i in range(3):
        bernstein(3, xi[i], v[i], dv[i])
    lattice_values(LATTICE, v, N)


@njit
def deriv(xi, dN):
    """∂B_a/∂ξ_i at ``xi`` into ``dN`` (64, 3)."""
    v = np.empty((3, 4))
    dv = np.empty((3, 4))
    for i in range(3):
        bernstein(3, xi[i], v[i], dv[i])
    lattice_gradients(LATTICE, v, dv, dN)


def bernstein_values(xi):
    """B_a (k, 64) and ∂B_a/∂ξ (k, 64, 3) at the points ``xi`` (k, 3), numpy (validity check, tests)."""
    return bezier_hex.bernstein_values(DEGREE, LATTICE, xi)


def homogeneous_determinants(X, weights, xi):
    """W⁴ det J (m, k) of m elements (control points X (m, 64, 3), weights (m, 64)) at ``xi`` (k, 3)."""
    return bezier_hex.homogeneous_determinants(DEGREE, LATTICE, X, weights, xi)


DESCRIPTOR = rational_descriptor("nurbs64", 7, DEGREE, REFERENCE_NODES, hexahedron_rule(4))
