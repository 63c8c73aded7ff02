"""Rational triquadratic Bézier hexahedron: one span of a quadratic NURBS volume after Bézier extraction.

The 27 nodes are the span's Bézier control points, in the order and at the lattice positions of
``hexahedron27`` (corners, edge middles, face centres, centre; :mod:`.hex27`), each with a weight
w_a > 0. The element's functions are R_a = w_a B_a / W, W = Σ_b w_b B_b, with B_a the triquadratic
Bernstein polynomials on [-1, 1]³ (tensor products of ((1-ξ)/2)², (1-ξ²)/2, ((1+ξ)/2)²).

What every rational Bézier hexahedron shares (the Bernstein kernels, the validity check's
determinants, the descriptor) is in :mod:`.bezier_hex`; ``shape`` and ``deriv``
below give the polynomial part B_a, the rational quotient is applied by
:func:`mortar1d3d.elements.solid.dispatch.rational_shape` (the descriptor says ``rational=True``).
NURBS patches become meshes of these elements in :mod:`mortar1d3d.nurbs.mesh`.
"""
import numpy as np

from ..._config import njit
from ...quadrature import hexahedron_rule
from .bezier_hex import rational_descriptor, tensor_bernstein, tensor_bernstein_gradients
from .hex_family import QUADRATIC_LATTICE, QUADRATIC_NODES, triquadratic_bernstein_matrix

DEGREE = 2
#: lattice index (0, 1, 2) per direction of every node
LATTICE = QUADRATIC_LATTICE
#: B_a at the reference nodes (27, 27): row = node; maps Bernstein coefficients to nodal values
NODE_VALUES = np.linalg.inv(triquadratic_bernstein_matrix())


@njit
def shape(xi, N):
    """The 27 triquadratic Bernstein polynomials B_a at ``xi`` (3,) into ``N`` (27,)."""
    tensor_bernstein(DEGREE, LATTICE, xi, N)


@njit
def deriv(xi, dN):
    """∂B_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    tensor_bernstein_gradients(DEGREE, LATTICE, xi, dN)


DESCRIPTOR = rational_descriptor("nurbs27", 6, DEGREE, QUADRATIC_NODES, hexahedron_rule(3))
