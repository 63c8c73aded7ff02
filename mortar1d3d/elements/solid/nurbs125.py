"""Rational quartic Bézier hexahedron: one span of a degree-4 NURBS volume after Bézier extraction.

The 125 nodes are the span's Bézier control points at the lattice positions ξ = -1, -1/2, 0, 1/2, 1 per
direction, each with a weight w_a > 0: the 8 corners in VTK order, then the other 117 lattice points
in C order of their lattice index (:func:`.bezier_hex.bezier_nodes`). The element's functions are
R_a = w_a B_a / W with B_a the triquartic Bernstein polynomials on [-1, 1]³; everything but the node
order and the two kernels below is shared with the other degrees in :mod:`.bezier_hex`.

Volume rule: 5 × 5 × 5 Gauss points (exact for the triquartic polynomial part of a stiffness
integrand on an affine span; no rule is exact for rational functions).
"""
from ..._config import njit
from ...quadrature import hexahedron_rule
from . import bezier_hex
from .bezier_hex import rational_descriptor, tensor_bernstein, tensor_bernstein_gradients

DEGREE = 4
#: reference nodes, lattice index (0 … 4) per direction of every node, and B_a at the reference nodes
#: (125, 125; row = node: maps Bernstein coefficients to nodal values)
REFERENCE_NODES, LATTICE, NODE_VALUES = bezier_hex.lattice_tables(DEGREE)


@njit
def shape(xi, N):
    """The 125 triquartic Bernstein polynomials B_a at ``xi`` (3,) into ``N`` (125,)."""
    tensor_bernstein(DEGREE, LATTICE, xi, N)


@njit
def deriv(xi, dN):
    """∂B_a/∂ξ_i at ``xi`` into ``dN`` (125, 3)."""
    tensor_bernstein_gradients(DEGREE, LATTICE, xi, dN)


DESCRIPTOR = rational_descriptor("nurbs125", 8, DEGREE, REFERENCE_NODES, hexahedron_rule(5))
