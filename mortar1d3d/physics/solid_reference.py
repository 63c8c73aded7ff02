"""The solid's reference configuration at its Gauss points: volume rules, ∂N/∂X and w det J.

Each element type's volume rule comes from its descriptor
(:attr:`~mortar1d3d.elements.descriptor.SolidElementType.quadrature`, built in
:mod:`mortar1d3d.quadrature`; each type's module says which rule and why). The kernels read them as
flat tables indexed by element code (:data:`RULE_PTR`, :data:`RULE_XI`, :data:`RULE_W`).

:func:`reference_gauss_points` evaluates, once per mesh, the reference derivatives ``∂N_a/∂X``
and the weights ``w det J`` of every Gauss point of every element, which the element kernels
(:mod:`~mortar1d3d.physics.solid_kernels`) then read at every evaluation.
"""
import numpy as np

from .._config import CHUNK, njit
from .._parallel import in_parallel
from .._schedule import n_chunks
from ..elements.solid.dispatch import BY_CODE, MAX_NODES, N_NODES, RATIONAL, SOLID_MODULES, deriv, weighted_derivatives
from ..errors import MeshError, format_ids

#: volume rule per element code (from the element descriptors): (points (n_gp, 3), weights (n_gp,))
RULES = {code: d.quadrature for code, d in BY_CODE.items()}
_N_CODES = len(BY_CODE)
#: Gauss points per element code
N_GAUSS = np.array([len(RULES[c][1]) for c in range(_N_CODES)], dtype=np.int64)
#: rows ``RULE_PTR[code]:RULE_PTR[code + 1]`` of :data:`RULE_XI` and :data:`RULE_W` are the rule of ``code``
RULE_PTR = np.concatenate([[0], np.cumsum(N_GAUSS)]).astype(np.int64)
RULE_XI = np.ascontiguousarray(np.vstack([RULES[c][0] for c in range(_N_CODES)]))
RULE_W = np.concatenate([RULES[c][1] for c in range(_N_CODES)])


def shape_table(code):
    """(n_gp, n_nodes) shape function values at the Gauss points (pure Python: no compilation)."""
    d = BY_CODE[code]
    shape = SOLID_MODULES[d.name].shape.py_func
    points = RULES[code][0]
    table = np.empty((len(points), d.n_nodes))
    for q, xi in enumerate(points):
        shape(xi, table[q])
    return table


def reference_gauss_points(points, connectivity, codes):
    """∂N/∂X and w det J at every Gauss point of every element (reference configuration).

    Parameters
    ----------
    points : (n_nodes, 3) float64
        Or (n_nodes, 4) with the node weights of rational elements in column 3
        (:attr:`mortar1d3d.mesh.SolidMesh.kernel_points`).
    connectivity : (n_elements, m) int64, C-contiguous, m >= the nodes of every element (padded with -1)
    codes : (n_elements,) int64, C-contiguous
        Element type codes.

    Returns
    -------
    gp_ptr : (n_elements + 1,) int64
        Gauss points ``gp_ptr[e]:gp_ptr[e + 1]`` belong to element e.
    dn_ptr : (n_elements + 1,) int64
        Element e's ``∂N/∂X`` start at ``dNdX[dn_ptr[e]]`` (layout in :func:`reference_kernel`).
    dNdX : (dn_ptr[-1],) float64
    wJ : (gp_ptr[-1],) float64
        ``w det J`` per Gauss point.

    Raises
    ------
    MeshError
        ``det J <= 0`` at a Gauss point, naming the elements.
    """
    n_gp = N_GAUSS[codes]
    gp_ptr = np.concatenate([[0], np.cumsum(n_gp)]).astype(np.int64)
    dn_ptr = np.concatenate([[0], np.cumsum(3 * n_gp * N_NODES[codes])]).astype(np.int64)
    dNdX = np.empty(dn_ptr[-1])
    wJ = np.empty(gp_ptr[-1])
    status = np.empty(len(codes), dtype=np.int64)
    reference_kernel(points, connectivity, codes, gp_ptr, dn_ptr, RULE_PTR, RULE_XI, RULE_W, dNdX, wJ, status)
    bad = np.flatnonzero(status)
    if bad.size:
        raise MeshError(f"solid elements with det J <= 0 at a Gauss point: {format_ids(bad)}")
    return gp_ptr, dn_ptr, dNdX, wJ


@njit
def reference_kernel(points, connectivity, codes, gp_ptr, dn_ptr, rule_ptr, rule_xi, rule_w, dNdX, wJ, status):
    """∂N_a/∂X and w det J at every Gauss point (reference configuration); status 1 if det J <= 0.

    Gauss point q of element e (n nodes) keeps ``∂N_a/∂X_j`` at ``dNdX[dn_ptr[e] + 3nq + jn + a]``:
    node index fastest, so that the loops over nodes in the element kernel vectorise.
    """
    n_el = codes.shape[0]
    _reference_kernel_workers(n_chunks(n_el, CHUNK), points, connectivity, codes, gp_ptr, dn_ptr, rule_ptr, rule_xi,
                             rule_w, dNdX, wJ, status, n_el)


@njit
def _reference_kernel_worker(c, points, connectivity, codes, gp_ptr, dn_ptr, rule_ptr, rule_xi, rule_w, dNdX, wJ,
                            status, n_el):
    dN = np.empty((MAX_NODES, 3))
    N = np.empty(MAX_NODES)
    for e in range(c * CHUNK, min(n_el, (c + 1) * CHUNK)):
        code = codes[e]
        n = N_NODES[code]
        status[e] = 0
        for q in range(gp_ptr[e + 1] - gp_ptr[e]):
            r = rule_ptr[code] + q
            if RATIONAL[code]:
                weighted_derivatives(code, rule_xi[r], connectivity[e], points, N, dN)
            else:
                deriv(code, rule_xi[r], dN)
            j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
            for a in range(n):
                x = points[connectivity[e, a]]
                j00 += x[0] * dN[a, 0]
                j01 += x[0] * dN[a, 1]
                j02 += x[0] * dN[a, 2]
                j10 += x[1] * dN[a, 0]
                j11 += x[1] * dN[a, 1]
                j12 += x[1] * dN[a, 2]
                j20 += x[2] * dN[a, 0]
                j21 += x[2] * dN[a, 1]
                j22 += x[2] * dN[a, 2]
            c00 = j11 * j22 - j12 * j21
            c01 = j12 * j20 - j10 * j22
            c02 = j10 * j21 - j11 * j20
            det = j00 * c00 + j01 * c01 + j02 * c02
            if not det > 0.0:
                status[e] = 1
                det = 1.0
            inv = 1.0 / det
            # J⁻¹ (row i = ∂ξ_i/∂X); ∂N/∂X_j = Σ_i ∂N/∂ξ_i (J⁻¹)_ij
            i00 = c00 * inv
            i01 = (j02 * j21 - j01 * j22) * inv
            i02 = (j01 * j12 - j02 * j11) * inv
            i10 = c01 * inv
            i11 = (j00 * j22 - j02 * j20) * inv
            i12 = (j02 * j10 - j00 * j12) * inv
            i20 = c02 * inv
            i21 = (j01 * j20 - j00 * j21) * inv
            i22 = (j00 * j11 - j01 * j10) * inv
            base = dn_ptr[e] + 3 * n * q
            for a in range(n):
                d0 = dN[a, 0]
                d1 = dN[a, 1]
                d2 = dN[a, 2]
                dNdX[base + a] = d0 * i00 + d1 * i10 + d2 * i20
                dNdX[base + n + a] = d0 * i01 + d1 * i11 + d2 * i21
                dNdX[base + 2 * n + a] = d0 * i02 + d1 * i12 + d2 * i22
            wJ[gp_ptr[e] + q] = rule_w[r] * det


_reference_kernel_workers = in_parallel(_reference_kernel_worker)
