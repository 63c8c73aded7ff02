"""Face tables for surface loads on rational (NURBS Bézier) elements, one table per face.

The surface-load kernels of :mod:`mortar1d3d.physics.surface` read the face functions and their
tangential derivatives from tables indexed by (element type code, local face, point, face node):
the functions of a polynomial element are the same on every element of a type, so one table per
(type, face) suffices. A rational element's functions R_a = w_a B_a / W depend on its node weights,
so they differ from element to element. Here every face of a face set gets its own table (it plays
the role of a "type" of its own, with one face), and the same kernels run on it unchanged:

    R_a = w_a B_a / W,    ∂R_a/∂ξ = (w_a ∂B_a/∂ξ − R_a ∂W/∂ξ) / W,    W = Σ_b w_b B_b,

restricted to the face nodes (the other nodes' B_a vanish on the face, so R on a face depends only
on the face's own weights: neighbouring elements agree there). Faces of polynomial elements in the
same set keep their type's table.

Quadrature: R is a quotient, so no Gauss rule integrates the loads exactly. The rule follows the
face's degree p (:func:`rational_face_points`): with unit weights the pressure integrand
``N_a (x_,u × x_,v)`` is a polynomial of degree 3p − 1 per direction (N_a: p; a tangent component:
p − 1 in its own direction and p in the other, so the cross product: 2p − 1), which ⌈3p/2⌉ Gauss
points integrate exactly; one point more per direction for the rational weight W in the
functions and the geometry. That is 4 × 4 points on quadratic faces, 6 × 6 on cubic and 7 × 7 on quartic ones; the
error falls quickly with ``n`` (tests/test_nurbs_pressure.py).
"""
import numpy as np

from ..elements.solid.dispatch import BY_CODE, RATIONAL, deriv, shape
from ..quadrature import gauss_legendre


def rational_face_points(degree):
    """Gauss points per direction on a rational face of ``degree`` p: ⌈3p/2⌉ (exact for the degree-(3p − 1)
    integrand with unit weights, module docstring) plus one for the rational weight."""
    return (3 * int(degree) + 1) // 2 + 1


class FaceInstanceTables:
    """The tables of :class:`~mortar1d3d.physics.surface._FaceTables` with one entry per face of a
    face set: index them with code ``i`` (the face's position in the set) and face 0. ``n_gauss``:
    Gauss points per direction on every rational face, or None for :func:`rational_face_points` of
    each face's degree.

    nodes : (n, 1, m) int64, n_nodes : (n, 1) int64, n_points : (n, 1) int64,
    weights : (n, 1, q) float64, N, dN_du, dN_dv : (n, 1, q, m) float64, orientation : (n, 1) float64
    """

    def __init__(self, solid, code, face, element, tables, n_gauss=None):
        n = len(code)
        groups = sorted(set(zip(code[RATIONAL[code]].tolist(), face[RATIONAL[code]].tolist())))
        rule = {c: int(n_gauss) if n_gauss is not None else rational_face_points(BY_CODE[c].degree)
                for c, _ in groups}
        q_rat = max([r * r for r in rule.values()], default=0)
        m_max, q_max = tables.nodes.shape[2], max(tables.weights.shape[2], q_rat)
        self.nodes = tables.nodes[code, face][:, None, :].copy()
        self.n_nodes = tables.n_nodes[code, face][:, None].copy()
        self.orientation = tables.orientation[code, face][:, None].copy()
        self.n_points = tables.n_points[code, face][:, None].copy()
        self.weights = np.zeros((n, 1, q_max))
        self.N, self.dN_du, self.dN_dv = (np.zeros((n, 1, q_max, m_max)) for _ in range(3))
        q0 = tables.weights.shape[2]
        polynomial = ~RATIONAL[code]
        self.weights[polynomial, 0, :q0] = tables.weights[code[polynomial], face[polynomial]]
        for name in ("N", "dN_du", "dN_dv"):
            getattr(self, name)[polynomial, 0, :q0] = getattr(tables, name)[code[polynomial], face[polynomial]]
        for c, f in groups:
            d = BY_CODE[c]
            t, w = gauss_legendre(rule[c])
            q = rule[c] * rule[c]
            uv = np.column_stack([np.repeat(t, rule[c]), np.tile(t, rule[c])])
            if d.family_type.face_shapes[f].n_corners != 4:
                raise ValueError(f"rational {d.name} face {f}: only quadrilateral faces are tabulated")
            idx = np.flatnonzero((code == c) & (face == f))
            origin, a, b, _normal = d.faces[f]
            B, dB = polynomial_values(c, origin + uv[:, :1] * a + uv[:, 1:] * b, d.n_nodes)
            wts = solid.weights[solid.connectivity[element[idx], : d.n_nodes]]          # (k, n)
            R, dR = rational_values(B, dB, wts)
            local = tables.nodes[c, f, : tables.n_nodes[c, f]]
            m = len(local)
            self.n_points[idx, 0] = q
            self.weights[idx, 0, :q] = np.outer(w, w).ravel()
            self.N[idx, 0, :q, :m] = R[:, :, local]
            self.dN_du[idx, 0, :q, :m] = dR[:, :, local] @ a
            self.dN_dv[idx, 0, :q, :m] = dR[:, :, local] @ b


def polynomial_values(code, xi, n):
    """The polynomial part B (q, n) and ∂B/∂ξ (q, n, 3) of type ``code`` at the points ``xi`` (q, 3)."""
    B, dB = np.empty((len(xi), n)), np.empty((len(xi), n, 3))
    for q, x in enumerate(np.ascontiguousarray(xi)):
        shape(code, x, B[q])
        deriv(code, x, dB[q])
    return B, dB


def rational_values(B, dB, weights):
    """R_a = w_a B_a / W and ∂R_a/∂ξ (quotient rule) of elements with node ``weights`` (k, n) from the
    polynomial values B (q, n) and derivatives dB (q, n, 3) at q points: (k, q, n) and (k, q, n, 3)."""
    wB = B[None] * weights[:, None, :]
    wdB = dB[None] * weights[:, None, :, None]
    W = wB.sum(axis=2)
    R = wB / W[:, :, None]
    dR = (wdB - R[..., None] * wdB.sum(axis=2)[:, :, None, :]) / W[:, :, None, None]
    return R, dR


def kernel_tables(solid, code, face, element, tables, n_gauss=None):
    """``(codes, faces, tables)`` that the surface kernels index: the type tables unchanged when no
    face is rational, else one table per face (:class:`FaceInstanceTables`; ``n_gauss`` None: the
    rule of each face's degree)."""
    if not RATIONAL[code].any():
        return code, face, tables
    return (np.arange(len(code), dtype=np.int64), np.zeros(len(code), dtype=np.int64),
            FaceInstanceTables(solid, code, face, element, tables, n_gauss))


__all__ = ["FaceInstanceTables", "kernel_tables", "polynomial_values", "rational_values", "rational_face_points"]
