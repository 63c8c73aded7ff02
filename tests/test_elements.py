"""Element interpolations: solid shape functions, dispatch registry, beam centrelines, multipliers.

Everything is evaluated through the compiled (njit) kernels: ``dispatch.shape/deriv`` with the
type code, and each element module's own ``shape/deriv``.
"""
import importlib
import itertools

import numpy as np
import pytest
from meshio.gmsh.common import _gmsh_to_meshio_order

from mortar1d3d.elements import beam
from mortar1d3d.elements.beam import hermite, line2, line3, registry as beam_registry
from mortar1d3d.elements.solid import dispatch, hex8, hex20, hex27, tet4, tet10, wedge6
from mortar1d3d.elements.solid import registry

import naive

# ``mortar1d3d.elements.multiplier`` (the attribute) is the function re-exported by the package
# ``__init__``, which shadows the submodule of the same name: fetch the module itself.
multiplier = importlib.import_module("mortar1d3d.elements.multiplier")

NAMES = list(dispatch.NODAL_ELEMENTS)      # nurbs27 (rational Bézier): tests/test_nurbs_engine.py
QUADRATIC = [n for n in NAMES if dispatch.SOLID_ELEMENTS[n].degree == 2]
LINEAR = [n for n in NAMES if dispatch.SOLID_ELEMENTS[n].degree == 1]
TOL = 1e-9  # parameter tolerance of the inside test (docs/conventions.md §2)


def descriptor(name):
    return dispatch.SOLID_ELEMENTS[name]


def random_points(d, n, rng):
    """n points uniformly distributed inside the reference element of ``d``."""
    return naive.random_parameters(d.family, rng, n)


def shape_values(code, points):
    """(len(points), n_nodes) shape function values through ``dispatch.shape``."""
    n = dispatch.N_NODES[code]
    out = np.empty((len(points), n))
    N = np.empty(dispatch.MAX_NODES)
    for q, xi in enumerate(np.ascontiguousarray(points, dtype=np.float64)):
        dispatch.shape(code, xi, N)
        out[q] = N[:n]
    return out


def shape_derivatives(code, points):
    """(len(points), n_nodes, 3) derivatives through ``dispatch.deriv``."""
    n = dispatch.N_NODES[code]
    out = np.empty((len(points), n, 3))
    dN = np.empty((dispatch.MAX_NODES, 3))
    for q, xi in enumerate(np.ascontiguousarray(points, dtype=np.float64)):
        dispatch.deriv(code, xi, dN)
        out[q] = dN[:n]
    return out


def random_affine(rng):
    """A well-conditioned random affine map x = A ξ + b (det A > 0)."""
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(Q) < 0:
        Q[:, 0] *= -1
    A = Q @ np.diag(rng.uniform(0.5, 2.0, 3))
    return A, rng.normal(size=3)


def random_quadratic(rng):
    """Random quadratic map f: R^3 -> R^3 (all monomials of total degree <= 2) and its gradient."""
    c = rng.normal(size=3)
    B = rng.normal(size=(3, 3))
    C = rng.normal(size=(3, 3, 3))
    C = 0.5 * (C + C.transpose(0, 2, 1))

    def f(xi):
        xi = np.atleast_2d(xi)
        return c + xi @ B.T + np.einsum("kij,qi,qj->qk", C, xi, xi)

    def df(xi):
        xi = np.atleast_2d(xi)
        return B[None] + 2.0 * np.einsum("kij,qj->qki", C, xi)

    return f, df


# --------------------------------------------------------------------------------------------
# solid shape functions
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_partition_of_unity(name):
    d = descriptor(name)
    rng = np.random.default_rng(1)
    pts = np.vstack([random_points(d, 50, rng), d.reference_nodes, d.centre])
    N = shape_values(d.code, pts)
    dN = shape_derivatives(d.code, pts)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", NAMES)
def test_kronecker_property_at_reference_nodes(name):
    d = descriptor(name)
    N = shape_values(d.code, d.reference_nodes)
    np.testing.assert_allclose(N, np.eye(d.n_nodes), rtol=0, atol=1e-15)
    assert d.reference_nodes.shape == (d.n_nodes, 3)
    # nodes are distinct
    assert len({tuple(p) for p in d.reference_nodes}) == d.n_nodes


@pytest.mark.parametrize("name", NAMES)
def test_derivatives_against_central_differences(name):
    d = descriptor(name)
    rng = np.random.default_rng(2)
    pts = np.vstack([random_points(d, 20, rng), d.reference_nodes[:4]])
    h = 1e-6
    dN = shape_derivatives(d.code, pts)
    for q, xi in enumerate(pts):
        fd = np.empty((d.n_nodes, 3))
        for i in range(3):
            e = np.zeros(3)
            e[i] = h
            fd[:, i] = (shape_values(d.code, [xi + e])[0] - shape_values(d.code, [xi - e])[0]) / (2 * h)
        np.testing.assert_allclose(dN[q], fd, rtol=0, atol=1e-8, err_msg=f"{name} at xi={xi}")


@pytest.mark.parametrize("name", NAMES)
def test_linear_completeness(name):
    d = descriptor(name)
    rng = np.random.default_rng(3)
    A, b = random_affine(rng)
    X = d.reference_nodes @ A.T + b
    pts = random_points(d, 30, rng)
    N = shape_values(d.code, pts)
    dN = shape_derivatives(d.code, pts)
    np.testing.assert_allclose(N @ X, pts @ A.T + b, rtol=0, atol=1e-13)
    J = np.einsum("qai,ak->qki", dN, X)
    np.testing.assert_allclose(J, np.broadcast_to(A, J.shape), rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", QUADRATIC)
def test_quadratic_completeness(name):
    d = descriptor(name)
    rng = np.random.default_rng(4)
    f, df = random_quadratic(rng)
    X = f(d.reference_nodes)
    pts = random_points(d, 30, rng)
    N = shape_values(d.code, pts)
    dN = shape_derivatives(d.code, pts)
    np.testing.assert_allclose(N @ X, f(pts), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("qai,ak->qki", dN, X), df(pts), rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", LINEAR)
def test_linear_elements_do_not_reproduce_quadratics(name):
    # keeps the completeness test honest: a quadratic function is not interpolated exactly
    d = descriptor(name)
    xi = np.full((1, 3), 0.2)
    N = shape_values(d.code, xi)[0]
    assert abs(N @ d.reference_nodes[:, 0] ** 2 - 0.04) > 1e-3


@pytest.mark.parametrize("name, monomial, exact", [
    ("hexahedron20", (2, 1, 1), True),    # ξ²ηζ is in the serendipity space
    ("hexahedron20", (2, 2, 0), False),   # ξ²η² is not
    ("hexahedron27", (2, 2, 2), True),    # triquadratic
    ("tetra10", (1, 1, 1), False),        # ξηζ (cubic) is not
    ("wedge", (0, 1, 1), True),           # ξ2 ζ: linear on the triangle times linear in ζ
    ("wedge", (1, 1, 0), False),          # ξ1 ξ2 is not
    ("wedge", (0, 0, 2), False),          # nor ζ²
])
def test_interpolation_space(name, monomial, exact):
    d = descriptor(name)
    rng = np.random.default_rng(5)
    pts = random_points(d, 20, rng)
    g = lambda p: np.prod(p ** np.array(monomial), axis=-1)  # noqa: E731
    err = np.abs(shape_values(d.code, pts) @ g(d.reference_nodes) - g(pts)).max()
    assert (err < 1e-13) == exact, err


# gmsh reference nodes (https://gmsh.info/doc/texinfo/gmsh.html#Node-ordering), built as midpoints
_HEX_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=np.float64)
_TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
_GMSH_HEX_EDGES = [(0, 1), (0, 3), (0, 4), (1, 2), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 7),
                   (5, 6), (6, 7)]
_GMSH_HEX_FACES = [(0, 1, 2, 3), (0, 1, 5, 4), (0, 3, 7, 4), (1, 2, 6, 5), (2, 3, 7, 6), (4, 5, 6, 7)]
_GMSH_TET_EDGES = [(0, 1), (1, 2), (0, 2), (0, 3), (2, 3), (1, 3)]
# gmsh's prism: the triangle u, v >= 0, u + v <= 1 at w = -1, then at w = +1
_PRISM_CORNERS = np.array([[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=np.float64)


def _gmsh_reference_nodes(name):
    if name in ("hexahedron", "tetra", "wedge"):
        return {"hexahedron": _HEX_CORNERS, "tetra": _TET_CORNERS, "wedge": _PRISM_CORNERS}[name].copy()
    if name == "tetra10":
        sets = [(i,) for i in range(4)] + _GMSH_TET_EDGES
        corners = _TET_CORNERS
    else:
        sets = [(i,) for i in range(8)] + _GMSH_HEX_EDGES
        if name == "hexahedron27":
            sets += _GMSH_HEX_FACES + [tuple(range(8))]
        corners = _HEX_CORNERS
    return np.array([corners[list(s)].mean(axis=0) for s in sets])


@pytest.mark.parametrize("name", NAMES)
def test_node_order_matches_gmsh_through_meshio(name):
    d = descriptor(name)
    gmsh = _gmsh_reference_nodes(name)
    assert gmsh.shape == (d.n_nodes, 3)
    perm = _gmsh_to_meshio_order(name, np.arange(d.n_nodes)[None, :])[0]
    np.testing.assert_array_equal(gmsh[perm], d.reference_nodes)
    # spot checks of the VTK layout
    if name == "hexahedron27":
        np.testing.assert_array_equal(d.reference_nodes[20:], [[-1, 0, 0], [1, 0, 0], [0, -1, 0],
                                                              [0, 1, 0], [0, 0, -1], [0, 0, 1], [0, 0, 0]])
    if name == "tetra10":
        np.testing.assert_array_equal(d.reference_nodes[8], [0.5, 0, 0.5])   # edge (1, 3)
        np.testing.assert_array_equal(d.reference_nodes[9], [0, 0.5, 0.5])   # edge (2, 3)


def test_quadratic_nodes_extend_linear_nodes():
    np.testing.assert_array_equal(hex20.REFERENCE_NODES[:8], hex8.REFERENCE_NODES)
    np.testing.assert_array_equal(hex27.REFERENCE_NODES[:20], hex20.REFERENCE_NODES)
    np.testing.assert_array_equal(tet10.REFERENCE_NODES[:4], tet4.REFERENCE_NODES)


# --------------------------------------------------------------------------------------------
# reference geometry: inside test, faces
# --------------------------------------------------------------------------------------------
def _face_corner_params(d, f):
    return d.family_type.face_shapes[f].corners


def _face_centre(d, f):
    return dispatch.FACE_CENTROIDS[d.code, f]


@pytest.mark.parametrize("name", NAMES)
def test_is_inside(name):
    d = descriptor(name)
    code = d.code
    for xi in d.reference_nodes:
        assert dispatch.is_inside(code, xi, TOL), xi
        assert dispatch.outside_distance(code, xi) <= 1e-15
    assert dispatch.is_inside(code, d.centre.copy(), TOL)
    assert dispatch.outside_distance(code, d.centre.copy()) < -0.2
    for f, face in enumerate(d.faces):
        n = face[3] / np.linalg.norm(face[3])
        c = _face_centre(d, f)
        assert dispatch.is_inside(code, c, TOL)
        assert dispatch.is_inside(code, c - 1e-6 * n, TOL)
        assert not dispatch.is_inside(code, c + 1e-6 * n, TOL), (face, c + 1e-6 * n)
        assert dispatch.is_inside(code, c + 0.5 * TOL * n, TOL)
        assert not dispatch.is_inside(code, c + 0.5 * TOL * n, 0.0)
    # far outside in every direction
    for direction in itertools.product((-1, 0, 1), repeat=3):
        if any(direction):
            assert not dispatch.is_inside(code, d.centre + 2.0 * np.array(direction, float), TOL)


@pytest.mark.parametrize("name", NAMES)
def test_centre(name):
    d = descriptor(name)
    xi = np.full(3, np.nan)
    dispatch.centre(d.code, xi)
    np.testing.assert_array_equal(xi, d.centre)
    # the centre is the centroid of the corner nodes
    n_corners = len(d.family_type.corners)
    np.testing.assert_allclose(d.centre, d.reference_nodes[:n_corners].mean(axis=0), atol=1e-15)


@pytest.mark.parametrize("name", NAMES)
def test_faces(name):
    d = descriptor(name)
    faces = dispatch.faces(d.code)
    np.testing.assert_array_equal(faces, d.faces)
    assert d.n_faces == len(d.family_type.face_shapes) == len(d.face_nodes)
    assert d.faces.shape == (d.n_faces, 4, 3)
    corner_sets = set()
    for f, (face, nodes) in enumerate(zip(d.faces, d.face_nodes)):
        origin, a, b, n = face
        shape = d.family_type.face_shapes[f]
        hits = []
        for u, v in _face_corner_params(d, f):
            p = origin + u * a + v * b
            match = np.flatnonzero(np.all(d.reference_nodes == p, axis=1))
            assert len(match) == 1, (face, p)
            hits.append(int(match[0]))
        assert set(hits) == set(nodes), (hits, nodes)
        assert hits == list(nodes)     # same cyclic order as the parameter corners
        corner_sets.add(frozenset(nodes))
        # normal: orthogonal to the face, pointing away from the centre
        assert abs(n @ a) < 1e-15 and abs(n @ b) < 1e-15
        assert n @ (d.centre - origin) < 0
        # every reference node is on the inner side or on the face
        side = (d.reference_nodes - origin) @ n
        assert np.all(side <= 1e-15)
        # the nodes on the face plane are those of that face (corners + mid-edge/face nodes): their
        # face parameters lie in the face's shape (on its corners, edges or inside), the functions of
        # the other nodes vanish on the face and those of the face's nodes are independent there
        # (the face is determined by its own nodes: conforming neighbours)
        on = np.flatnonzero(np.abs(side) <= 1e-15)
        assert set(nodes) <= set(on.tolist())
        uv = np.linalg.lstsq(np.column_stack([a, b]), (d.reference_nodes[on] - origin).T, rcond=None)[0].T
        corners = shape.corners
        for k in range(len(corners)):
            edge, to = corners[(k + 1) % len(corners)] - corners[k], uv - corners[k]
            assert np.all(edge[0] * to[:, 1] - edge[1] * to[:, 0] >= -1e-15)     # left of every edge
        weights = np.random.default_rng(f).dirichlet(np.ones(len(corners)), 40)   # points of the face
        N = shape_values(d.code, origin + (weights @ corners) @ np.stack([a, b]))
        off = np.setdiff1d(np.arange(d.n_nodes), on)
        assert np.abs(N[:, off]).max(initial=0.0) <= 1e-14
        assert np.linalg.matrix_rank(N[:, on], tol=1e-10) == len(on)
    assert len(corner_sets) == d.n_faces    # all faces distinct


# --------------------------------------------------------------------------------------------
# bounding matrix (convex hull of the mapped element)
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", LINEAR)
def test_bounding_matrix_linear_is_identity(name):
    d = descriptor(name)
    rng = np.random.default_rng(6)
    A, b = random_affine(rng)
    X = d.reference_nodes @ A.T + b + 0.1 * rng.normal(size=(d.n_nodes, 3))
    np.testing.assert_array_equal(d.bounding_matrix @ X, X)


@pytest.mark.parametrize("name", NAMES)
def test_bounding_matrix_rows_are_affine_combinations(name):
    d = descriptor(name)
    assert d.bounding_matrix.shape[1] == d.n_nodes
    np.testing.assert_allclose(d.bounding_matrix.sum(axis=1), 1.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("name, lattice", [("hexahedron20", hex27.REFERENCE_NODES),
                                           ("hexahedron27", hex27.REFERENCE_NODES),
                                           ("tetra10", tet10.REFERENCE_NODES)])
def test_bounding_matrix_of_affine_element_is_node_lattice(name, lattice):
    # Bernstein control points of an affine map are the images of the equally spaced lattice
    d = descriptor(name)
    rng = np.random.default_rng(7)
    A, b = random_affine(rng)
    X = d.reference_nodes @ A.T + b
    np.testing.assert_allclose(d.bounding_matrix @ X, lattice @ A.T + b, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", QUADRATIC)
def test_bounding_matrix_contains_curved_element(name):
    d = descriptor(name)
    rng = np.random.default_rng(8)
    for _ in range(2):
        A, b = random_affine(rng)
        f, _df = random_quadratic(rng)
        X = d.reference_nodes @ A.T + b + 0.15 * f(d.reference_nodes)
        X += 0.05 * rng.normal(size=X.shape)     # any nodal values: still a quadratic map
        P = d.bounding_matrix @ X
        lo, hi = P.min(axis=0), P.max(axis=0)
        pts = np.vstack([random_points(d, 2000, rng), d.reference_nodes])
        x = shape_values(d.code, pts) @ X
        assert np.all(x >= lo - 1e-12) and np.all(x <= hi + 1e-12)
        # the box is not absurdly loose: it is within the nodes' box grown by the element size
        size = np.ptp(X, axis=0).max()
        assert np.all(lo >= X.min(axis=0) - size) and np.all(hi <= X.max(axis=0) + size)


# --------------------------------------------------------------------------------------------
# dispatch chains vs the registry
# --------------------------------------------------------------------------------------------
def test_registry_codes_and_sizes():
    codes = sorted(d.code for d in dispatch.SOLID_ELEMENTS.values())
    assert codes == list(range(len(dispatch.SOLID_ELEMENTS)))
    assert set(dispatch.BY_CODE) == set(codes)
    assert dispatch.MAX_NODES == max(d.n_nodes for d in dispatch.SOLID_ELEMENTS.values()) == 125
    assert set(NAMES) == {"hexahedron", "hexahedron20", "hexahedron27", "tetra", "tetra10", "wedge"}
    for name, d in dispatch.SOLID_ELEMENTS.items():
        assert d.name == name
        assert dispatch.SOLID_MODULES[name].DESCRIPTOR is d
        assert dispatch.BY_CODE[d.code] is d
        assert dispatch.N_NODES[d.code] == d.n_nodes
        assert dispatch.n_nodes(d.code) == d.n_nodes
        assert registry.FAMILIES[dispatch.FAMILY[d.code]] is d.family_type
        assert dispatch.solid_element(name) is d
        assert d.dim == 3
    expected = {"hexahedron": (8, 1, "hex"), "hexahedron20": (20, 2, "hex"), "hexahedron27": (27, 2, "hex"),
                "tetra": (4, 1, "tet"), "tetra10": (10, 2, "tet"), "wedge": (6, 1, "wedge"), "nurbs27": (27, 2, "hex"),
                "nurbs64": (64, 3, "hex"), "nurbs125": (125, 4, "hex")}
    assert {n: (d.n_nodes, d.degree, d.family) for n, d in dispatch.SOLID_ELEMENTS.items()} == expected


def test_registry_lists_are_in_code_order():
    assert [m.DESCRIPTOR.code for m in registry.SOLID_TYPES] == list(range(len(registry.SOLID_TYPES)))
    assert [f.code for f in registry.FAMILIES] == list(range(len(registry.FAMILIES)))
    assert {f.name for f in registry.FAMILIES} == {"hex", "tet", "wedge"}
    for d in dispatch.SOLID_ELEMENTS.values():
        assert d.family_type in registry.FAMILIES
        np.testing.assert_array_equal(d.reference_nodes[: len(d.family_type.corners)], d.family_type.corners)


def _line_degree_by_sampling(d, rng, lines=6, samples=15):
    """Degree in η of N_a(ξ(η)) along random straight lines ξ(η) = c + η v, found by fitting: the
    smallest degree whose least-squares polynomial reproduces every N_a to round-off."""
    eta = np.linspace(-1.0, 1.0, samples)
    N = np.empty(d.n_nodes)
    worst = 0
    for _ in range(lines):
        c, v = d.centre + 0.1 * rng.normal(size=3), rng.normal(size=3)
        values = np.empty((samples, d.n_nodes))
        for q, e in enumerate(eta):
            dispatch.shape(d.code, c + 0.2 * e * v, N)
            values[q] = N[: d.n_nodes]
        for degree in range(samples - 1):
            fit = np.polynomial.polynomial.polyfit(eta, values, degree)
            if np.abs(np.polynomial.polynomial.polyval(eta, fit).T - values).max() < 1e-11:
                break
        worst = max(worst, degree)
    return worst


@pytest.mark.parametrize("name", NAMES)
def test_line_degree_table_matches_the_shape_functions(name):
    # what the exact Gauss counts of integration="auto" rely on, found from the kernels themselves
    d = descriptor(name)
    assert dispatch.LINE_DEGREE[d.code] == d.line_degree == _line_degree_by_sampling(d, np.random.default_rng(3))


def _monomial_integral(d, alpha):
    """Integral of ξ^alpha over the family's domain, exact to round-off for degrees up to 13
    (:func:`naive.domain_rule`)."""
    points, weights = naive.domain_rule(d.family)
    return weights @ np.prod(points ** np.asarray(alpha), axis=1)


@pytest.mark.parametrize("name", NAMES)
def test_volume_rule_integrates_the_reference_stiffness_exactly(name):
    # K_ab = ∫ ∇N_a · ∇N_b dξ on the reference element, integrated exactly through the monomial
    # expansion of the shape functions, against the descriptor's quadrature (the solid model's rule)
    from mortar1d3d.physics.solid import RULES
    d = descriptor(name)
    exps = d.monomials
    coefficients = np.linalg.inv(np.prod(d.reference_nodes[:, None, :] ** exps[None, :, :], axis=2))  # [monomial, node]
    exact = np.zeros((d.n_nodes, d.n_nodes))
    for i in range(3):
        for m1, e1 in enumerate(exps):
            for m2, e2 in enumerate(exps):
                if e1[i] == 0 or e2[i] == 0:
                    continue
                alpha = e1 + e2 - 2 * np.eye(3, dtype=np.int64)[i]
                exact += e1[i] * e2[i] * _monomial_integral(d, alpha) * np.outer(coefficients[m1], coefficients[m2])
    points, weights = d.quadrature
    assert RULES[d.code] is d.quadrature
    dN = np.empty((dispatch.MAX_NODES, 3))
    K = np.zeros((d.n_nodes, d.n_nodes))
    for xi, w in zip(points, weights):
        dispatch.deriv(d.code, np.array(xi), dN)
        K += w * dN[: d.n_nodes] @ dN[: d.n_nodes].T
    np.testing.assert_allclose(K, exact, atol=1e-13 * np.abs(exact).max())


@pytest.mark.parametrize("name", NAMES)
def test_derived_face_and_axis_tables(name):
    d = descriptor(name)
    for f, nodes in enumerate(d.face_nodes):
        # the centroid of a face (a Newton start of the crossing search) is the mean of its corners
        np.testing.assert_allclose(dispatch.FACE_CENTROIDS[d.code, f], d.reference_nodes[list(nodes)].mean(axis=0),
                                   atol=1e-15)
    for i in range(3):
        offset = d.reference_nodes[dispatch.AXIS_NODES[d.code, i]] - d.reference_nodes[0]
        np.testing.assert_array_equal(offset, dispatch.AXIS_SPAN[d.code] * np.eye(3)[i])


@pytest.mark.parametrize("name", NAMES)
def test_box_meets_never_misses_the_domain(name):
    # the point search discards a box only where it misses the element: sample each discarded box
    d = descriptor(name)
    rng = np.random.default_rng(5)
    tol = 1e-9
    for _ in range(400):
        m, r = rng.uniform(-1.5, 1.5, 3), rng.uniform(0.01, 0.5)
        if dispatch.box_meets(d.code, m[0], m[1], m[2], r, tol):
            continue
        samples = m + r * rng.uniform(-1.0, 1.0, (200, 3))
        samples = np.vstack([samples, m + r * np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T])
        assert all(dispatch.outside_distance(d.code, x) > tol for x in samples), (m, r)


def test_solid_element_unknown_name():
    with pytest.raises(ValueError, match="unknown solid element type 'pyramid'.*hexahedron"):
        dispatch.solid_element("pyramid")


@pytest.mark.parametrize("name", NAMES)
def test_dispatch_equals_module_kernels(name):
    d = descriptor(name)
    module = dispatch.SOLID_MODULES[name]
    rng = np.random.default_rng(9)
    for xi in random_points(d, 10, rng):
        # dispatch writes exactly n_nodes entries
        N = np.full(dispatch.MAX_NODES, np.nan)
        dN = np.full((dispatch.MAX_NODES, 3), np.nan)
        dispatch.shape(d.code, xi, N)
        dispatch.deriv(d.code, xi, dN)
        assert np.all(np.isnan(N[d.n_nodes:])) and np.all(np.isnan(dN[d.n_nodes:]))
        # the module's own compiled kernels
        Nm = np.empty(d.n_nodes)
        dNm = np.empty((d.n_nodes, 3))
        module.shape(xi, Nm)
        module.deriv(xi, dNm)
        np.testing.assert_array_equal(N[:d.n_nodes], Nm)
        np.testing.assert_array_equal(dN[:d.n_nodes], dNm)
        # and the pure-Python versions (used by mesh validation) agree
        Np = np.empty(d.n_nodes)
        dNp = np.empty((d.n_nodes, 3))
        module.shape.py_func(xi, Np)
        module.deriv.py_func(xi, dNp)
        np.testing.assert_allclose(Np, Nm, rtol=0, atol=1e-15)
        np.testing.assert_allclose(dNp, dNm, rtol=0, atol=1e-14)


def test_hex8_closed_form():
    xi = np.array([0.3, -0.7, 0.1])
    N = np.empty(8)
    hex8.shape(xi, N)
    assert N[6] == pytest.approx(0.125 * 1.3 * 0.3 * 1.1, abs=1e-16)
    assert N[0] == pytest.approx(0.125 * 0.7 * 1.7 * 0.9, abs=1e-16)


def test_wedge6_closed_form():
    # N_a = L_a (1 - ζ)/2, N_a+3 = L_a (1 + ζ)/2 with L = (1 - ξ1 - ξ2, ξ1, ξ2), written out
    xi = np.array([0.2, 0.5, -0.4])
    N, dN = np.empty(6), np.empty((6, 3))
    wedge6.shape(xi, N)
    wedge6.deriv(xi, dN)
    np.testing.assert_allclose(N, [0.3 * 0.7, 0.2 * 0.7, 0.5 * 0.7, 0.3 * 0.3, 0.2 * 0.3, 0.5 * 0.3],
                               rtol=0, atol=1e-16)
    np.testing.assert_allclose(dN, [[-0.7, -0.7, -0.15], [0.7, 0, -0.1], [0, 0.7, -0.25],
                                    [-0.3, -0.3, 0.15], [0.3, 0, 0.1], [0, 0.3, 0.25]], rtol=0, atol=1e-16)


def test_wedge_family_by_hand():
    d = dispatch.SOLID_ELEMENTS["wedge"]
    f = d.family_type
    # two triangles (ζ = ∓1) and three quadrilaterals, each face's shape and node count its own
    assert [s.name for s in f.face_shapes] == ["triangle"] * 2 + ["quadrilateral"] * 3
    np.testing.assert_allclose(dispatch.FACE_CENTROIDS[d.code, :5], [[1 / 3, 1 / 3, -1], [1 / 3, 1 / 3, 1],
                                                                     [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0]])
    # spans of the affine check differ per axis: ξ1, ξ2 from 0 to 1, ζ from -1 to 1
    np.testing.assert_array_equal(dispatch.AXIS_NODES[d.code], [1, 2, 3])
    np.testing.assert_array_equal(dispatch.AXIS_SPAN[d.code], [1.0, 1.0, 2.0])
    # det J: columns ∂x/∂ξ1, ∂x/∂ξ2 ∈ P0 ⊗ P1 and ∂x/∂ζ ∈ P1 ⊗ P0, so det J ∈ P1(ξ1, ξ2) ⊗ P2(ζ)
    assert d.jacobian_degree == (1, 2)
    assert d.line_degree == 2
    assert dispatch.outside_distance(d.code, np.array([0.5, 0.5, 0.0])) == 0.0
    assert dispatch.outside_distance(d.code, np.array([0.2, 0.2, 1.5])) == 0.5
    assert dispatch.outside_distance(d.code, np.array([0.7, 0.5, 0.0])) == pytest.approx(0.2, abs=1e-15)
    # two wedges fill a grid cell, over the halves of its bottom square
    np.testing.assert_array_equal(f.cube_split[:, :3, :2], [[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]])


def test_tet10_closed_form():
    xi = np.array([0.2, 0.3, 0.1])
    L = np.array([0.4, 0.2, 0.3, 0.1])
    N = np.empty(10)
    tet10.shape(xi, N)
    np.testing.assert_allclose(N[:4], L * (2 * L - 1), atol=1e-16)
    np.testing.assert_allclose(N[4:], 4 * np.array([L[0] * L[1], L[1] * L[2], L[0] * L[2],
                                                    L[0] * L[3], L[1] * L[3], L[2] * L[3]]), atol=1e-16)


@pytest.mark.parametrize("name", ["hexahedron27", "tetra10"])
def test_newton_kernels_equal_the_node_sums(name):
    """The map and Jacobian the Newton path uses on hex27 and tet10 (``projection.map_point`` /
    ``jacobian``: the types' own contractions, which never form the shape functions) equal
    Σ_a N_a X_a and Σ_a X_a ⊗ ∇N_a of the registry's shape functions to round-off, on random
    curved elements, at ξ inside and beyond the element (the Newton iterates go there); and they
    reproduce a quadratic map x(ξ) (in both types' spaces) with its gradient exactly up to round-off."""
    from mortar1d3d.geometry import projection as pr

    d = descriptor(name)
    n = d.n_nodes
    rng = np.random.default_rng(27)
    X, N, dN, _, _, _, _ = pr.point_buffers()
    N_ref, dN_ref = np.empty(n), np.empty((n, 3))
    for _ in range(20):
        X[:n, :3] = d.reference_nodes + rng.uniform(-0.3, 0.3, (n, 3))
        X[:n, :3] -= X[0, :3]           # local coordinates, node 0 at the origin, as the kernels get them
        scale = np.abs(X[:n, :3]).max()
        for xi in rng.uniform(-1.5, 1.5, (10, 3)):
            dispatch.shape(d.code, xi, N_ref)
            dispatch.deriv(d.code, xi, dN_ref)
            np.testing.assert_allclose(pr.map_point(d.code, X, xi, N), N_ref @ X[:n, :3], rtol=0,
                                       atol=1e-14 * scale)
            np.testing.assert_allclose(np.reshape(pr.jacobian(d.code, X, xi, N, dN), (3, 3)), X[:n, :3].T @ dN_ref,
                                       rtol=0, atol=1e-14 * scale)

    # x(ξ) = (1 + ξ0 ξ1, ξ2² - 2 ξ0, 3 ξ1 + ξ0 ξ2): quadratic with only mixed and pure squares that both
    # spaces hold; nodes x(ξ_a) reproduce it and its gradient
    def f(z):
        return np.array([1 + z[0] * z[1], z[2] ** 2 - 2 * z[0], 3 * z[1] + z[0] * z[2]])

    def grad(z):
        return np.array([[z[1], z[0], 0.0], [-2.0, 0.0, 2 * z[2]], [z[2], 3.0, z[0]]])

    for a in range(n):
        X[a, :3] = f(d.reference_nodes[a])
    for xi in rng.uniform(-1.0, 1.0, (10, 3)):
        np.testing.assert_allclose(pr.map_point(d.code, X, xi, N), f(xi), rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.reshape(pr.jacobian(d.code, X, xi, N, dN), (3, 3)), grad(xi), rtol=0,
                                   atol=1e-14)


# --------------------------------------------------------------------------------------------
# Lagrange multiplier functions
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["line2", "line3", "line4"])
def test_multiplier_functions(name):
    m = multiplier.multiplier(name)
    n = m.n_functions
    assert n == {"line2": 2, "line3": 3, "line4": 4}[name]
    assert m.n_interior == n - 2
    np.testing.assert_allclose(m.nodes, {"line2": [-1, 1], "line3": [-1, 1, 0],
                                         "line4": [-1, 1, -1 / 3, 1 / 3]}[name], atol=1e-16)
    Phi = np.full(multiplier.MAX_FUNCTIONS, np.nan)
    values = np.empty((n, n))
    for k, eta in enumerate(m.nodes):
        multiplier.shape(n, eta, Phi)
        values[k] = Phi[:n]
    np.testing.assert_allclose(values, np.eye(n), rtol=0, atol=1e-15)
    assert np.all(np.isnan(Phi[n:]))
    etas = np.linspace(-1, 1, 17)
    V = np.empty((len(etas), n))
    for k, eta in enumerate(etas):
        multiplier.shape(n, eta, Phi)
        V[k] = Phi[:n]
    np.testing.assert_allclose(V.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    # reproduces polynomials of degree n - 1
    coeffs = np.array([-0.2, 0.7, -1.1, 0.3])[-n:]
    np.testing.assert_allclose(V @ np.polyval(coeffs, m.nodes), np.polyval(coeffs, etas), rtol=0, atol=1e-13)


def test_multiplier_unknown_name():
    assert set(multiplier.MULTIPLIERS) == {"line2", "line3", "line4"}
    with pytest.raises(ValueError, match="unknown Lagrange multiplier type 'line5'"):
        multiplier.multiplier("line5")


# --------------------------------------------------------------------------------------------
# beam centrelines
# --------------------------------------------------------------------------------------------
def _hermite(eta, L):
    H = np.empty(4)
    dH = np.empty(4)
    hermite.shape(eta, L, H)
    hermite.deriv(eta, L, dH)
    return H, dH


def test_hermite_closed_form():
    eta, L = 0.37, 2.3
    H, _ = _hermite(eta, L)
    expected = [(2 - 3 * eta + eta ** 3) / 4, L / 8 * (1 - eta - eta ** 2 + eta ** 3),
                (2 + 3 * eta - eta ** 3) / 4, L / 8 * (-1 - eta + eta ** 2 + eta ** 3)]
    np.testing.assert_allclose(H, expected, rtol=1e-15, atol=0)


def test_hermite_derivative_against_central_differences():
    h = 1e-6
    for L in (0.1, 1.0, 3.7):
        for eta in np.linspace(-1, 1, 9):
            _, dH = _hermite(eta, L)
            fd = (_hermite(eta + h, L)[0] - _hermite(eta - h, L)[0]) / (2 * h)
            np.testing.assert_allclose(dH, fd, rtol=0, atol=1e-8 * max(L, 1))


def test_hermite_interpolates_positions_and_tangents():
    rng = np.random.default_rng(10)
    r1, r2 = rng.normal(size=3), rng.normal(size=3)
    t1, t2 = rng.normal(size=3), rng.normal(size=3)
    t1 /= np.linalg.norm(t1)
    t2 /= np.linalg.norm(t2)
    L = 1.7
    Q = np.array([r1, t1, r2, t2])
    H, dH = _hermite(-1.0, L)
    np.testing.assert_allclose(H @ Q, r1, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dH @ Q, 0.5 * L * t1, rtol=0, atol=1e-15)
    H, dH = _hermite(1.0, L)
    np.testing.assert_allclose(H @ Q, r2, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dH @ Q, 0.5 * L * t2, rtol=0, atol=1e-15)
    # a straight segment with L = chord is parametrised at constant speed L/2
    t = (r2 - r1) / np.linalg.norm(r2 - r1)
    c = np.linalg.norm(r2 - r1)
    Q = np.array([r1, t, r2, t])
    for eta in np.linspace(-1, 1, 7):
        H, dH = _hermite(eta, c)
        np.testing.assert_allclose(H @ Q, r1 + 0.5 * (1 + eta) * (r2 - r1), rtol=0, atol=1e-14)
        np.testing.assert_allclose(dH @ Q, 0.5 * (r2 - r1), rtol=0, atol=1e-14)


def test_lagrange_kronecker_and_derivatives():
    H = np.empty(3)
    dH = np.empty(3)
    for k, eta in enumerate((-1.0, 1.0)):
        line2.shape(eta, 1.0, H)
        np.testing.assert_array_equal(H[:2], np.eye(2)[k])
    for k, eta in enumerate((-1.0, 1.0, 0.0)):
        line3.shape(eta, 1.0, H)
        np.testing.assert_array_equal(H, np.eye(3)[k])
    h = 1e-6
    Hp, Hm = np.empty(3), np.empty(3)
    for eta in np.linspace(-1, 1, 9):
        line2.deriv(eta, 1.0, dH)
        line2.shape(eta + h, 1.0, Hp)
        line2.shape(eta - h, 1.0, Hm)
        np.testing.assert_allclose(dH[:2], (Hp[:2] - Hm[:2]) / (2 * h), rtol=0, atol=1e-8)
        line3.deriv(eta, 1.0, dH)
        line3.shape(eta + h, 1.0, Hp)
        line3.shape(eta - h, 1.0, Hm)
        np.testing.assert_allclose(dH, (Hp - Hm) / (2 * h), rtol=0, atol=1e-8)
        line3.shape(eta, 1.0, H)
        assert H.sum() == pytest.approx(1.0, abs=1e-15)


BEAM_NAMES = list(beam.BEAM_ELEMENTS)


@pytest.mark.parametrize("name", BEAM_NAMES)
def test_beam_second_derivatives_against_central_differences(name):
    et = beam.beam_element(name)
    n = et.n_functions
    h = 1e-5
    dHp, dHm, ddH = np.empty(n), np.empty(n), np.empty(n)
    for L in (0.3, 2.1):
        for eta in np.linspace(-1, 1, 7):
            beam.deriv2(et.code, eta, L, ddH)
            beam.deriv(et.code, eta + h, L, dHp)
            beam.deriv(et.code, eta - h, L, dHm)
            np.testing.assert_allclose(ddH, (dHp - dHm) / (2 * h), rtol=0, atol=1e-8 * max(L, 1))


@pytest.mark.parametrize("name", BEAM_NAMES)
def test_beam_degree_matches_the_functions(name):
    # the exact Gauss counts of integration="auto" take the centreline degree from the descriptor:
    # fit the functions (L = 1.7) with polynomials and find the smallest degree that reproduces them
    et = beam.beam_element(name)
    eta = np.linspace(-1.0, 1.0, 11)
    H = beam.evaluate(et, eta, 1.7)[:, : et.n_functions]
    degree = next(p for p in range(10)
                  if np.abs(np.polynomial.polynomial.polyval(eta, np.polynomial.polynomial.polyfit(eta, H, p)).T
                            - H).max() < 1e-13)
    assert degree == et.degree == beam.DEGREE[et.code]


@pytest.mark.parametrize("name", BEAM_NAMES)
@pytest.mark.parametrize("order", [0, 1, 2])
def test_beam_evaluate_has_the_kernels_bits(name, order):
    et = beam.beam_element(name)
    eta = np.linspace(-1.0, 1.0, 13)
    lengths = np.array([0.4, 1.0, 2.7])
    table = beam.evaluate(et, eta[None, :], lengths[:, None], derivative=order)
    assert table.shape == (3, 13, beam.MAX_FUNCTIONS)
    kernel = (beam.shape, beam.deriv, beam.deriv2)[order]
    out = np.empty(beam.MAX_FUNCTIONS)
    for i, L in enumerate(lengths):
        for q, e in enumerate(eta):
            out[:] = 0.0
            kernel(et.code, e, L, out)
            np.testing.assert_array_equal(table[i, q], out)


@pytest.mark.parametrize("name", BEAM_NAMES)
def test_beam_dispatch_equals_modules(name):
    et = beam.beam_element(name)
    module = beam_registry.BEAM_TYPES[et.code]
    assert module.DESCRIPTOR is et
    assert beam.n_functions(et.code) == et.n_functions
    assert len(et.function_node) == len(et.function_offset) == et.n_functions <= beam.MAX_FUNCTIONS
    L = 1.3
    for eta in (-1.0, -0.4, 0.25, 1.0):
        for kernel, own in ((beam.shape, module.shape), (beam.deriv, module.deriv), (beam.deriv2, module.deriv2)):
            H = np.full(beam.MAX_FUNCTIONS, np.nan)
            Hm = np.empty(et.n_functions)
            kernel(et.code, eta, L, H)
            own(eta, L, Hm)
            np.testing.assert_array_equal(H[:et.n_functions], Hm)
            assert np.all(np.isnan(H[et.n_functions:]))


def test_beam_element_registry():
    assert {n: e.code for n, e in beam.BEAM_ELEMENTS.items()} == {"hermite": 0, "line": 1, "line3": 2}
    assert [m.DESCRIPTOR.code for m in beam_registry.BEAM_TYPES] == [0, 1, 2]
    assert beam.MAX_FUNCTIONS == 4
    assert beam.beam_element("hermite").dofs_per_node == 6
    with pytest.raises(ValueError, match="unknown beam element type 'line4'"):
        beam.beam_element("line4")


@pytest.mark.parametrize("name", BEAM_NAMES)
def test_beam_coefficients_and_control_points(name):
    """Each centreline type's coefficients reproduce its nodes (and tangents), and its Bézier control
    points hold the curve in their convex hull: the curve's points are convex combinations of them
    (checked by a non-negative least-squares fit that must sum to one and reproduce the point)."""
    from scipy.optimize import nnls
    et = beam.beam_element(name)
    rng = np.random.default_rng(7)
    positions = rng.uniform(-1, 1, (et.n_nodes, 3))
    tangents = rng.normal(size=(et.n_nodes, 3))
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    nodes = np.arange(et.n_nodes)
    L = 1.9
    Q = np.full((beam.MAX_FUNCTIONS, 3), np.nan)
    origin = positions[0].copy()
    beam.coefficients(et.code, positions, tangents, nodes, origin, Q)
    H = np.empty(beam.MAX_FUNCTIONS)
    for eta, node in ((-1.0, 0), (1.0, 1)):
        beam.shape(et.code, eta, L, H)
        np.testing.assert_allclose(H[: et.n_functions] @ Q[: et.n_functions] + origin, positions[node], atol=1e-15)
    ctrl = np.empty((beam.MAX_FUNCTIONS, 3))
    n = beam.control_points(et.code, Q, L, ctrl)
    assert 2 <= n <= beam.MAX_FUNCTIONS
    A = np.vstack([ctrl[:n].T, np.ones(n)])
    for eta in np.linspace(-1, 1, 9):
        beam.shape(et.code, eta, L, H)
        r = H[: et.n_functions] @ Q[: et.n_functions]
        weights, residual = nnls(A, np.append(r, 1.0))
        assert residual < 1e-12, (eta, residual)


def test_dispatch_tables_stay_cachable():
    """Numba freezes a global array into compiled code only below 1 MB (10**6 bytes); a kernel that reads
    a larger one is compiled again in every process ("Cannot cache ... dynamic globals"). Every table of
    the registry must stay below that as types grow (padded to 125 nodes, the monomial matrices alone
    would take 1.1 MB)."""
    tables = {k: v for k, v in vars(dispatch).items() if isinstance(v, np.ndarray)}
    assert {"TO_MONOMIAL", "CONTROL_MATRIX", "REFERENCE_NODES", "MONOMIALS"} <= set(tables)
    assert {k: v.nbytes for k, v in tables.items() if v.nbytes >= 10 ** 6} == {}
    # the flat monomial matrices: each type's block where MONOMIAL_START says
    for d in dispatch.SOLID_ELEMENTS.values():
        n, start = d.n_nodes, dispatch.MONOMIAL_START[d.code]
        block = dispatch.TO_MONOMIAL[start: start + n * n].reshape(n, n)
        y = d.reference_nodes - d.centre
        vandermonde = np.prod(y[:, None, :] ** d.monomials[None, :, :], axis=2)
        values = dispatch.SOLID_MODULES[d.name].NODE_VALUES if d.rational else np.eye(n)
        assert np.abs(vandermonde @ block - values).max() < 1e-9 * max(1.0, np.abs(block).max())


def _dense_rows_skipping_zeros(matrix, X):
    """Σ_b M[k, b] X[b, :3] row by row, b ascending, zero entries skipped: the sums the kernels made
    before their matrices were stored sparse (Python floats: the same IEEE operations)."""
    out = np.zeros((matrix.shape[0], 3))
    for k in range(matrix.shape[0]):
        for i in range(3):
            v = 0.0
            for b in range(matrix.shape[1]):
                if matrix[k, b] != 0.0:
                    v += matrix[k, b] * X[b, i]
            out[k, i] = v
    return out


@pytest.mark.parametrize("name", sorted(dispatch.SOLID_ELEMENTS))
def test_sparse_control_and_monomial_tables_give_the_dense_sums_bit_for_bit(name):
    """control_points and monomial_coefficients sum only the stored nonzero entries of the bounding and
    monomial matrices: the same terms in the same order as the dense loops that skipped zeros, so the
    same bits (boxes, hull planes, sizes h and the one-to-one certificates do not move). The sparse
    rows hold exactly the nonzero entries."""
    d = dispatch.SOLID_ELEMENTS[name]
    n, code = d.n_nodes, d.code
    X = np.random.default_rng(code).standard_normal((dispatch.MAX_NODES, 4)) * 10.0 ** np.arange(-3, 1)[None, :]
    C = np.full((dispatch.MAX_CONTROL, 3), np.nan)
    count = dispatch.control_points(code, X, C)
    expected = X[:n, :3] if dispatch.CONTROL_IS_NODES[code] else _dense_rows_skipping_zeros(d.bounding_matrix, X)
    assert count == len(expected)
    assert np.array_equal(C[:count], expected)
    if not dispatch.CONTROL_IS_NODES[code]:
        start = dispatch.CONTROL_START[code]
        rows = dispatch.CONTROL_ROWS[start: start + count + 1]
        assert rows[-1] - rows[0] == np.count_nonzero(d.bounding_matrix) < d.bounding_matrix.size
        # the figures the docs quote: nonzero entries of the control and monomial matrices (of 729, of 100)
        entries = (rows[-1] - rows[0], np.count_nonzero(dispatch.TO_MONOMIAL[dispatch.MONOMIAL_START[code]:][: n * n]))
        assert entries == {"hexahedron27": (125, 216), "tetra10": (22, 43)}.get(name, entries)
    block = dispatch.TO_MONOMIAL[dispatch.MONOMIAL_START[code]:][: n * n].reshape(n, n)
    a = np.full((dispatch.MAX_NODES, 4), np.nan)
    start = dispatch.MONOMIAL_SPARSE_START[code]
    rows = dispatch.MONOMIAL_ROWS[start: start + n + 1]
    assert rows[-1] - rows[0] == np.count_nonzero(block)
    if d.rational:
        # rational types: the same rows times (w X, w), as the dense loop over the weighted nodes
        from mortar1d3d.geometry.rational import rational_coefficients
        rational_coefficients(code, X, a)
        expected = np.zeros((n, 4))
        for k in range(n):
            for b in np.flatnonzero(block[k] != 0.0):
                w = block[k, b] * X[b, 3]
                expected[k] += (w * X[b, 0], w * X[b, 1], w * X[b, 2], w)
        assert np.array_equal(a[:n], expected)
        return
    dispatch.monomial_coefficients(code, X, a)
    assert np.array_equal(a[:n, :3], _dense_rows_skipping_zeros(block, X))


@pytest.mark.parametrize("name", sorted(dispatch.SOLID_ELEMENTS))
def test_curved_monomials_are_those_of_degree_two_and_more_in_order(name):
    """The derivative bounds of the one-to-one certificate and the point search sum over
    ``CURVED_MONOMIALS``: every monomial of total degree >= 2, ascending (the order, hence the bits,
    of the loop over all monomials that skipped the others), with its degree."""
    d = dispatch.SOLID_ELEMENTS[name]
    degree = np.asarray(d.monomials).sum(axis=1)
    count = dispatch.N_CURVED[d.code]
    np.testing.assert_array_equal(dispatch.CURVED_MONOMIALS[d.code, :count], np.flatnonzero(degree >= 2))
    np.testing.assert_array_equal(dispatch.CURVED_DEGREE[d.code, :count], degree[degree >= 2])
    assert count == {"hexahedron": 4, "tetra": 0, "tetra10": 6, "hexahedron27": 23}.get(name, count)
