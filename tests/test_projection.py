"""``project_points``: Newton projection of points into solid elements, with its three outcomes.

Points are made from known parameters (x = x(ξ_true) with the element modules' shape
functions, which tests/test_elements.py checks), so the answer is known without a second
projection code: converged inside, converged outside (x(ξ) = p still holds), not converged.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import BY_CODE, SOLID_ELEMENTS, SOLID_MODULES
from mortar1d3d.geometry.projection import INSIDE, NOT_CONVERGED, OUTSIDE
from mortar1d3d.geometry.search import solid_bounding_boxes

from naive import random_parameters

SOLID_TYPES = [n for n, d in SOLID_ELEMENTS.items() if not d.rational]     # nurbs27: tests/test_nurbs_engine.py


def distorted(element, seed=1):
    return generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element), 0.15, seed=seed)


def mapped(solid, s, xi):
    """x(ξ) of element s, for the rows of ``xi`` (numpy, from the element module)."""
    d = BY_CODE[int(solid.element_codes[s])]
    X = solid.points[solid.connectivity[s, : d.n_nodes]]
    N = np.empty(d.n_nodes)
    out = np.empty((len(xi), 3))
    for i, x in enumerate(xi):
        SOLID_MODULES[d.name].shape.py_func(np.ascontiguousarray(x), N)
        out[i] = N @ X
    return out


def parameters(family, rng, n, margin):
    """n parameter points inside the reference element shrunk by ``margin`` (negative: outside
    it by at least -margin, and still within 0.2 of it), as distances beyond the face planes."""
    if margin >= 0:
        return random_parameters(family, rng, n, high=-margin)
    return random_parameters(family, rng, n, low=-margin, high=0.2, grow=0.2)


@pytest.mark.parametrize("element", SOLID_TYPES)
def test_recovers_known_parameters_inside_and_outside(element):
    solid = distorted(element)
    family = BY_CODE[int(solid.element_codes[0])].family
    h = solid_bounding_boxes(solid)[1]
    rng = np.random.default_rng(5)
    for margin, expected in ((1e-6, INSIDE), (-1e-6, OUTSIDE)):
        for s in (0, solid.n_elements - 1):
            xi_true = parameters(family, rng, 40, margin)
            p = mapped(solid, s, xi_true)
            xi, status = m13.project_points(solid, p, s)
            assert xi.shape == (40, 3) and status.dtype == np.int64
            np.testing.assert_array_equal(status, expected)
            # x(ξ) = p to the design tolerance (1e-12 h), and ξ is the one the point was made from
            assert np.abs(mapped(solid, s, xi) - p).max() <= 1e-12 * h[s]
            np.testing.assert_allclose(xi, xi_true, rtol=0, atol=1e-10)


def test_one_element_per_point_and_points_on_nodes():
    solid = distorted("hexahedron20")
    d = BY_CODE[int(solid.element_codes[0])]
    elements = np.repeat(np.arange(solid.n_elements), d.n_nodes)
    p = solid.points[solid.connectivity[:, : d.n_nodes].ravel()]
    xi, status = m13.project_points(solid, p, elements)
    np.testing.assert_array_equal(status, INSIDE)                    # nodes lie on the boundary: inside
    np.testing.assert_allclose(xi, np.tile(d.reference_nodes, (solid.n_elements, 1)), rtol=0, atol=1e-12)


def test_not_converged_far_outside_a_curved_element():
    solid = distorted("hexahedron27")
    # far from a curved element its (extended) map folds: Newton runs away or stalls
    xi, status = m13.project_points(solid, [[1e4, -3e4, 2e4], [0.3, 0.3, 0.3]], 0)
    assert status[0] == NOT_CONVERGED and np.isnan(xi[0]).all()
    assert status[1] in (INSIDE, OUTSIDE) and np.isfinite(xi[1]).all()
    # an affine element has an exact inverse map: the same point is simply outside
    box = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "tetra")
    xi, status = m13.project_points(box, [[1e4, -3e4, 2e4]], 0)
    assert status[0] == OUTSIDE
    np.testing.assert_allclose(mapped(box, 0, xi), [[1e4, -3e4, 2e4]], rtol=1e-12)


def test_agrees_with_the_integration_points_of_assemble_mortar():
    solid = distorted("tetra10")
    beams = generate.random_curved_beams(2, 6, seed=3)
    ops = m13.assemble_mortar(beams, solid)
    pts = ops.points
    xi, status = m13.project_points(solid, pts["position"], pts["solid_element"])
    np.testing.assert_array_equal(status, INSIDE)
    np.testing.assert_allclose(xi, pts["xi"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("points, elements, error, message", [
    ([[0.1, 0.1, 0.1]], 8, m13.MeshError, r"out of range \[0, 8\) at points 0"),
    ([[0.1, 0.1, 0.1], [0.2, 0.2, 0.2]], [0, -1], m13.MeshError, "out of range.*at points 1"),
    ([[0.1, 0.1, 0.1]], [0, 1], m13.MeshError, "one element id or 1 of them"),
    ([[0.1, 0.1, 0.1]], 0.0, m13.MeshError, "integer element ids"),
    ([[0.1, np.nan, 0.1]], 0, m13.MeshError, "NaN or infinite coordinates at rows 0"),
    ([0.1, 0.1, 0.1], 0, m13.MeshError, r"shape \(n, 3\)"),
])
def test_bad_input(points, elements, error, message):
    solid = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "hexahedron")
    with pytest.raises(error, match=message):
        m13.project_points(solid, points, elements)
    with pytest.raises(TypeError, match="SolidMesh"):
        m13.project_points(solid.points, points, elements)


@pytest.mark.parametrize("element", SOLID_TYPES)
def test_polish_from_the_residual_left_by_the_locators(element):
    """``project_point`` and ``locate_point`` leave p - x(ξ) in ``trial``; the integration points polish
    from it (``polish_residual``) instead of evaluating the map again. Same bits as ``polish``, for
    points inside, outside and within 1e-8 of a face (the locator's rare path polishes there)."""
    from mortar1d3d.geometry import projection as pr
    from mortar1d3d.geometry.search import solid_frames

    solid = distorted(element)
    family = BY_CODE[int(solid.element_codes[0])].family
    _, h, origin = solid_frames(solid)
    table = np.empty((solid.n_elements, 5, 3))
    pr.linear_maps(solid.kernel_points, solid.connectivity, solid.element_codes, origin, h, table, 1)
    X, N, dN, _, _, _, trial = pr.point_buffers()
    a, stack = pr.search_buffers()
    rng = np.random.default_rng(7)
    s = solid.n_elements - 1
    code = int(solid.element_codes[s])
    pr.load_element(solid.kernel_points, solid.connectivity, s, code, origin, X)
    polished = 0
    for margin in (0.1, 1e-8, -1e-8, -0.1):
        for p in mapped(solid, s, parameters(family, rng, 20, margin)) - origin[s]:
            for locate in (False, True):
                xi = np.empty(3)
                if locate:
                    ok = pr.locate_point(code, X, *p, h[s], 1e-9, table, s, xi, trial, N, dN, a,
                                         stack) != NOT_CONVERGED
                else:
                    ok = pr.linear_parameters(code, table, s, *p, xi) and pr.project_point(
                        code, X, *p, h[s], xi, trial, N, dN) == 0
                assert ok
                again = xi.copy()
                pr.polish(code, X, *p, h[s], again, np.empty(3), N, dN)
                before = xi.copy()
                pr.polish_residual(code, X, *p, h[s], xi, trial, N, dN)
                np.testing.assert_array_equal(xi, again)
                polished += not np.array_equal(xi, before)
    # the step changed some points, so the comparison is not vacuous (a tet4 is affine: at round-off at once)
    assert polished > 0 or element == "tetra"


@pytest.mark.parametrize("element", [n for n, d in SOLID_ELEMENTS.items() if n != "hexahedron"])
def test_map_and_jacobian_in_one_call_have_the_bits_of_the_separate_calls(element):
    """The Newton iterations of every type but hex8 take x(ξ) and J(ξ) from one call where they need
    both (``_map_jacobian_other``; hex27 shares the contractions of the two): the same bits as
    ``map_point`` and ``jacobian``, for moved nodes (rational types: weights 0.4 to 2.5) and ξ inside
    and beyond the element. x and J are checked against a central difference of the map too, so the
    12 values are x and J in that order."""
    from mortar1d3d.geometry import projection as pr

    d = SOLID_ELEMENTS[element]
    rng = np.random.default_rng(5)
    X, N, dN, _, _, _, _ = pr.point_buffers()
    for _ in range(5):
        X[: d.n_nodes, :3] = d.reference_nodes + rng.uniform(-0.1, 0.1, (d.n_nodes, 3))
        X[: d.n_nodes, 3] = rng.uniform(0.4, 2.5, d.n_nodes) if d.rational else 1.0
        for xi in rng.uniform(-1.2, 1.2, (8, 3)):
            both = pr._map_jacobian_other(d.code, X, xi, N, dN)
            x = pr.map_point(d.code, X, xi, N)
            J = pr.jacobian(d.code, X, xi, N, dN)
            assert both == x + J            # tuples of floats: bit for bit
            step = 1e-6
            for k in range(3):
                e = np.zeros(3)
                e[k] = step
                fd = (np.subtract(pr.map_point(d.code, X, xi + e, N), pr.map_point(d.code, X, xi - e, N))
                      / (2 * step))
                np.testing.assert_allclose(np.array(J).reshape(3, 3)[:, k], fd, rtol=0, atol=1e-6)
