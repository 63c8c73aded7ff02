"""Surface loads: boundary faces, dead traction, follower pressure and its load stiffness."""
from math import factorial

import numba
import numpy as np
import pytest

from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
from mortar1d3d.physics.surface import FACE_DTYPE, Pressure, boundary_faces, face_nodes, traction_force
from mortar1d3d.quadrature import quadrilateral_rule, triangle_rule, wedge_rule

from naive import surface_loads

TYPES = [n for n, d in SOLID_ELEMENTS.items() if not d.rational]     # nurbs27: test_nurbs_model
SIDES = {"x_min": (0, -1.0), "x_max": (0, 1.0), "y_min": (1, -1.0), "y_max": (1, 1.0),
         "z_min": (2, -1.0), "z_max": (2, 1.0)}


def rotation(vector):
    """Rotation matrix of the rotation vector ``vector`` (Rodrigues)."""
    angle = np.linalg.norm(vector)
    k = np.asarray(vector) / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def side_areas(lower, upper):
    e = np.subtract(upper, lower)
    return {"x": e[1] * e[2], "y": e[0] * e[2], "z": e[0] * e[1]}


def faces_per_cube_side(family):
    """(3,) faces of the elements that fill one grid cell of ``generate.box`` (the family's
    ``cube_split``) lying on the cell's side normal to each axis (hex 1, 1, 1; tet 2, 2, 2)."""
    count = np.zeros(3, dtype=np.int64)
    for corners in family.cube_split:
        for nodes in family.face_nodes:
            count += (corners[list(nodes)] == 0).all(axis=0)
    return count


def polygon_area(X):
    """Area of the flat polygon with corners X (k, 3) in cyclic order (a fan of triangles)."""
    return sum(0.5 * np.linalg.norm(np.cross(X[k] - X[0], X[k + 1] - X[0])) for k in range(1, len(X) - 1))


# ---------------------------------------------------------------------------------------------
# quadrature


def assert_exact_on_the_triangle(points, weights, degree):
    """∫ u^i v^j over the triangle u, v >= 0, u + v <= 1 (= i! j! / (i + j + 2)!) for every i + j <= degree."""
    for i in range(degree + 1):
        for j in range(degree + 1 - i):
            exact = factorial(i) * factorial(j) / factorial(i + j + 2)
            got = weights @ (points[:, 0] ** i * points[:, 1] ** j)
            assert got == pytest.approx(exact, rel=1e-14, abs=1e-16)


def test_triangle_rule_integrates_degree_4_exactly():
    points, weights = triangle_rule()
    assert_exact_on_the_triangle(points, weights, 4)
    # ... and not degree 5 (the rule is what it claims, no more)
    assert abs(weights @ (points[:, 0] ** 5) - 1 / 42) > 1e-6


def test_triangle_rule_of_degree_2_and_the_wedge_rule():
    points, weights = triangle_rule(2)
    assert len(weights) == 3
    assert_exact_on_the_triangle(points, weights, 2)
    assert abs(weights @ points[:, 0] ** 3 - 1 / 20) > 1e-4
    # the prism: P2 on the triangle times degree 3 in ζ, exactly
    points, weights = wedge_rule(2, 2)
    assert len(weights) == 6 and weights.sum() == pytest.approx(1.0, rel=1e-15)
    for i in range(3):
        for j in range(3 - i):
            for k in range(5):
                exact = factorial(i) * factorial(j) / factorial(i + j + 2) * (2 / (k + 1) if k % 2 == 0 else 0)
                got = weights @ (points[:, 0] ** i * points[:, 1] ** j * points[:, 2] ** k)
                if k <= 3:
                    assert got == pytest.approx(exact, rel=1e-14, abs=1e-16)
                elif i == j == 0:
                    assert abs(got - exact) > 1e-3                     # ζ⁴: not
    with pytest.raises(ValueError, match="degree 2 or 4"):
        triangle_rule(3)


def test_quadrilateral_rule_integrates_degree_5_per_direction():
    points, weights = quadrilateral_rule()
    for i in range(7):
        for j in range(7):
            exact = (2 / (i + 1) if i % 2 == 0 else 0) * (2 / (j + 1) if j % 2 == 0 else 0)
            got = weights @ (points[:, 0] ** i * points[:, 1] ** j)
            if i <= 5 and j <= 5:
                assert got == pytest.approx(exact, rel=1e-14, abs=1e-14)
            elif i == 6 and j == 0:
                assert abs(got - exact) > 1e-3


@pytest.mark.parametrize("name, expected", [("hexahedron", 4), ("hexahedron20", 8), ("hexahedron27", 9),
                                            ("tetra", 3), ("tetra10", 6), ("wedge", (3, 3, 4, 4, 4))])
def test_face_nodes_lie_on_the_face(name, expected):
    d = SOLID_ELEMENTS[name]
    expected = expected if isinstance(expected, tuple) else (expected,) * d.n_faces
    for f in range(d.n_faces):
        local = face_nodes(d.code, f)
        assert len(local) == expected[f]
        origin, _, _, normal = d.faces[f]
        assert np.allclose((d.reference_nodes[local] - origin) @ normal, 0.0)
        assert set(d.face_nodes[f]) <= set(local.tolist())


# ---------------------------------------------------------------------------------------------
# boundary faces


@pytest.mark.parametrize("name", TYPES)
def test_boundary_face_count_and_outward_normals(name):
    cells = (2, 1, 3)
    lower, upper = np.array([0.0, -1.0, 0.5]), np.array([1.0, 1.0, 2.0])
    solid = generate.box(lower, upper, cells, name)
    faces = boundary_faces(solid)
    per_side = faces_per_cube_side(SOLID_ELEMENTS[name].family_type)
    assert len(faces) == 2 * sum(per_side[axis] * np.prod(np.delete(cells, axis)) for axis in range(3))
    assert faces.dtype == FACE_DTYPE
    assert (faces["code"] == SOLID_ELEMENTS[name].code).all()
    assert len(np.unique(faces[["element", "face"]])) == len(faces)

    areas = side_areas(lower, upper)
    on_a_side = 0
    for side, (axis, sign) in SIDES.items():
        selected = boundary_faces(solid, solid.point_sets[side])
        on_a_side += len(selected)
        assert len(selected) == per_side[axis] * np.prod(np.delete(cells, axis))
        # p = -1 turns -p ∫ N n da into ∫ N n da: the summed force of a face is its area-weighted
        # normal, which must point out of the box on every face
        for one in selected:
            normal = Pressure(solid, one[None], -1.0).evaluate(tangent=False)[0].reshape(-1, 3).sum(axis=0)
            expected = np.zeros(3)
            expected[axis] = sign * areas["xyz"[axis]] / (len(selected))
            assert np.allclose(normal, expected, rtol=0, atol=1e-14)
    assert on_a_side == len(faces)


def test_node_filter_needs_every_face_node():
    solid = generate.box([0, 0, 0], [1, 1, 1], (2, 2, 2), "hexahedron20")
    x_max = solid.point_sets["x_max"]
    assert len(boundary_faces(solid, x_max)) == 4
    mask = np.zeros(solid.n_nodes, dtype=bool)
    mask[x_max] = True
    assert len(boundary_faces(solid, mask)) == 4
    corners = x_max[np.isin(x_max, solid.connectivity[:, :8])]     # x_max without its mid-side nodes
    assert len(corners) == 9
    assert len(boundary_faces(solid, corners)) == 0


# ---------------------------------------------------------------------------------------------
# dead traction


@pytest.mark.parametrize("name", TYPES)
def test_traction_sums_to_traction_times_area(name):
    lower, upper = np.array([0.0, 0.0, 0.0]), np.array([2.0, 0.5, 3.0])
    solid = generate.box(lower, upper, (2, 2, 1), name)
    t = np.array([1.5, -2.0, 0.25])
    faces = boundary_faces(solid, solid.point_sets["x_max"])
    f = traction_force(solid, faces, t).reshape(-1, 3)
    assert np.allclose(f.sum(axis=0), t * 0.5 * 3.0, rtol=1e-14, atol=0)
    loaded = np.flatnonzero(np.abs(f).sum(axis=1))
    assert set(loaded) <= set(solid.point_sets["x_max"])


# share of the total force per node kind: local node ids of the element types
@pytest.mark.parametrize("name, share", [
    ("hexahedron", {range(0, 8): 1 / 4}),
    ("tetra", {range(0, 4): 1 / 3}),
    ("hexahedron20", {range(0, 8): -1 / 12, range(8, 20): 1 / 3}),
    ("hexahedron27", {range(0, 8): 1 / 36, range(8, 20): 1 / 9, range(20, 26): 4 / 9}),
    ("tetra10", {range(0, 4): 0.0, range(4, 10): 1 / 3}),
    ("wedge", {range(0, 6): 1 / 4}),         # the first face on x_max is a quadrilateral
])
def test_consistent_nodal_forces_of_one_face(name, share):
    solid = generate.box([0, 0, 0], [1.0, 2.0, 0.5], (1, 1, 1), name)
    faces = boundary_faces(solid, solid.point_sets["x_max"])[:1]
    f = traction_force(solid, faces, [0.0, 0.0, 3.0]).reshape(-1, 3)
    element, face = faces["element"][0], faces["face"][0]
    local = face_nodes(faces["code"][0], face)
    corners = solid.connectivity[element, list(SOLID_ELEMENTS[name].face_nodes[face])]
    total = 3.0 * polygon_area(solid.points[corners])                      # area of the face × t
    for a in local:
        expected = next(s for r, s in share.items() if a in r)
        node = solid.connectivity[element, a]
        assert f[node] == pytest.approx([0, 0, expected * total], abs=1e-14)
    others = np.setdiff1d(np.arange(solid.n_nodes), solid.connectivity[element, local])
    assert not f[others].any()
    assert f[:, 2].sum() == pytest.approx(total, rel=1e-14)


def test_consistent_nodal_forces_of_a_wedge_triangle_face():
    # z_max of a wedge box is made of the wedges' top triangles (face 1): a third of the force per corner
    solid = generate.box([0, 0, 0], [1.0, 2.0, 0.5], (1, 1, 1), "wedge")
    faces = boundary_faces(solid, solid.point_sets["z_max"])
    assert len(faces) == 2 and set(faces["face"].tolist()) == {1}
    f = traction_force(solid, faces[:1], [0.0, 0.0, 3.0]).reshape(-1, 3)
    corners = solid.connectivity[faces["element"][0], [3, 4, 5]]
    total = 3.0 * polygon_area(solid.points[corners])
    assert total == pytest.approx(3.0, rel=1e-15)                          # half of the 1 × 2 top
    for node in corners:
        assert f[node] == pytest.approx([0, 0, total / 3], abs=1e-14)
    assert not f[np.setdiff1d(np.arange(solid.n_nodes), corners)].any()
    both = traction_force(solid, faces, [0.0, 0.0, 3.0]).reshape(-1, 3)
    assert both[:, 2].sum() == pytest.approx(6.0, rel=1e-14)


# ---------------------------------------------------------------------------------------------
# follower pressure


@pytest.mark.parametrize("name", TYPES)
def test_pressure_closed_surface_rigid_rotation_and_inflation(name):
    rng = np.random.default_rng(7)
    lower, upper = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.5, 2.0])
    solid = generate.box(lower, upper, (1, 2, 1), name)
    X = solid.points
    p = 3.0
    closed = Pressure(solid, boundary_faces(solid), p)
    f0, _ = closed.evaluate(tangent=False)
    u = 0.1 * rng.standard_normal(X.shape)
    f1, _ = closed.evaluate(u, tangent=False)
    assert np.abs(f0.reshape(-1, 3).sum(axis=0)).max() < 1e-14
    assert np.abs(f1.reshape(-1, 3).sum(axis=0)).max() < 1e-13
    assert np.abs(f1).max() > 0.1

    side = Pressure(solid, boundary_faces(solid, solid.point_sets["x_max"]), p)
    f, _ = side.evaluate(np.zeros_like(X), tangent=False)
    assert np.allclose(f.reshape(-1, 3).sum(axis=0), [-p * 0.5 * 2.0, 0, 0], rtol=1e-14, atol=1e-14)

    R = rotation([0.3, -0.5, 0.7])
    f_rot, _ = side.evaluate(X @ R.T - X + [0.2, -1.0, 4.0], tangent=False)
    assert np.allclose(f_rot.reshape(-1, 3), f.reshape(-1, 3) @ R.T, rtol=0, atol=1e-14)

    alpha = 0.35
    f_inflated, _ = side.evaluate(alpha * X, tangent=False)
    assert np.allclose(f_inflated, (1 + alpha) ** 2 * f, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("name", TYPES)
def test_load_stiffness_matches_finite_differences(name):
    rng = np.random.default_rng(11)
    solid = generate.box([0, 0, 0], [1.0, 0.7, 0.5], (1, 1, 1), name)
    faces = boundary_faces(solid)
    faces = faces[~np.isin(np.arange(len(faces)), [0, 3])]     # an open surface
    load = Pressure(solid, faces, 2.5)
    u = 0.1 * rng.standard_normal(solid.points.shape)
    f, K = load.evaluate(u)
    K = K.toarray()
    h = 1e-4
    K_fd = np.empty_like(K)
    flat = u.ravel()
    for j in range(flat.size):
        e = np.zeros_like(flat)
        e[j] = h
        K_fd[:, j] = (load.evaluate(flat + e, tangent=False)[0] - load.evaluate(flat - e, tangent=False)[0]) / (2 * h)
    # f is quadratic in u: central differences are exact up to round-off
    assert np.abs(K - K_fd).max() <= 1e-8 * np.abs(K).max()
    assert np.abs(K).max() > 0.01
    assert np.abs(K - K.T).max() > 1e-3 * np.abs(K).max()        # open surface: not symmetric


@pytest.mark.parametrize("name", ["hexahedron20", "tetra10"])
def test_load_stiffness_of_a_closed_surface_is_symmetric(name):
    # f = -p ∂V/∂x for the volume V enclosed by the (exactly integrated) surface
    rng = np.random.default_rng(5)
    solid = generate.box([0, 0, 0], [1, 1, 1], (1, 1, 2), name)
    load = Pressure(solid, boundary_faces(solid), 1.0)
    _, K = load.evaluate(0.1 * rng.standard_normal(solid.points.shape))
    assert abs(K - K.T).max() <= 1e-13 * abs(K).max()


def test_tangent_counter():
    solid = generate.box([0, 0, 0], [1, 1, 1], (1, 1, 1), "hexahedron")
    load = Pressure(solid, boundary_faces(solid), 1.0)
    assert load.n_tangents == 0
    f, K = load.evaluate(tangent=False)
    assert K is None and load.n_tangents == 0
    f2, K = load.evaluate(np.zeros(3 * solid.n_nodes))
    assert load.n_tangents == 1 and K.shape == (24, 24)
    assert np.array_equal(f, f2)


# slow reference: tests/naive.py surface_loads (all volume shape functions, 5 × 5 Gauss; collapsed
# Gauss on triangles), no tabulation


@pytest.mark.parametrize("name", TYPES)
def test_against_slow_reference(name):
    rng = np.random.default_rng(3)
    box = generate.box([0, 0, 0], [1, 1, 1], (1, 1, 1), name)
    A = np.array([[1.0, 0.3, -0.2], [0.1, 0.8, 0.25], [-0.15, 0.2, 1.1]])
    t, p = np.array([0.3, -1.0, 2.0]), 1.7
    # affine reference (flat parallelogram/triangle faces, dA0 constant): everything exact;
    # curved reference faces: |X_,u × X_,v| is not a polynomial and the two rules differ slightly
    for points, traction_tol in ((box.points @ A.T, 1e-13),
                                 (box.points + 0.03 * rng.standard_normal(box.points.shape), 2e-3)):
        solid = type(box)(points, box.cells)
        faces = boundary_faces(solid)[::2]
        u = 0.1 * rng.standard_normal(points.shape)
        ref_traction, ref_pressure = surface_loads(solid, faces, u, t, p)
        f_pressure, _ = Pressure(solid, faces, p).evaluate(u, tangent=False)
        # the pressure integrand is a polynomial that both rules integrate exactly
        assert np.allclose(f_pressure, ref_pressure, rtol=0, atol=1e-13)
        f_traction = traction_force(solid, faces, t)
        assert np.allclose(f_traction, ref_traction, rtol=0, atol=traction_tol * np.abs(ref_traction).max())
        assert np.abs(f_traction).max() > 0.01


# ---------------------------------------------------------------------------------------------
# determinism, validation


def test_bit_identical_for_one_and_two_threads():
    solid = generate.box([0, 0, 0], [1, 1, 1], (3, 2, 2), "tetra10")
    faces = boundary_faces(solid)
    u = 0.05 * np.random.default_rng(1).standard_normal(solid.points.shape)
    before = numba.get_num_threads()
    results = []
    try:
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            f, K = Pressure(solid, faces, 2.0).evaluate(u)
            results.append((f, K, traction_force(solid, faces, [1.0, 2.0, 3.0])))
    finally:
        numba.set_num_threads(before)
    (f1, K1, t1), (f2, K2, t2) = results
    assert np.array_equal(f1, f2) and np.array_equal(t1, t2)
    assert np.array_equal(K1.indptr, K2.indptr) and np.array_equal(K1.indices, K2.indices)
    assert np.array_equal(K1.data, K2.data)


def test_invalid_input_is_rejected():
    solid = generate.box([0, 0, 0], [1, 1, 1], (1, 1, 1), "hexahedron")
    faces = boundary_faces(solid)
    with pytest.raises(TypeError):
        traction_force(solid, np.array([[0, 1]]), [1, 0, 0])
    bad = faces.copy()
    bad["face"][0] = 6
    with pytest.raises(ValueError, match="face index"):
        Pressure(solid, bad, 1.0)
    bad = faces.copy()
    bad["code"][0] = 3
    with pytest.raises(ValueError, match="code"):
        traction_force(solid, bad, [1, 0, 0])
    with pytest.raises(ValueError, match="traction"):
        traction_force(solid, faces, [1, 0])
    with pytest.raises(ValueError, match="displacement"):
        Pressure(solid, faces, 1.0).evaluate(np.zeros(5))
    with pytest.raises(ValueError, match="node"):
        boundary_faces(solid, [0, 99])
