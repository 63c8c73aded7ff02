"""integration="auto": segment-based results where beams cross faces, element-based points where
they do not, the minimal exact Gauss rule where the integrand is a polynomial.

The comparisons are against the two other integrations of the same library (which
tests/test_mortar.py and tests/test_reference.py check independently); the certificate and
affinity tests use hand-built geometry.
"""
import numba
import numpy as np
import pytest
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
from mortar1d3d.geometry.beam import AFFINE_TOL, beam_is_affine
from mortar1d3d.geometry.projection import affine_inverse
from mortar1d3d.integration.points import exact_gauss_count

ROUND_OFF = 1e-13


def relative(A, B):
    return spla.norm(A - B) / spla.norm(B)


def assert_same_operators(a, b, tol=ROUND_OFF):
    assert relative(a.D, b.D) < tol
    assert relative(a.M, b.M) < tol
    assert np.abs(a.kappa - b.kappa).max() < tol * np.abs(b.kappa).max()
    assert a.D.shape == b.D.shape and a.M.shape == b.M.shape


def straight_beam(p, q, elements):
    """Hermite beam on the segment p-q (tangents along the chord: an affine centreline)."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    t = np.linspace(0.0, 1.0, elements + 1)[:, None]
    d = (q - p) / np.linalg.norm(q - p)
    return m13.BeamMesh.hermite(p + t * (q - p), np.tile(d, (elements + 1, 1)),
                                np.column_stack([np.arange(elements), np.arange(1, elements + 1)]))


def sheared(solid):
    """The same mesh under an affine map: hex8 cells become parallelepipeds (still affine)."""
    A = np.array([[1.0, 0.3, 0.1], [0.0, 0.9, 0.2], [0.1, 0.0, 1.1]])
    (descriptor, conn), = solid.blocks
    return m13.SolidMesh(solid.points @ A.T, {descriptor.name: conn})


# -- the target behaviour ---------------------------------------------------------------------------

@pytest.mark.parametrize("element", ["hexahedron", "tetra", "hexahedron27"])
def test_straight_fibres_crossing_faces_equal_segment_based(element):
    beams, _ = generate.fibre_cube(3, 4, 5)
    solid = generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), element)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=2)
    segment = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    assert auto.diagnostics["face_crossings"] > 0 and auto.diagnostics["numeric_pairs"] == 0
    # same segments, and the exact rule makes 2 requested points as good as 8
    np.testing.assert_array_equal(auto.segments["solid_element"], segment.segments["solid_element"])
    np.testing.assert_allclose(auto.segments["eta_start"], segment.segments["eta_start"], atol=1e-12)
    assert_same_operators(auto, segment)
    n_exact = exact_gauss_count(0, int(solid.element_codes[0]), 2)
    assert auto.n_integration_points == n_exact * len(auto.segments)
    assert auto.diagnostics["exact_rule_segments"] == len(auto.segments)


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27", "tetra10"])
def test_curved_beams_in_curved_elements_equal_segment_based(element):
    beams = generate.random_curved_beams(3, 8, seed=2)
    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element), 0.15, seed=1)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=5, lm="line3")
    segment = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=5, lm="line3")
    assert auto.diagnostics["face_crossings"] > 0
    assert auto.diagnostics["exact_rule_segments"] == 0          # not polynomial: the user's rule
    assert auto.n_integration_points == segment.n_integration_points
    assert_same_operators(auto, segment)


@pytest.mark.parametrize("name,p,q", [
    ("in a shared face", (0.1, 0.5, 0.3), (0.9, 0.5, 0.3)),
    ("on a shared edge", (0.1, 0.5, 0.5), (0.9, 0.5, 0.5)),
    ("through the centre node", (0.1, 0.1, 0.1), (0.9, 0.9, 0.9)),
    ("partly outside", (-0.3, 0.2, 0.3), (1.4, 0.6, 0.7)),
])
def test_degenerate_positions_follow_the_ownership_rule(name, p, q):
    solid = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "tetra")
    beams = straight_beam(p, q, 3)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=6)
    segment = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=6)
    np.testing.assert_array_equal(auto.segments["solid_element"], segment.segments["solid_element"])
    assert auto.embedded_length == pytest.approx(segment.embedded_length, rel=1e-14)
    assert_same_operators(auto, segment)


def test_beams_inside_single_elements_equal_element_based():
    solid = sheared(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "hexahedron"))
    centres = solid.points[solid.connectivity[:, :8]].mean(axis=1)
    # one short straight beam element around the centre of each cell
    d = np.array([0.6, -0.3, 0.74]) / np.linalg.norm([0.6, -0.3, 0.74])
    positions = np.vstack([np.vstack([c - 0.1 * d, c + 0.1 * d]) for c in centres])
    elements = np.arange(len(positions)).reshape(-1, 2)
    beams = m13.BeamMesh.hermite(positions, np.tile(d, (len(positions), 1)), elements)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=1)
    n_exact = exact_gauss_count(0, 0, 2)
    element = m13.assemble_mortar(beams, solid, integration="element", n_gauss=n_exact)
    assert auto.diagnostics["beam_elements_uncut"] == beams.n_elements
    assert auto.diagnostics["face_crossings"] == 0
    np.testing.assert_allclose(auto.points["eta"], element.points["eta"], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(auto.points["solid_element"], element.points["solid_element"])
    assert_same_operators(auto, element)


def test_curved_beam_certified_inside_uses_element_based_points():
    solid = generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "hexahedron")
    # a helix piece well inside cell 0 = [0, 0.5]^3
    beams = m13.BeamMesh.from_curve(lambda t: np.array([0.25 + 0.1 * np.cos(t), 0.25 + 0.1 * np.sin(t), 0.15 + 0.02 * t]),
                                    lambda t: np.array([-0.1 * np.sin(t), 0.1 * np.cos(t), 0.02]), 0.0, 4.0, 4)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=4)
    element = m13.assemble_mortar(beams, solid, integration="element", n_gauss=4)
    assert auto.diagnostics["certified_inside"] == beams.n_elements
    assert auto.diagnostics["numeric_pairs"] == 0 and auto.diagnostics["exact_rule_segments"] == 0
    assert auto.n_integration_points == element.n_integration_points == 4 * beams.n_elements
    assert_same_operators(auto, element)


def test_certificate_refuses_a_control_polygon_outside_the_element():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), "hexahedron")
    # a bow whose Bézier control points leave the cube (y > 1) while the curve stays inside
    t1 = np.array([1.0, 3.0, 0.0]) / np.sqrt(10.0)
    t2 = np.array([1.0, -3.0, 0.0]) / np.sqrt(10.0)
    beams = m13.BeamMesh.hermite(np.array([[0.05, 0.7, 0.5], [0.95, 0.7, 0.5]]), np.array([t1, t2]),
                                 np.array([[0, 1]]))
    L = beams.lengths[0]
    assert (beams.positions[0] + L / 3 * t1)[1] > 1.0                     # polygon outside
    assert beams.evaluate(0, np.linspace(-1, 1, 201))[:, 1].max() < 1.0   # curve inside
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=6)
    segment = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=6)
    assert auto.diagnostics["certified_inside"] == 0 and auto.diagnostics["numeric_pairs"] == 1
    assert auto.diagnostics["beam_elements_uncut"] == 1
    assert_same_operators(auto, segment)


def test_auto_is_bit_identical_for_any_thread_count():
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs 2 Numba threads")
    beams, solid = generate.fibre_cube(3, 4, 5, curved=True)
    default = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=3)
        numba.set_num_threads(2)
        two = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=3)
    finally:
        numba.set_num_threads(default)
    assert one.diagnostics["certified_inside"] > 0 and one.diagnostics["numeric_pairs"] > 0
    assert (one.D != two.D).nnz == 0 and (one.M != two.M).nnz == 0
    np.testing.assert_array_equal(one.kappa, two.kappa)


# -- building blocks ----------------------------------------------------------------------------------

def _local_nodes(solid, s):
    d = solid.blocks[0][0]
    X = solid.points[solid.connectivity[s, : d.n_nodes]]
    return np.ascontiguousarray(X - X[0]), float(np.linalg.norm(X.max(0) - X.min(0))), int(solid.element_codes[s])


@pytest.mark.parametrize("element", [n for n, d in SOLID_ELEMENTS.items() if not d.rational])
def test_affine_inverse_maps_nodes_to_their_reference_coordinates(element):
    solid = sheared(generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element))
    X, h, code = _local_nodes(solid, 0)
    Ainv = np.empty((3, 3))
    assert affine_inverse(code, X, h, AFFINE_TOL, Ainv)
    reference = solid.blocks[0][0].reference_nodes
    np.testing.assert_allclose(reference[0] + X @ Ainv.T, reference, atol=1e-13)
    # a node moved by 1e-6 h makes the element non-affine (tet4 has no node that can do that: its
    # shape functions are linear)
    if SOLID_ELEMENTS[element].monomials.sum(axis=1).max() > 1:
        X[-1, 1] += 1e-6 * h
        assert not affine_inverse(code, X, h, AFFINE_TOL, Ainv)


def test_beam_affinity():
    ddH = np.empty(4)
    straight = straight_beam((0.1, 0.2, 0.3), (0.7, 0.1, 0.5), 2)
    Q = straight.coefficients()
    Q[:, 2] -= Q[:, 0]
    Q[:, 0] = 0.0
    assert beam_is_affine(0, Q[0], straight.lengths[0], ddH)
    bent = Q[0].copy()
    bent[1] = (bent[1] + np.array([0.0, 1e-6, 0.0])) / np.linalg.norm(bent[1] + np.array([0.0, 1e-6, 0.0]))
    assert not beam_is_affine(0, bent, straight.lengths[0], ddH)
    line3 = np.array([[0, 0, 0], [1.0, 0, 0], [0.5, 0, 0], [0, 0, 0]])
    assert beam_is_affine(2, line3, 1.0, ddH)
    line3[2, 1] = 1e-9
    assert not beam_is_affine(2, line3, 1.0, ddH)


def test_exact_gauss_counts():
    # (beam, solid, n_phi) -> degree n_phi - 1 + max(beam degree, line degree of N)
    assert exact_gauss_count(0, 0, 2) == 3      # hermite, hex8, line2: degree 4
    assert exact_gauss_count(0, 3, 2) == 3      # hermite, tet4, line2: degree 4
    assert exact_gauss_count(1, 3, 2) == 2      # line, tet4, line2: degree 2
    assert exact_gauss_count(0, 2, 4) == 5      # hermite, hex27, line4: degree 9
    assert exact_gauss_count(2, 4, 3) == 3      # line3, tet10, line3: degree 4


def test_exact_rule_is_exact_on_a_parallelepiped_mesh():
    solid = sheared(generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), "hexahedron"))
    beams = straight_beam((0.05, 0.1, 0.2), (1.2, 0.8, 0.9), 7)
    auto = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=1, lm="line4")
    reference = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=12, lm="line4")
    assert auto.diagnostics["exact_rule_segments"] == len(auto.segments)
    assert auto.n_integration_points == 4 * len(auto.segments)           # hermite, hex8, line4: degree 6
    assert_same_operators(auto, reference)
    one = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=1, lm="line4")
    assert relative(one.M, reference.M) > 1e-3                            # the requested rule alone is not


def test_unknown_integration_lists_auto():
    beams, solid = generate.fibre_cube(2, 1, 2)
    with pytest.raises(ValueError, match="auto"):
        m13.assemble_mortar(beams, solid, integration="hybrid")
