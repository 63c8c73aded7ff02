"""Registry of solid element types and the kernels that dispatch on their integer code.

This is the only module that knows every solid element type. To add one: write its module
(``shape``, ``deriv``, ``DESCRIPTOR``), import it here, add it to ``SOLID_ELEMENTS`` and to the
``if`` chains below. ``tests/test_elements.py`` checks the chains against the registry.

Dispatching on an integer inside the kernels (rather than compiling one kernel per element
type) keeps one compiled version of every kernel, which Numba's on-disk cache can store.
"""
import numpy as np

from ..._config import njit
from . import hex8, hex20, hex27, tet4, tet10
from ._family import HEX, HEX_FACES, TET, TET_FACES, hex_outside_distance, tet_outside_distance

SOLID_MODULES = {m.DESCRIPTOR.name: m for m in (hex8, hex20, hex27, tet4, tet10)}
SOLID_ELEMENTS = {name: m.DESCRIPTOR for name, m in SOLID_MODULES.items()}
BY_CODE = {d.code: d for d in SOLID_ELEMENTS.values()}
MAX_NODES = max(d.n_nodes for d in SOLID_ELEMENTS.values())
MAX_FACES = 6

# per code: number of nodes, family
N_NODES = np.array([BY_CODE[c].n_nodes for c in range(len(BY_CODE))], dtype=np.int64)
FAMILY = np.array([HEX if BY_CODE[c].family == "hex" else TET for c in range(len(BY_CODE))], dtype=np.int64)


def _control_tables():
    """Per code: the bounding matrix (control points from nodes) and the control points of each face.

    The control points of a face are the rows of ``bounding_matrix`` that combine only nodes lying
    on that face (for Bernstein control points these are exactly the face's own control points,
    whose hull contains the face). Derived from the descriptors, so a new element type needs no
    entry here.
    """
    n_codes = len(BY_CODE)
    n_ctrl = np.array([BY_CODE[c].bounding_matrix.shape[0] for c in range(n_codes)], dtype=np.int64)
    matrix = np.zeros((n_codes, n_ctrl.max(), MAX_NODES))
    identity = np.zeros(n_codes, dtype=np.bool_)
    face_ctrl = np.zeros((n_codes, MAX_FACES, n_ctrl.max()), dtype=np.int64)
    face_count = np.zeros((n_codes, MAX_FACES), dtype=np.int64)
    for c, d in BY_CODE.items():
        T = d.bounding_matrix
        matrix[c, : T.shape[0], : d.n_nodes] = T
        identity[c] = T.shape == (d.n_nodes, d.n_nodes) and np.array_equal(T, np.eye(d.n_nodes))
        for f, (origin, _a, _b, normal) in enumerate(d.faces):
            on_face = (d.reference_nodes - origin) @ normal == 0.0
            rows = [k for k in range(T.shape[0]) if np.all(on_face[T[k] != 0.0])]
            face_count[c, f] = len(rows)
            face_ctrl[c, f, : len(rows)] = rows
    return n_ctrl, matrix, identity, face_ctrl, face_count


#: per code: number of control points, bounding matrix, whether it is the identity (linear
#: elements: the control points are the nodes), control points of each face and their number
N_CONTROL, CONTROL_MATRIX, CONTROL_IS_NODES, FACE_CONTROL, N_FACE_CONTROL = _control_tables()


def _monomial_tables():
    """Per code: monomial exponents α, the matrix from nodes to the coefficients of x(ξ) = Σ_α a_α y^α
    with y = ξ - ξ_c (the element centre), and the parameter box and its max-norm radius about ξ_c.

    ``a = TO_MONOMIAL[code] @ X`` (nodes X, one row per node) inverts the Vandermonde matrix of the
    shape functions' space at the reference nodes; the geometry kernels bound derivatives of the
    map with these coefficients (:func:`mortar1d3d.geometry.projection.derivative_bounds`).
    """
    n_codes = len(BY_CODE)
    exps = np.zeros((n_codes, MAX_NODES, 3), dtype=np.int64)
    to_monomial = np.zeros((n_codes, MAX_NODES, MAX_NODES))
    centre = np.zeros((n_codes, 3))
    box = np.zeros((n_codes, 2, 3))
    radius = np.zeros(n_codes)
    for c, d in BY_CODE.items():
        y = d.reference_nodes - d.centre
        vandermonde = np.prod(y[:, None, :] ** d.monomials[None, :, :], axis=2)     # [node, monomial]
        exps[c, : d.n_nodes] = d.monomials
        to_monomial[c, : d.n_nodes, : d.n_nodes] = np.linalg.inv(vandermonde)
        centre[c] = d.centre
        box[c] = d.parameter_box
        radius[c] = np.abs(y).max()
    return exps, to_monomial, centre, box, radius


#: per code: monomial exponents, nodes → monomial coefficients about the centre, the centre, the
#: parameter box (lower, upper corner) and the max-norm radius of the element about its centre
MONOMIALS, TO_MONOMIAL, CENTRE, PARAMETER_BOX, RADIUS = _monomial_tables()


def solid_element(name):
    """Descriptor of the solid element type called ``name`` (meshio name)."""
    try:
        return SOLID_ELEMENTS[name]
    except KeyError:
        raise ValueError(f"unknown solid element type {name!r}; known types: "
                         f"{', '.join(SOLID_ELEMENTS)}") from None


@njit
def shape(code, xi, N):
    """Shape function values of element type ``code`` at ``xi`` into ``N[:n_nodes]``."""
    if code == 0:
        hex8.shape(xi, N)
    elif code == 1:
        hex20.shape(xi, N)
    elif code == 2:
        hex27.shape(xi, N)
    elif code == 3:
        tet4.shape(xi, N)
    else:
        tet10.shape(xi, N)


@njit
def deriv(code, xi, dN):
    """Shape function derivatives of element type ``code`` at ``xi`` into ``dN[:n_nodes, :]``."""
    if code == 0:
        hex8.deriv(xi, dN)
    elif code == 1:
        hex20.deriv(xi, dN)
    elif code == 2:
        hex27.deriv(xi, dN)
    elif code == 3:
        tet4.deriv(xi, dN)
    else:
        tet10.deriv(xi, dN)


@njit
def n_nodes(code):
    return N_NODES[code]


@njit
def outside_distance(code, xi):
    """How far ``xi`` lies outside the reference element (<= 0 inside, parameter units)."""
    if FAMILY[code] == HEX:
        return hex_outside_distance(xi)
    return tet_outside_distance(xi)


@njit
def is_inside(code, xi, tol):
    return outside_distance(code, xi) <= tol


@njit
def faces(code):
    """Face table (n_faces, 4, 3) of element type ``code``: origin, a, b, outward normal."""
    if FAMILY[code] == HEX:
        return HEX_FACES
    return TET_FACES


@njit
def centre(code, xi):
    """Write the parameter-space centre (Newton start) of type ``code`` into ``xi``."""
    if FAMILY[code] == HEX:
        xi[0] = xi[1] = xi[2] = 0.0
    else:
        xi[0] = xi[1] = xi[2] = 0.25


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
    for k in range(n):
        v0 = v1 = v2 = 0.0
        for a in range(N_NODES[code]):
            w = CONTROL_MATRIX[code, k, a]
            if w != 0.0:
                v0 += w * X[a, 0]
                v1 += w * X[a, 1]
                v2 += w * X[a, 2]
        C[k, 0], C[k, 1], C[k, 2] = v0, v1, v2
    return n
