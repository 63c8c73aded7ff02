"""Derivative bounds of rational element maps x(ξ) = X̃(ξ) / W(ξ) for the certified point location.

:mod:`.projection` bounds a polynomial map's second derivatives by its monomial coefficients
(:func:`~.projection.curvature_bound`). A rational element (NURBS span after Bézier extraction) has
polynomial numerator X̃ = Σ w_a B_a X_a and denominator W = Σ w_a B_a; with their monomial
coefficients about the element centre (:func:`rational_coefficients`) and, on the box
|y|∞ <= ρ (y = ξ - ξ_c), the bounds of a polynomial P = Σ c_α y^α

    |P| <= B0 = Σ |c_α| ρ^|α|,   Σ_j |∂_j P| <= B1 = Σ |c_α| |α| ρ^(|α|-1),
    Σ_jk |∂_jk P| <= B2 = Σ |c_α| |α|(|α|-1) ρ^(|α|-2),   W >= W_min = c_0 - Σ_{α≠0} |c_α| ρ^|α|,

the quotient rule gives (from X̃ = x W, differentiated once and twice)

    |x_i| <= A0 = B0(X̃_i) / W_min,   Σ_j |∂_j x_i| <= A1 = (B1(X̃_i) + A0 B1(W)) / W_min,
    Σ_jk |∂_jk x_i| <= (B2(X̃_i) + 2 A1 B1(W) + A0 B2(W)) / W_min,

which is what :func:`rational_curvature_bound` returns (the largest over i); infinite where W_min <= 0.
Near the point m of a small box the values bound better: |P| <= |P(m)| + r B1, W >= W(m) - r B1.
"""
import numpy as np

from .._config import njit
from ..elements.solid import dispatch as solid


@njit
def rational_coefficients(code, X, a):
    """Monomial coefficients about ξ_c of X̃ (``a[k, :3]``) and W (``a[k, 3]``) of a rational element with
    local control points ``X[:, :3]`` and weights ``X[:, 3]``: ``TO_MONOMIAL``'s block times (w X, w), its
    nonzero terms only (the sparse rows of :func:`~mortar1d3d.elements.solid.dispatch.monomial_coefficients`)."""
    rows = solid.MONOMIAL_ROWS
    start = solid.MONOMIAL_SPARSE_START[code]
    for k in range(solid.n_nodes(code)):
        a0 = a1 = a2 = a3 = 0.0
        for q in range(rows[start + k], rows[start + k + 1]):
            b = solid.MONOMIAL_COLUMNS[q]
            w = solid.MONOMIAL_VALUES[q] * X[b, 3]
            a0 += w * X[b, 0]
            a1 += w * X[b, 1]
            a2 += w * X[b, 2]
            a3 += w
        a[k, 0], a[k, 1], a[k, 2], a[k, 3] = a0, a1, a2, a3


@njit
def _bounds(code, a, column, radius, y0, y1, y2):
    """On |y|∞ <= radius: B0, B1, B2 of the polynomial in ``a[:, column]``, its constant term and its value
    at y."""
    b0 = b1 = b2 = 0.0
    constant = value = 0.0
    for k in range(solid.n_nodes(code)):
        e0, e1, e2 = solid.MONOMIALS[code, k, 0], solid.MONOMIALS[code, k, 1], solid.MONOMIALS[code, k, 2]
        degree = e0 + e1 + e2
        value += a[k, column] * y0 ** e0 * y1 ** e1 * y2 ** e2
        c = abs(a[k, column])
        if degree == 0:
            constant += a[k, column]
        else:
            b0 += c * radius ** degree
            b1 += c * degree * radius ** (degree - 1)
            if degree >= 2:
                b2 += c * degree * (degree - 1) * radius ** (degree - 2)
    return b0, b1, b2, constant, value


@njit
def rational_curvature_bound(code, a, m0, m1, m2, r):
    """K >= max_i Σ_{j,k} |∂²x_i/∂ξ_j∂ξ_k| over the box |ξ - m|∞ <= ``r`` for x = X̃ / W (module docstring);
    ``a`` from :func:`rational_coefficients`. np.inf where W is not bounded away from zero there.

    The derivative bounds B1, B2 hold on the box |ξ - ξ_c|∞ <= ρ = |m - ξ_c|∞ + r, which contains
    this one; the lower bound of W and the upper bounds of |X̃_i| take the better of the expansion
    about ξ_c (c_0 ∓ B0) and the value at m with the mean value theorem (P(m) ∓ r B1), so that they
    approach the values at m as boxes shrink (a small box near a corner of a strongly rational
    element still gets a finite bound).
    """
    y0 = m0 - solid.CENTRE[code, 0]
    y1 = m1 - solid.CENTRE[code, 1]
    y2 = m2 - solid.CENTRE[code, 2]
    radius = max(abs(y0), abs(y1), abs(y2)) + r
    # column 3 as an int64 like the loop's i below: a literal 3 would compile _bounds a second time
    w0, w1, w2, wc, wm = _bounds(code, a, np.int64(3), radius, y0, y1, y2)
    w_min = max(wc - w0, wm - r * w1)
    if not w_min > 0.0:
        return np.inf
    K = 0.0
    for i in range(3):
        b0, b1, b2, c, v = _bounds(code, a, i, radius, y0, y1, y2)
        a0 = min(b0 + abs(c), abs(v) + r * b1) / w_min
        a1 = (b1 + a0 * w1) / w_min
        K = max(K, (b2 + 2.0 * a1 * w1 + a0 * w2) / w_min)
    return K


#: the largest total degree |α| of a monomial of any element type (triquadratic: 6)
MAX_DEGREE = int(solid.MONOMIALS.sum(axis=-1).max())


@njit
def degree_sums(code, a):
    """(MAX_DEGREE + 1, 4): row d >= 1 the sums Σ_{|α| = d} |c_α| of every column of ``a``
    (:func:`rational_coefficients`), row 0 the constant terms c_0.

    About the centre (y = 0) the bounds of :func:`rational_curvature_bound` depend on the
    coefficients only through these sums (B0 = Σ_d S_d ρ^d, ...): one pass over the monomials
    serves every radius (:func:`centre_curvature_bound`).
    """
    sums = np.zeros((MAX_DEGREE + 1, 4))
    for k in range(solid.n_nodes(code)):
        degree = solid.MONOMIALS[code, k, 0] + solid.MONOMIALS[code, k, 1] + solid.MONOMIALS[code, k, 2]
        for column in range(4):
            sums[degree, column] += a[k, column] if degree == 0 else abs(a[k, column])
    return sums


@njit
def _degree_bounds(sums, column, radius):
    """B0, B1, B2 of :func:`_bounds` on |y|∞ <= radius from the degree sums of ``column``."""
    b0 = b1 = b2 = 0.0
    for degree in range(1, MAX_DEGREE + 1):
        c = sums[degree, column]
        b0 += c * radius ** degree
        b1 += c * degree * radius ** (degree - 1)
        if degree >= 2:
            b2 += c * degree * (degree - 1) * radius ** (degree - 2)
    return b0, b1, b2


@njit
def centre_curvature_bound(sums, r):
    """:func:`rational_curvature_bound` about the centre (m = ξ_c) from :func:`degree_sums`: the same
    bounds, their terms summed by degree (equal up to round-off), without a pass over the
    monomials per radius. What the one-to-one certificate of every element needs
    (:func:`~.projection.certified_margin`, a few radii per element)."""
    w0, w1, w2 = _degree_bounds(sums, 3, r)
    wc = sums[0, 3]
    w_min = max(wc - w0, wc - r * w1)
    if not w_min > 0.0:
        return np.inf
    K = 0.0
    for i in range(3):
        b0, b1, b2 = _degree_bounds(sums, i, r)
        c = abs(sums[0, i])
        a0 = min(b0 + c, c + r * b1) / w_min
        a1 = (b1 + a0 * w1) / w_min
        K = max(K, (b2 + 2.0 * a1 * w1 + a0 * w2) / w_min)
    return K


@njit
def centre_point(code, a):
    """x(ξ_c) = X̃(ξ_c) / W(ξ_c) from the coefficients of :func:`rational_coefficients` (their constant terms)."""
    const = 0
    for k in range(solid.n_nodes(code)):
        if solid.MONOMIALS[code, k, 0] + solid.MONOMIALS[code, k, 1] + solid.MONOMIALS[code, k, 2] == 0:
            const = k
    return a[const, 0] / a[const, 3], a[const, 1] / a[const, 3], a[const, 2] / a[const, 3]


@njit
def normalise_coefficients(code, a, L, x0, x1, x2, out):
    """The coefficients (into ``out``, which may be ``a``) of the numerator of z = L (x - x0) =
    L (X̃ - x0 W) / W from those of X̃, W (:func:`rational_coefficients`; ``out[:, 3]`` keeps W).

    With L = J(m)⁻¹ and x0 = x(m), Dz(m) = I and z(m) = 0: the curvature bound of z gives
    ‖L (J(ξ) - J(m))‖∞ <= K_z |ξ - m|∞ directly (no factor ‖L‖, and |z| is small near m), as
    :func:`~.projection.injectivity_bound` does for polynomial maps.
    """
    for k in range(solid.n_nodes(code)):
        v0 = a[k, 0] - x0 * a[k, 3]
        v1 = a[k, 1] - x1 * a[k, 3]
        v2 = a[k, 2] - x2 * a[k, 3]
        out[k, 3] = a[k, 3]
        out[k, 0] = L[0, 0] * v0 + L[0, 1] * v1 + L[0, 2] * v2
        out[k, 1] = L[1, 0] * v0 + L[1, 1] * v1 + L[1, 2] * v2
        out[k, 2] = L[2, 0] * v0 + L[2, 1] * v1 + L[2, 2] * v2


@njit
def uniform_weights(code, X):
    """Whether the rational element's weights (column 3 of ``X``) are all equal: then its map is the
    polynomial Bernstein map, affine when its control points are."""
    for a in range(1, solid.n_nodes(code)):
        if X[a, 3] != X[0, 3]:
            return False
    return True


@njit
def linearisation_error(code, X, L, x0, x1, x2, radius, a, out):
    """ε (into ``out`` (3,)) of a rational Bézier hexahedron with local control points ``X[:, :3]`` and weights
    ``X[:, 3]`` > 0: for every ξ with |ξ - ξ_c|∞ <= ``radius`` (at least the element's radius), the linearised
    parameters ζ = ξ_c + L (x(ξ) - x_c) of its point (``L``: the inverse Jacobian at the centre, (x0, x1, x2) =
    x_c: the element's linearisation, :func:`~.projection.linear_maps`) satisfy |ζ_i - ξ_i| <= ε_i. Returns the
    lower bound of W used (ε NaN where it is not positive). ``a``: scratch (n_nodes, 4).

    With y = ξ - ξ_c, x = X̃ / W and Z = L (X̃ - x_c W) (:func:`normalise_coefficients`), ζ - ξ = (Z - y W) / W:
    the numerator is a polynomial whose coefficient of y^β in component i is Z_i's minus W's of y^(β - e_i)
    (``MONOMIAL_BELOW``), plus W's coefficients shifted past the type's monomials (``MONOMIAL_ABOVE`` false).
    Its constant and linear terms vanish up to round-off (Z(0) = 0, DZ(0) = W(0) I) and are kept in the sum,
    so |ζ_i - ξ_i| <= Σ_β |n_β,i| ρ^|β| / W_min on the box (ρ = ``radius``). W is bounded below by the better of
    its expansion about the centre (c_0 - Σ_{α≠0} |c_α| ρ^|α|) and its Bernstein coefficients: inside the
    element W >= min_a w_a, and a point of the box lies within ρ - r (r the element's radius) of the element in
    every direction, so W >= min_a w_a - (ρ - r) Σ_α |c_α| |α| ρ^(|α|-1) (the mean value theorem with the
    bound of Σ_j |∂_j W| of :mod:`this module <mortar1d3d.geometry.rational>`).
    """
    rational_coefficients(code, X, a)
    normalise_coefficients(code, a, L, x0, x1, x2, a)
    out[0] = out[1] = out[2] = 0.0
    w_centre = w_rest = w_slope = 0.0
    w_least = np.inf
    for k in range(solid.n_nodes(code)):
        w_least = min(w_least, X[k, 3])
        degree = solid.MONOMIALS[code, k, 0] + solid.MONOMIALS[code, k, 1] + solid.MONOMIALS[code, k, 2]
        scale = radius ** degree
        c = a[k, 3]
        if degree == 0:
            w_centre += c
        else:
            w_rest += abs(c) * scale
            w_slope += abs(c) * degree * radius ** (degree - 1)
        for i in range(3):
            v = a[k, i]
            below = solid.MONOMIAL_BELOW[code, k, i]
            if below >= 0:
                v -= a[below, 3]
            out[i] += abs(v) * scale
            if not solid.MONOMIAL_ABOVE[code, k, i]:
                out[i] += abs(c) * scale * radius
    w_min = max(w_centre - w_rest, w_least - (radius - solid.RADIUS[code]) * w_slope)
    if not w_min > 0.0:
        out[0] = out[1] = out[2] = np.nan
        return w_min
    out[0] /= w_min
    out[1] /= w_min
    out[2] /= w_min
    return w_min
