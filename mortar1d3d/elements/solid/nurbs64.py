"""Rational tricubic Bézier hexahedron: one span of a cubic NURBS volume after Bézier extraction.

The 64 nodes are the span's Bézier control points at the lattice positions ξ = -1, -1/3, 1/3, 1 per
direction, each with a weight w_a > 0: the 8 corners in VTK order, then the other 56 lattice points
in C order of their lattice index (:func:`.bezier_hex.bezier_nodes`). The element's functions are
R_a = w_a B_a / W with B_a the tricubic Bernstein polynomials on [-1, 1]³; everything but the node
order and the two kernels below is shared with the other degrees in :mod:`.bezier_hex`.

Volume rule: 4 × 4 × 4 Gauss points (exact for the tricubic polynomial part of a stiffness
integrand on an affine span; no rule is exact for rational functions).
"""
from ..._config import njit
from ...quadrature import hexahedron_rule
from . import bezier_hex
from .bezier_hex import rational_descriptor, tensor_bernstein, tensor_bernstein_gradients

DEGREE = 3
#: reference nodes, lattice index (0 … 3) per direction of every node, and B_a at the reference nodes
#: (64, 64; row = node: maps Bernstein coefficients to nodal values)
REFERENCE_NODES, LATTICE, NODE_VALUES = bezier_hex.lattice_tables(DEGREE)


@njit
def shape(xi, N):
    """The 64 tricubic Bernstein polynomials B_a at ``xi`` (3,) into ``N`` (64,)."""
    tensor_bernstein(DEGREE, LATTICE, xi, N)


@njit
def deriv(xi, dN):
    """∂B_a/∂ξ_i at ``xi`` into ``dN`` (64, 3)."""
    tensor_bernstein_gradients(DEGREE, LATTICE, xi, dN)


DESCRIPTOR = rational_descriptor("nurbs64", 7, DEGREE, REFERENCE_NODES, hexahedron_rule(4))
