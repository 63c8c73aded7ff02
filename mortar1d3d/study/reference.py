"""An independent reference for the study's reference rule: adaptive quadrature of one segment.

:func:`adaptive_segment_integrals` integrates κ, D and M over one segment with
``scipy.integrate.quad_vec``, with its own centreline formulas (:func:`_hermite`, :func:`_lagrange`)
and its own projection (:func:`newton_projection`, also the tests' independent projection);
:func:`pair_reference_check` compares the library's segment-based operators with it, entry by entry.
"""
import numpy as np
from scipy.integrate import quad_vec

from ..elements.multiplier import multiplier
from ..elements.solid.dispatch import BY_CODE, SOLID_MODULES
from ..mesh import BeamMesh
from ..mortar.assemble import assemble_mortar, lm_numbering


def _hermite(eta, L):
    """Hermite functions and η-derivatives of docs/conventions.md §2 (own formulas, numpy)."""
    H = np.array([(2 - 3 * eta + eta ** 3) / 4, L / 8 * (1 - eta - eta ** 2 + eta ** 3),
                  (2 + 3 * eta - eta ** 3) / 4, L / 8 * (-1 - eta + eta ** 2 + eta ** 3)])
    dH = np.array([(-3 + 3 * eta ** 2) / 4, L / 8 * (-1 - 2 * eta + 3 * eta ** 2),
                   (3 - 3 * eta ** 2) / 4, L / 8 * (-1 + 2 * eta + 3 * eta ** 2)])
    return H, dH


_LM_NODES = {"line2": (-1.0, 1.0), "line3": (-1.0, 1.0, 0.0), "line4": (-1.0, 1.0, -1.0 / 3.0, 1.0 / 3.0)}


def _lagrange(nodes, eta):
    return np.array([np.prod([(eta - b) / (a - b) for b in nodes if b != a]) for a in nodes])


def newton_projection(module, X, p, xi0, h=None, iterations=60, escape=None):
    """ξ with x(ξ) = p in one solid element, by Newton's method in numpy (own iteration).

    The independent projection of the study's reference check and of the tests: it shares only
    the element module's pure-Python shape functions with the library (checked on their own in
    tests/test_elements.py), not the library's projection kernels.

    Parameters
    ----------
    module : module
        The solid element's module (``SOLID_MODULES[name]``): its ``shape`` and ``deriv`` kernels.
    X : (n_nodes, 3) float64
        The element's nodes.
    p : (3,) float64
        The point.
    xi0 : (3,) array_like
        Start of the iteration (not modified).
    h : float, optional
        Length scale of the stopping test ``|p - x(ξ)| <= 1e-15 h``; default the diagonal of the
        nodes' bounding box.
    iterations : int, optional
        At most this many Newton steps.
    escape : float, optional
        Stop as soon as ``max |ξ_i| > escape`` (a point far outside the element, where Newton may
        diverge); default: never.

    Returns
    -------
    xi : (3,) float64
        The last iterate: the converged parameters, or where the iteration stopped (the caller
        checks the residual if it needs to know).
    """
    if h is None:
        h = np.linalg.norm(X.max(axis=0) - X.min(axis=0))
    n = X.shape[0]
    N, dN = np.empty(n), np.empty((n, 3))
    xi = np.array(xi0, dtype=float)
    for _ in range(iterations):
        module.shape.py_func(xi, N)
        r = p - N @ X
        if np.linalg.norm(r) <= 1e-15 * h:
            break
        module.deriv.py_func(xi, dN)
        xi = xi + np.linalg.solve(X.T @ dN, r)
        if escape is not None and np.abs(xi).max() > escape:
            break
    return xi


def adaptive_segment_integrals(beams, solid, beam_element, solid_element, eta_a, eta_b, lm="line2", epsrel=1e-13):
    """κ_j, D_jk, M_ja of one segment by adaptive quadrature (``scipy.integrate.quad_vec``).

    Independent of the library's kernels: Hermite functions from docs/conventions.md §2 in numpy, Lagrange
    multipliers from their nodes, the solid point by a numpy Newton iteration (warm-started
    along the segment). Only the shape functions of the solid element modules are shared (they
    are checked on their own in tests/test_elements.py).

    Returns
    -------
    kappa : (n_phi,), D : (n_phi, 4), M : (n_phi, n_nodes)
    """
    if beams.element_type.name != "hermite":
        raise ValueError("adaptive_segment_integrals: Hermite beams only")
    d = BY_CODE[int(solid.element_codes[solid_element])]
    module = SOLID_MODULES[d.name]
    X = solid.points[solid.connectivity[solid_element, : d.n_nodes]]
    h = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    n1, n2 = beams.elements[beam_element]
    q = np.array([beams.positions[n1], beams.tangents[n1], beams.positions[n2], beams.tangents[n2]])
    L = beams.lengths[beam_element]
    nodes = _LM_NODES[lm]
    n_phi = len(nodes)
    N = np.empty(d.n_nodes)
    start = [d.centre.astype(float)]

    def integrand(eta):
        H, dH = _hermite(eta, L)
        r, dr = H @ q, dH @ q
        xi = newton_projection(module, X, r, start[0], h)
        start[0] = xi
        module.shape.py_func(xi, N)
        phi = _lagrange(nodes, eta) * np.linalg.norm(dr)
        return np.concatenate([phi, np.outer(phi, H).ravel(), np.outer(phi, N).ravel()])

    values, _ = quad_vec(integrand, eta_a, eta_b, epsabs=0.0, epsrel=epsrel, norm="max", limit=400)
    return values[:n_phi], values[n_phi:n_phi + 4 * n_phi].reshape(n_phi, 4), values[n_phi + 4 * n_phi:].reshape(n_phi, -1)


def pair_reference_check(beams, solid, beam_elements, n_gauss, lm="line2"):
    """Compare segment-based operators (``n_gauss`` per segment) with adaptive quadrature.

    The chosen beam elements get nodes of their own (a copy of the beam mesh with every element
    detached), so that every LM row belongs to one element and the operators can be compared
    entry by entry with :func:`adaptive_segment_integrals` summed over the element's segments.
    Also checks that interior segment ends lie on a face of their solid element.

    Returns
    -------
    dict
        ``D``, ``M``, ``kappa``: largest entry difference over the largest entry; ``face``:
        largest distance to the reference element's boundary (absolute value) of the interior segment ends (parameter
        units); ``segments``: how many segments were integrated.
    """
    beam_elements = np.atleast_1d(np.asarray(beam_elements, dtype=np.int64))
    nodes = beams.elements[beam_elements].ravel()
    sub = BeamMesh.hermite(beams.positions[nodes], beams.tangents[nodes],
                           np.arange(2 * len(beam_elements)).reshape(-1, 2))
    ops = assemble_mortar(sub, solid, integration="segment", n_gauss=n_gauss, lm=lm)
    lm_type = multiplier(lm)
    index, n_lm = lm_numbering(sub, lm_type)
    columns = sub.function_columns()
    D = np.zeros((n_lm, sub.n_centreline_dofs // 3))
    M = np.zeros((n_lm, solid.n_nodes))
    kappa = np.zeros(n_lm)
    face = 0.0
    for seg in ops.segments:
        e, s = int(seg["beam_element"]), int(seg["solid_element"])
        k, De, Me = adaptive_segment_integrals(sub, solid, e, s, seg["eta_start"], seg["eta_end"], lm)
        d = BY_CODE[int(solid.element_codes[s])]
        conn = solid.connectivity[s, : d.n_nodes]
        for j in range(lm_type.n_functions):
            kappa[index[e, j]] += k[j]
            D[index[e, j], columns[e]] += De[j]
            M[index[e, j], conn] += Me[j]
        X = solid.points[conn]
        h = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
        for eta in (seg["eta_start"], seg["eta_end"]):
            if -1.0 < eta < 1.0:
                H, _ = _hermite(eta, sub.lengths[e])
                q = np.array([sub.positions[sub.elements[e, 0]], sub.tangents[sub.elements[e, 0]],
                              sub.positions[sub.elements[e, 1]], sub.tangents[sub.elements[e, 1]]])
                xi = newton_projection(SOLID_MODULES[d.name], X, H @ q, d.centre, h)
                face = max(face, abs(d.family_type.outside_distance.py_func(xi)))
    D_lib = ops.D.toarray()[0::3, 0::3]
    M_lib = ops.M.toarray()[0::3, 0::3]
    return {"D": float(np.abs(D_lib - D).max() / np.abs(D).max()),
            "M": float(np.abs(M_lib - M).max() / np.abs(M).max()),
            "kappa": float(np.abs(ops.kappa - kappa).max() / np.abs(kappa).max()),
            "face": face, "segments": len(ops.segments)}
