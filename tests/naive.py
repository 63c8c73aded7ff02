"""Slow, obvious reference implementations (pure Python loops) for kernel tests."""
import numpy as np

from mortar1d3d.elements.beam import hermite, lagrange
from mortar1d3d.elements.multiplier import shape as multiplier_shape
from mortar1d3d.elements.solid.dispatch import BY_CODE, SOLID_MODULES
from mortar1d3d.mortar.assemble import lm_numbering
from mortar1d3d.elements.multiplier import multiplier


def beam_functions(beams, element, eta):
    H = np.zeros(4)
    name = beams.element_type.name
    if name == "hermite":
        hermite.shape.py_func(eta, beams.lengths[element], H)
    elif name == "line":
        lagrange.line2_shape.py_func(eta, H)
    else:
        lagrange.line3_shape.py_func(eta, H)
    return H[: beams.element_type.n_functions]


def solid_functions(solid, element, xi):
    d = BY_CODE[int(solid.element_codes[element])]
    N = np.empty(d.n_nodes)
    SOLID_MODULES[d.name].shape.py_func(np.asarray(xi, dtype=float), N)
    return N, solid.connectivity[element, : d.n_nodes]


def operators_from_points(beams, solid, ops):
    """Scalar D, M (dense) and κ summed point by point from ``ops.points`` (design.md §1)."""
    lm_type = multiplier(ops.lm)
    index, n_lm = lm_numbering(beams, lm_type)
    columns = beams.function_columns()
    D = np.zeros((n_lm, beams.n_centreline_dofs // 3))
    M = np.zeros((n_lm, solid.n_nodes))
    kappa = np.zeros(n_lm)
    Phi = np.empty(4)
    for p in ops.points:
        e, s, w = int(p["beam_element"]), int(p["solid_element"]), p["weight"]
        multiplier_shape.py_func(lm_type.n_functions, p["eta"], Phi)
        H = beam_functions(beams, e, p["eta"])
        N, nodes = solid_functions(solid, s, p["xi"])
        for j in range(lm_type.n_functions):
            row = index[e, j]
            kappa[row] += Phi[j] * w
            for k, h in enumerate(H):
                D[row, columns[e, k]] += Phi[j] * h * w
            for a, n in enumerate(N):
                M[row, nodes[a]] += Phi[j] * n * w
    return D, M, kappa
