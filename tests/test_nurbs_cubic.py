"""Cubic NURBS spans (issue 19, p-refinement): the ``nurbs64`` rational Bézier element in the engine and
the model, as the quadratic ``nurbs27`` is tested in test_nurbs_engine.py.

References: the exact hollow-cylinder sector (radius, angle, height) with crossings by bisection
(tests/naive.py), the NURBS functions by Cox–de Boor over the knot vectors (the patch's own
``evaluate``), central differences for derivatives.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import nurbs
from mortar1d3d.elements.solid import dispatch
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
from mortar1d3d.elements.validity import FOLDED, INVERTED, VALID, jacobian_validity
from mortar1d3d.geometry.projection import INSIDE, OUTSIDE

import naive
from test_nurbs_engine import _crossing_beam

NURBS64 = SOLID_ELEMENTS["nurbs64"]
RNG = np.random.default_rng(64)


def sector(angle=90.0, elements=(1, 1, 1), r=(0.1, 0.2), height=0.3):
    return nurbs.bezier_mesh(nurbs.hollow_cylinder(r[0], r[1], height, angle=angle, elements=elements, degree=3))


def test_rational_functions_partition_of_unity_and_derivatives():
    """R_a = w_a B_a / W of nurbs64 with random weights: Σ R_a = 1, Σ ∂R_a = 0, ∂R_a against central
    differences (h = 1e-6: error ~h² · |∂³R| + round-off/h)."""
    code = NURBS64.code
    X = np.zeros((64, 4))
    X[:, 3] = RNG.uniform(0.5, 2.0, 64)
    N, dN = np.empty(64), np.empty((64, 3))
    Np, Nm = np.empty(64), np.empty(64)
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
    B = np.empty(64)
    dispatch.shape(code, np.array([-1.0, -1.0, -1.0]), B)
    assert B[0] == 1.0 and np.abs(B[1:]).max() == 0.0
    xi = RNG.uniform(-1, 1, 3)
    dispatch.shape(code, xi, B)
    assert np.abs(B @ NURBS64.reference_nodes - xi).max() < 1e-15     # Bernstein points of a linear map


@pytest.mark.parametrize("angle, elements", [(90.0, (1, 1, 1)), (360.0, (2, 4, 1))])
def test_cubic_cylinder_is_exact_and_elevation_keeps_the_geometry(angle, elements):
    """The Bézier mesh of the degree-elevated pipe: its elements (the engine's kernel) give the points of
    the quadratic patch (Cox–de Boor) to round-off, and its inner/outer faces lie on the exact radius."""
    quadratic = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=angle, elements=elements)
    bm = nurbs.bezier_mesh(nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=angle, elements=elements, degree=3))
    assert bm.solid.blocks[0][0].name == "nurbs64" and bm.solid.n_elements == np.prod(elements)
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


def test_points_are_found_where_they_are():
    """The trust property on cubic curved spans: x(ξ) inside is INSIDE at ξ to 1e-10; x(ξ) just beyond a
    face is never INSIDE."""
    bm = sector(360.0, (1, 3, 1), r=(0.2, 0.3), height=1.0)
    patch = bm.nurbs.patches[0]
    xi = RNG.uniform(-1, 1, (40, 3))
    x = patch.evaluate_elements(xi)
    elements = np.repeat(np.arange(patch.n_elements), len(xi))
    found, status = m13.project_points(bm.solid, x.reshape(-1, 3), elements)
    assert (status == INSIDE).all()
    assert np.abs(found - np.tile(xi, (patch.n_elements, 1))).max() < 1e-10
    out = xi.copy()
    axis = RNG.integers(0, 3, len(out))
    out[np.arange(len(out)), axis] = np.where(RNG.uniform(size=len(out)) < 0.5, -1.0, 1.0) * (1 + 1e-6)
    found, status = m13.project_points(bm.solid, patch.evaluate_elements(out).reshape(-1, 3), elements)
    assert not (status == INSIDE).any()
    hit = status == OUTSIDE
    assert hit.mean() > 0.95 and (np.abs(found[hit]).max(axis=1) > 1 + 1e-7).all()


def test_curved_beam_crossing_the_inner_face_twice_has_two_pieces():
    """The 90° hollow-cylinder element, now one cubic span: the curved line dips into the hole (two
    crossings of the inner face) and gives two pieces at the crossings found by bisection."""
    bm = sector()
    beams = _crossing_beam([[0.16, -0.02, 0.05], [0.06, 0.06, 0.2], [-0.02, 0.16, 0.1]])
    reference = naive.indicator_crossings(lambda eta: beams.evaluate(0, eta),
                                          lambda x: naive.in_sector(x, 0.1, 0.2, 90.0, 0.3))
    assert len(reference) == 4
    ops = m13.assemble_mortar(beams, bm.solid, integration="segment", n_gauss=6)
    seg = np.sort(ops.segments, order="eta_start")
    assert len(seg) == 2 and (seg["solid_element"] == 0).all()
    found = np.column_stack([seg["eta_start"], seg["eta_end"]]).ravel()
    assert np.abs(found - reference).max() < 1e-12
    assert ops.constraint_residual < 1e-14


@pytest.mark.parametrize("integration", ["segment", "element"])
def test_operators_on_a_closed_cubic_pipe(integration):
    """Curved beams through a closed cubic pipe of 2 × 4 × 2 elements: D q_B − M X_S = 0 on the mesh
    and on the control points, M against Σ w Φ_j R_i with R_i by Cox–de Boor, and (segment-based)
    the coupled length equals the length inside the pipe by bisection (tiling)."""
    bm = nurbs.bezier_mesh(nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=360.0, elements=(2, 4, 2), degree=3))
    beams = m13.BeamMesh.join([_crossing_beam([[0.35, -0.05, 0.1], [0.0, 0.45, 0.5], [-0.35, 0.05, 0.9]]),
                               _crossing_beam([[0.28, -0.2, 0.3], [0.1, 0.1, 0.6], [-0.28, 0.2, 0.45]])])
    ops = m13.assemble_mortar(beams, bm.solid, integration=integration, n_gauss=6)
    assert ops.constraint_residual < 1e-13
    M = bm.nodes_to_control(ops.M)
    Dq = ops.D @ beams.centreline_dofs()
    assert np.linalg.norm(Dq - M @ bm.nurbs.control.ravel()) < 1e-13 * np.linalg.norm(Dq)
    patch, ids = bm.nurbs.patches[0], bm.nurbs.patch_ids[0]
    lm_rows, _ = naive.lm_rows(beams, 2)
    expected = np.zeros((ops.n_lm, bm.nurbs.n_control))
    for p in ops.points:
        R = naive.nurbs_functions(patch, int(p["solid_element"]), p["xi"])
        rows = lm_rows[int(p["beam_element"])]
        np.add.at(expected, (rows[:, None], ids[None, :]), p["weight"] * np.outer(naive.multiplier_values("line2", p["eta"]), R))
    assert np.abs(M.toarray()[0::3, 0::3] - expected).max() < 1e-14
    if integration == "segment":
        inside = 0.0
        for e in range(beams.n_elements):
            eta = naive.indicator_crossings(lambda t: beams.evaluate(e, t),
                                            lambda x: naive.in_sector(x, 0.2, 0.3, 360.0, 1.0))
            start_inside = naive.in_sector(beams.evaluate(e, [-1.0]), 0.2, 0.3, 360.0, 1.0)[0]
            bounds = np.concatenate([[-1.0] if start_inside else [], eta])
            bounds = np.concatenate([bounds, [1.0]]) if len(bounds) % 2 else bounds
            inside += sum(naive.arc_length(beams, e, a, b) for a, b in bounds.reshape(-1, 2))
        assert abs(ops.embedded_length - inside) < 1e-8 * inside


def test_validity_of_cubic_elements():
    bm = sector(360.0, (2, 4, 1))
    n = NURBS64.n_nodes
    X = bm.solid.points[bm.solid.connectivity[:, :n]]
    W = bm.solid.weights[bm.solid.connectivity[:, :n]]
    h = np.linalg.norm(X.max(axis=1) - X.min(axis=1), axis=1)
    assert (jacobian_validity(NURBS64, X, h, W) == VALID).all()
    assert (jacobian_validity(NURBS64, X * [1, 1, -1], h, W) == INVERTED).all()
    # an interior control point pushed far through the element: folded inside, fine at the corners
    interior = np.flatnonzero((np.abs(NURBS64.reference_nodes) < 1).all(axis=1))[0]
    Y = X[:1].copy()
    Y[0, interior] += 20.0 * (Y[0, 1] - Y[0, 0])
    assert jacobian_validity(NURBS64, Y, h[:1], W[:1])[0] == FOLDED


def test_vtu_of_cubic_spans(tmp_path):
    """A cubic span is written as 2 × 2 × 2 hexahedron27 cells through its exact points, each cell with
    its span's cell data."""
    import meshio

    from mortar1d3d.io.vtu import write_solid

    solid = sector(90.0, (1, 2, 1), height=0.05).solid
    path = write_solid(tmp_path / "c.vtu", solid, point_data={"x": solid.points},
                       cell_data={"id": np.arange(solid.n_elements) * 10})
    mesh = meshio.read(path)
    assert mesh.cells_dict["hexahedron27"].shape == (16, 27)
    assert np.abs(mesh.point_data["x"] - mesh.points).max() < 1e-15
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    on_inner = np.abs(r - 0.1) < 1e-9
    assert on_inner.sum() == 2 * 4 * 9 and np.abs(r[on_inner] - 0.1).max() < 1e-15
    assert mesh.cell_data["id"][0].tolist() == [0] * 8 + [10] * 8
