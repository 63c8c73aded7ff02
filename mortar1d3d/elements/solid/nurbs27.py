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
# kernels, the separate passes of the rational quotient, and the 27 R_a and 81 ∂R_a written out and
# read back for the sums over the nodes. The map is evaluated in homogeneous coordinates as a tensor
# contraction (as hex27.map_nodes): P = Σ_a B_a w_a (X_a, 1) = Σ_i u_i Σ_j v_j Σ_k w_k (w X, w)_ijk,
# first over k, then j, then i, and x = (P_0, P_1, P_2) / P_3; the Jacobian contracts the same way
# with the derivatives of the 1D values (its three columns share the sums over k and j) and applies
# the quotient rule once to the 4 × 3 derivatives of P: J_ml = (∂_l P_m - x_m ∂_l P_3) / P_3. That is
# 4 × (9 + 3 + 1) multiply-adds per 3-tuple of 1D values instead of 27 products of four factors,
# 27 × 4 sums, 27 quotients and 27 × 12 multiply-adds over R_a and ∂R_a. The 1D values stay in tuples
# (registers); the loops of three are unrolled by the compiler (the node index a constant of NODE).
# The sums are associated differently from Σ_a R_a X_a with R_a = w_a B_a / W: the results differ
# from the general rational path by round-off (tests/test_nurbs_engine.py).
#: node index a of lattice position (i, j, k): NODE[LATTICE[a, 0], LATTICE[a, 1], LATTICE[a, 2]] = a
NODE = QUADRATIC_LATTICE_NODE


@njit_inline
def _bernstein2(x):
    """The quadratic Bernstein polynomials on [-1, 1] at ``x`` and their derivatives (two 3-tuples): the
    values of :func:`.bezier_hex.bernstein` with p = 2."""
    t = 0.5 * (1.0 + x)
    s = 1.0 - t
    return (s * s, 2.0 * s * t, t * t), (-s, s - t, t)


@njit_inline
def map_nodes(X, xi):
    """x(ξ) = Σ_a R_a(ξ) X_a = Σ_a w_a B_a X_a / Σ_a w_a B_a for nodes ``X`` (27, 4; weights in column
    3) as (x0, x1, x2)."""
    u, _ = _bernstein2(xi[0])
    v, _ = _bernstein2(xi[1])
    w, _ = _bernstein2(xi[2])
    x0 = x1 = x2 = x3 = 0.0
    for i in range(3):
        c0 = c1 = c2 = c3 = 0.0
        for j in range(3):
            a0 = a1 = a2 = a3 = 0.0
            for k in range(3):
                n = NODE[i, j, k]
                f = w[k] * X[n, 3]
                a0 += f * X[n, 0]
                a1 += f * X[n, 1]
                a2 += f * X[n, 2]
                a3 += f
            c0 += v[j] * a0
            c1 += v[j] * a1
            c2 += v[j] * a2
            c3 += v[j] * a3
        x0 += u[i] * c0
        x1 += u[i] * c1
        x2 += u[i] * c2
        x3 += u[i] * c3
    inv = 1.0 / x3
    return x0 * inv, x1 * inv, x2 * inv


@njit_inline
def jacobian_nodes(X, xi):
    """J[m, l] = ∂x_m/∂ξ_l at ``xi`` for nodes ``X`` (27, 4; weights in column 3) as a 9-tuple, row by row."""
    u, du = _bernstein2(xi[0])
    v, dv = _bernstein2(xi[1])
    w, dw = _bernstein2(xi[2])
    # P_m (m = 0..3; 3 the weight) and its derivatives along ξ_0, ξ_1, ξ_2: p, q, r, s
    p0 = p1 = p2 = p3 = q0 = q1 = q2 = q3 = r0 = r1 = r2 = r3 = s0 = s1 = s2 = s3 = 0.0
    for i in range(3):
        # C = Σ_j v_j A_j, D = Σ_j dv_j A_j, E = Σ_j v_j B_j with A_j = Σ_k w_k (wX)_ijk, B_j = Σ_k dw_k (wX)_ijk
        c0 = c1 = c2 = c3 = d0 = d1 = d2 = d3 = e0 = e1 = e2 = e3 = 0.0
        for j in range(3):
            a0 = a1 = a2 = a3 = b0 = b1 = b2 = b3 = 0.0
            for k in range(3):
                n = NODE[i, j, k]
                y3 = X[n, 3]
                y0, y1, y2 = y3 * X[n, 0], y3 * X[n, 1], y3 * X[n, 2]
                a0 += w[k] * y0
                a1 += w[k] * y1
                a2 += w[k] * y2
                a3 += w[k] * y3
                b0 += dw[k] * y0
                b1 += dw[k] * y1
                b2 += dw[k] * y2
                b3 += dw[k] * y3
            c0 += v[j] * a0
            c1 += v[j] * a1
            c2 += v[j] * a2
            c3 += v[j] * a3
            d0 += dv[j] * a0
            d1 += dv[j] * a1
            d2 += dv[j] * a2
            d3 += dv[j] * a3
            e0 += v[j] * b0
            e1 += v[j] * b1
            e2 += v[j] * b2
            e3 += v[j] * b3
        p0 += u[i] * c0
        p1 += u[i] * c1
        p2 += u[i] * c2
        p3 += u[i] * c3
        q0 += du[i] * c0
        q1 += du[i] * c1
        q2 += du[i] * c2
        q3 += du[i] * c3
        r0 += u[i] * d0
        r1 += u[i] * d1
        r2 += u[i] * d2
        r3 += u[i] * d3
        s0 += u[i] * e0
        s1 += u[i] * e1
        s2 += u[i] * e2
        s3 += u[i] * e3
    inv = 1.0 / p3
    x0, x1, x2 = p0 * inv, p1 * inv, p2 * inv
    return ((q0 - x0 * q3) * inv, (r0 - x0 * r3) * inv, (s0 - x0 * s3) * inv,
            (q1 - x1 * q3) * inv, (r1 - x1 * r3) * inv, (s1 - x1 * s3) * inv,
            (q2 - x2 * q3) * inv, (r2 - x2 * r3) * inv, (s2 - x2 * s3) * inv)
