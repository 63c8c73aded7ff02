"""27-node triquadratic hexahedron (meshio ``hexahedron27``, VTK_TRIQUADRATIC_HEXAHEDRON).

Nodes 0-19 as in ``hex20``; face centres 20-25 on the faces ξ=-1, ξ=+1, η=-1, η=+1,
ζ=-1, ζ=+1; node 26 at the centre. N_a is a tensor product of 1D quadratic Lagrange
polynomials through -1, 0, +1.
"""

from ..._config import njit, njit_inline
from ...quadrature import hexahedron_rule
from ..descriptor import SolidElementType
from .hex_family import (HEXAHEDRON, QUADRATIC_LATTICE, QUADRATIC_LATTICE_NODE as LATTICE_NODE, QUADRATIC_NODES,
                         triquadratic_bernstein_matrix)

REFERENCE_NODES = QUADRATIC_NODES


@njit_inline
def _line3(x):
    """The 1D quadratic Lagrange polynomials through -1, 0, +1 at ``x`` and their derivatives (two 3-tuples)."""
    return (0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)), (x - 0.5, -2.0 * x, x + 0.5)


# The tensor products below keep the 1D values in tuples (registers), not in arrays: an array here
# would be a heap allocation per call, and these two kernels run in every Newton step on a hex27.
# The products are those of hex_family.lattice_values / lattice_gradients, in the same order.
@njit
def shape(xi, N):
    """Write the 27 shape function values at ``xi`` (3,) into ``N`` (27,)."""
    u, _ = _line3(xi[0])
    v, _ = _line3(xi[1])
    w, _ = _line3(xi[2])
    for a in range(27):
        N[a] = u[QUADRATIC_LATTICE[a, 0]] * v[QUADRATIC_LATTICE[a, 1]] * w[QUADRATIC_LATTICE[a, 2]]


@njit
def deriv(xi, dN):
    """Write ∂N_a/∂ξ_i at ``xi`` into ``dN`` (27, 3)."""
    u, du = _line3(xi[0])
    v, dv = _line3(xi[1])
    w, dw = _line3(xi[2])
    for a in range(27):
        l0, l1, l2 = QUADRATIC_LATTICE[a, 0], QUADRATIC_LATTICE[a, 1], QUADRATIC_LATTICE[a, 2]
        dN[a, 0] = du[l0] * v[l1] * w[l2]
        dN[a, 1] = u[l0] * dv[l1] * w[l2]
        dN[a, 2] = u[l0] * v[l1] * dw[l2]


# The map and its Jacobian on the Newton path, as tensor contractions of the nodes with the 1D values:
# x(ξ) = Σ_i u_i Σ_j v_j Σ_k w_k X_ijk, first over k, then j, then i. That is 3 × 9 + 3 × 3 + 3
# multiply-adds per coordinate for the map instead of 27 products of three factors and a sum over 27
# nodes, and the three columns of J share the inner sums. No 27-entry array is written or read
# (the shape functions are never formed). The sums are associated differently from Σ_a N_a X_a,
# so the results differ from shape() and a node sum by round-off (tests/test_elements.py).
@njit_inline
def map_nodes(X, xi):
    """x(ξ) = Σ_a N_a(ξ) X_a for nodes ``X`` (27, ≥3) as (x0, x1, x2)."""
    u, _ = _line3(xi[0])
    v, _ = _line3(xi[1])
    w, _ = _line3(xi[2])
    x0 = x1 = x2 = 0.0
    for i in range(3):
        c0 = c1 = c2 = 0.0
        for j in range(3):
            a0 = a1 = a2 = 0.0
            for k in range(3):
                n = LATTICE_NODE[i, j, k]
                a0 += w[k] * X[n, 0]
                a1 += w[k] * X[n, 1]
                a2 += w[k] * X[n, 2]
            c0 += v[j] * a0
            c1 += v[j] * a1
            c2 += v[j] * a2
        x0 += u[i] * c0
        x1 += u[i] * c1
        x2 += u[i] * c2
    return x0, x1, x2


@njit_inline
def map_jacobian_nodes(X, xi):
    """x(ξ) and J[m, l] = ∂x_m/∂ξ_l at ``xi`` for nodes ``X`` (27, ≥3) as a 12-tuple (x0, x1, x2, then J row
    by row): the sums of :func:`map_nodes` are the C below, so x costs nine products more than J, and has
    the same bits as :func:`map_nodes`."""
    u, du = _line3(xi[0])
    v, dv = _line3(xi[1])
    w, dw = _line3(xi[2])
    x0 = x1 = x2 = 0.0
    j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
    for i in range(3):
        # per coordinate: C = Σ_j v_j A_j, D = Σ_j dv_j A_j, E = Σ_j v_j B_j with A_j = Σ_k w_k X_ijk,
        # B_j = Σ_k dw_k X_ijk
        c0 = c1 = c2 = d0 = d1 = d2 = e0 = e1 = e2 = 0.0
        for j in range(3):
            a0 = a1 = a2 = b0 = b1 = b2 = 0.0
            for k in range(3):
                n = LATTICE_NODE[i, j, k]
                y0, y1, y2 = X[n, 0], X[n, 1], X[n, 2]
                a0 += w[k] * y0
                a1 += w[k] * y1
                a2 += w[k] * y2
                b0 += dw[k] * y0
                b1 += dw[k] * y1
                b2 += dw[k] * y2
            c0 += v[j] * a0
            c1 += v[j] * a1
            c2 += v[j] * a2
            d0 += dv[j] * a0
            d1 += dv[j] * a1
            d2 += dv[j] * a2
            e0 += v[j] * b0
            e1 += v[j] * b1
            e2 += v[j] * b2
        x0 += u[i] * c0
        x1 += u[i] * c1
        x2 += u[i] * c2
        j00 += du[i] * c0
        j10 += du[i] * c1
        j20 += du[i] * c2
        j01 += u[i] * d0
        j11 += u[i] * d1
        j21 += u[i] * d2
        j02 += u[i] * e0
        j12 += u[i] * e1
        j22 += u[i] * e2
    return x0, x1, x2, j00, j01, j02, j10, j11, j12, j20, j21, j22


@njit_inline
def jacobian_nodes(X, xi):
    """J[m, l] = ∂x_m/∂ξ_l at ``xi`` for nodes ``X`` (27, ≥3) as a 9-tuple, row by row (the J of
    :func:`map_jacobian_nodes`; inlined, its unused x is dropped)."""
    _, _, _, j00, j01, j02, j10, j11, j12, j20, j21, j22 = map_jacobian_nodes(X, xi)
    return j00, j01, j02, j10, j11, j12, j20, j21, j22


DESCRIPTOR = SolidElementType(
    name="hexahedron27", code=2, n_nodes=27, degree=2, family_type=HEXAHEDRON,
    # Bernstein control points of a triquadratic map: tensor product of the 1D conversion
    reference_nodes=REFERENCE_NODES, bounding_matrix=triquadratic_bernstein_matrix(),
    monomials=[(i, j, k) for i in range(3) for j in range(3) for k in range(3)],   # triquadratic
    quadrature=hexahedron_rule(3),
)
