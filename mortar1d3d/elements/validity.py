"""Where is det J positive? A check of solid elements that cannot miss a fold between sample points.

det J of an element's map is a polynomial in ξ: of degree ``p`` in each direction on a
hexahedron (``descriptor.jacobian_degree``; Q2 for hex8, Q5 for hex20 and hex27) and of total
degree ``p`` on a tetrahedron (P0 for tet4, P3 for tet10). On any sub-box (sub-simplex) of the
parameter domain it has a Bernstein–Bézier form, and the polynomial lies between its smallest and
largest Bernstein coefficient there, while the coefficients at the corners equal its values.
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
from math import comb, factorial

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


# -------------------------------------------------------------------------------------- cells
# A hexahedral cell is a box (lower, upper) in [-1, 1]^3; a tetrahedral cell a simplex (4 vertices).

@lru_cache(maxsize=None)
def _box_lattice(p):
    """Lattice points t ∈ [0, 1]^3 ((p+1)^3, 3) of Q_p and the matrix from values there to Bernstein
    coefficients (tensor product of the 1D inverse)."""
    t = np.linspace(0.0, 1.0, p + 1) if p > 0 else np.array([0.5])
    k = np.arange(p + 1)
    basis = np.array([[comb(p, j) * x ** j * (1 - x) ** (p - j) for j in k] for x in t])
    inverse = np.linalg.inv(basis)
    grid = np.stack(np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid, np.kron(np.kron(inverse, inverse), inverse)


@lru_cache(maxsize=None)
def _simplex_lattice(p):
    """Barycentric lattice points ((p+1)(p+2)(p+3)/6, 4) of P_p on a tetrahedron and the matrix from
    values there to Bernstein coefficients."""
    if p == 0:
        return np.full((1, 4), 0.25), np.ones((1, 1))
    index = np.array([(i, j, k, p - i - j - k) for i in range(p + 1) for j in range(p + 1 - i)
                      for k in range(p + 1 - i - j)])
    lam = index / p
    basis = np.array([[factorial(p) / np.prod([factorial(int(a)) for a in alpha]) * np.prod(lam_row ** alpha)
                       for alpha in index] for lam_row in lam])
    return lam, np.linalg.inv(basis)


def _samples(descriptor, cells):
    """Sample points (n_cells, n_samples, 3) of the cells and the matrix to Bernstein coefficients."""
    p = descriptor.jacobian_degree
    if descriptor.family == "hex":
        grid, to_bernstein = _box_lattice(p)
        lower, upper = cells
        points = lower[:, None, :] + grid[None, :, :] * (upper - lower)[:, None, :]
    else:
        lam, to_bernstein = _simplex_lattice(p)
        points = np.einsum("sv,cvi->csi", lam, cells)
    return points, to_bernstein


def _whole(descriptor, n):
    if descriptor.family == "hex":
        return np.full((n, 3), -1.0), np.full((n, 3), 1.0)
    return np.broadcast_to(descriptor.reference_nodes[:4], (n, 4, 3)).copy()


def _children(descriptor, cells):
    """The 8 children of every cell (halved boxes; red refinement of simplices)."""
    if descriptor.family == "hex":
        lower, upper = cells
        mid = 0.5 * (lower + upper)
        lo, hi = [], []
        for corner in range(8):
            pick = np.array([(corner >> i) & 1 for i in range(3)], dtype=bool)
            lo.append(np.where(pick, mid, lower))
            hi.append(np.where(pick, upper, mid))
        return np.concatenate(lo), np.concatenate(hi)
    v = cells
    m = {(i, j): 0.5 * (v[:, i] + v[:, j]) for i in range(4) for j in range(i + 1, 4)}
    children = [(v[:, 0], m[0, 1], m[0, 2], m[0, 3]), (m[0, 1], v[:, 1], m[1, 2], m[1, 3]),
                (m[0, 2], m[1, 2], v[:, 2], m[2, 3]), (m[0, 3], m[1, 3], m[2, 3], v[:, 3]),
                (m[0, 1], m[0, 2], m[0, 3], m[1, 3]), (m[0, 1], m[0, 2], m[1, 2], m[1, 3]),
                (m[0, 2], m[0, 3], m[1, 3], m[2, 3]), (m[0, 2], m[1, 2], m[1, 3], m[2, 3])]
    return np.concatenate([np.stack(c, axis=1) for c in children])


def _take(descriptor, cells, index):
    if descriptor.family == "hex":
        return cells[0][index], cells[1][index]
    return cells[index]


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


def jacobian_validity(descriptor, X, h):
    """Classify elements by the sign of det J over the whole element.

    Parameters
    ----------
    descriptor : SolidElementType
    X : (m, n_nodes, 3) float
        Node coordinates of m elements of this type.
    h : (m,) float
        Element sizes (bounding-box diagonals): |det J| <= 1e-12 h³ counts as zero.

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
        out[sl] = _classify(descriptor, X[sl], zero[sl])
    return out


@lru_cache(maxsize=None)
def _halves_1d(p):
    """Bernstein coefficients of a degree-p polynomial on [0, 1/2] and on [1/2, 1] from those on [0, 1]
    (de Casteljau at 1/2): the lower and the upper (p+1, p+1) matrix."""
    lower = np.array([[comb(i, j) * 0.5 ** i if j <= i else 0.0 for j in range(p + 1)] for i in range(p + 1)])
    upper = np.array([[comb(p - i, j - i) * 0.5 ** (p - i) if j >= i else 0.0 for j in range(p + 1)]
                      for i in range(p + 1)])
    return lower, upper


def _box_children(coefficients, p):
    """Coefficients ((8 n), (p+1)^3) of the 8 half-boxes of n boxes (child k: upper half of axis i if bit i),
    one axis at a time."""
    n = len(coefficients)
    c = coefficients.reshape(n, p + 1, p + 1, p + 1)
    lower, upper = _halves_1d(p)
    children = []
    for child in range(8):
        a, b, d = (upper if (child >> i) & 1 else lower for i in range(3))
        children.append(np.einsum("ai,bj,ck,nijk->nabc", a, b, d, c, optimize=True).reshape(n, -1))
    return np.concatenate(children)


def _corner_rows(p):
    """Rows of the (p+1)^3 lattice at the box corners (where a coefficient equals the value)."""
    n = p + 1
    return [i * n * n + j * n + k for i in (0, p) for j in (0, p) for k in (0, p)]


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


def _bernstein(descriptor, X, zero):
    m = len(X)
    out = np.full(m, VALID, dtype=np.int64)
    points, to_bernstein = _samples(descriptor, _whole(descriptor, 1))
    dN = shape_gradients(descriptor, points[0])
    det = _jacobian_determinant(X, dN)
    threshold = zero[:, None]
    # negative at a corner of the element: a node order that is not VTK's (or a corner folded over);
    # negative only inside: a fold
    if descriptor.family == "hex":
        corners = _corner_rows(descriptor.jacobian_degree)
    else:
        lam, _ = _simplex_lattice(descriptor.jacobian_degree)
        corners = np.flatnonzero(lam.max(axis=1) == 1.0) if len(lam) > 1 else np.array([0])
    out[(det[:, corners] < -threshold).any(axis=1)] = INVERTED
    bad = (det <= threshold).any(axis=1) & (out == VALID)
    out[bad & (det < -threshold).any(axis=1)] = FOLDED
    out[bad & (out == VALID)] = DEGENERATE
    coefficients = det @ to_bernstein.T
    owner = np.arange(m)
    cells = _whole(descriptor, m)
    hexahedral = descriptor.family == "hex"
    if hexahedral:
        corners = _corner_rows(descriptor.jacobian_degree)
    for depth in range(MAX_DEPTH + 1):
        undecided = (coefficients.min(axis=1) <= zero[owner]) & (out[owner] == VALID)
        if not undecided.any():
            return out
        if depth == MAX_DEPTH:
            out[owner[undecided]] = DEGENERATE
            return out
        index = np.flatnonzero(undecided)
        owner = np.tile(owner[index], 8)
        if hexahedral:
            # children's coefficients by subdivision; their corner coefficients are values of det J
            coefficients = _box_children(coefficients[index], descriptor.jacobian_degree)
            values = coefficients[:, corners]
        else:
            cells = _children(descriptor, _take(descriptor, cells, index))
            points, _ = _samples(descriptor, cells)
            values = _determinants(descriptor, X[owner], points)
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
