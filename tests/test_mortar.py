"""Mortar operators: certificates, invariance, broad phase, bounding boxes, threads, bad input.

Reference values are computed independently of the library's kernels wherever that is
cheap: arc lengths from the centreline formulas of docs/conventions.md §2 and candidate pairs by numpy
brute force (tests/naive.py), Newton projections into solid elements in numpy here (with the
element modules' shape functions, which tests/test_elements.py checks).
"""
import warnings

import numba
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import BY_CODE, SOLID_ELEMENTS, SOLID_MODULES
from mortar1d3d.geometry.search import beam_bounding_boxes, find_candidate_pairs, solid_bounding_boxes
from mortar1d3d.study.reference import newton_projection

from naive import arc_length, brute_force_pairs, constraint_residual, outside_distance, reference_samples

SOLID_TYPES = [n for n, d in SOLID_ELEMENTS.items() if not d.rational]     # nurbs27: test_nurbs_engine
LM_TYPES = ["line2", "line3", "line4"]
INTEGRATIONS = ["segment", "element"]
N_INTERIOR = {"line2": 0, "line3": 1, "line4": 2}


# -- scenes --------------------------------------------------------------------------------------

def distorted(element, cells=2, amplitude=0.15, seed=1):
    """The unit cube, ``cells``³ grid cells of ``element``, interior nodes moved (curved faces)."""
    return generate.distort(generate.box((0, 0, 0), (1, 1, 1), (cells,) * 3, element), amplitude, seed=seed)


def curved_beams(seed=2, count=3, elements=8):
    """Random helix pieces, fully inside the unit cube (margin 0.05)."""
    return generate.random_curved_beams(count, elements, seed=seed)


def lagrange_beams(kind, seed=3):
    """Lagrange ``line``/``line3`` beams through points of random curves (inside the unit cube)."""
    hermite = curved_beams(seed=seed, count=2, elements=8)
    if kind == "line":
        return m13.BeamMesh.lagrange(hermite.positions, hermite.elements, "line")
    mids = np.vstack([hermite.evaluate(e, [0.0]) for e in range(hermite.n_elements)])
    positions = np.vstack([hermite.positions, mids])
    elements = np.column_stack([hermite.elements, hermite.n_nodes + np.arange(hermite.n_elements)])
    return m13.BeamMesh.lagrange(positions, elements, "line3")


# -- independent projection into a solid element ----------------------------------------------------

def element_of(solid, s):
    d = BY_CODE[int(solid.element_codes[s])]
    return d, SOLID_MODULES[d.name], solid.points[solid.connectivity[s, : d.n_nodes]]


def project(solid, s, p, iterations=40):
    """Newton for x(ξ) = p in element s (numpy, from the element centre); ξ and |x(ξ) - p| / h."""
    d, module, X = element_of(solid, s)
    h = np.linalg.norm(X.max(axis=0) - X.min(axis=0))
    xi = newton_projection(module, X, p, d.centre, h, iterations, escape=1e3)
    N = np.empty(d.n_nodes)
    module.shape.py_func(xi, N)
    return xi, np.linalg.norm(p - N @ X) / h


def lowest_containing_element(solid, p, tol=1e-9):
    for s in range(solid.n_elements):
        xi, res = project(solid, s, p)
        if res < 1e-10 and outside_distance(BY_CODE[int(solid.element_codes[s])].family, xi) <= tol:
            return s
    return -1


# -- checks shared by the certificate tests ---------------------------------------------------------

def assert_segments_tile(ops, beams):
    """Segments of every (fully embedded) beam element: disjoint, in order, tiling [-1, 1] exactly."""
    seg = ops.segments
    assert np.all(np.diff(seg["beam_element"]) >= 0)
    for e in range(beams.n_elements):
        s = seg[seg["beam_element"] == e]
        assert len(s) >= 1, f"beam element {e} has no segment"
        assert s["eta_start"][0] == -1.0 and s["eta_end"][-1] == 1.0, (e, s)
        np.testing.assert_array_equal(s["eta_end"][:-1], s["eta_start"][1:])
        assert np.all(s["eta_end"] > s["eta_start"])
        # neighbouring pieces in the same element would have been merged
        assert np.all(s["solid_element"][1:] != s["solid_element"][:-1])


def assert_segments_lie_in_their_elements(ops, beams, solid, samples=5):
    """Interior points of each segment project into its solid element; the cuts lie on its boundary."""
    for row in ops.segments:
        e, s, a, b = int(row["beam_element"]), int(row["solid_element"]), row["eta_start"], row["eta_end"]
        family = BY_CODE[int(solid.element_codes[s])].family
        eta = a + (b - a) * (np.arange(samples) + 0.5) / samples
        for p in beams.evaluate(e, eta):
            xi, res = project(solid, s, p)
            assert res < 1e-12
            assert outside_distance(family, xi) <= 1e-9, (row, xi)
        for cut in (a, b):
            if abs(cut) == 1.0:
                continue
            xi, res = project(solid, s, beams.evaluate(e, [cut])[0])
            assert res < 1e-12
            assert abs(outside_distance(family, xi)) <= 1e-8, (row, cut, xi)


def assert_partition_of_unity(ops, beams):
    """Σ_a N_a = 1 and H1 + H3 = 1 (Lagrange: Σ H = 1): M·1 = D·(unit translation) = κ per component."""
    ones = np.ones(ops.M.shape[1])
    for k in range(3):
        MX = (ops.M @ ones).reshape(-1, 3)[:, k]
        np.testing.assert_allclose(MX, ops.kappa, rtol=0, atol=1e-14 * ops.kappa.max())
    shift = np.zeros((beams.n_nodes, beams.element_type.dofs_per_node))
    shift[:, :3] = 1.0
    Dq = (ops.D @ shift.ravel()).reshape(-1, 3)
    for k in range(3):
        np.testing.assert_allclose(Dq[:, k], ops.kappa, rtol=0, atol=1e-14 * ops.kappa.max())


def assert_shapes(ops, beams, solid, lm):
    n_lm = beams.n_nodes + N_INTERIOR[lm] * beams.n_elements
    assert ops.n_lm == n_lm and ops.kappa.shape == (n_lm,)
    assert ops.D.shape == (3 * n_lm, beams.n_centreline_dofs)
    assert ops.M.shape == (3 * n_lm, 3 * solid.n_nodes)
    assert np.all(ops.kappa >= 0.0)


# -- 1. certificates -------------------------------------------------------------------------------

@pytest.mark.parametrize("lm", LM_TYPES)
@pytest.mark.parametrize("integration", INTEGRATIONS)
@pytest.mark.parametrize("element", SOLID_TYPES)
def test_certificates_on_distorted_meshes(element, integration, lm):
    solid = distorted(element)
    beams = curved_beams()
    ops = m13.assemble_mortar(beams, solid, integration=integration, lm=lm)
    assert_shapes(ops, beams, solid, lm)
    assert ops.diagnostics["points_not_converged"] == 0
    assert ops.diagnostics["points_outside_element"] == 0
    # the projections meet the design tolerance |x(ξ_g) - r(η_g)| <= 1e-12 h (docs/conventions.md §2;
    # h: the element size the library uses, the diagonal of its unpadded bounding box)
    h = solid_bounding_boxes(solid)[1]
    for p in ops.points:
        d, module, X = element_of(solid, p["solid_element"])
        N = np.empty(d.n_nodes)
        module.shape.py_func(p["xi"], N)
        assert np.linalg.norm(N @ X - p["position"]) <= 1e-12 * h[p["solid_element"]] + 1e-15
        np.testing.assert_allclose(p["position"], beams.evaluate(p["beam_element"], [p["eta"]])[0],
                                   rtol=0, atol=1e-15)
    # the certificate with the tolerance the design's projection tolerance guarantees, as reported
    # and recomputed here from the matrices
    assert ops.constraint_residual < 2e-12
    assert constraint_residual(ops, beams.centreline_dofs(), solid.points.ravel()) < 2e-12
    np.testing.assert_allclose(ops.embedded_length, ops.points["weight"].sum(), rtol=1e-14)
    assert_partition_of_unity(ops, beams)
    if integration == "segment":
        assert_segments_tile(ops, beams)
        assert ops.n_integration_points == 6 * len(ops.segments)
        reference = sum(arc_length(beams, r["beam_element"], r["eta_start"], r["eta_end"], 6)
                        for r in ops.segments)
        np.testing.assert_allclose(ops.embedded_length, reference, rtol=1e-13)
        np.testing.assert_allclose(ops.embedded_length, ops.beam_length, rtol=1e-12)
    else:
        assert ops.diagnostics["points_uncoupled"] == 0
        assert ops.n_integration_points == 6 * beams.n_elements
        reference = sum(arc_length(beams, e, -1.0, 1.0, 6) for e in range(beams.n_elements))
        np.testing.assert_allclose(ops.embedded_length, reference, rtol=1e-13)
        # segments of element-based integration: runs of points in one solid element, in η order
        seg = ops.segments
        assert np.all(seg["eta_start"] <= seg["eta_end"])
        x = np.polynomial.legendre.leggauss(6)[0]
        np.testing.assert_array_equal(ops.points["eta"], np.tile(x, beams.n_elements))


# The certificate ‖D q_B - M X_S‖ / ‖D q_B‖ at round-off (docs/conventions.md §1: round-off for any correct projection).
# Integration points get one Newton step past the 1e-12 h convergence test (projection.polish);
# without it these scenes gave 1e-13..2.6e-13 on hex8/hex20/tet10.


def _residual_cases():
    cases = []
    for element in SOLID_TYPES:
        for integration in INTEGRATIONS:
            for lm in LM_TYPES:
                cases.append(pytest.param(element, integration, lm,
                                          id=f"{element}-{integration}-{lm}"))
    return cases


@pytest.mark.parametrize("element, integration, lm", _residual_cases())
def test_constraint_residual_is_round_off(element, integration, lm):
    ops = m13.assemble_mortar(curved_beams(), distorted(element), integration=integration, lm=lm)
    assert ops.constraint_residual < 1e-13


@pytest.mark.parametrize("integration", INTEGRATIONS)
def test_constraint_residual_measures_a_violated_constraint(integration):
    """The certificate is not just small: it is ‖D q − M x‖ / ‖D q‖, also when that is not zero."""
    from mortar1d3d.mortar.sparse import relative_residual
    beams, solid = curved_beams(), distorted("hexahedron20")
    ops = m13.assemble_mortar(beams, solid, integration=integration, lm="line3")
    q, x = beams.centreline_dofs(), solid.points.ravel()
    rng = np.random.default_rng(3)
    for amplitude in (1e-9, 1e-3, 1.0):
        moved = x + amplitude * rng.uniform(-1, 1, x.shape)
        expected = constraint_residual(ops, q, moved)
        assert expected > 1e-3 * amplitude
        np.testing.assert_allclose(relative_residual(ops.D, q, ops.M, moved), expected, rtol=1e-12)
    # a rigid translation of the solid alone violates the constraint by κ t: ‖κ t‖ / ‖D q‖
    t = np.array([0.1, -0.2, 0.3])
    expected = np.linalg.norm(np.outer(ops.kappa, t)) / np.linalg.norm(ops.D @ q)
    np.testing.assert_allclose(relative_residual(ops.D, q, ops.M, (solid.points + t).ravel()), expected,
                               rtol=1e-10)
    assert relative_residual(ops.D, np.zeros_like(q), ops.M, x) == 0.0     # D q = 0: defined as 0



@pytest.mark.parametrize("kind", ["hermite", "line"])
def test_constraint_residual_is_read_lazily_from_the_assembled_positions(kind):
    """``constraint_residual`` is computed on first access, from the positions the operators were assembled
    with: the same bits as computing it from ``centreline_dofs`` at once, also after the meshes moved."""
    from mortar1d3d.mortar.sparse import relative_residual
    beams, solid = curved_beams() if kind == "hermite" else lagrange_beams(kind), distorted("hexahedron")
    ops = m13.assemble_mortar(beams, solid, integration="element")
    q, x = beams.centreline_dofs(), solid.points.ravel().copy()
    expected = relative_residual(ops.D, q, ops.M, x)
    assert 0.0 < expected < 1e-13
    beams.positions[:] += 0.5        # moved after the assembly: the certificate is of the assembled positions
    solid.points[:] *= 2.0
    assert ops.constraint_residual == expected
    assert ops.constraint_residual == expected     # computed once, then the value
    # ... which the moved meshes' positions violate
    assert relative_residual(ops.D, beams.centreline_dofs(), ops.M, solid.points.ravel()) > 1e-2

@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27", "tetra10"])
def test_segments_lie_in_their_elements(element):
    """Independent check of the segmentation: sampled points inside the owner, cuts on its boundary."""
    solid = distorted(element)
    beams = curved_beams()
    ops = m13.assemble_mortar(beams, solid)
    assert_segments_lie_in_their_elements(ops, beams, solid)


def test_element_based_owner_is_lowest_containing_element():
    solid = distorted("tetra10")
    beams = curved_beams(count=2, elements=4)
    ops = m13.assemble_mortar(beams, solid, integration="element")
    owners = [lowest_containing_element(solid, p) for p in ops.points["position"]]
    np.testing.assert_array_equal(ops.points["solid_element"], owners)


@pytest.mark.parametrize("kind", ["line", "line3"])
@pytest.mark.parametrize("integration", INTEGRATIONS)
def test_certificates_lagrange_beams(kind, integration):
    solid = distorted("tetra10")
    beams = lagrange_beams(kind)
    for lm in LM_TYPES:
        ops = m13.assemble_mortar(beams, solid, integration=integration, lm=lm)
        assert_shapes(ops, beams, solid, lm)
        assert ops.diagnostics["points_not_converged"] == 0
        assert ops.diagnostics["points_outside_element"] == 0
        assert ops.constraint_residual < 2e-12
        assert_partition_of_unity(ops, beams)
        if integration == "segment":
            assert_segments_tile(ops, beams)
            reference = sum(arc_length(beams, r["beam_element"], r["eta_start"], r["eta_end"], 6)
                            for r in ops.segments)
            np.testing.assert_allclose(ops.embedded_length, reference, rtol=1e-13)
            np.testing.assert_allclose(ops.embedded_length, ops.beam_length, rtol=1e-12)
        else:
            reference = sum(arc_length(beams, e, -1.0, 1.0, 6) for e in range(beams.n_elements))
            np.testing.assert_allclose(ops.embedded_length, reference, rtol=1e-13)
    if kind == "line":   # straight pieces: the length is exact
        lengths = np.linalg.norm(np.diff(beams.positions[beams.elements], axis=1)[:, 0], axis=1)
        np.testing.assert_allclose(ops.embedded_length, lengths.sum(), rtol=1e-14)


def test_partially_embedded_beam():
    """A straight beam leaving the cube: only the inside part is coupled, exactly."""
    solid = distorted("hexahedron27")
    x0, x1 = np.array([-0.5, 0.3, 0.4]), np.array([0.7, 0.6, 0.55])
    positions = x0 + np.linspace(0, 1, 4)[:, None] * (x1 - x0)
    tangent = (x1 - x0) / np.linalg.norm(x1 - x0)
    beams = m13.BeamMesh.hermite(positions, np.tile(tangent, (4, 1)), [[0, 1], [1, 2], [2, 3]])
    inside = np.linalg.norm(x1 - x0) * (x1[0] - 0.0) / (x1[0] - x0[0])
    for integration in INTEGRATIONS:
        ops = m13.assemble_mortar(beams, solid, integration=integration)
        assert ops.constraint_residual < 2e-12
    assert ops.diagnostics["points_uncoupled"] >= 6                 # element 0's points, at least
    assert not np.any(ops.points["beam_element"] == 0)
    ops = m13.assemble_mortar(beams, solid, integration="segment")
    np.testing.assert_allclose(ops.embedded_length, inside, rtol=1e-12)
    assert not np.any(ops.segments["beam_element"] == 0)          # element 0 lies outside
    assert ops.kappa[0] == 0.0 and ops.kappa[1] > 0.0
    seg = ops.segments[ops.segments["beam_element"] == 1]
    # entry point at x = 0: η of element 1 (x from -0.1 to 0.3)
    np.testing.assert_allclose(seg["eta_start"][0], -1 + 2 * 0.1 / 0.4, atol=1e-12)
    assert seg["eta_end"][-1] == 1.0


# -- 2. invariance ---------------------------------------------------------------------------------

def snapped(points, bits=40):
    """Coordinates on a 2^-bits grid: translations by integers are then exact in binary."""
    return np.round(np.asarray(points) * 2.0 ** bits) / 2.0 ** bits


def invariance_scene(element):
    solid = distorted(element, seed=4)
    solid = m13.SolidMesh(snapped(solid.points), solid.cells)
    beams = curved_beams(seed=5)
    beams = m13.BeamMesh.hermite(snapped(beams.positions), beams.tangents, beams.elements)
    return beams, solid


def test_hermite_lengths_translation_invariant():
    beams, _ = invariance_scene("hexahedron")
    moved = m13.BeamMesh.hermite(beams.positions + [1e3, -2e3, 5e2], beams.tangents, beams.elements)
    np.testing.assert_allclose(moved.lengths, beams.lengths, rtol=1e-13)   # the translation is exact


def random_rotation(seed=7):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def assert_same_segments(seg, ref, atol=1e-12):
    np.testing.assert_array_equal(seg["beam_element"], ref["beam_element"])
    np.testing.assert_array_equal(seg["solid_element"], ref["solid_element"])
    np.testing.assert_allclose(seg["eta_start"], ref["eta_start"], rtol=0, atol=atol)
    np.testing.assert_allclose(seg["eta_end"], ref["eta_end"], rtol=0, atol=atol)


def assert_no_segment_on_a_face(ops, beams, solid):
    """Guard of the renumbering tests: no piece runs along a shared face (ownership may differ there)."""
    for row in ops.segments:
        p = beams.evaluate(int(row["beam_element"]), [0.5 * (row["eta_start"] + row["eta_end"])])[0]
        xi, _ = project(solid, int(row["solid_element"]), p)
        assert outside_distance(BY_CODE[int(solid.element_codes[row["solid_element"]])].family, xi) < -1e-6


@pytest.mark.parametrize("integration", INTEGRATIONS)
@pytest.mark.parametrize("element", SOLID_TYPES)
def test_invariance_rigid_motion_and_scaling(element, integration):
    beams, solid = invariance_scene(element)
    ref = m13.assemble_mortar(beams, solid, integration=integration, lm="line3")
    MX, Dq = (ref.M @ solid.points.ravel()).reshape(-1, 3), (ref.D @ beams.centreline_dofs()).reshape(-1, 3)
    scale = np.abs(MX).max()
    R = random_rotation()
    t = np.array([1e3, -2e3, 5e2])
    cases = {
        "translation": (lambda x: x + t, lambda v: v, 1.0),
        "rotation": (lambda x: x @ R.T, lambda v: v @ R.T, 1.0),
        "scaling": (lambda x: 1e-3 * x, lambda v: v, 1e-3),
    }
    for name, (move, turn, factor) in cases.items():
        solid2 = m13.SolidMesh(move(solid.points), solid.cells)
        beams2 = m13.BeamMesh.hermite(move(beams.positions), turn(beams.tangents), beams.elements)
        ops = m13.assemble_mortar(beams2, solid2, integration=integration, lm="line3")
        assert_same_segments(ops.segments, ref.segments)
        np.testing.assert_allclose(ops.kappa, factor * ref.kappa, rtol=1e-12, atol=1e-14 * factor)
        np.testing.assert_allclose(ops.embedded_length, factor * ref.embedded_length, rtol=1e-12)
        assert ops.constraint_residual < 2e-12
        # M X_S and D q_B (= ∫Φ r ds) move with the geometry (translation: by κ t, with the κ of
        # the translated scene, whose lengths carry the round-off of the large coordinates)
        MX2 = (ops.M @ solid2.points.ravel()).reshape(-1, 3)
        Dq2 = (ops.D @ beams2.centreline_dofs()).reshape(-1, 3)
        atol = 1e-12 * factor * scale
        if name == "translation":
            MX2, Dq2 = MX2 - ops.kappa[:, None] * t, Dq2 - ops.kappa[:, None] * t
            # the subtraction cancels the digits of |κ t| (~ 100 here, for values ~ 0.04)
            atol = 1e-13 * (scale + ops.kappa.max() * np.abs(t).max())
        np.testing.assert_allclose(MX2, factor * move(MX) if name != "translation" else MX, rtol=0, atol=atol)
        np.testing.assert_allclose(Dq2, factor * move(Dq) if name != "translation" else Dq, rtol=0, atol=atol)
        # M itself: scalar weights ∫Φ_j N_a ds, independent of the frame, proportional to the size
        np.testing.assert_allclose((ops.M - factor * ref.M).toarray(), 0.0, atol=1e-12 * factor * abs(ref.M).max())


def test_invariance_solid_node_renumbering():
    beams, solid = invariance_scene("hexahedron27")
    ref = m13.assemble_mortar(beams, solid)
    assert_no_segment_on_a_face(ref, beams, solid)
    perm = np.random.default_rng(11).permutation(solid.n_nodes)      # old node i -> new node perm[i]
    points = np.empty_like(solid.points)
    points[perm] = solid.points
    solid2 = m13.SolidMesh(points, {"hexahedron27": perm[solid.cells["hexahedron27"]]})
    for integration in INTEGRATIONS:
        ref = m13.assemble_mortar(beams, solid, integration=integration)
        ops = m13.assemble_mortar(beams, solid2, integration=integration)
        assert_same_segments(ops.segments, ref.segments)
        np.testing.assert_allclose(ops.kappa, ref.kappa, rtol=1e-12)
        np.testing.assert_allclose((ops.D - ref.D).toarray(), 0.0, atol=1e-13)
        cols = (3 * perm[:, None] + np.arange(3)).ravel()                # old column -> new column
        np.testing.assert_allclose(ops.M[:, cols].toarray(), ref.M.toarray(), rtol=0, atol=1e-13)
        np.testing.assert_allclose(ops.M @ solid2.points.ravel(), ref.M @ solid.points.ravel(), atol=1e-13)
        assert ops.constraint_residual < 2e-12


@pytest.mark.parametrize("element", ["hexahedron", "tetra"])
def test_invariance_solid_element_renumbering(element):
    beams, solid = invariance_scene(element)
    order = np.random.default_rng(12).permutation(solid.n_elements)  # new element j = old element order[j]
    new_id = np.argsort(order)                                       # old element i -> new element new_id[i]
    solid2 = m13.SolidMesh(solid.points, {element: solid.cells[element][order]})
    for integration in INTEGRATIONS:
        ref = m13.assemble_mortar(beams, solid, integration=integration)
        if integration == "segment":
            assert_no_segment_on_a_face(ref, beams, solid)
        ops = m13.assemble_mortar(beams, solid2, integration=integration)
        expected = ref.segments.copy()
        expected["solid_element"] = new_id[ref.segments["solid_element"]]
        assert_same_segments(ops.segments, expected)
        np.testing.assert_array_equal(ops.points["solid_element"], new_id[ref.points["solid_element"]])
        np.testing.assert_allclose(ops.kappa, ref.kappa, rtol=1e-13)
        np.testing.assert_allclose((ops.D - ref.D).toarray(), 0.0, atol=1e-13)
        np.testing.assert_allclose((ops.M - ref.M).toarray(), 0.0, atol=1e-13)


@pytest.mark.parametrize("lm", LM_TYPES)
def test_invariance_beam_renumbering(lm):
    beams, solid = invariance_scene("hexahedron20")
    rng = np.random.default_rng(13)
    node_id = rng.permutation(beams.n_nodes)                     # old node i -> new node node_id[i]
    order = rng.permutation(beams.n_elements)                    # new element j = old element order[j]
    element_id = np.argsort(order)                               # old element e -> new element
    positions, tangents = np.empty_like(beams.positions), np.empty_like(beams.tangents)
    positions[node_id], tangents[node_id] = beams.positions, beams.tangents
    beams2 = m13.BeamMesh.hermite(positions, tangents, node_id[beams.elements[order]])
    np.testing.assert_array_equal(beams2.lengths, beams.lengths[order])
    # LM nodes: beam nodes keep their node's (new) id; interior ones follow their element
    n, k = beams.n_nodes, N_INTERIOR[lm]
    lm_id = np.concatenate([node_id, (n + k * element_id[:, None] + np.arange(k)).ravel()]).astype(np.int64)
    for integration in INTEGRATIONS:
        ref = m13.assemble_mortar(beams, solid, integration=integration, lm=lm)
        ops = m13.assemble_mortar(beams2, solid, integration=integration, lm=lm)
        kappa = np.empty_like(ref.kappa)
        kappa[lm_id] = ref.kappa
        np.testing.assert_allclose(ops.kappa, kappa, rtol=1e-13, atol=0)
        seg = np.sort(ops.segments, order=["beam_element", "eta_start"])
        expected = ref.segments.copy()
        expected["beam_element"] = element_id[ref.segments["beam_element"]]
        expected = np.sort(expected, order=["beam_element", "eta_start"])
        assert_same_segments(seg, expected)
        rows = (3 * lm_id[:, None] + np.arange(3)).ravel()          # old LM DOF -> new LM DOF
        cols = (6 * node_id[:, None] + np.arange(6)).ravel()         # old centreline DOF -> new
        np.testing.assert_allclose(ops.D[rows][:, cols].toarray(), ref.D.toarray(), rtol=0, atol=1e-13)
        np.testing.assert_allclose(ops.M[rows].toarray(), ref.M.toarray(), rtol=0, atol=1e-13)
        np.testing.assert_allclose((ops.D @ beams2.centreline_dofs())[rows], ref.D @ beams.centreline_dofs(),
                                   rtol=0, atol=1e-13)
        np.testing.assert_allclose((ops.M @ solid.points.ravel())[rows], ref.M @ solid.points.ravel(),
                                   rtol=0, atol=1e-13)


# -- 3. broad phase = brute force ------------------------------------------------------------------

def assert_pairs_equal_brute_force(beam_boxes, solid_boxes):
    offsets, solids = find_candidate_pairs(beam_boxes, solid_boxes)
    assert offsets.shape == (len(beam_boxes) + 1,) and offsets[0] == 0
    assert np.all(np.diff(offsets) >= 0) and offsets[-1] == len(solids)
    expected = brute_force_pairs(beam_boxes, solid_boxes)
    for e in range(len(beam_boxes)):
        mine = solids[offsets[e]:offsets[e + 1]]
        assert np.all(np.diff(mine) > 0), f"beam element {e}: not sorted ascending / repeated"
        np.testing.assert_array_equal(mine, np.flatnonzero(expected[e]), err_msg=f"beam element {e}")
    return offsets, solids


def random_boxes(rng, n, lower=-1.0, upper=1.0, log_size=(-3.0, 0.5)):
    lo = rng.uniform(lower, upper, (n, 3))
    size = 10.0 ** rng.uniform(*log_size, (n, 3))
    return np.stack([lo, lo + size], axis=1)


@pytest.mark.parametrize("seed", range(4))
def test_broad_phase_random_boxes(seed):
    rng = np.random.default_rng(seed)
    solid_boxes = random_boxes(rng, 300, log_size=(-4.0, 0.3))       # sizes from 1e-4 to 2
    beam_boxes = random_boxes(rng, 200, lower=-1.5, upper=1.5, log_size=(-4.0, 0.0))
    # beam boxes entirely outside the solid grid, one covering all of it, degenerate (point) boxes
    beam_boxes = np.concatenate([beam_boxes, [[[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]],
                                              [[-4.0, -4.0, -4.0], [-3.0, -3.0, -3.0]],
                                              [[-0.5, 4.0, -0.5], [0.5, 4.5, 0.5]],
                                              [[-1e3, -1e3, -1e3], [1e3, 1e3, 1e3]]]])
    points = solid_boxes[rng.integers(0, 300, 5), 1]                 # point boxes on solid corners
    beam_boxes = np.concatenate([beam_boxes, np.stack([points, points], axis=1)])
    offsets, solids = assert_pairs_equal_brute_force(beam_boxes, solid_boxes)
    assert offsets[201] == offsets[200] and offsets[202] == offsets[201] and offsets[203] == offsets[202]
    assert offsets[204] - offsets[203] == len(solid_boxes)
    assert len(solids) > 0


def test_broad_phase_widely_varying_sizes():
    """A few huge solid boxes among many tiny ones (the grid cell follows the median size)."""
    rng = np.random.default_rng(21)
    tiny = random_boxes(rng, 500, log_size=(-6.0, -4.0))
    huge = random_boxes(rng, 3, lower=-10.0, upper=-5.0, log_size=(1.0, 1.2))
    solid_boxes = np.concatenate([tiny[:250], huge, tiny[250:]])
    beam_boxes = np.concatenate([random_boxes(rng, 100, log_size=(-6.0, 0.0)),
                                 random_boxes(rng, 20, lower=-20.0, upper=20.0, log_size=(-1.0, 1.0)),
                                 [[[100.0, 0.0, 0.0], [101.0, 1.0, 1.0]]]])
    offsets, _ = assert_pairs_equal_brute_force(beam_boxes, solid_boxes)
    assert offsets[-1] == offsets[-2]
    # some candidate lists are long enough for numpy's sort (compiled on first use), not the insertion sort
    from mortar1d3d.geometry.search import _INSERTION_SORT_MAX
    assert np.diff(offsets).max() > _INSERTION_SORT_MAX


def test_broad_phase_touching_boxes_count():
    """Closed boxes: sharing a face, edge or corner is an overlap (exact coordinates)."""
    g = np.stack(np.meshgrid(*[np.arange(3.0)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    solid_boxes = np.stack([g, g + 1.0], axis=1)                     # 27 unit cubes
    beam_boxes = np.array([[[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]],       # a grid vertex: 8 cubes
                           [[0.2, 0.2, 0.2], [2.0, 0.3, 0.3]],       # ends on a face
                           [[-1.0, -1.0, -1.0], [0.0, 0.0, 0.0]],    # touching the corner (0, 0, 0)
                           [[0.5, -1.0, 0.5], [0.6, 0.0, 0.6]],      # touching the y = 0 face from outside
                           [[2.5, 2.5, 2.5], [2.5, 3.0, 3.0]]])      # inside, reaching the corner (3, 3, 3)
    offsets, _ = assert_pairs_equal_brute_force(beam_boxes, solid_boxes)
    np.testing.assert_array_equal(np.diff(offsets), [8, 3, 1, 1, 1])


def test_broad_phase_touching_the_upper_face_of_the_grid():
    g = np.stack(np.meshgrid(*[np.arange(3.0)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    solid_boxes = np.stack([g, g + 1.0], axis=1)                     # 27 unit cubes in [0, 3]^3
    beam_boxes = np.array([[[3.0, 0.5, 0.5], [4.0, 0.6, 0.6]],       # touches the x = 3 face of cube 18
                           [[3.0, 3.0, 3.0], [3.0, 3.0, 3.0]]])      # the corner (3, 3, 3) of cube 26
    assert_pairs_equal_brute_force(beam_boxes, solid_boxes)


def test_broad_phase_real_meshes():
    solid = distorted("hexahedron20", cells=3, amplitude=0.2)
    beams = m13.BeamMesh.join([curved_beams(seed=8, count=4, elements=5),
                               m13.BeamMesh.hermite([[1.5, 0.2, 0.2], [2.5, 0.2, 0.3]],
                                                    [[1.0, 0, 0], [1.0, 0, 0]], [[0, 1]])])
    solid_boxes, h_solid = solid_bounding_boxes(solid)
    beam_boxes, h_beam = beam_bounding_boxes(beams)
    assert solid_boxes.shape == (27, 2, 3) and beam_boxes.shape == (21, 2, 3)
    assert np.all(h_solid > 0) and np.all(h_beam > 0)
    offsets, _ = assert_pairs_equal_brute_force(beam_boxes, solid_boxes)
    assert offsets[-1] == offsets[-2]                               # the last beam element is outside
    tet = distorted("tetra", cells=3)
    assert_pairs_equal_brute_force(beam_boxes, solid_bounding_boxes(tet)[0])


def test_broad_phase_box_far_beyond_the_grid():
    g = np.stack(np.meshgrid(*[np.arange(4.0)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    solid_boxes = np.stack([g, g + 1.0], axis=1)                     # 64 unit cubes, grid cell 1
    beam_boxes = np.array([[[-1e19] * 3, [1e19] * 3], [[0.5] * 3, [1e19] * 3]])
    assert_pairs_equal_brute_force(beam_boxes, solid_boxes)


# -- 4. bounding boxes are conservative ---------------------------------------------------------------

@pytest.mark.parametrize("element", SOLID_TYPES)
def test_solid_boxes_contain_elements(element):
    solid = distorted(element, cells=2, amplitude=0.2, seed=9)
    boxes, h = solid_bounding_boxes(solid)
    d = BY_CODE[int(solid.element_codes[0])]
    xi = reference_samples(d.family)
    N = np.empty((len(xi), d.n_nodes))
    for q, x in enumerate(xi):
        SOLID_MODULES[element].shape.py_func(x, N[q])
    for s in range(solid.n_elements):
        X = solid.points[solid.connectivity[s, : d.n_nodes]]
        x = N @ X
        assert np.all(x >= boxes[s, 0]) and np.all(x <= boxes[s, 1]), f"element {s}"
        np.testing.assert_allclose(h[s], np.linalg.norm(boxes[s, 1] - boxes[s, 0]), rtol=1e-8)


@pytest.mark.parametrize("kind", ["hermite", "line", "line3"])
def test_beam_boxes_contain_beams(kind):
    beams = curved_beams(seed=10, count=4, elements=3) if kind == "hermite" else lagrange_beams(kind, seed=10)
    boxes, h = beam_bounding_boxes(beams)
    eta = np.linspace(-1.0, 1.0, 101)
    for e in range(beams.n_elements):
        x = beams.evaluate(e, eta)
        assert np.all(x >= boxes[e, 0]) and np.all(x <= boxes[e, 1]), f"beam element {e}"
        assert np.all(boxes[e, 1] - boxes[e, 0] < 1.0)                # not trivially huge
    if kind == "hermite":
        # the box is the hull of the Bézier points r1, r1 + L/3 t1, r2 - L/3 t2, r2 (+ padding)
        e = 0
        r1, r2 = beams.positions[beams.elements[e]]
        t1, t2 = beams.tangents[beams.elements[e]]
        L = beams.lengths[e]
        control = np.array([r1, r1 + L / 3 * t1, r2 - L / 3 * t2, r2])
        np.testing.assert_allclose(boxes[e, 0], control.min(axis=0), atol=1e-8 * h[e])
        np.testing.assert_allclose(boxes[e, 1], control.max(axis=0), atol=1e-8 * h[e])


# -- 5. threads ------------------------------------------------------------------------------------

@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs at least 2 Numba threads")
@pytest.mark.parametrize("scene", ["straight", "curved", "curved-distorted"])
def test_bit_identical_for_any_thread_count(scene):
    # 200 beam elements, > 600 pairs and points: several chunks of CHUNK = 64 per worker and kernel;
    # the distorted cube (no parallelepiped left) takes the Newton path everywhere
    beams, solid = generate.fibre_cube(4, 25, 8, curved=scene != "straight")
    if scene.endswith("distorted"):
        solid = generate.distort(solid, 0.1, seed=1)
    before = numba.get_num_threads()
    results = {}
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                results[threads] = [m13.assemble_mortar(beams, solid, integration=integration, lm=lm)
                                    for integration, lm in (("segment", "line2"), ("element", "line3"))]
    finally:
        numba.set_num_threads(before)
    assert numba.get_num_threads() == before
    for one, two in zip(results[1], results[2]):
        for name in ("D", "M"):
            for part in ("data", "indices", "indptr"):
                assert np.array_equal(getattr(getattr(one, name), part), getattr(getattr(two, name), part))
        assert np.array_equal(one.kappa, two.kappa)
        assert np.array_equal(one.segments, two.segments)
        assert np.array_equal(one.points, two.points)


# -- 6. bad input ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def small_scene():
    return generate.fibre_cube(2, 1, 2)


@pytest.mark.parametrize("kwargs, error, name", [
    (dict(integration="mortar"), ValueError, "integration"),
    (dict(integration=None), ValueError, "integration"),
    (dict(n_gauss=0), ValueError, "n_gauss"),
    (dict(n_gauss=2.5), (TypeError, ValueError), "n_gauss"),
    (dict(n_gauss=True), (TypeError, ValueError), "n_gauss"),
    (dict(n_gauss="6"), (TypeError, ValueError), "n_gauss"),
    (dict(search_points=1), ValueError, "search_points"),
    (dict(search_points=2.0), (TypeError, ValueError), "search_points"),
])
def test_bad_parameters(small_scene, kwargs, error, name):
    beams, solid = small_scene
    with pytest.raises(error, match=name):
        m13.assemble_mortar(beams, solid, **kwargs)


def test_bad_meshes(small_scene):
    beams, solid = small_scene
    with pytest.raises(TypeError, match="beams"):
        m13.assemble_mortar(solid, solid)
    with pytest.raises(TypeError, match="beams"):
        m13.assemble_mortar(beams.positions, solid)
    with pytest.raises(TypeError, match="solid"):
        m13.assemble_mortar(beams, beams)
    with pytest.raises(TypeError, match="solid"):
        m13.assemble_mortar(beams, solid.points)


def test_unknown_lm_is_rejected(small_scene):
    beams, solid = small_scene
    with pytest.raises(ValueError, match="line5") as info:
        m13.assemble_mortar(beams, solid, lm="line5")
    assert "line2" in str(info.value)                                # lists the known types


def test_unknown_lm_message_names_the_parameter(small_scene):
    beams, solid = small_scene
    with pytest.raises(ValueError, match=r"\blm\b"):
        m13.assemble_mortar(beams, solid, lm="line5")


def test_documented_defaults():
    import inspect
    defaults = {k: v.default for k, v in inspect.signature(m13.assemble_mortar).parameters.items()
                if v.default is not inspect.Parameter.empty}
    assert defaults == {"integration": "segment", "n_gauss": 6, "lm": "line2", "search_points": 6}


@pytest.mark.parametrize("outcome", ["not_converged", "outside"])
def test_points_that_fail_are_reported_and_never_silently_dropped(small_scene, monkeypatch, outcome):
    """A projection that failed leaves its point out, with a warning and a count; a point outside its
    segment's element is kept (its ξ is still exact) but flagged the same way."""
    from mortar1d3d.integration import points
    from mortar1d3d.mortar import assemble as module
    beams, solid = small_scene
    ref = m13.assemble_mortar(beams, solid, integration="element", n_gauss=4)
    marked = np.array([1, 5, 6])

    def element_points(ctx, n_gauss):
        out = list(points.element_points(ctx, n_gauss))
        out[-1] = out[-1].copy()
        out[-1][marked] = points.POINT_NOT_CONVERGED if outcome == "not_converged" else points.POINT_OUTSIDE
        return tuple(out)

    monkeypatch.setattr(module, "element_points", element_points)
    message = "3 integration points did not converge" if outcome == "not_converged" else "3 integration points of"
    with pytest.warns(RuntimeWarning, match=message):
        ops = m13.assemble_mortar(beams, solid, integration="element", n_gauss=4)
    key = "points_not_converged" if outcome == "not_converged" else "points_outside_element"
    assert ops.diagnostics[key] == 3
    if outcome == "not_converged":
        assert ops.n_integration_points == ref.n_integration_points - 3
        np.testing.assert_allclose(ops.embedded_length, ref.embedded_length - ref.points["weight"][marked].sum(),
                                   rtol=1e-14)
        np.testing.assert_array_equal(ops.points["eta"], np.delete(ref.points["eta"], marked))
    else:
        assert ops.n_integration_points == ref.n_integration_points
        np.testing.assert_array_equal(ops.kappa, ref.kappa)


def test_good_parameters_accept_numpy_integers(small_scene):
    beams, solid = small_scene
    ops = m13.assemble_mortar(beams, solid, n_gauss=np.int64(4), search_points=np.int32(8))
    assert ops.n_gauss == 4 and ops.n_integration_points == 4 * len(ops.segments)


# -- 7. the benchmark scene -------------------------------------------------------------------------

@pytest.mark.parametrize("curved", [False, True])
def test_fibre_cube_no_warnings(curved):
    beams, solid = generate.fibre_cube(5, 30, 6, curved=curved)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ops = m13.assemble_mortar(beams, solid)
    assert ops.diagnostics["points_not_converged"] == 0
    assert ops.diagnostics["points_outside_element"] == 0


@pytest.mark.parametrize("curved", [False, True])
def test_fibre_cube_certificates(curved):
    beams, solid = generate.fibre_cube(5, 30, 6, curved=curved)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ops = m13.assemble_mortar(beams, solid)
        fine = m13.assemble_mortar(beams, solid, n_gauss=16)
    assert ops.constraint_residual < 1e-13
    assert ops.diagnostics["points_not_converged"] == 0
    assert_segments_tile(ops, beams)
    assert_partition_of_unity(ops, beams)
    # Σκ is the 6-point rule on the segments (independent reference) ...
    reference = sum(arc_length(beams, r["beam_element"], r["eta_start"], r["eta_end"], 6)
                    for r in ops.segments)
    np.testing.assert_allclose(ops.embedded_length, reference, rtol=1e-13)
    if curved:
        # ... which on helix pieces (120° per element) differs from the arc length by its
        # quadrature error; with 16 points only the 10-point rule of the element lengths is left
        np.testing.assert_allclose(ops.embedded_length, ops.beam_length, rtol=1e-6)
        np.testing.assert_allclose(fine.embedded_length, fine.beam_length, rtol=1e-11)
    else:
        np.testing.assert_allclose(ops.embedded_length, ops.beam_length, rtol=1e-13)
        np.testing.assert_allclose(ops.beam_length, 30 * 0.3, rtol=1e-13)
        np.testing.assert_allclose(fine.embedded_length, fine.beam_length, rtol=1e-13)
    # every fibre is fully inside: every beam node's LM is coupled
    assert np.all(ops.kappa > 0)


# -- 4. block CSR of the local matrices = a stable sort and sums in gather order --------------------

@pytest.mark.parametrize("n_cols, width_range", [(40, (2, 9)), (400, (30, 61))])
def test_gathered_block_csr_sums_in_gather_order(n_cols, width_range):
    """Random groups (several per beam element, columns in no order, repeated within and across
    groups): each row's columns ascending and each sum in the gather order (beam elements, groups,
    columns), bit for bit. The first case gives rows of a few distinct columns, the second rows of
    far more than ``sparse._RANK_MAX`` (the two ways the fill orders a row)."""
    from mortar1d3d.mortar import sparse
    rng = np.random.default_rng(7)
    n_beam, n_phi, block = 30, 2, 3
    lm_index = np.stack([np.arange(n_beam), np.arange(1, n_beam + 1)], axis=1).astype(np.int64)
    n_rows = n_beam + 1
    beam_groups = np.concatenate([[0], np.cumsum(rng.integers(1, 4, n_beam))]).astype(np.int64)
    n_groups = beam_groups[-1]
    width = rng.integers(*width_range, n_groups).astype(np.int64)
    col_table = np.full((n_groups, width.max()), -1, dtype=np.int64)
    for g in range(n_groups):
        col_table[g, :width[g]] = rng.integers(0, n_cols, width[g])
    entry_start = np.concatenate([[0], np.cumsum(n_phi * width)[:-1]]).astype(np.int64)
    vals = rng.standard_normal(int((n_phi * width).sum())) * 10.0 ** rng.integers(-8, 8, int((n_phi * width).sum()))
    src_offsets, src = sparse.row_sources(lm_index, n_phi, n_rows)
    matrix = sparse.gathered_block_csr(src_offsets, src, n_phi, beam_groups, entry_start, width, col_table,
                                       np.arange(n_groups, dtype=np.int64), vals, (n_rows, n_cols), block)
    longest = 0
    for r in range(n_rows):
        sums = {}
        for e in range(n_beam):                       # beam elements ascending, as row_sources lists them
            for j in range(n_phi):
                if lm_index[e, j] != r:
                    continue
                for g in range(beam_groups[e], beam_groups[e + 1]):
                    for q in range(width[g]):
                        c = int(col_table[g, q])
                        v = vals[entry_start[g] + j * width[g] + q]
                        sums[c] = sums[c] + v if c in sums else v
        cols = sorted(sums)
        longest = max(longest, len(cols))
        for i in range(block):
            row = block * r + i
            got = slice(matrix.indptr[row], matrix.indptr[row + 1])
            np.testing.assert_array_equal(matrix.indices[got], block * np.array(cols) + i)
            assert matrix.data[got].tobytes() == np.array([sums[c] for c in cols]).tobytes()
    assert (longest <= sparse._RANK_MAX) == (n_cols == 40)
