"""The engine's shortcuts give the results of the general path.

- Affine elements (every tet4, parallelepiped hex8, straight-edged quadratic elements) are
  located with their exact inverse map instead of Newton: the same points, segments and
  operators as the Newton path on a mesh perturbed just enough to leave the affine class.
- The crossing search skips faces whose control-point box misses the beam element's box: the
  control points of each face must contain the face (checked on curved faces of every type).
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import (MAX_CONTROL, FACE_CONTROL, N_FACE_CONTROL, SOLID_ELEMENTS,
                                                SOLID_MODULES, control_points)
from mortar1d3d._schedule import workers
from mortar1d3d.geometry.projection import linear_maps
from mortar1d3d.geometry.context import KernelInput
from mortar1d3d.study.reference import newton_projection

SOLID_TYPES = [n for n, d in SOLID_ELEMENTS.items() if not d.rational]     # nurbs27: test_nurbs_engine
#: types whose shape functions are linear: every element is affine, whatever its nodes (tet4)
ALWAYS_AFFINE = [n for n, d in SOLID_ELEMENTS.items() if d.monomials.sum(axis=1).max() <= 1]

# a shear and stretch: maps the unit-cube grid onto parallelepipeds (every element stays affine)
SHEAR = np.array([[1.0, 0.2, 0.1], [0.05, 0.9, 0.15], [0.0, 0.1, 1.1]])
SHIFT = np.array([0.3, -0.2, 0.1])


def sheared(solid, wobble=0.0, seed=4):
    """``solid`` mapped by SHEAR, SHIFT; ``wobble`` > 0 moves every node randomly by wobble · h."""
    points = solid.points @ SHEAR.T + SHIFT
    if wobble:
        points = points + wobble * 0.5 * np.random.default_rng(seed).uniform(-1, 1, points.shape)
    return m13.SolidMesh(points, solid.cells)


def sheared_beams(seed=2):
    """Random helix pieces inside the unit cube, mapped like the solid (so they stay inside it)."""
    beams = generate.random_curved_beams(3, 8, seed=seed)
    tangents = beams.tangents @ SHEAR.T
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    return m13.BeamMesh.hermite(beams.positions @ SHEAR.T + SHIFT, tangents, beams.elements)


def inverse_maps(solid):
    ctx = KernelInput(generate.random_curved_beams(1, 2, seed=1), solid)
    return ctx.linear


@pytest.mark.parametrize("element", SOLID_TYPES)
def test_affine_maps_are_found_exactly_for_parallelepipeds(element):
    box = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element)
    solid = sheared(box)
    table = inverse_maps(solid)
    assert (table[:, 4, 0] == 1.0).all()
    # ξ = ξ_c + L (x - x_c) takes every node to its reference coordinates
    descriptor = SOLID_ELEMENTS[element]
    reference = descriptor.reference_nodes
    n = len(reference)
    for s in range(solid.n_elements):
        X = solid.points[solid.connectivity[s, :n]]
        xi = descriptor.centre + (X - X[0] - table[s, 3]) @ table[s, :3].T
        np.testing.assert_allclose(xi, reference, rtol=0, atol=1e-14)
    # a perturbation far below any tolerance of the method, but above round-off: Newton path
    # (a tet4 stays affine whatever its nodes)
    exact = inverse_maps(sheared(box, wobble=1e-11))[:, 4, 0] == 1.0
    assert exact.all() if element in ALWAYS_AFFINE else not exact.any()


@pytest.mark.parametrize("element", SOLID_TYPES)
def test_curved_elements_get_their_centre_linearisation(element):
    """Distorted elements are left to Newton, which starts from ξ_c + J(ξ_c)⁻¹ (x - x(ξ_c))."""
    box = generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), element)
    solid = generate.distort(box, 0.15, seed=1)
    ctx = KernelInput(generate.random_curved_beams(1, 2, seed=1), solid)
    table = np.empty((solid.n_elements, 5, 3))
    linear_maps(ctx.points, ctx.conn, ctx.codes, ctx.solid_origin, ctx.solid_h, table, workers())
    np.testing.assert_array_equal(table, ctx.linear)
    descriptor = SOLID_ELEMENTS[element]
    module = SOLID_MODULES[element]
    n = descriptor.n_nodes
    N, dN = np.empty(n), np.empty((n, 3))
    module.shape(descriptor.centre, N)
    module.deriv(descriptor.centre, dN)
    moved = 0
    for s in range(solid.n_elements):
        X = solid.points[solid.connectivity[s, :n]] - solid.points[solid.connectivity[s, 0]]
        np.testing.assert_allclose(table[s, 3], N @ X, atol=1e-15)
        inverse = np.linalg.inv(X.T @ dN)
        np.testing.assert_allclose(table[s, :3], inverse, rtol=1e-12, atol=1e-12 * abs(inverse).max())
        moved += table[s, 4, 0] == 0.0
    # a tet4 is affine whatever its nodes; the other types: every element with a moved node (every
    # element of a hexahedral or tetrahedral split of 3 × 3 × 3 cells; a wedge split leaves two
    # wedges per layer without an interior node, which stay affine)
    node_moved = (solid.points != box.points).any(axis=1)
    with_moved_node = int(node_moved[solid.connectivity[:, :n]].any(axis=1).sum())
    if element not in ALWAYS_AFFINE and SOLID_ELEMENTS[element].family in ("hex", "tet"):
        assert with_moved_node == solid.n_elements
    assert moved == (0 if element in ALWAYS_AFFINE else with_moved_node)


@pytest.mark.parametrize("integration", ["segment", "element"])
@pytest.mark.parametrize("element", SOLID_TYPES)
def test_affine_location_gives_the_points_of_a_newton_projection(element, integration):
    solid = sheared(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element))
    ops = m13.assemble_mortar(sheared_beams(), solid, integration=integration, n_gauss=3)
    n = SOLID_ELEMENTS[element].n_nodes
    for p in ops.points:
        X = solid.points[solid.connectivity[p["solid_element"], :n]]
        xi = newton_projection(SOLID_MODULES[element], X, p["position"], p["xi"] * 0.9, iterations=30)
        np.testing.assert_allclose(p["xi"], xi, atol=1e-13)
    assert ops.constraint_residual < 1e-14


@pytest.mark.parametrize("integration", ["segment", "element"])
@pytest.mark.parametrize("element", [e for e in SOLID_TYPES if e not in ALWAYS_AFFINE])
def test_affine_location_gives_the_newton_operators(element, integration):
    box = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element)
    beams = sheared_beams()
    exact = m13.assemble_mortar(beams, sheared(box), integration=integration, n_gauss=4, lm="line3")
    newton = m13.assemble_mortar(beams, sheared(box, wobble=1e-11), integration=integration, n_gauss=4, lm="line3")
    assert exact.n_integration_points == newton.n_integration_points > 0
    np.testing.assert_array_equal(exact.segments["solid_element"], newton.segments["solid_element"])
    np.testing.assert_allclose(exact.segments["eta_start"], newton.segments["eta_start"], rtol=0, atol=1e-8)
    np.testing.assert_allclose(exact.points["xi"], newton.points["xi"], rtol=0, atol=1e-9)
    for name in ("D", "M"):
        a, b = getattr(exact, name), getattr(newton, name)
        assert abs(a - b).max() <= 1e-9 * abs(b).max()
    np.testing.assert_allclose(exact.kappa, newton.kappa, rtol=1e-9)
    # both are exact to round-off in their own geometry
    assert exact.constraint_residual < 1e-14 and newton.constraint_residual < 1e-14


@pytest.mark.parametrize("element", SOLID_TYPES)
def test_face_control_points_contain_the_face(element):
    """The hull of ``FACE_CONTROL`` points holds every point of the (curved) face."""
    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element), 0.2, seed=7)
    descriptor = SOLID_ELEMENTS[element]
    code, n = descriptor.code, descriptor.n_nodes
    module = SOLID_MODULES[element]
    u = np.linspace(0.0, 1.0, 9)
    shapes = descriptor.family_type.face_shapes
    C = np.empty((MAX_CONTROL, 3))
    N = np.empty(n)
    checked = 0
    for s in range(solid.n_elements):
        X = solid.points[solid.connectivity[s, :n]]
        control_points(code, np.ascontiguousarray(X), C)
        for f, (origin, a, b, _normal) in enumerate(descriptor.faces):
            ctrl = C[FACE_CONTROL[code, f, : N_FACE_CONTROL[code, f]]]
            lo, hi = ctrl.min(axis=0), ctrl.max(axis=0)
            corners = shapes[f].corners
            lower, upper = corners.min(axis=0), corners.max(axis=0)
            for i in u:
                for j in u:
                    # a lattice over the face shape's box, the points in the shape (left of every edge)
                    uv = lower + np.array([i, j]) * (upper - lower)
                    edges = np.roll(corners, -1, axis=0) - corners
                    if ((edges[:, 0] * (uv - corners)[:, 1] - edges[:, 1] * (uv - corners)[:, 0]) < -1e-15).any():
                        continue
                    xi = origin + uv[0] * a + uv[1] * b
                    module.shape(xi, N)
                    x = N @ X
                    assert np.all(x >= lo - 1e-14) and np.all(x <= hi + 1e-14), (element, s, f, xi)
                    checked += 1
    assert checked > 0


def test_face_control_points_of_linear_faces_are_its_corner_nodes():
    for element in ("hexahedron", "tetra"):
        d = SOLID_ELEMENTS[element]
        for f, nodes in enumerate(d.face_nodes):
            assert sorted(FACE_CONTROL[d.code, f, : N_FACE_CONTROL[d.code, f]]) == sorted(nodes)


def test_pairs_out_of_reach_are_the_pairs_whose_beam_box_misses_every_face_box():
    """The count in the diagnostics, against numpy boxes of the hex8 faces (corner nodes)."""
    beams, solid = generate.fibre_cube(4, 30, 6)
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=2)
    ctx = KernelInput(beams, solid)
    pair_beam = np.repeat(np.arange(beams.n_elements), np.diff(ctx.pair_offsets))
    X = solid.points[solid.connectivity[ctx.pair_solid, :8]]
    box = ctx.beam_boxes[pair_beam]
    margin = 1e-6 * (ctx.solid_h[ctx.pair_solid] + np.linalg.norm(box[:, 1] - box[:, 0], axis=1))[:, None]
    reached = np.zeros(len(pair_beam), dtype=bool)
    for nodes in SOLID_ELEMENTS["hexahedron"].face_nodes:
        face = X[:, list(nodes)]
        reached |= np.all((face.max(axis=1) >= box[:, 0] - margin) & (face.min(axis=1) <= box[:, 1] + margin), axis=1)
    assert ops.diagnostics["pairs_out_of_reach"] == np.count_nonzero(~reached)
    assert 0 < ops.diagnostics["pairs_out_of_reach"] < ops.diagnostics["candidate_pairs"]
    # beam elements all of whose pairs are out of reach: of the boxes, or of the linearised maps
    from mortar1d3d.geometry import segmentation
    unsearched = segmentation.pair_crossings(ctx, pair_beam, ctx.pair_solid, 6)[3]
    assert np.array_equal(unsearched == segmentation.BOX_MISS, ~reached)
    assert ops.diagnostics["pairs_out_of_linear_reach"] == np.count_nonzero(unsearched == segmentation.LINEAR_MISS)
    whole = np.logical_and.reduceat(unsearched != segmentation.SEARCHED, ctx.pair_offsets[:-1])
    assert ops.diagnostics["beam_elements_out_of_reach"] == np.count_nonzero(whole)
    assert ops.diagnostics["beam_elements_out_of_reach"] >= np.count_nonzero(
        np.logical_and.reduceat(~reached, ctx.pair_offsets[:-1]))


@pytest.mark.parametrize("element, curved", [("hexahedron", False), ("hexahedron", True), ("tetra10", False)])
def test_pairs_out_of_linear_reach_lie_entirely_inside_or_outside(element, curved):
    """Pairs the linearised map leaves unsearched: the centreline, located at 201 points, is inside the
    element at all of them or at none (no face crossing), on distorted cubes with straight and curved
    beams."""
    from mortar1d3d.geometry import segmentation
    from mortar1d3d.geometry.projection import INSIDE, project_points
    beams, cube = generate.fibre_cube(4, 40, 4, curved=curved)
    if element != "hexahedron":
        cube = generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 4), element=element)
    solid = generate.distort(cube, 0.1, seed=1)
    ctx = KernelInput(beams, solid)
    pair_beam = ctx.pair_beam()
    _, _, crossing_count, unsearched = segmentation.pair_crossings(ctx, pair_beam, ctx.pair_solid, 6)
    decided = np.flatnonzero(unsearched == segmentation.LINEAR_MISS)
    assert len(decided) > 0
    eta = np.linspace(-1.0, 1.0, 201)
    kinds = set()
    for p in decided:
        x = beams.evaluate(ctx.beam_ids[pair_beam[p]], eta)
        _, status = project_points(solid, x, np.full(len(eta), ctx.pair_solid[p]))
        inside = status == INSIDE
        assert inside.all() or not inside.any(), (element, curved, p)
        kinds.add(bool(inside[0]))
    # inside and outside both decided (the tetrahedra's outside pairs by their sample intervals, each beyond
    # some face's plane: their boxes drop the others)
    assert kinds == {False, True}
    assert crossing_count[unsearched == segmentation.SEARCHED].sum() > 0


@pytest.mark.parametrize("element", ["hexahedron", "tetra10"])
def test_crossing_table_overflow_is_searched_again(monkeypatch, element):
    """Pairs whose crossings do not fit the first, small table get the same crossings on a second pass."""
    from mortar1d3d.geometry import segmentation

    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), element), 0.15, seed=3)
    beams = generate.random_curved_beams(3, 6, seed=5)
    reference = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=3)
    assert reference.diagnostics["face_crossings"] > 10
    monkeypatch.setattr(segmentation, "_FIRST_CAPACITY", 1)     # nearly every crossing pair overflows
    ctx = KernelInput(beams, solid)
    pair_beam = np.repeat(np.arange(beams.n_elements), np.diff(ctx.pair_offsets))
    crossing_eta, crossing_face, crossing_count, _ = segmentation.pair_crossings(ctx, pair_beam, ctx.pair_solid, 6)
    assert crossing_count.max() > 1 and crossing_eta.shape[1] == crossing_count.max()   # the second pass ran
    assert crossing_face.shape == crossing_eta.shape
    for p, count in enumerate(crossing_count):          # every crossing names a face of its element
        assert np.all((crossing_face[p, :count] >= 0) & (crossing_face[p, :count] < 6))
    again = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=3)
    assert again.diagnostics["face_crossings"] == reference.diagnostics["face_crossings"]
    np.testing.assert_array_equal(again.segments, reference.segments)
    assert abs(again.M - reference.M).max() == 0.0 and abs(again.D - reference.D).max() == 0.0


def test_linear_reach_decides_a_beam_near_the_centre_and_refuses_crossings_and_near_faces():
    """One trilinear hexahedron (the unit cube with its node (1, 1, 1) moved to (0.7, 1, 1), so that the
    box of the face x = 1 reaches x = 0.7): a short beam at x = 0.70-0.74 meets that box but is left
    unsearched, and its one segment is the whole element; a beam through the planar face x = 0 and a
    beam inside, 0.08 from the face x = 1 (within the bound of the map's nonlinear part, about 0.32 in
    ξ), are searched, and the first one's segment starts on the face (a closed form: η = 0)."""
    from mortar1d3d.geometry import segmentation
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
                      dtype=float)
    points[6] += (-0.3, 0.0, 0.0)
    solid = m13.SolidMesh(points, {"hexahedron": np.arange(8)[None, :]})
    ends = [((0.70, 0.5, 0.5), (0.74, 0.52, 0.5)),       # meets the box of face x = 1: decided
            ((-0.2, 0.3, 0.4), (0.2, 0.3, 0.4)),         # through the face x = 0 (nodes 0, 3, 4, 7: not moved)
            ((0.9, 0.2, 0.2), (0.9, 0.3, 0.25))]         # inside, 0.08-0.09 from face x = 1: not decidable
    beams = m13.BeamMesh.hermite([p for pair in ends for p in pair],
                                 [np.subtract(b, a) / np.linalg.norm(np.subtract(b, a)) for a, b in ends
                                  for _ in range(2)], [[0, 1], [2, 3], [4, 5]])
    ctx = KernelInput(beams, solid)
    _, _, count, unsearched = segmentation.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, 6)
    assert list(unsearched) == [segmentation.LINEAR_MISS, segmentation.SEARCHED, segmentation.SEARCHED]
    assert list(count > 0) == [False, True, False]
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=2)
    s = ops.segments
    assert list(s["beam_element"]) == [0, 1, 2]
    assert s["eta_start"][0] == -1.0 and s["eta_end"][0] == 1.0
    # beam 1: x = 0.2 η on y = 0.3, z = 0.4 (a straight Hermite element), inside for x >= 0
    assert abs(s["eta_start"][1]) < 1e-12 and s["eta_end"][1] == 1.0
    assert s["eta_start"][2] == -1.0 and s["eta_end"][2] == 1.0
    assert ops.diagnostics["pairs_out_of_linear_reach"] == 1


def element_bounds(ctx):
    """``segmentation.linear_errors`` of every element of the context, candidate of a beam element or not."""
    from mortar1d3d.geometry import segmentation
    errors = np.full((len(ctx.codes), 3), np.nan)
    segmentation._linear_errors(np.arange(len(ctx.codes)), ctx.codes, ctx.conn, ctx.points, ctx.solid_origin,
                                ctx.linear, errors)
    return errors


def test_curved_tetrahedra_bound_their_linearised_map_by_bernstein_coefficients():
    """The bound ε of a curved tet10 (``segmentation._linear_error``: the Bernstein coefficients of the remainder
    of its map linearised at the centre) holds at 2000 random parameters of each of the 48 elements of a distorted
    cube (0.15 cells), 500 up to 2.5e-5 outside the simplex (the growth the bound covers: ``_BERNSTEIN_GROWTH`` 1e-4
    of the centre's distance 1/4 to each face) and its nodes: the largest deviation sampled comes to over 85 % of
    ε on average (over 45 % on every element). The sum of the monomial terms over the box |ξ - ξ_c|∞ <= 3/4
    (the bound before) is over 5 times larger on average (ε under 0.2 of it), and larger on every element
    (ε under 0.65 of it)."""
    import naive
    from mortar1d3d.geometry import segmentation
    assert segmentation._BERNSTEIN_GROWTH == 1e-4
    solid = generate.distort(generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), "tetra10"), 0.15, seed=1)
    ctx = KernelInput(generate.random_curved_beams(1, 2, seed=1), solid)
    assert (ctx.linear[:, 4, 0] == 0.0).all()
    errors = element_bounds(ctx)
    rng = np.random.default_rng(0)
    xi = np.vstack([naive.random_parameters("tet", rng, 2000),
                    naive.random_parameters("tet", rng, 500, low=0.0, high=2.5e-5, grow=1e-4),
                    SOLID_ELEMENTS["tetra10"].reference_nodes])
    sampled, tighter = [], []
    for s in range(solid.n_elements):
        X = solid.points[solid.connectivity[s]] - solid.points[solid.connectivity[s, 0]]
        deviation = naive.linear_map_deviation("tetra10", X, ctx.linear[s, :3], ctx.linear[s, 3], xi).max(axis=0)
        assert np.all(deviation <= errors[s])
        sampled.append(deviation / errors[s])
        tighter.append(errors[s] / naive.monomial_error_bound("tetra10", X, ctx.linear[s, :3], 0.75 * (1.0 + 1e-6)))
    assert np.mean(sampled) > 0.85 and np.min(sampled) > 0.45
    assert np.mean(tighter) < 0.2 and np.max(tighter) < 0.65


@pytest.mark.parametrize("element, inside", [("hexahedron", 500), ("hexahedron27", 300), ("tetra10", 10)])
def test_linear_side_agrees_with_the_locator(element, inside):
    """Points the linearised map decides (``segmentation._linear_side``: inside, or outside, for certain)
    are located there by the library's locator too: 4000 random points around the elements of a distorted
    cube (0.1 cells), each against the element it was drawn near and that element's neighbour. The
    curved tetrahedra, small against their bound, are decided inside only near their centres."""
    from mortar1d3d.geometry import segmentation
    from mortar1d3d.geometry.projection import INSIDE, project_points
    cube = generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (3, 3, 3), element=element)
    solid = generate.distort(cube, 0.1, seed=2)
    ctx = KernelInput(generate.random_curved_beams(1, 2, seed=1), solid)
    errors = element_bounds(ctx)
    rng = np.random.default_rng(7)
    elements = rng.integers(0, solid.n_elements, 4000)
    elements = np.concatenate([elements, (elements + 1) % solid.n_elements])
    centre = solid.points[solid.connectivity[elements % solid.n_elements]].mean(axis=1)
    spread = 0.5 * ctx.solid_h[elements[:4000], None]
    x = np.concatenate([centre[:4000] + spread * rng.uniform(-1, 1, (4000, 3))] * 2)
    side = np.array([segmentation._linear_side(ctx.codes[s], s, ctx.linear, errors, *(x[i] - ctx.solid_origin[s]),
                                               segmentation._SIDE_MARGIN) for i, s in enumerate(elements)])
    _, status = project_points(solid, x, elements)
    assert np.all(status[side < 0] == INSIDE)
    assert np.all(status[side > 0] != INSIDE)
    # it decides most points, in both ways, and leaves some near the faces to the locator
    assert np.count_nonzero(side < 0) > inside and np.count_nonzero(side > 0) > 5000
    assert np.count_nonzero(side == 0) > 100


def test_linear_side_decides_the_centre_and_far_points_and_refuses_points_near_a_face():
    """The hexahedron of the test above (node (1, 1, 1) moved to (0.7, 1, 1): the bound of its map's
    nonlinear part is about 0.32 in ξ): its centre is inside for certain, a point 0.5 beyond the planar
    face x = 0 outside for certain; points 0.05 inside and 0.05 outside that face, within the bound,
    are left to the locator; an affine element is always left to its exact inverse map."""
    from mortar1d3d.geometry import segmentation
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
                      dtype=float)
    curved = points.copy()
    curved[6] += (-0.3, 0.0, 0.0)
    for nodes, expected in ((curved, [-1, 1, 0, 0]), (points, [0, 0, 0, 0])):
        solid = m13.SolidMesh(nodes, {"hexahedron": np.arange(8)[None, :]})
        ctx = KernelInput(generate.random_curved_beams(1, 2, seed=1), solid)
        errors = element_bounds(ctx)
        # the moved node bends the map in x only
        assert (errors[0, 0] > 0.3 if nodes is curved else errors[0, 0] < 1e-14) and np.all(errors[0, 1:] < 1e-14)
        sides = [segmentation._linear_side(ctx.codes[0], 0, ctx.linear, errors, *(np.array(x) - ctx.solid_origin[0]),
                                           segmentation._SIDE_MARGIN)
                 for x in ((0.45, 0.5, 0.5), (-0.5, 0.5, 0.5), (0.05, 0.5, 0.5), (-0.05, 0.5, 0.5))]
        assert sides == expected


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27", "tetra10"])
def test_tiling_and_its_check_give_the_same_answers_without_the_linearised_map(element):
    """The tiling's owners and the tiling check's probes, decided by the linearised map where it can
    (``segmentation._linear_side``), against the same stages with no element bound (every point
    projected): the same segments, bit for bit, and the same verdicts of the check, on a distorted cube
    with curved fibres, and with a segment's owner replaced (the check must fail there either way)."""
    from mortar1d3d.geometry import segmentation
    beams, cube = generate.fibre_cube(4, 60, 4, curved=True)
    if element != "hexahedron":
        cube = generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 4), element=element)
    solid = generate.distort(cube, 0.12, seed=3)
    ctx = KernelInput(beams, solid)
    errors = segmentation.linear_errors(ctx)
    blind = np.full_like(errors, np.nan)
    eta, face, count, unsearched = segmentation.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, 6, errors)
    tiled = segmentation.tile(ctx, eta, face, count, errors)
    reference = segmentation.tile(ctx, eta, face, count, blind)
    for a, b in zip(tiled, reference):
        np.testing.assert_array_equal(a, b)
    # the map decides most of the segments' midpoints in their owners (the comparison is not empty)
    mid = [beams.evaluate(b, [0.5 * (a + c)])[0] for b, a, c in zip(tiled[0], tiled[2], tiled[3])]
    sides = [segmentation._linear_side(ctx.codes[s], s, ctx.linear, errors, *(x - ctx.solid_origin[s]),
                                       segmentation._SIDE_MARGIN) for s, x in zip(tiled[1], mid)]
    least = {"hexahedron": len(sides) // 2, "hexahedron27": len(sides) // 10, "tetra10": 20}[element]
    assert sides.count(1) == 0 and sides.count(-1) > least
    certain = np.zeros(ctx.n_beam, dtype=bool)
    good = segmentation.check_tiling(ctx, *tiled[1:4], tiled[4], certain, errors)
    assert not good.any()
    np.testing.assert_array_equal(good, segmentation.check_tiling(ctx, *tiled[1:4], tiled[4], certain, blind))
    owners = tiled[1].copy()
    owners[::7] = (owners[::7] + 5) % solid.n_elements        # a wrong owner every seventh segment
    bad = segmentation.check_tiling(ctx, owners, *tiled[2:4], tiled[4], certain, errors)
    assert bad.any()
    np.testing.assert_array_equal(bad, segmentation.check_tiling(ctx, owners, *tiled[2:4], tiled[4], certain, blind))


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27", "tetra10"])
def test_crossings_are_the_same_with_the_intervals_the_linearised_map_rules_out(element):
    """The crossing search without the sample intervals the linearised map rules out
    (``segmentation._live_intervals``) against the same search with no element bound (every sample
    projected, every interval searched): the same crossings of the same faces (η to 1e-12: the samples
    are warm-started from other samples), on a distorted cube with curved fibres."""
    from mortar1d3d.geometry import segmentation
    beams, cube = generate.fibre_cube(4, 60, 4, curved=True)
    if element != "hexahedron":
        cube = generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 4), element=element)
    ctx = KernelInput(beams, generate.distort(cube, 0.12, seed=3))
    errors = segmentation.linear_errors(ctx)
    found = segmentation.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, 6, errors)
    blind = segmentation.pair_crossings(ctx, ctx.pair_beam(), ctx.pair_solid, 6, np.full_like(errors, np.nan))
    def distinct(table, p):
        """(face, η) of pair p's crossings, one of each crossing found from several starts (within 1e-9)."""
        out = []
        for face, eta in sorted(zip(table[1][p, :table[2][p]], table[0][p, :table[2][p]])):
            if not out or out[-1][0] != face or eta - out[-1][1] > 1e-9:
                out.append((face, eta))
        return np.array(out).reshape(-1, 2)

    assert found[2].sum() > 50
    for p in np.flatnonzero(found[2] + blind[2]):
        np.testing.assert_allclose(distinct(found, p), distinct(blind, p), rtol=0, atol=1e-12)
    # blind, only the boxes decide pairs; with the bound, more pairs are left unsearched
    assert np.count_nonzero(found[3] == segmentation.LINEAR_MISS) > 0 == np.count_nonzero(
        blind[3] == segmentation.LINEAR_MISS)


def test_live_intervals_skip_samples_far_from_the_faces_and_keep_those_near_a_crossing():
    """The hexahedron with the moved node (bound about 0.32 in ξ, in x only) and a straight beam along x
    from -0.5 to 0.5 (y = 0.3, z = 0.4), through its planar face x = 0 at η = 0: of the six samples
    (x = -0.5, -0.3, ..., 0.5) the first interval lies beyond that face's plane by more than the bound
    and the last one behind every face's plane by more: neither is searched, and their outer samples are
    not projected; the three intervals within the bound of the face x = 0 are searched for it."""
    from mortar1d3d.elements.solid.dispatch import faces
    from mortar1d3d.geometry import segmentation
    from mortar1d3d.geometry.beam import beam_point
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
                      dtype=float)
    points[6] += (-0.3, 0.0, 0.0)
    solid = m13.SolidMesh(points, {"hexahedron": np.arange(8)[None, :]})
    beams = m13.BeamMesh.hermite([(-0.5, 0.3, 0.4), (0.5, 0.3, 0.4)], [(1.0, 0.0, 0.0)] * 2, [[0, 1]])
    ctx = KernelInput(beams, solid)
    errors = segmentation.linear_errors(ctx)
    code = ctx.codes[0]
    S = 6
    eta = np.linspace(-1.0, 1.0, S)
    shift = ctx.beam_origin[0] - ctx.solid_origin[0]
    H, dH = np.empty(8), np.empty(8)
    rs = np.array([beam_point(ctx.beam_code, ctx.Q[0], ctx.lengths[0], *shift, t, H, dH) for t in eta])
    reach = np.ones(6, dtype=bool)
    live, need, zs = np.zeros((S, 6), dtype=bool), np.zeros(S, dtype=bool), np.empty((S, 6))
    assert segmentation._live_intervals(code, 0, ctx.solid_h[0], ctx.linear, errors, eta, rs, reach, zs, live, need)
    x_minus = int(np.flatnonzero(np.all(faces(code)[:, 3] == (-1.0, 0.0, 0.0), axis=1))[0])
    assert list(need) == [False, True, True, True, True, False]
    assert list(live[:S - 1, x_minus]) == [False, True, True, True, False]
    assert not live[:S - 1, np.arange(6) != x_minus].any()
    # the crossing is found: one segment from the face (η = 0) to the end
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=2)
    assert abs(ops.segments["eta_start"][0]) < 1e-12 and ops.segments["eta_end"][0] == 1.0
