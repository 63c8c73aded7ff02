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

from ..._config import njit, njit_inline
from ...quadrature import hexahedron_rule
from .bezier_hex import rational_descriptor, tensor_bernstein, tensor_bernstein_gradients
from .hex_family import QUADRATIC_LATTICE, QUADRATIC_LATTICE_NODE, QUADRATIC_NODES, triquadratic_bernstein_matrix

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


# The Newton path of a NURBS mesh (map and Jacobian, every iteration) without the general path's
# costs: the registry's dispatch, four arrays allocated per Jacobian by the degree-p Bernstein
# kernels, and the separate passes of the rational quotient. The 1D values stay in tuples
# (registers), as in hex27; the products, the sums over the 27 nodes and the quotient are those of
# ``shape``/``deriv`` and dispatch.rational_shape / rational_deriv, in the same order: the same bits
# (the node sums are projection's, as for every type).
#
# The products are formed over the lattice (i, j, k) in loops of three, which the compiler unrolls
# into straight code (constant tuple indices, the node index a constant of NODE); read in node order
# a, the tuples' runtime indices LATTICE[a] would be branches per factor. The partial products
# u_i v_j (and du_i v_j, u_i dv_j) are shared by the three nodes of a lattice line: the same values,
# as a product is evaluated left to right. The sums over the nodes then run in node order, as before.
#: node index a of lattice position (i, j, k): NODE[LATTICE[a, 0], LATTICE[a, 1], LATTICE[a, 2]] = a
NODE = QUADRATIC_LATTICE_NODE


@njit_inline
def _bernstein2(x):
    """The quadratic Bernstein polynomials on [-1, 1] at ``x`` and their derivatives (two 3-tuples): the
    values of :func:`.bezier_hex.bernstein` with p = 2, the same operations (2 s t as s t + t s)."""
    t = 0.5 * (1.0 + x)
    s = 1.0 - t
    return (s * s, s * t + t * s, t * t), (-1.0 * s, 1.0 * (s - t), 1.0 * t)


@njit_inline
def _normalise(N):
    """R_a = N_a / W, W = Σ_a N_a (node order), over the 27 nodes of ``N``."""
    W = 0.0
    for a in range(27):
        W += N[a]
    inv = 1.0 / W
    for a in range(27):
        N[a] *= inv


@njit_inline
def rational_shape(X, xi, N):
    """R_a = w_a B_a / W at ``xi`` into ``N`` (27,), weights in ``X[:, 3]``."""
    u, _ = _bernstein2(xi[0])
    v, _ = _bernstein2(xi[1])
    w, _ = _bernstein2(xi[2])
    for i in range(3):
        for j in range(3):
            uv = u[i] * v[j]
            for k in range(3):
                a = NODE[i, j, k]
                N[a] = uv * w[k] * X[a, 3]
    _normalise(N)


@njit_inline
def rational_deriv(X, xi, N, dN):
    """∂R_a/∂ξ = (w_a ∂B_a - R_a ∂W) / W at ``xi`` into ``dN`` (27, 3), R_a into ``N``; weights in
    ``X[:, 3]``."""
    u, du = _bernstein2(xi[0])
    v, dv = _bernstein2(xi[1])
    w, dw = _bernstein2(xi[2])
    for i in range(3):
        for j in range(3):
            uv = u[i] * v[j]
            duv = du[i] * v[j]
            udv = u[i] * dv[j]
            for k in range(3):
                a = NODE[i, j, k]
                weight = X[a, 3]
                N[a] = uv * w[k] * weight
                dN[a, 0] = duv * w[k] * weight
                dN[a, 1] = udv * w[k] * weight
                dN[a, 2] = uv * dw[k] * weight
    W = W0 = W1 = W2 = 0.0
    for a in range(27):
        W += N[a]
        W0 += dN[a, 0]
        W1 += dN[a, 1]
        W2 += dN[a, 2]
    inv = 1.0 / W
    for a in range(27):
        n = N[a] * inv
        N[a] = n
        dN[a, 0] = (dN[a, 0] - n * W0) * inv
        dN[a, 1] = (dN[a, 1] - n * W1) * inv
        dN[a, 2] = (dN[a, 2] - n * W2) * inv
