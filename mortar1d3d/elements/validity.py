"""Where is det J positive? A check of solid elements that cannot miss a fold between sample points.

det J of an element's map is a polynomial in ξ of a degree the family's cells derive from the
element's monomials (``descriptor.jacobian_degree``): per direction on a hexahedron (Q2 for hex8,
Q5 for hex20 and hex27), total on a tetrahedron (P0 for tet4, P3 for tet10), per factor on a
product domain. On any sub-cell of the parameter domain (the family's ``cells``) it has a
Bernstein–Bézier form, and the polynomial lies between its smallest and largest Bernstein
coefficient there, while the coefficients at the corners equal its values.
So (Johnen, Remacle & Geuzaine, J Comput Phys 233, 2013):

- every coefficient > 0 on a cell: det J > 0 throughout the cell;
- a value <= 0 at a sample point: the element folds (or is inverted, or degenerate) there;
- otherwise the cell is halved in every direction and the test repeats on the children, whose
  coefficients converge to the values as the cells shrink.

The coefficients come from det J sampled at the cell's Bézier lattice points (the polynomial is
determined by those values), evaluated with the shape function gradients of the element's
monomial basis, in numpy: nothing is compiled here.
"""
from functools import lru_cache

import numpy as np

#: outcome per element
VALID, INVERTED, FOLDED, DEGENERATE = 0, 1, 2, 3
#: halvings of an undecided cell before the element is called degenerate (det J within round-off of
#: zero somewhere: no positive bound separates it from zero)
MAX_DEPTH = 8
#: elements treated per numpy batch (bounds the memory of the (elements, samples, 3, 3) Jacobians)
_BATCH = 512


@lru_cache(maxsize=None)
def _gradient_basis(descriptor):
    """Monomial exponents and the inverse Vandermonde matrix of the element's shape functions in ξ."""
    exps = descriptor.monomials.astype(float)
    vandermonde = np.prod(descriptor.reference_nodes[:, None, :] ** exps[None, :, :], axis=2)
    return exps, np.linalg.inv(vandermonde)


def shape_gradients(descriptor, xi):
    """∂N_a/∂ξ_i (k, n_nodes, 3) at the points ``xi`` (k, 3), from the monomial basis (vectorised)."""
    exps, inverse = _gradient_basis(descriptor)
    xi = np.asarray(xi, dtype=float)
    powers = xi[:, None, :] ** exps[None, :, :]                   # (k, monomials, 3)
    grad = np.empty(powers.shape)
    for i in range(3):
        e = exps[:, i]
        d = np.where(e > 0, e * xi[:, None, i] ** np.maximum(e - 1, 0), 0.0)
        grad[..., i] = d * np.prod(np.delete(powers, i, axis=2), axis=2)
    return np.einsum("kmi,ma->kai", grad, inverse)


def _jacobian_determinant(X, dN):
    """det J (m, s) of elements with nodes X (m, n_nodes, 3) at points with shape gradients dN (s, n_nodes, 3),
    or per element (m, s, n_nodes, 3).

    The nine entries J_ij = Σ_a X_ai ∂N_a/∂ξ_j are formed as contiguous (m, s) arrays and combined
    by the rule of Sarrus (np.linalg.det on many 3 × 3 matrices is several times slower).
    """
    if dN.ndim == 3:
        J = [[X[:, :, i] @ dN[:, :, j].T for j in range(3)] for i in range(3)]
    else:
        J = [[np.einsum("ma,msa->ms", X[:, :, i], dN[..., j]) for j in range(3)] for i in range(3)]
    return (J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0])
            + J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]))


def _determinants(descriptor, X, points):
    """det J (n_cells, n_samples) of the elements with nodes X (n_cells, n_nodes, 3) at their points."""
    n_cells, n_samples, _ = points.shape
    dN = shape_gradients(descriptor, points.reshape(-1, 3)).reshape(n_cells, n_samples, descriptor.n_nodes, 3)
    return _jacobian_determinant(X, dN)


def jacobian_validity(descriptor, X, h, weights=None):
    """Classify elements by the sign of det J over the whole element.

    Parameters
    ----------
    descriptor : SolidElementType
    X : (m, n_nodes, 3) float
        Node coordinates of m elements of this type.
    h : (m,) float
        Element sizes (bounding-box diagonals): |det J| <= 1e-12 h³ counts as zero.
    weights : (m, n_nodes) float, optional
        Node weights of rational elements (``descriptor.rational``): their check bounds the
        determinant of the homogeneous Jacobian, W⁴ det J (a polynomial, of degree
        ``descriptor.jacobian_degree``), with the weights scaled to a largest weight of 1.

    Returns
    -------
    (m,) int64
        ``VALID`` (det J > 0 throughout: proved by positive Bernstein coefficients), ``INVERTED``
        (det J < 0 at a corner: typically a node order that is not VTK's), ``FOLDED`` (det J <= 0
        inside the element, > 0 at its corners: e.g. a mid-edge node too far from the edge's middle),
        ``DEGENERATE`` (det J within 1e-12 h³ of zero somewhere, or no positive bound found after
        ``MAX_DEPTH`` halvings).
    """
    X = np.asarray(X, dtype=float)
    m = len(X)
    out = np.full(m, VALID, dtype=np.int64)
    zero = 1e-12 * np.asarray(h, dtype=float) ** 3
    for start in range(0, m, _BATCH):
        sl = slice(start, min(start + _BATCH, m))
        if descriptor.rational:
            w = np.asarray(weights, dtype=float)[sl]
            out[sl] = _bernstein(descriptor, X[sl] - X[sl, :1, :], zero[sl], w / w.max(axis=1, keepdims=True))
        else:
            out[sl] = _classify(descriptor, X[sl], zero[sl])
    return out


@lru_cache(maxsize=None)
def _centred_basis(descriptor):
    """Monomial degrees, the matrix from nodes to monomial coefficients about the centre ξ_c (in
    y = ξ - ξ_c) and the element's max-norm radius about ξ_c."""
    exps = descriptor.monomials
    y = descriptor.reference_nodes - descriptor.centre
    vandermonde = np.prod(y[:, None, :] ** exps[None, :, :].astype(float), axis=2)
    linear = [int(np.flatnonzero((exps == np.eye(3, dtype=np.int64)[i]).all(axis=1))[0]) for i in range(3)]
    return exps.sum(axis=1), np.linalg.inv(vandermonde), linear, float(np.abs(y).max())


def _near_affine(descriptor, X, zero):
    """Elements proved valid without sampling: J(ξ) = J_c (I + E(ξ)) with ‖E‖∞ <= ρ < 1 throughout.

    With x = Σ_α a_α y^α, J_c = [a_e1, a_e2, a_e3] and E = Σ_{|α|>=2} (J_c⁻¹ a_α) ∇(y^α)ᵀ, bounded on
    the element (|y|∞ <= R) by ρ = max_i Σ_α |α| R^(|α|-1) |(J_c⁻¹ a_α)_i|. Then det J(ξ) >=
    det J_c (1 - ρ)³ > 0 (no eigenvalue of E reaches -1). Mildly curved and distorted elements pass
    here; the others get the Bernstein test.
    """
    degree, to_monomial, linear, radius = _centred_basis(descriptor)
    a = np.einsum("ka,mai->mki", to_monomial, X)                      # (m, monomials, 3)
    Jc = a[:, linear, :].transpose(0, 2, 1)                            # columns a_e1, a_e2, a_e3
    det_c = np.linalg.det(Jc)
    ok = det_c > 0.0
    if not ok.any() or (degree <= 1).all():
        return ok & (det_c > zero)
    nonlinear = degree >= 2
    b = np.zeros((len(X), int(nonlinear.sum()), 3))
    b[ok] = np.einsum("mij,mkj->mki", np.linalg.inv(Jc[ok]), a[ok][:, nonlinear, :])
    weight = degree[nonlinear] * radius ** (degree[nonlinear] - 1.0)
    rho = (np.abs(b) * weight[None, :, None]).sum(axis=1).max(axis=1)
    return ok & (rho < 1.0) & (det_c * (1.0 - np.minimum(rho, 1.0)) ** 3 > zero)


def _classify(descriptor, X, zero):
    # local coordinates: det J is invariant, and far-away meshes keep their digits
    X = X - X[:, :1, :]
    out = np.full(len(X), VALID, dtype=np.int64)
    rest = np.flatnonzero(~_near_affine(descriptor, X, zero))
    if len(rest):
        out[rest] = _bernstein(descriptor, X[rest], zero[rest])
    return out


def _bernstein(descriptor, X, zero, weights=None):
    m = len(X)
    out = np.full(m, VALID, dtype=np.int64)
    cells = descriptor.family_type.cells
    p = descriptor.jacobian_degree
    lattice, to_bernstein = cells.lattice(p)
    corners = cells.corner_rows(p)
    if descriptor.rational:
        from .solid.bezier_hex import homogeneous_determinants, lattice_indices
        q = descriptor.degree
        det = homogeneous_determinants(q, lattice_indices(descriptor.reference_nodes, q), X, weights,
                                       cells.points(cells.whole(1), lattice)[0])
    else:
        dN = shape_gradients(descriptor, cells.points(cells.whole(1), lattice)[0])
        det = _jacobian_determinant(X, dN)
    threshold = zero[:, None]
    # negative at a corner of the element: a node order that is not VTK's (or a corner folded over);
    # negative only inside: a fold
    out[(det[:, corners] < -threshold).any(axis=1)] = INVERTED
    bad = (det <= threshold).any(axis=1) & (out == VALID)
    out[bad & (det < -threshold).any(axis=1)] = FOLDED
    out[bad & (out == VALID)] = DEGENERATE
    coefficients = det @ to_bernstein.T
    owner = np.arange(m)
    where = cells.whole(m)
    subdivide = getattr(cells, "child_coefficients", None)
    for depth in range(MAX_DEPTH + 1):
        undecided = (coefficients.min(axis=1) <= zero[owner]) & (out[owner] == VALID)
        if not undecided.any():
            return out
        if depth == MAX_DEPTH:
            out[owner[undecided]] = DEGENERATE
            return out
        index = np.flatnonzero(undecided)
        owner = np.tile(owner[index], cells.n_children)
        if subdivide is not None:
            # children's coefficients by exact subdivision; their corner coefficients are values of det J
            coefficients = subdivide(coefficients[index], p)
            values = coefficients[:, corners]
        else:
            # children sampled afresh
            where = cells.children(cells.take(where, index))
            values = _determinants(descriptor, X[owner], cells.points(where, lattice))
            coefficients = values @ to_bernstein.T
        threshold = zero[owner][:, None]
        bad = (values <= threshold).any(axis=1) & (out[owner] == VALID)
        if bad.any():
            # the element's corners (depth 0) have det J > 0 unless it is inverted: a negative value
            # anywhere is a fold, a value within round-off of zero a degenerate element
            folded = bad & (values < -threshold).any(axis=1)
            out[owner[folded]] = FOLDED
            rest = owner[bad & ~folded]
            out[rest[out[rest] == VALID]] = DEGENERATE
    return out
