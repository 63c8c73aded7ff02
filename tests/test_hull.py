"""The hull planes of the candidate test (``geometry.search``: :func:`solid_hulls`, :func:`in_hull`,
:func:`hull_pairs`): one half-space per face of every solid element, which pairs and points must lie
in before a Newton projection.

The planes may only reject what no inside test accepts. Checked here: points x(ξ) made with the
monomial reference of tests/naive.py (no shape function of the library) for ξ inside every element
type, on its boundary and up to 1e-6 outside (the loosest inside tolerance) all pass; on undistorted
tetrahedra the planes are the faces' own planes (closed form); NURBS spans with unequal weights
pass likewise; and ``assemble_mortar`` gives the same bits with the planes as with planes that bound
nothing. tests/test_naive_references.py checks the pairs against the pairs a beam really enters.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate, nurbs
from mortar1d3d.elements.solid.dispatch import BY_CODE, MAX_FACES, NODAL_ELEMENTS
from mortar1d3d.geometry import context
from mortar1d3d.geometry.search import HULL_MARGIN, in_hull, solid_frames, solid_hulls

import naive


def hulls(solid):
    """The planes of every element of ``solid``, the element sizes and origins."""
    _, h, origin = solid_frames(solid)
    return solid_hulls(solid.kernel_points, solid.connectivity, solid.element_codes, origin, h), h, origin


def passes(hull, s, x_local):
    """in_hull for every row of ``x_local`` (points in element s's frame)."""
    return np.array([in_hull(hull, s, *x) for x in x_local])


def mapped(solid, s, xi):
    """x(ξ) (m, 3) of element s by the monomial reference (tests/naive.py)."""
    d = BY_CODE[int(solid.element_codes[s])]
    N, _ = naive.shape_values(d.name, xi)
    return N @ solid.points[solid.connectivity[s, : d.n_nodes]]


def band(family, rng, n, width):
    """n parameter points up to ``width`` beyond a face plane of the reference element (random inside
    points moved onto a random face along its normal, then out by up to ``width``)."""
    faces = naive.family(family).faces
    xi = naive.random_parameters(family, rng, n)
    f = rng.integers(0, len(faces), n)
    origin, normal = faces[f, 0], faces[f, 3]
    scale = (np.einsum("ni,ni->n", normal, xi - origin) - width * rng.uniform(0.0, 1.0, n)) / (normal ** 2).sum(axis=1)
    return xi - scale[:, None] * normal


@pytest.mark.parametrize("element", list(NODAL_ELEMENTS))
def test_planes_keep_every_point_an_inside_test_accepts(element):
    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element), 0.15, seed=1)
    descriptor = BY_CODE[int(solid.element_codes[0])]
    family = descriptor.family
    hull, h, origin = hulls(solid)
    if not descriptor.hull_test:
        # a type without planes (its descriptor's hull_test: hex8): zero rows, no bound
        assert not hull.any()
        return
    rng = np.random.default_rng(7)
    rejected = 0
    for s in range(solid.n_elements):
        inside = np.vstack([naive.random_parameters(family, rng, 100), naive.reference_samples(family, 5),
                            band(family, rng, 100, 1e-6)])
        assert naive.outside_distance(family, inside).max() > 0.5e-6
        assert passes(hull, s, mapped(solid, s, inside) - origin[s]).all(), (element, s)
        # well outside (0.3 to 0.5 beyond a face plane in parameter units): mostly rejected, so the
        # planes are not vacuous
        far = naive.random_parameters(family, rng, 100, low=0.3, high=0.5, grow=0.5)
        rejected += np.count_nonzero(~passes(hull, s, mapped(solid, s, far) - origin[s]))
    assert rejected > 0.5 * 100 * solid.n_elements, rejected


@pytest.mark.parametrize("element", ["tetra", "tetra10"])
def test_planes_of_straight_tetrahedra_are_their_faces(element):
    solid = generate.box((0, 0, 0), (1, 2, 3), (1, 1, 1), element)          # the six Kuhn tetrahedra
    hull, h, origin = hulls(solid)
    faces = BY_CODE[int(solid.element_codes[0])].family_type.face_nodes
    for s in range(solid.n_elements):
        corners = solid.points[solid.connectivity[s, :4]] - origin[s]
        for f, nodes in enumerate(faces):
            a, b, c = corners[list(nodes)]
            normal = np.cross(b - a, c - a)
            normal /= np.linalg.norm(normal)
            opposite = corners[[k for k in range(4) if k not in nodes][0]]
            normal *= np.sign(normal @ (a - opposite))                     # away from the fourth corner
            np.testing.assert_allclose(hull[s, f, :3], normal, rtol=0, atol=1e-15)
            # the face's own plane moved out by the margin (and a few ulps for the round-off of shifting
            # frames, far below the margin): between 1 and 2 margins beyond the face
            assert normal @ a + HULL_MARGIN * h[s] <= hull[s, f, 3] <= normal @ a + 2 * HULL_MARGIN * h[s]
        np.testing.assert_array_equal(hull[s, 4:], 0.0)                     # a tetrahedron has 4 faces
    assert hull.shape[1] == MAX_FACES


def test_planes_of_rational_spans_keep_their_points():
    """NURBS spans with weights 0.8…1.25 of the pipe's (as tests/test_nurbs_engine.py's ``jittered``)."""
    rng = np.random.default_rng(3)
    patch = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=360.0, elements=(2, 4, 2)).patches[0]
    control = patch.control + rng.uniform(-0.002, 0.002, patch.control.shape)
    control[:, -1] = control[:, 0]
    weights = patch.weights * rng.uniform(0.8, 1.25, patch.weights.shape)
    weights[:, -1] = weights[:, 0]
    bm = nurbs.bezier_mesh(nurbs.NurbsSolid([nurbs.NurbsPatch(control, weights, patch.knots, patch.degrees)]))
    span = bm.nurbs.patches[0]
    hull, h, origin = hulls(bm.solid)
    xi = np.vstack([rng.uniform(-1, 1, (60, 3)), naive.reference_samples("hex", 3)])
    edge = rng.uniform(-1, 1, (60, 3))
    edge[np.arange(60), rng.integers(0, 3, 60)] = np.where(rng.uniform(size=60) < 0.5, -1.0, 1.0) * (1 + 1e-6)
    x = span.evaluate_elements(np.vstack([xi, edge]))                      # (elements, points, 3)
    far = rng.uniform(-1, 1, (60, 3))
    far[np.arange(60), rng.integers(0, 3, 60)] = np.where(rng.uniform(size=60) < 0.5, -1.0, 1.0) * 1.5
    y = span.evaluate_elements(far)
    assert len(x) == bm.solid.n_elements
    rejected = 0
    for s in range(bm.solid.n_elements):
        assert passes(hull, s, x[s] - origin[s]).all(), s
        rejected += np.count_nonzero(~passes(hull, s, y[s] - origin[s]))
    assert rejected > 0.5 * 60 * bm.solid.n_elements, rejected


def no_planes(points, conn, codes, solid_origin, solid_h, margin=None, elements=None):
    """Planes that bound nothing (normal 0, offset 0): every pair and point goes to Newton, as before them."""
    return np.zeros((conn.shape[0], MAX_FACES, 4))


def _mixed_mesh():
    """A distorted hex8 block (a type without planes) beside a distorted tet10 block (with them), the
    two meshed independently and joined at x = 1 without shared nodes."""
    hexes = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), "hexahedron"), 0.1, seed=1)
    tets = generate.distort(generate.box((1, 0, 0), (2, 1, 1), (3, 3, 3), "tetra10"), 0.1, seed=2)
    return m13.SolidMesh(np.vstack([hexes.points, tets.points]),
                         {"hexahedron": hexes.connectivity[:, :8], "tetra10": tets.connectivity[:, :10] + hexes.n_nodes})


def _mixed_beams():
    """fibre_cube's 30 straight fibres stretched along x over both blocks."""
    beams, _ = generate.fibre_cube(4, 30, 4)
    stretch = np.array([2.0, 1.0, 1.0])
    t = beams.tangents * stretch
    return m13.BeamMesh.hermite(beams.positions * stretch, t / np.linalg.norm(t, axis=1)[:, None], beams.elements)


@pytest.mark.parametrize("element", ["tetra10", "hexahedron27", "mixed"])
def test_operators_are_the_same_without_the_planes(element, monkeypatch):
    """Planes or none: the same operators. Element-based to the bit; segment-based the same segments,
    points and CSR structure with values equal to round-off (a crossing-search sample beyond a
    plane keeps its warm-started Newton solution, which without planes is solved again from the
    linearised map: the face-Newton starts differ at the Newton tolerance, the crossings they
    converge to by round-off). ``mixed``: hex8 (no planes, zero rows) and tet10 (planes) in one
    mesh, so that the per-type choice is tested where both kinds meet."""
    if element == "mixed":
        beams, solid = _mixed_beams(), _mixed_mesh()
        hull, _, _ = hulls(solid)
        hex8 = solid.element_codes == BY_CODE[0].code
        assert BY_CODE[0].name == "hexahedron" and hex8.any() and (~hex8).any()
        assert not hull[hex8].any() and hull[~hex8].any()
    else:
        beams, _ = generate.fibre_cube(4, 30, 4)
        solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (4, 4, 4), element), 0.1, seed=1)
    results = {}
    for planes in ("hull", "none"):
        if planes == "none":
            monkeypatch.setattr(context, "solid_hulls", no_planes)
        for integration in ("element", "segment"):
            ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
            results[planes, integration] = ops
    for integration in ("element", "segment"):
        a, b = results["hull", integration], results["none", integration]
        exact = integration == "element"

        def same(x, y, scale, what):
            if exact:
                assert np.asarray(x).tobytes() == np.asarray(y).tobytes(), (integration, what)
            else:
                np.testing.assert_allclose(x, y, rtol=0.0, atol=1e-14 * scale, err_msg=f"{integration} {what}")

        # the planes drop pairs (tetrahedra: most of the boxes' overlaps), and nothing else changes
        assert a.diagnostics["candidate_pairs"] < b.diagnostics["candidate_pairs"]
        for name in ("D", "M"):
            x, y = getattr(a, name).tocsr(), getattr(b, name).tocsr()
            np.testing.assert_array_equal(x.indptr, y.indptr)
            np.testing.assert_array_equal(x.indices, y.indices)
            same(x.data, y.data, np.abs(y.data).max(), name)
        same(a.kappa, b.kappa, np.abs(b.kappa).max(), "kappa")
        for field in ("beam_element", "solid_element"):
            np.testing.assert_array_equal(a.segments[field], b.segments[field])
        for field in ("eta_start", "eta_end"):
            same(a.segments[field], b.segments[field], 1.0, field)
        # the beams run through both kinds of elements (else the mixed case would test one kind)
        assert len(set(solid.element_codes[a.segments["solid_element"]].tolist())) == len(set(solid.element_codes))
        for field, values in a.point_fields.items():
            if np.asarray(values).dtype.kind in "iub":
                np.testing.assert_array_equal(values, b.point_fields[field], err_msg=field)
            else:
                same(values, b.point_fields[field], max(1.0, np.abs(b.point_fields[field]).max()), field)


def test_a_mesh_without_hull_types_gets_the_kernels_zeros_without_it():
    """A hex8 mesh (no type with hull planes) gets from :func:`solid_hulls` exactly what the kernel
    writes for it (0, 0, 0, 0 rows: no bound) without the kernel being run; a mesh with one such
    element runs it."""
    from mortar1d3d.geometry import search

    b, solid = generate.fibre_cube(3, 2, 3)
    _, h, origin = solid_frames(solid)
    args = (solid.kernel_points, solid.connectivity, solid.element_codes, origin, h)
    kernel = np.full((solid.n_elements, MAX_FACES, 4), np.nan)
    search._solid_hulls(*args, HULL_MARGIN, np.ones(solid.n_elements, dtype=np.bool_), kernel, 1)
    skipped = solid_hulls(*args)
    assert skipped.shape == kernel.shape and not np.isnan(kernel).any()
    assert skipped.tobytes() == kernel.tobytes() == bytes(kernel.nbytes)
    tet = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), "tetra")
    hull, _, _ = hulls(tet)
    assert np.count_nonzero(hull[:, :4, :3]) > 0


def test_the_kernel_input_has_planes_for_its_candidate_elements_only():
    """:class:`KernelInput` asks :func:`solid_hulls` for the elements of its box pairs only (no kernel
    tests another element's hull): their rows are the planes of every element's, bit for bit, and the
    rows of every other element are 0, 0, 0, 0 (no bound). ``elements`` may repeat an element; the
    beams here run through part of the cube only, so some elements have no pair."""
    beams, _ = generate.fibre_cube(4, 3, 4)
    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (4, 4, 4), "tetra10"), 0.1, seed=1)
    full, _, _ = hulls(solid)
    ctx = context.KernelInput(beams, solid)
    boxes = context.find_candidate_pairs(ctx.beam_boxes, ctx.solid_boxes)[1]
    used = np.zeros(solid.n_elements, dtype=bool)
    used[boxes] = True
    assert 0 < used.sum() < 0.8 * solid.n_elements and len(boxes) > used.sum()
    assert ctx.hull[used].tobytes() == full[used].tobytes()
    assert not ctx.hull[~used].any() and full[~used][:, :4].any()
    # the pairs the planes keep, and the result, are those of the planes of every element
    offsets, pairs = context.hull_pairs(*context.find_candidate_pairs(ctx.beam_boxes, ctx.solid_boxes), full,
                                        ctx.solid_origin, ctx.beam_code, ctx.Q, ctx.lengths, ctx.beam_origin,
                                        ctx.beam_boxes)
    np.testing.assert_array_equal(ctx.pair_offsets, offsets)
    np.testing.assert_array_equal(ctx.pair_solid, pairs)
