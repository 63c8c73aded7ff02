"""NURBS patches (issue 19 items 1-2): rational basis kernels, Bézier extraction, exact circles and
cylinders, generators, knot insertion and degree elevation.

References are independent of the kernels: Cox–de Boor over the whole knot vector in numpy
(``NurbsPatch.evaluate``, ``knots.bspline_values``) and the closed-form circle.
"""
import numpy as np
import pytest

from mortar1d3d import nurbs
from mortar1d3d.nurbs import knots as kv
from mortar1d3d.nurbs.basis import local_bsplines, rational_bernstein, rational_local

RNG = np.random.default_rng(19)


def _basis(degrees, xi, weights):
    n = int(np.prod(np.add(degrees, 1)))
    R, dR = np.empty(n), np.empty((n, 3))
    W = rational_bernstein(*degrees, np.ascontiguousarray(xi, dtype=float), np.ascontiguousarray(weights), R, dR)
    return R, dR, W


@pytest.mark.parametrize("degrees", [(2, 2, 2), (1, 2, 3), (3, 1, 2)])
def test_rational_basis_partition_of_unity_and_derivatives(degrees):
    n = int(np.prod(np.add(degrees, 1)))
    weights = RNG.uniform(0.3, 2.0, n)
    for xi in RNG.uniform(-1, 1, (5, 3)):
        R, dR, W = _basis(degrees, xi, weights)
        assert W > 0
        assert abs(R.sum() - 1.0) < 1e-14
        assert np.abs(dR.sum(axis=0)).max() < 1e-13
        h = 1e-6
        for d in range(3):
            e = np.zeros(3)
            e[d] = h
            diff = (_basis(degrees, xi + e, weights)[0] - _basis(degrees, xi - e, weights)[0]) / (2 * h)
            assert np.abs(diff - dR[:, d]).max() < 1e-8, d


def test_rational_basis_is_the_nurbs_basis_of_the_element():
    """Bézier route (extraction, rational Bernstein with Bézier weights) = element-local Cox–de Boor
    with the control weights = global Cox–de Boor (numpy), on a refined cylinder of degree (2, 3, 2)."""
    solid = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=200.0, elements=(2, 4, 2), degree=2)
    patch = solid.patches[0].elevate(1)
    control, wb, functions, E = patch.bezier_elements()
    ranges = patch.element_ranges()
    p = patch.degrees
    n = int(np.prod(np.add(p, 1)))
    w_all = patch.weights.reshape(-1)
    xi = RNG.uniform(-1, 1, (4, 3))
    for e in range(patch.n_elements):
        k = [kv.spans(U, q) for U, q in zip(patch.knots, p)]
        idx = np.unravel_index(e, patch.element_shape)
        local = [np.ascontiguousarray(U[k[d][idx[d]] - p[d] + 1: k[d][idx[d]] + p[d] + 1]) for d, U in enumerate(patch.knots)]
        for x in xi:
            Rb, dRb, _ = _basis(p, x, wb[e])
            R_cp = E[e] @ Rb                                          # NURBS functions from the Bézier ones
            R_loc, dR_loc = np.empty(n), np.empty((n, 3))
            rational_local(*p, x, *local, np.ascontiguousarray(w_all[functions[e]]), R_loc, dR_loc)
            assert np.abs(R_cp - R_loc).max() < 1e-13
            assert np.abs(E[e] @ dRb - dR_loc).max() < 1e-11
            u = ranges[e, :, 0] + 0.5 * (x + 1) * (ranges[e, :, 1] - ranges[e, :, 0])
            assert np.abs(R_cp @ patch.control.reshape(-1, 3)[functions[e]] - patch.evaluate(u[None])[0]).max() < 1e-15


def test_local_bsplines_match_global_recursion():
    U = np.array([0, 0, 0, 0, 0.3, 0.5, 0.5, 1, 1, 1, 1.0])
    p = 3
    v, dv = np.empty(8), np.empty(8)
    for k in kv.spans(U, p):
        for x in (-1.0, -0.2, 0.6):
            u = U[k] + 0.5 * (x + 1) * (U[k + 1] - U[k])
            local_bsplines(p, np.ascontiguousarray(U[k - p + 1: k + p + 1]), x, v, dv)
            assert np.abs(v[: p + 1] - kv.bspline_values(U, p, [u])[0, k - p: k + 1]).max() < 1e-15
            d = kv.bspline_values(U, p, [u], derivative=True)[0, k - p: k + 1] * 0.5 * (U[k + 1] - U[k])
            assert np.abs(dv[: p + 1] - d).max() < 1e-13


@pytest.mark.parametrize("angle, elements, degree", [(90.0, (1, 1, 1), 2), (360.0, (1, 3, 1), 2),
                                                     (360.0, (2, 8, 1), 3), (135.0, (1, 4, 2), 2)])
def test_cylinder_is_exact(angle, elements, degree):
    """Points on the inner and outer surfaces lie at the exact radius; every point of the volume within
    the radii and the height; the end faces at the exact angles."""
    solid = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=angle, elements=elements, degree=degree)
    patch = solid.patches[0]
    xi = RNG.uniform(-1, 1, (30, 3))
    x = patch.evaluate_elements(xi)
    r = np.hypot(x[..., 0], x[..., 1])
    assert r.min() > 0.1 and r.max() < 0.2 and x[..., 2].min() > 0 and x[..., 2].max() < 0.3
    first = np.unravel_index(np.arange(patch.n_elements), patch.element_shape)[0]
    for side, radius, ids in ((-1.0, 0.1, first == 0), (1.0, 0.2, first == elements[0] - 1)):
        on = xi.copy()
        on[:, 0] = side
        y = patch.evaluate_elements(on)[ids]
        assert np.abs(np.hypot(y[..., 0], y[..., 1]) - radius).max() < 4e-16 * 0.2 / radius * 2
    theta = np.arctan2(x[..., 1], x[..., 0]) % (2 * np.pi)
    if angle < 360:
        assert theta.max() < np.radians(angle)
        # the end faces: θ = 0 on the first circumferential span's side -1, θ = angle on the last's side +1
        second = np.unravel_index(np.arange(patch.n_elements), patch.element_shape)[1]
        for side, expected, ids in ((-1.0, 0.0, second == 0), (1.0, np.radians(angle), second == elements[1] - 1)):
            on = xi.copy()
            on[:, 1] = side
            y = patch.evaluate_elements(on)[ids]
            assert np.abs(np.arctan2(y[..., 1], y[..., 0]) - expected).max() < 1e-14


def test_closed_pipe_seam_is_identified():
    solid = nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=360.0, elements=(1, 6, 2))
    patch = solid.patches[0]
    n0, n1, n2 = patch.shape
    ids = solid.patch_ids[0].reshape(patch.shape)
    assert (ids[:, 0, :] == ids[:, -1, :]).all()
    assert solid.n_control == patch.n_control - n0 * n2
    # the seam is the only identification
    assert len(np.unique(ids[:, :-1, :])) == n0 * (n1 - 1) * n2


def test_three_patches_of_120_degrees_share_their_faces():
    """The issue's input-file geometry: three 120° patches of a hollow cylinder (radii 0.2 / 0.3, height 1)."""
    patches = [nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=120.0, start=120.0 * k, elements=(1, 1, 1)).patches[0]
               for k in range(3)]
    solid = nurbs.NurbsSolid(patches)
    per_patch = patches[0].n_control
    shared = 3 * 3 * 3           # each of the three interfaces: a 3 × 3 net
    assert solid.n_control == 3 * per_patch - shared
    for k in range(3):
        a = solid.face_control(k, "u1_max")
        b = solid.face_control((k + 1) % 3, "u1_min")
        assert np.array_equal(a, b)


def test_brick_geometry_and_ranges():
    solid = nurbs.brick([0, 0, 0], [1, 2, 3], elements=(2, 1, 3), degree=3)
    patch = solid.patches[0]
    assert patch.element_shape == (2, 1, 3) and patch.degrees == (3, 3, 3)
    xi = RNG.uniform(-1, 1, (10, 3))
    x = patch.evaluate_elements(xi)
    ranges = patch.element_ranges()
    expected = (ranges[:, None, :, 0] + 0.5 * (xi[None] + 1) * (ranges[:, None, :, 1] - ranges[:, None, :, 0]))
    assert np.abs(x - expected * [1, 2, 3]).max() < 1e-14


@pytest.mark.parametrize("direction", [0, 1, 2])
def test_refinement_leaves_geometry_unchanged_and_nests_spaces(direction):
    base = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=90.0, elements=(1, 1, 1)).patches[0]
    u = RNG.uniform(0, 1, (40, 3))
    x = base.evaluate(u)
    inserted = base.insert_knots(direction, [0.3, 0.3, 0.71])
    elevated = base.elevate(direction, 2)
    both = inserted.elevate(direction)
    for refined in (inserted, elevated, both):
        assert np.abs(refined.evaluate(u) - x).max() < 1e-15
    # nested: every old B-spline is the combination T of the new ones, at points anywhere
    for U, p, new in ((base.knots[direction], 2, [0.3, 0.3, 0.71]),):
        V, T = kv.insertion_matrix(U, p, new)
        W, S = kv.elevation_matrix(V, p)
        t = RNG.uniform(0, 1, 50)
        old = kv.bspline_values(U, p, t)
        assert np.abs(kv.bspline_values(V, p, t) @ T - old).max() < 1e-15
        assert np.abs(kv.bspline_values(W, p + 1, t) @ S @ T - old).max() < 1e-14
        assert (T >= 0).all() and np.allclose(T.sum(axis=1), 1.0)   # new points: convex combinations of old


def test_extraction_reproduces_bsplines():
    U = np.array([0, 0, 0, 0, 0.3, 0.5, 0.5, 1, 1, 1, 1.0])
    p = 3
    C, first = kv.extraction_operators(U, p)
    for e, k in enumerate(kv.spans(U, p)):
        x = np.linspace(-1, 1, 9)
        u = U[k] + 0.5 * (x + 1) * (U[k + 1] - U[k])
        assert np.abs(kv.bspline_values(U, p, u)[:, first[e]: first[e] + p + 1]
                      - kv.bernstein_values(p, x) @ C[e].T).max() < 1e-15


@pytest.mark.parametrize("bad, message", [
    (dict(knots=[0, 0, 1, 1]), "at least 6 knots"),
    (dict(knots=[0, 0, 0, 0.5, 0.4, 1, 1, 1]), "non-decreasing"),
    (dict(knots=[0, 0, 0.2, 0.5, 1, 1, 1]), "open"),
    (dict(knots=[0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1]), "more than 2 times"),
])
def test_bad_knots(bad, message):
    with pytest.raises(ValueError, match=message):
        kv.check_knots(bad["knots"], 2)


def test_bad_generator_input():
    with pytest.raises(ValueError, match="at least 3"):
        nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=360.0, elements=(1, 2, 1))
    with pytest.raises(ValueError, match="r_inner < r_outer"):
        nurbs.hollow_cylinder(0.3, 0.2, 0.3)
    with pytest.raises(ValueError, match="weights positive"):
        base = nurbs.brick([0, 0, 0], [1, 1, 1]).patches[0]
        nurbs.NurbsPatch(base.control, -base.weights, base.knots, base.degrees)
