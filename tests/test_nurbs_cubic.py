"""Cubic and quartic NURBS spans (issue 19, p-refinement): the ``nurbs64`` and ``nurbs125`` rational Bézier
elements in the engine and the model, as the quadratic ``nurbs27`` is tested in test_nurbs_engine.py.

References: the patch's own NURBS evaluation by Cox–de Boor over the knot vectors, the exact radius,
central differences for derivatives.
"""
import numpy as np
import pytest

from mortar1d3d import nurbs
from mortar1d3d.elements.solid import dispatch
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
from mortar1d3d.elements.validity import FOLDED, INVERTED, VALID, jacobian_validity

RNG = np.random.default_rng(64)
#: the degrees above 2 and their element types
HIGHER = [(3, "nurbs64"), (4, "nurbs125")]


def sector(angle=90.0, elements=(1, 1, 1), r=(0.1, 0.2), height=0.3, degree=3):
    return nurbs.bezier_mesh(nurbs.hollow_cylinder(r[0], r[1], height, angle=angle, elements=elements, degree=degree))


@pytest.mark.parametrize("degree, name", HIGHER)
def test_rational_functions_partition_of_unity_and_derivatives(degree, name):
    """R_a = w_a B_a / W with random weights: Σ R_a = 1, Σ ∂R_a = 0, ∂R_a against central
    differences (h = 1e-6: error ~h² · |∂³R| + round-off/h)."""
    element = SOLID_ELEMENTS[name]
    code, n = element.code, (degree + 1) ** 3
    assert element.n_nodes == n and element.degree == degree
    X = np.zeros((n, 4))
    X[:, 3] = RNG.uniform(0.5, 2.0, n)
    N, dN = np.empty(n), np.empty((n, 3))
    Np, Nm = np.empty(n), np.empty(n)
    for xi in RNG.uniform(-1, 1, (20, 3)):
        dispatch.rational_deriv(code, xi, X, N, dN)
        assert abs(N.sum() - 1.0) < 1e-14 and np.abs(dN.sum(axis=0)).max() < 1e-13
        assert N.min() > 0.0
        for i in range(3):
            step = np.zeros(3)
            step[i] = 1e-6
            dispatch.rational_shape(code, xi + step, X, Np)
            dispatch.rational_shape(code, xi - step, X, Nm)
            assert np.abs((Np - Nm) / 2e-6 - dN[:, i]).max() < 1e-8
    # polynomial part: the Bernstein basis is 1 at its own corner, reproduces linear fields
    B = np.empty(n)
    dispatch.shape(code, np.array([-1.0, -1.0, -1.0]), B)
    assert B[0] == 1.0 and np.abs(B[1:]).max() == 0.0
    xi = RNG.uniform(-1, 1, 3)
    dispatch.shape(code, xi, B)
    assert np.abs(B @ element.reference_nodes - xi).max() < 1e-15     # Bernstein points of a linear map


@pytest.mark.parametrize("degree, name", HIGHER)
@pytest.mark.parametrize("angle, elements", [(90.0, (1, 1, 1)), (360.0, (2, 4, 1))])
def test_cubic_cylinder_is_exact_and_elevation_keeps_the_geometry(angle, elements, degree, name):
    """The Bézier mesh of the degree-elevated pipe: its elements (the engine's kernel) give the points of
    the quadratic patch (Cox–de Boor) to round-off, and its inner/outer faces lie on the exact radius."""
    quadratic = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=angle, elements=elements)
    bm = sector(angle, elements, degree=degree)
    assert bm.solid.blocks[0][0].name == name and bm.solid.n_elements == np.prod(elements)
    patch = quadratic.patches[0]
    xi = RNG.uniform(-1, 1, (25, 3))
    xi[:5, 0] = -1.0                                    # on the inner face
    xi[5:10, 0] = 1.0                                   # on the outer face
    x = nurbs.mesh.element_values(bm.solid, xi, bm.solid.points)          # (n_el, 25, 3), the engine's R_a
    ranges = patch.element_ranges()                                       # (n_el, 3, 2)
    u = ranges[:, None, :, 0] + 0.5 * (xi[None] + 1.0) * (ranges[:, None, :, 1] - ranges[:, None, :, 0])
    reference = patch.evaluate(u.reshape(-1, 3)).reshape(x.shape)
    assert np.abs(x - reference).max() < 1e-15
    r = np.hypot(x[..., 0], x[..., 1])
    first = bm.element_span[:, 0]
    assert np.abs(r[first == 0, :5] - 0.1).max() < 2e-16
    assert np.abs(r[first == elements[0] - 1, 5:10] - 0.2).max() < 3e-16


# point location on cubic spans (the trust property), the curved beam crossing one cubic span's inner face
# twice, and the operators and certificates on a closed cubic pipe: test_nurbs_engine.py, with the cubic
# cases in its parameters


@pytest.mark.parametrize("degree, name", HIGHER)
def test_validity_of_cubic_elements(degree, name):
    element = SOLID_ELEMENTS[name]
    bm = sector(360.0, (2, 4, 1), degree=degree)
    n = element.n_nodes
    X = bm.solid.points[bm.solid.connectivity[:, :n]]
    W = bm.solid.weights[bm.solid.connectivity[:, :n]]
    h = np.linalg.norm(X.max(axis=1) - X.min(axis=1), axis=1)
    assert (jacobian_validity(element, X, h, W) == VALID).all()
    assert (jacobian_validity(element, X * [1, 1, -1], h, W) == INVERTED).all()
    # an interior control point pushed far through the element: folded inside, fine at the corners
    interior = np.flatnonzero((np.abs(element.reference_nodes) < 1).all(axis=1))[0]
    Y = X[:1].copy()
    Y[0, interior] += 20.0 * (Y[0, 1] - Y[0, 0])
    assert jacobian_validity(element, Y, h[:1], W[:1])[0] == FOLDED


@pytest.mark.parametrize("degree", [3, 4])
def test_vtu_of_cubic_spans(tmp_path, degree):
    """A span of degree p is written as (p-1)³ hexahedron27 cells through its exact points, each cell with
    its span's cell data."""
    import meshio

    from mortar1d3d.io.vtu import write_solid

    solid = sector(90.0, (1, 2, 1), height=0.05, degree=degree).solid
    per_span = (degree - 1) ** 3
    path = write_solid(tmp_path / "c.vtu", solid, point_data={"x": solid.points, "one": np.ones(solid.n_nodes)},
                       cell_data={"id": np.arange(solid.n_elements) * 10})
    mesh = meshio.read(path)
    assert mesh.cells_dict["hexahedron27"].shape == (2 * per_span, 27)
    assert np.abs(mesh.point_data["x"] - mesh.points).max() < 1e-15
    # sampled with the rational functions, which sum to one (independent of how the points are made)
    assert np.abs(mesh.point_data["one"] - 1.0).max() < 1e-14
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    on_inner = np.abs(r - 0.1) < 1e-9
    # the inner face: 2 spans × (p-1)² cell faces × 9 points (points shared by two cells are repeated)
    assert on_inner.sum() == 2 * (degree - 1) ** 2 * 9 and np.abs(r[on_inner] - 0.1).max() < 1e-15
    assert mesh.cell_data["id"][0].tolist() == [0] * per_span + [10] * per_span
