"""Per-code tables and the kernels' dispatch, derived from the registry of solid element types.

Everything here is computed from the descriptors listed in
:mod:`~mortar1d3d.elements.solid.registry`: the element types by integer code (nodes, family,
reference nodes, faces, centres, parameter boxes, line degrees, the axes of the affine check,
control-point and monomial tables) and the njit functions that pick an element type's shape
functions (or a family's inside test) by code. Nothing names a type or a family here.

Dispatching on an integer inside the kernels (rather than compiling one kernel per element
type) keeps one compiled version of every kernel, which Numba's on-disk cache can store. The
branches are unrolled over the registry's codes at compile time (:mod:`..selector`): the same
code as a hand-written ``if`` chain, generated from the list.
"""
import numpy as np
from numba import literal_unroll, types

from ..._config import njit, njit_inline
from ..selector import kernel_selector
from .registry import FAMILIES, LINKED_TYPES, SOLID_TYPES

SOLID_MODULES = {m.DESCRIPTOR.name: m for m in SOLID_TYPES}
SOLID_ELEMENTS = {name: m.DESCRIPTOR for name, m in SOLID_MODULES.items()}
#: the types whose nodes are points of the element (Lagrange interpolation): what meshes from files,
#: :func:`mortar1d3d.generate.box` and scenes' ``solid.mesh.element`` take (rational Bézier types come
#: from :mod:`mortar1d3d.nurbs`)
NODAL_ELEMENTS = {name: d for name, d in SOLID_ELEMENTS.items() if not d.rational}
BY_CODE = {d.code: d for d in SOLID_ELEMENTS.values()}
if sorted(BY_CODE) != list(range(len(SOLID_TYPES))) or [f.code for f in FAMILIES] != list(range(len(FAMILIES))):
    raise ImportError("solid element registry: codes must be 0, 1, 2, ... in registry order")
_N_CODES = len(BY_CODE)
MAX_NODES = max(d.n_nodes for d in SOLID_ELEMENTS.values())
MAX_FACES = max(f.n_faces for f in FAMILIES)

#: per code: number of nodes, family code, number of faces, degree of N along a straight line
N_NODES = np.array([BY_CODE[c].n_nodes for c in range(_N_CODES)], dtype=np.int64)
FAMILY = np.array([BY_CODE[c].family_type.code for c in range(_N_CODES)], dtype=np.int64)
N_FACES = np.array([BY_CODE[c].n_faces for c in range(_N_CODES)], dtype=np.int64)
LINE_DEGREE = np.array([BY_CODE[c].line_degree for c in range(_N_CODES)], dtype=np.int64)
#: per code: whether the type is rational (nodes carry weights; :func:`rational_shape`)
RATIONAL = np.array([BY_CODE[c].rational for c in range(_N_CODES)], dtype=np.bool_)
#: per code: whether its elements get hull planes (``SolidElementType.hull_test``)
HULL_TEST = np.array([BY_CODE[c].hull_test for c in range(_N_CODES)], dtype=np.bool_)


def _face_tables():
    """Per code: the face table (padded to MAX_FACES) and each face's centroid in parameter space."""
    faces = np.zeros((_N_CODES, MAX_FACES, 4, 3))
    centroids = np.zeros((_N_CODES, MAX_FACES, 3))
    for c, d in BY_CODE.items():
        faces[c, : d.n_faces] = d.faces
        centroids[c, : d.n_faces] = d.family_type.face_centroids
    return faces, centroids


#: per code: faces (origin, a, b, outward normal; padded) and their centroids (Newton starts)
FACES, FACE_CENTROIDS = _face_tables()


def _corner_tables():
    """Per code: the corner nodes of every face (padded with 0) and their number (0 for padding faces),
    and the number of corners of the element (its first nodes, in the family's VTK order)."""
    nodes = np.zeros((_N_CODES, MAX_FACES, 4), dtype=np.int64)
    count = np.zeros((_N_CODES, MAX_FACES), dtype=np.int64)
    corners = np.zeros(_N_CODES, dtype=np.int64)
    for c, d in BY_CODE.items():
        corners[c] = len(d.family_type.corners)
        for f, face in enumerate(d.family_type.face_nodes):
            nodes[c, f, : len(face)] = face
            count[c, f] = len(face)
    return nodes, count, corners


#: per code: corner nodes of every face (the family's ``face_nodes``, padded), their number, and the
#: element's number of corners (:func:`mortar1d3d.geometry.search.hull_planes` takes its planes from them)
FACE_CORNERS, N_FACE_CORNERS, N_CORNERS = _corner_tables()


def _axis_tables():
    """Per code: nodes a with ξ_a - ξ_0 along each parameter axis (the affine check) and that distance."""
    axes = np.zeros((_N_CODES, 3), dtype=np.int64)
    span = np.zeros((_N_CODES, 3))
    for c, d in BY_CODE.items():
        offsets = d.reference_nodes - d.reference_nodes[0]
        for i in range(3):
            along = np.flatnonzero((np.abs(np.delete(offsets, i, axis=1)) == 0).all(axis=1) & (offsets[:, i] > 0))
            if not len(along):
                raise ImportError(f"{d.name}: the affine check needs a node along each parameter axis from node 0")
            axes[c, i] = along[np.argmax(offsets[along, i])]
            span[c, i] = offsets[axes[c, i], i]
    return axes, span


#: per code and axis: the node spanning the parameter axis from node 0 and their distance (hex 1, 3, 4
#: at 2, 2, 2; tet 1, 2, 3 at 1, 1, 1), for the affine check of :mod:`mortar1d3d.geometry.projection`
AXIS_NODES, AXIS_SPAN = _axis_tables()
#: per code: reference node coordinates (padded)
REFERENCE_NODES = np.zeros((_N_CODES, MAX_NODES, 3))
for _c, _d in BY_CODE.items():
    REFERENCE_NODES[_c, : _d.n_nodes] = _d.reference_nodes


def _is_identity(d):
    return d.bounding_matrix.shape == (d.n_nodes, d.n_nodes) and np.array_equal(d.bounding_matrix, np.eye(d.n_nodes))


def _control_tables():
    """Per code: the bounding matrix (control points from nodes) and the control points of each face.

    The control points of a face are the rows of ``bounding_matrix`` that combine only nodes lying
    on that face (for Bernstein control points these are exactly the face's own control points,
    whose hull contains the face). Derived from the descriptors, so a new element type needs no
    entry here.
    """
    n_codes = len(BY_CODE)
    n_ctrl = np.array([BY_CODE[c].bounding_matrix.shape[0] for c in range(n_codes)], dtype=np.int64)
    identity = np.array([_is_identity(BY_CODE[c]) for c in range(n_codes)], dtype=np.bool_)
    # only the types whose control points are not their nodes read the matrix: it is as large as
    # theirs (Numba freezes a global array into the compiled code only below 1 MB; a larger one
    # would make every kernel that reads it uncachable)
    other = [BY_CODE[c] for c in range(n_codes) if not identity[c]] or [BY_CODE[0]]
    matrix = np.zeros((n_codes, max(d.bounding_matrix.shape[0] for d in other), max(d.n_nodes for d in other)))
    face_ctrl = np.zeros((n_codes, MAX_FACES, n_ctrl.max()), dtype=np.int64)
    face_count = np.zeros((n_codes, MAX_FACES), dtype=np.int64)
    for c, d in BY_CODE.items():
        T = d.bounding_matrix
        if not identity[c]:
            matrix[c, : T.shape[0], : d.n_nodes] = T
        for f, (origin, _a, _b, normal) in enumerate(d.faces):
            on_face = (d.reference_nodes - origin) @ normal == 0.0
            rows = [k for k in range(T.shape[0]) if np.all(on_face[T[k] != 0.0])]
            face_count[c, f] = len(rows)
            face_ctrl[c, f, : len(rows)] = rows
    return n_ctrl, matrix, identity, face_ctrl, face_count


#: per code: number of control points, bounding matrix (filled for the types whose control points are
#: not their nodes only), whether it is the identity (linear and rational Bézier elements: the control
#: points are the nodes), control points of each face and their number
N_CONTROL, CONTROL_MATRIX, CONTROL_IS_NODES, FACE_CONTROL, N_FACE_CONTROL = _control_tables()


def _sparse_rows(blocks):
    """The nonzero entries of one matrix per code, row by row and in column order within a row (the
    terms a dense row sum that skips zeros adds, in its order): per code the index of its first row
    pointer, the row pointers (row k of code c: entries ``rows[start[c] + k]`` up to
    ``rows[start[c] + k + 1]``), and every entry's column and value."""
    start = np.zeros(len(blocks), dtype=np.int64)
    rows, columns, values = [], [], []
    for c, block in enumerate(blocks):
        start[c] = len(rows)
        for row in block:
            rows.append(len(columns))
            nonzero = np.flatnonzero(row != 0.0)
            columns.extend(nonzero)
            values.extend(row[nonzero])
        rows.append(len(columns))
    return start, np.array(rows, dtype=np.int64), np.array(columns, dtype=np.int64), np.array(values)


#: the bounding matrices' nonzero entries (:func:`_sparse_rows`; identity types: none): what
#: :func:`control_points` sums, without testing the zeros of a quadratic type's matrix (hex27: 125
#: nonzero entries of 729, tet10: 22 of 100)
CONTROL_START, CONTROL_ROWS, CONTROL_COLUMNS, CONTROL_VALUES = _sparse_rows(
    [np.zeros((0, 0)) if CONTROL_IS_NODES[c] else BY_CODE[c].bounding_matrix for c in range(_N_CODES)])
#: the most control points of any type (the size of a buffer for :func:`control_points`)
MAX_CONTROL = int(N_CONTROL.max())


def _monomial_tables():
    """Per code: monomial exponents α, the matrix from nodes to the coefficients of x(ξ) = Σ_α a_α y^α
    with y = ξ - ξ_c (the element centre), and the parameter box and its max-norm radius about ξ_c.

    ``a = T @ X`` (nodes X, one row per node; T the code's n × n block of the flat ``TO_MONOMIAL``
    at ``MONOMIAL_START[code]``) inverts the Vandermonde matrix of the
    shape functions' space at the reference nodes; the geometry kernels bound derivatives of the
    map with these coefficients (:func:`mortar1d3d.geometry.projection.derivative_bounds`). For a
    rational type the matrix takes the Bernstein coefficients (w_a X_a, and w_a) of the homogeneous
    map instead of nodal values: its module's ``NODE_VALUES`` (B_a at the nodes) comes first.
    """
    n_codes = len(BY_CODE)
    exps = np.zeros((n_codes, MAX_NODES, 3), dtype=np.int64)
    # one n × n block per type, flat (a (codes, MAX_NODES, MAX_NODES) table would pass the 1 MB below
    # which Numba freezes a global array into cachable code)
    offset = np.zeros(n_codes + 1, dtype=np.int64)
    offset[1:] = np.cumsum([BY_CODE[c].n_nodes ** 2 for c in range(n_codes)])
    to_monomial = np.zeros(offset[-1])
    centre = np.zeros((n_codes, 3))
    box = np.zeros((n_codes, 2, 3))
    radius = np.zeros(n_codes)
    for c, d in BY_CODE.items():
        y = d.reference_nodes - d.centre
        vandermonde = np.prod(y[:, None, :] ** d.monomials[None, :, :], axis=2)     # [node, monomial]
        exps[c, : d.n_nodes] = d.monomials
        block = np.linalg.inv(vandermonde)
        if d.rational:
            block = block @ SOLID_MODULES[d.name].NODE_VALUES
        to_monomial[offset[c]: offset[c + 1]] = block.ravel()
        centre[c] = d.centre
        box[c] = d.parameter_box
        radius[c] = np.abs(y).max()
    return exps, to_monomial, offset[:-1].copy(), centre, box, radius


#: per code: monomial exponents, nodes → monomial coefficients about the centre (code c's n × n matrix,
#: row-major, at ``TO_MONOMIAL[MONOMIAL_START[c]:]``: entry (k, b) is ``TO_MONOMIAL[MONOMIAL_START[c] + k n + b]``),
#: the centre, the parameter box (lower, upper corner) and the max-norm radius of the element about its centre
MONOMIALS, TO_MONOMIAL, MONOMIAL_START, CENTRE, PARAMETER_BOX, RADIUS = _monomial_tables()
def _curved_monomials():
    """Per code: the number of monomials of total degree >= 2, their indices k (ascending) and degrees."""
    count = np.zeros(_N_CODES, dtype=np.int64)
    index = np.zeros((_N_CODES, MAX_NODES), dtype=np.int64)
    degree = np.zeros((_N_CODES, MAX_NODES), dtype=np.int64)
    for c, d in BY_CODE.items():
        total = np.asarray(d.monomials).sum(axis=1)
        curved = np.flatnonzero(total >= 2)
        count[c] = len(curved)
        index[c, : len(curved)] = curved
        degree[c, : len(curved)] = total[curved]
    return count, index, degree


#: per code: the monomials y^α with |α| >= 2 (the ones that bend the map, over which the derivative
#: bounds of :mod:`mortar1d3d.geometry.projection` sum): their number, indices k in ascending order
#: and degrees |α| (tet10: 6 of 10, hex27: 23 of 27)
N_CURVED, CURVED_MONOMIALS, CURVED_DEGREE = _curved_monomials()


def _bernstein_monomials():
    """Per code: for the types with ``bernstein_error``, the number of control points and the Bernstein
    coefficients on the reference element of every monomial y^α of degree >= 2 (row k: control point k of
    ``bounding_matrix``; column q: the monomial ``CURVED_MONOMIALS[code, q]``); 0 and zeros for the others.

    Every type's ``bounding_matrix`` takes the nodal values of a function of its space to its Bernstein
    coefficients (the nodes themselves for the linear types), whose range contains the function's on
    the element; a monomial's nodal values are y^α at the reference nodes, y = ξ - ξ_c.
    """
    chosen = [d for d in BY_CODE.values() if d.bernstein_error]
    for d in chosen:
        if d.rational:
            raise ImportError(f"{d.name}: the Bernstein error bound is for polynomial types")
    count = np.zeros(_N_CODES, dtype=np.int64)
    table = np.zeros((_N_CODES, max([d.bounding_matrix.shape[0] for d in chosen], default=1),
                      max([N_CURVED[d.code] for d in chosen], default=1)))
    for d in chosen:
        y = d.reference_nodes - d.centre
        curved = d.monomials[CURVED_MONOMIALS[d.code, : N_CURVED[d.code]]]
        values = np.prod(y[:, None, :] ** curved[None, :, :], axis=2)     # [node, curved monomial]
        coefficients = d.bounding_matrix @ values
        count[d.code] = coefficients.shape[0]
        table[d.code, : coefficients.shape[0], : coefficients.shape[1]] = coefficients
    return count, table


#: per code: the Bernstein coefficients of the curved monomials on the element (:func:`_bernstein_monomials`)
#: and their number of rows, 0 for the types without ``bernstein_error`` (tet10: 10 × 6), for the segmentation's
#: bound on the linearised map (:func:`mortar1d3d.geometry.segmentation._linear_error`)
N_BERNSTEIN, BERNSTEIN_MONOMIALS = _bernstein_monomials()
def _monomial_shifts():
    """Per code: the index of the monomial y^(α_k - e_i) of every monomial k and direction i (-1 if an
    exponent would be negative or the type has no such monomial), and whether y^(α_k + e_i) is one of the
    type's monomials."""
    below = np.full((_N_CODES, MAX_NODES, 3), -1, dtype=np.int64)
    above = np.zeros((_N_CODES, MAX_NODES, 3), dtype=np.bool_)
    for c, d in BY_CODE.items():
        index = {tuple(int(e) for e in alpha): k for k, alpha in enumerate(d.monomials)}
        for k, alpha in enumerate(d.monomials):
            for i in range(3):
                step = np.eye(3, dtype=np.int64)[i]
                below[c, k, i] = index.get(tuple(int(e) for e in np.asarray(alpha) - step), -1)
                above[c, k, i] = tuple(int(e) for e in np.asarray(alpha) + step) in index
    return below, above


#: per code: ``MONOMIAL_BELOW[c, k, i]`` the index of the monomial y^(α_k - e_i) (-1: none) and
#: ``MONOMIAL_ABOVE[c, k, i]`` whether y^(α_k + e_i) is a monomial of the type: how the coefficients of
#: y_i P(y) fall on the type's monomials (the rational types' linearisation error,
#: :func:`mortar1d3d.geometry.rational.linearisation_error`)
MONOMIAL_BELOW, MONOMIAL_ABOVE = _monomial_shifts()
#: the nonzero entries of every type's ``TO_MONOMIAL`` block (:func:`_sparse_rows`), for
#: :func:`monomial_coefficients` and, with the weights, :func:`mortar1d3d.geometry.rational.rational_coefficients`
#: (hex27 and nurbs27: 216 of 729 entries, tet10: 43 of 100)
MONOMIAL_SPARSE_START, MONOMIAL_ROWS, MONOMIAL_COLUMNS, MONOMIAL_VALUES = _sparse_rows(
    [TO_MONOMIAL[MONOMIAL_START[c]: MONOMIAL_START[c] + BY_CODE[c].n_nodes ** 2].reshape(BY_CODE[c].n_nodes, -1)
     for c in range(_N_CODES)])


def solid_element(name):
    """Descriptor of the solid element type called ``name`` (meshio name)."""
    try:
        return SOLID_ELEMENTS[name]
    except KeyError:
        raise ValueError(f"unknown solid element type {name!r}; known types: "
                         f"{', '.join(SOLID_ELEMENTS)}") from None


_CODES = tuple(range(len(SOLID_TYPES)))
_FAMILY_CODES = tuple(range(len(FAMILIES)))


#: ``_type_kernel(k, name)``: kernel ``name`` of the type with literal code k; ``_family_kernel``
#: likewise for families (resolved when a kernel is compiled, see :mod:`..selector`); the kernels of
#: types other than ``LINKED_TYPES`` are called through a symbol, not compiled into the caller, and
#: lazily: a type's kernels are compiled when a scene first evaluates an element of that type
_type_kernel = kernel_selector(SOLID_TYPES, linked=tuple(SOLID_TYPES.index(m) for m in LINKED_TYPES),
                               returns={"shape": types.none, "deriv": types.none})
_family_kernel = kernel_selector(FAMILIES)


# The dispatchers over the registry (``literal_unroll``) are never inlined at Numba IR level:
# inlined into a prange loop they stop Numba from parallelising it (the test suite turns that
# warning into an error). Table look-ups without a loop (n_nodes, centre) are inlined.
@njit
def shape(code, xi, N):
    """Shape function values of element type ``code`` at ``xi`` into ``N[:n_nodes]``."""
    for k in literal_unroll(_CODES):
        if k == code:
            _type_kernel(k, "shape")(xi, N)


@njit
def deriv(code, xi, dN):
    """Shape function derivatives of element type ``code`` at ``xi`` into ``dN[:n_nodes, :]``."""
    for k in literal_unroll(_CODES):
        if k == code:
            _type_kernel(k, "deriv")(xi, dN)


@njit_inline
def n_nodes(code):
    return N_NODES[code]


@njit
def outside_distance(code, xi):
    """How far ``xi`` lies outside the reference element (<= 0 inside, parameter units)."""
    family = FAMILY[code]
    distance = np.inf
    for k in literal_unroll(_FAMILY_CODES):
        if k == family:
            distance = _family_kernel(k, "outside_distance")(xi)
    return distance


@njit
def box_meets(code, m0, m1, m2, r, tol):
    """Whether the box |ξ - m|∞ <= r may meet the reference element of type ``code`` grown by ``tol``."""
    family = FAMILY[code]
    meets = True
    for k in literal_unroll(_FAMILY_CODES):
        if k == family:
            meets = _family_kernel(k, "box_meets")(m0, m1, m2, r, tol)
    return meets


@njit
def is_inside(code, xi, tol):
    return outside_distance(code, xi) <= tol


@njit
def faces(code):
    """Face table (n_faces, 4, 3) of element type ``code``: origin, a, b, outward normal."""
    return FACES[code, : N_FACES[code]]


@njit_inline
def centre(code, xi):
    """Write the parameter-space centre (Newton start) of type ``code`` into ``xi``."""
    xi[0], xi[1], xi[2] = CENTRE[code, 0], CENTRE[code, 1], CENTRE[code, 2]


@njit
def control_points(code, X, C):
    """Write the control points of an element with nodes ``X`` into ``C``; return their number.

    The element (and each face, with the points ``FACE_CONTROL[code, f]``) lies in their convex
    hull: nodes for linear elements, Bernstein control points for quadratic ones.
    """
    n = N_CONTROL[code]
    if CONTROL_IS_NODES[code]:
        for a in range(n):
            C[a, 0], C[a, 1], C[a, 2] = X[a, 0], X[a, 1], X[a, 2]
        return n
    _sparse_product(CONTROL_START[code], CONTROL_ROWS, CONTROL_COLUMNS, CONTROL_VALUES, n, X, C)
    return n


@njit
def monomial_coefficients(code, X, a):
    """Coefficients ``a[k]`` (3,) of the map x(ξ) = Σ_k a_k y^{α_k}, y = ξ - ξ_c, of a polynomial type's
    local nodes ``X``: ``TO_MONOMIAL``'s block times ``X``, its nonzero terms only."""
    _sparse_product(MONOMIAL_SPARSE_START[code], MONOMIAL_ROWS, MONOMIAL_COLUMNS, MONOMIAL_VALUES, N_NODES[code],
                    X, a)


@njit_inline
def _sparse_product(start, rows, columns, values, n, X, out):
    """out[k, :3] = Σ_b M[k, b] X[b, :3] for the first ``n`` rows of a matrix of :func:`_sparse_rows` (its rows
    from ``start``): the nonzero terms in column order, so the sums of a dense loop that skips zeros."""
    for k in range(n):
        v0 = v1 = v2 = 0.0
        for q in range(rows[start + k], rows[start + k + 1]):
            b = columns[q]
            w = values[q]
            v0 += w * X[b, 0]
            v1 += w * X[b, 1]
            v2 += w * X[b, 2]
        out[k, 0], out[k, 1], out[k, 2] = v0, v1, v2


@njit
def _divide_by_weight(n, N):
    """N[:n] holds w_a B_a: make it R_a = w_a B_a / W; returns W."""
    W = 0.0
    for a in range(n):
        W += N[a]
    inv = 1.0 / W
    for a in range(n):
        N[a] *= inv
    return W


@njit
def _quotient_rule(n, N, dN):
    """N[:n], dN[:n] hold w_a B_a and w_a ∂B_a: make them R_a and ∂R_a = (w_a ∂B_a - R_a ∂W) / W."""
    W0 = W1 = W2 = 0.0
    for a in range(n):
        W0 += dN[a, 0]
        W1 += dN[a, 1]
        W2 += dN[a, 2]
    W = _divide_by_weight(n, N)
    inv = 1.0 / W
    for a in range(n):
        dN[a, 0] = (dN[a, 0] - N[a] * W0) * inv
        dN[a, 1] = (dN[a, 1] - N[a] * W1) * inv
        dN[a, 2] = (dN[a, 2] - N[a] * W2) * inv
    return W


@njit
def rational_shape(code, xi, X, N):
    """The functions of element type ``code`` at ``xi`` into ``N``, rational ones with the node weights
    in column 3 of ``X`` (R_a = w_a B_a / W); returns W (1 for polynomial types)."""
    shape(code, xi, N)
    if not RATIONAL[code]:
        return 1.0
    for a in range(N_NODES[code]):
        N[a] *= X[a, 3]
    return _divide_by_weight(N_NODES[code], N)


@njit
def rational_deriv(code, xi, X, N, dN):
    """∂R_a/∂ξ_i of a rational type (weights in column 3 of ``X``) into ``dN``; ``N`` receives R_a.

    R_a = w_a B_a / W gives ∂R_a = (w_a ∂B_a - R_a ∂W) / W.
    """
    shape(code, xi, N)
    deriv(code, xi, dN)
    for a in range(N_NODES[code]):
        w = X[a, 3]
        N[a] *= w
        dN[a, 0] *= w
        dN[a, 1] *= w
        dN[a, 2] *= w
    return _quotient_rule(N_NODES[code], N, dN)


@njit
def weighted_values(code, nodes, points, N):
    """Turn the polynomial values ``N`` (from :func:`shape`) of a rational element with global node
    ids ``nodes`` into R_a = w_a B_a / W, weights ``points[node, 3]`` (the mesh's ``kernel_points``);
    polynomial types unchanged."""
    if not RATIONAL[code]:
        return
    for a in range(N_NODES[code]):
        N[a] *= points[nodes[a], 3]
    _divide_by_weight(N_NODES[code], N)


@njit
def weighted_derivatives(code, xi, nodes, points, N, dN):
    """∂N_a/∂ξ of element type ``code`` at ``xi`` into ``dN`` (``N`` receives the values), rational ones
    with the weights ``points[nodes[a], 3]`` (the mesh's ``kernel_points``)."""
    shape(code, xi, N)
    deriv(code, xi, dN)
    if not RATIONAL[code]:
        return
    for a in range(N_NODES[code]):
        w = points[nodes[a], 3]
        N[a] *= w
        dN[a, 0] *= w
        dN[a, 1] *= w
        dN[a, 2] *= w
    _quotient_rule(N_NODES[code], N, dN)
