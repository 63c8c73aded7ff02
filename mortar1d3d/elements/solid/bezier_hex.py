"""Rational Bernstein (Bézier) hexahedra of any degree p: what the element types ``nurbs27`` (p = 2) and
``nurbs64`` (p = 3) and ``nurbs125`` (p = 4) share, so that a type of another degree is its module (a node order, two thin
kernels and :func:`rational_descriptor`) plus its registry line.

A degree-p element has (p+1)³ nodes, the Bézier control points of one span of a NURBS volume after
Bézier extraction, at the lattice positions ξ = -1 + 2 l / p (l = 0 … p per direction), each with a
weight w_a > 0. Its functions are R_a = w_a B_a / W, W = Σ_b w_b B_b, with B_a the tensor products
of the 1D Bernstein polynomials C(p, l) t^l (1 - t)^(p-l), t = (1 + ξ)/2. The element kernels give B_a
(and ∂B_a/∂ξ) with :func:`tensor_bernstein` (the 1D :func:`bernstein` and the hexahedra's tensor
products, :func:`.hex_family.lattice_values`); the rational quotient takes the node weights and is applied by
:func:`mortar1d3d.elements.solid.dispatch.rational_shape`. Since the weights are positive, an element
and each of its faces lie in the convex hull of their control points: the bounding matrix is the
identity.

Node order: the 8 corners first, in VTK order (what the hexahedral family's ``face_nodes`` and the
affine check address), then the other lattice points. ``nurbs27`` keeps the ``hexahedron27`` order
of its lattice; higher degrees list the rest in C order of the lattice index (:func:`bezier_nodes`).
"""
from math import comb

import numpy as np

from ..._config import njit
from ..descriptor import SolidElementType
from .hex_family import CORNERS, HEXAHEDRON, lattice_gradients, lattice_values


def bezier_nodes(p):
    """Reference nodes ((p+1)³, 3) of a degree-p Bézier hexahedron: the corners in VTK order, then the
    other lattice points ξ = -1 + 2 l / p in C order of (l0, l1, l2)."""
    s = np.linspace(-1.0, 1.0, p + 1)
    grid = np.stack(np.meshgrid(s, s, s, indexing="ij"), axis=-1).reshape(-1, 3)
    on_corner = (np.abs(grid) == 1.0).all(axis=1)
    return np.concatenate([CORNERS, grid[~on_corner]])


def lattice_indices(nodes, p):
    """Lattice index l (0 … p) per direction (n, 3) int64 of reference nodes on the degree-p lattice."""
    return np.rint((np.asarray(nodes) + 1.0) * 0.5 * p).astype(np.int64)


def tensor_order(nodes, p):
    """Per node, its position (l0 (p+1) + l1) (p+1) + l2 in the C-order tensor numbering of the Bernstein
    functions (the numbering of :meth:`mortar1d3d.nurbs.NurbsPatch.bezier_elements`)."""
    L = lattice_indices(nodes, p)
    return (L[:, 0] * (p + 1) + L[:, 1]) * (p + 1) + L[:, 2]


@njit
def bernstein(p, x, v, dv):
    """Bernstein polynomials of degree ``p`` on [-1, 1] at ``x`` into ``v[:p+1]``, d/dx into ``dv[:p+1]``.

    The triangle B^q_a = (1 - t) B^{q-1}_a + t B^{q-1}_{a-1}, t = (1 + x)/2, and
    dB^p_a/dt = p (B^{p-1}_{a-1} - B^{p-1}_a) (dt/dx = 1/2).
    """
    t = 0.5 * (1.0 + x)
    s = 1.0 - t
    v[0] = 1.0
    for q in range(1, p + 1):
        if q == p:
            # the degree p-1 values give the derivatives before the last step overwrites them
            dv[0] = -0.5 * p * v[0]
            for a in range(1, p):
                dv[a] = 0.5 * p * (v[a - 1] - v[a])
            dv[p] = 0.5 * p * v[p - 1]
        v[q] = t * v[q - 1]
        for a in range(q - 1, 0, -1):
            v[a] = s * v[a] + t * v[a - 1]
        v[0] = s * v[0]
    if p == 0:
        dv[0] = 0.0


@njit
def tensor_bernstein(p, lattice, xi, N):
    """The tensor-product Bernstein polynomials B_a of degree ``p`` at ``xi`` (3,) into ``N``, node a at the
    lattice index ``lattice[a]``: the ``shape`` of every rational Bézier hexahedron."""
    v = np.empty((3, p + 1))
    dv = np.empty((3, p + 1))
    for i in range(3):
        bernstein(p, xi[i], v[i], dv[i])
    lattice_values(lattice, v, N)


@njit
def tensor_bernstein_gradients(p, lattice, xi, dN):
    """∂B_a/∂ξ_i of :func:`tensor_bernstein` into ``dN`` (n, 3): the ``deriv`` of every rational Bézier
    hexahedron."""
    v = np.empty((3, p + 1))
    dv = np.empty((3, p + 1))
    for i in range(3):
        bernstein(p, xi[i], v[i], dv[i])
    lattice_gradients(lattice, v, dv, dN)


def bernstein_values(p, lattice, xi):
    """B_a (k, n) and ∂B_a/∂ξ (k, n, 3) of the degree-p element with node lattice indices ``lattice``
    (n, 3) at the points ``xi`` (k, 3); numpy (validity check, output, tests)."""
    xi = np.asarray(xi, dtype=np.float64)
    t = 0.5 * (1.0 + xi)
    s = 1.0 - t
    l = np.arange(p + 1)
    binomial = np.array([comb(p, i) for i in l], dtype=np.float64)
    v = binomial * t[..., None] ** l * s[..., None] ** (p - l)              # (k, 3 directions, p+1)
    below = _degree_below(p, t, s)
    lower = np.concatenate([np.zeros(xi.shape + (1,)), below], axis=-1)
    upper = np.concatenate([below, np.zeros(xi.shape + (1,))], axis=-1)
    dv = 0.5 * p * (lower - upper)
    L = lattice
    B = v[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * v[:, 2, L[:, 2]]
    dB = np.stack([dv[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * v[:, 2, L[:, 2]],
                   v[:, 0, L[:, 0]] * dv[:, 1, L[:, 1]] * v[:, 2, L[:, 2]],
                   v[:, 0, L[:, 0]] * v[:, 1, L[:, 1]] * dv[:, 2, L[:, 2]]], axis=-1)
    return B, dB


def _degree_below(p, t, s):
    """The p Bernstein polynomials of degree p - 1 at t (s = 1 - t): (..., p)."""
    l = np.arange(p)
    binomial = np.array([comb(p - 1, i) for i in l], dtype=np.float64)
    return binomial * t[..., None] ** l * s[..., None] ** (p - 1 - l)


def homogeneous_determinants(p, lattice, X, weights, xi):
    """det [[W, ∇W], [X̃, ∇X̃]] = W⁴ det J (m, k) of m degree-p elements (control points X (m, n, 3),
    weights (m, n)) at the points ``xi`` (k, 3); X̃ = Σ w_a B_a X_a. Same sign as det J (W > 0)."""
    B, dB = bernstein_values(p, lattice, xi)
    wX = np.concatenate([weights[..., None], weights[..., None] * X], axis=-1)     # (m, n, 4): W first
    value = np.einsum("ka,mac->mkc", B, wX)                                       # (m, k, 4)
    grad = np.einsum("kad,mac->mkcd", dB, wX)                                     # (m, k, 4, 3)
    H = np.concatenate([value[..., None], grad], axis=-1)                         # (m, k, 4, 4)
    return np.linalg.det(H)


def lattice_tables(p):
    """The tables of a degree-p type in the node order of :func:`bezier_nodes`: reference nodes
    ((p+1)³, 3), lattice index (0 … p) per direction of every node, and B_a at the reference nodes
    (:func:`node_values`)."""
    nodes = bezier_nodes(p)
    return nodes, lattice_indices(nodes, p), node_values(p, nodes)


def node_values(p, nodes):
    """B_a at the reference nodes ((n, n): row = node), the map from Bernstein coefficients to nodal values."""
    return bernstein_values(p, lattice_indices(nodes, p), nodes)[0]


def rational_descriptor(name, code, p, nodes, quadrature):
    """The :class:`~mortar1d3d.elements.descriptor.SolidElementType` of the degree-p Bézier hexahedron
    with reference ``nodes`` and the volume rule ``quadrature``."""
    n = (p + 1) ** 3
    return SolidElementType(
        name=name, code=code, n_nodes=n, degree=p, family_type=HEXAHEDRON,
        reference_nodes=nodes, bounding_matrix=np.eye(n),
        monomials=[(i, j, k) for i in range(p + 1) for j in range(p + 1) for k in range(p + 1)],
        quadrature=quadrature, rational=True,
    )
