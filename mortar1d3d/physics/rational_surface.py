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

Quadrature: R is a quotient, so no Gauss rule integrates the loads exactly; rational faces use a
``n × n`` Gauss–Legendre rule (default 4, one point more per direction than the polynomial
quadratic faces; the error falls quickly with ``n``, tests/test_nurbs_pressure.py).
"""
import numpy as np

from ..elements.solid.dispatch import BY_CODE, RATIONAL, deriv, shape
from ..quadrature import gauss_legendre

#: Gauss points per direction on a rational face
RATIONAL_FACE_POINTS = 4


class FaceInstanceTables:
    """The tables of :class:`~mortar1d3d.physics.surface._FaceTables` with one entry per face of a
    face set: index them with code ``i`` (the face's position in the set) and face 0.

    nodes : (n, 1, m) int64, n_nodes : (n, 1) int64, n_points : (n, 1) int64,
    weights : (n, 1, q) float64, N, dN_du, dN_dv : (n, 1, q, m) float64, orientation : (n, 1) float64
    """

    def __init__(self, solid, code, face, element, tables, n_gauss=RATIONAL_FACE_POINTS):
        n = len(code)
        t, w = gauss_legendre(n_gauss)
        q_rat = n_gauss * n_gauss
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
        uv = np.column_stack([np.repeat(t, n_gauss), np.tile(t, n_gauss)])
        for c, f in sorted(set(zip(code[~polynomial].tolist(), face[~polynomial].tolist()))):
            d = BY_CODE[c]
            if d.family_type.face_shapes[f].n_corners != 4:
                raise ValueError(f"rational {d.name} face {f}: only quadrilateral faces are tabulated")
            idx = np.flatnonzero((code == c) & (face == f))
            origin, a, b, _normal = d.faces[f]
            B, dB = polynomial_values(c, origin + uv[:, :1] * a + uv[:, 1:] * b, d.n_nodes)
            wts = solid.weights[solid.connectivity[element[idx], : d.n_nodes]]          # (k, n)
            R, dR = rational_values(B, dB, wts)
            local = tables.nodes[c, f, : tables.n_nodes[c, f]]
            m = len(local)
            self.n_points[idx, 0] = q_rat
            self.weights[idx, 0, :q_rat] = np.outer(w, w).ravel()
            self.N[idx, 0, :q_rat, :m] = R[:, :, local]
            self.dN_du[idx, 0, :q_rat, :m] = dR[:, :, local] @ a
            self.dN_dv[idx, 0, :q_rat, :m] = dR[:, :, local] @ b


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


def kernel_tables(solid, code, face, element, tables, n_gauss=RATIONAL_FACE_POINTS):
    """``(codes, faces, tables)`` that the surface kernels index: the type tables unchanged when no
    face is rational, else one table per face (:class:`FaceInstanceTables`)."""
    if not RATIONAL[code].any():
        return code, face, tables
    return (np.arange(len(code), dtype=np.int64), np.zeros(len(code), dtype=np.int64),
            FaceInstanceTables(solid, code, face, element, tables, n_gauss))


__all__ = ["FaceInstanceTables", "kernel_tables", "polynomial_values", "rational_values", "RATIONAL_FACE_POINTS"]
