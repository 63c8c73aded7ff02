"""Rational triquadratic Bézier hexahedron: one span of a quadratic NURBS volume after Bézier extraction.

The 27 nodes are the span's Bézier control points, in the order and at the lattice positions of
``hexahedron27`` (corners, edge middles, face centres, centre; :mod:`.hex27`), each with a weight
w_a > 0. The element's functions are R_a = w_a B_a / W, W = Σ_b w_b B_b, with B_a the triquadratic
Bernstein polynomials on [-1, 1]³ (tensor products of ((1-ξ)/2)², (1-ξ²)/2, ((1+ξ)/2)²).

``shape`` and ``deriv`` below give the polynomial part B_a; the rational quotient takes the node
weights and is applied by :func:`mortar1d3d.elements.solid.dispatch.rational_shape` (the descriptor
says ``rational=True``). Since the weights are positive, the element and each of its faces lie in
the convex hull of their control points: the bounding matrix is the identity.
NURBS patches become meshes of these elements in :mod:`mortar1d3d.nurbs.mesh`.
"""
import numpy as np

from ..._config import njit
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import (HEXAHEDRON, QUADRATIC_LATTICE, QUADRATIC_NODES, lattice_gradients, lattice_values,
                         triquadratic_bernstein_matrix)

#: B_a at the reference nodes (27, 27): row = node; maps Bernstein coefficients to nodal values
NODE_VALUES = np.linalg.inv(triquadratic_bernstein_matrix())


@njit
def _bernstein2(x, v, dv):
    t = 0.5 * (1.0 + x)
    s = 1.0 - t
    v[0] = s * s
    v[1] = 2.0 * s * t
    v[2] = t * t
    dv[0] = -s
    dv[1] = s - t
    dv[2] = t


@njit
def shape(xi, N):
    """The 27 triquadratic Bernstein polynomials B_a at ``xi`` (3,) into ``N`` (27,)."""
    v = np.empty((3, 3))
    dv = np.empty((3, 3))
    for i in range(3):
        _bernstein2(xi[i], v[i], dv[i])
    lattice_values(v, N)


@njit
def deriv(xi, dN):
    """∂B_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    v = np.empty((3, 3))
    dv = np.empty((3, 3))
    for i in range(3):
        _bernstein2(xi[i], v[i], dv[i])
    lattice_gradients(v, dv, dN)


def bernstein_values(xi):
    """B_a (k, 27) and ∂B_a/∂ξ (k, 27, 3) at the points ``xi`` (k, 3), numpy (validity check, tests)."""
    xi = np.asarray(xi, dtype=np.float64)
    t = 0.5 * (1.0 + xi)
    s = 1.0 - t
    v = np.stack([s * s, 2 * s * t, t * t], axis=-1)                  # (k, 3 directions, 3)
    dv = np.stack([-s, s - t, t], axis=-1)
    L = QUADRATIC_LATTICE
    B = v[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * v[:, 2, L[:, 2]]
    dB = np.stack([dv[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * v[:, 2, L[:, 2]],
                   v[:, 0, L[:, 0]] * dv[:, 1, L[:, 1]] * v[:, 2, L[:, 2]],
                   v[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * dv[:, 2, L[:, 2]]], axis=-1)
    return B, dB


def homogeneous_determinants(X, weights, xi):
    """det [[W, ∇W], [X̃, ∇X̃]] = W⁴ det J (m, k) of m elements (control points X (m, 27, 3), weights
    (m, 27)) at the points ``xi`` (k, 3); X̃ = Σ w_a B_a X_a. Same sign as det J (W > 0)."""
    B, dB = bernstein_values(xi)
    wX = np.concatenate([weights[..., None], weights[..., None] * X], axis=-1)     # (m, 27, 4): W first
    value = np.einsum("ka,mac->mkc", B, wX)                                       # (m, k, 4)
    grad = np.einsum("kad,mac->mkcd", dB, wX)                                     # (m, k, 4, 3)
    H = np.concatenate([value[..., None], grad], axis=-1)                         # (m, k, 4, 4)
    return np.linalg.det(H)


DESCRIPTOR = SolidElementType(
    name="nurbs27", code=6, n_nodes=27, degree=2, family_type=HEXAHEDRON,
    reference_nodes=QUADRATIC_NODES, bounding_matrix=np.eye(27),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3)],
    quadrature=hexahedron_rule(3), rational=True,
)
