"""Validated meshes: Hermite arc lengths, input errors, meshio round trips, mixed solid blocks."""
import re
import warnings

import meshio
import numpy as np
import pytest

from mortar1d3d import generate
from mortar1d3d.elements.solid import dispatch
from mortar1d3d.errors import MeshError, format_ids
from mortar1d3d.mesh import BeamMesh, SolidMesh, hermite_lengths

from naive import adaptive_arc_length

HEX_POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                       [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
TET_POINTS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)


def two_hexes():
    """Two unit hexes side by side along x (12 nodes)."""
    points = np.vstack([HEX_POINTS, HEX_POINTS[[1, 2, 5, 6]] + [1, 0, 0]])
    cells = np.array([[0, 1, 2, 3, 4, 5, 6, 7], [1, 8, 9, 2, 5, 10, 11, 6]])
    return points, cells


def quarter_circle(n):
    return BeamMesh.from_curve(lambda t: [np.cos(t), np.sin(t), 0.0],
                               lambda t: [-np.sin(t), np.cos(t), 0.0], 0.0, 0.5 * np.pi, n)


# --------------------------------------------------------------------------------------------
# Hermite element length = arc length
# --------------------------------------------------------------------------------------------
def test_quarter_circle_lengths_are_arc_lengths():
    beams = quarter_circle(8)
    assert beams.n_elements == 8 and beams.n_nodes == 9
    np.testing.assert_allclose(np.linalg.norm(beams.tangents, axis=1), 1.0, rtol=0, atol=1e-15)
    # discretisation error of cubic Hermite interpolation of a circle: O(h^4), 3.2e-6 here
    assert abs(beams.lengths.sum() - 0.5 * np.pi) < 5e-6
    assert beams.length == pytest.approx(beams.lengths.sum(), rel=1e-15)
    # every element has the same shape: the same length
    np.testing.assert_allclose(beams.lengths, beams.lengths[0], rtol=1e-14)
    Q = beams.coefficients()
    for e in range(beams.n_elements):
        L = beams.lengths[e]
        assert adaptive_arc_length(beams, e) == pytest.approx(L, rel=1e-13, abs=0)
        # L is not the chord
        assert L > np.linalg.norm(Q[e, 2] - Q[e, 0]) * (1 + 1e-4)


def test_quarter_circle_length_converges_at_fourth_order():
    errors = [abs(quarter_circle(n).length - 0.5 * np.pi) for n in (4, 8, 16)]
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(rates, 4.0, atol=0.1)


def test_straight_beam_length_is_chord():
    positions = np.array([[0.3, -1.2, 2.5], [1.7, 0.4, -3.1], [2.2, 1.0, -5.0]])
    chords = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    # straight elements: each node's tangent along its (single, or both collinear) neighbours
    for k in range(2):
        p = positions[k:k + 2]
        t = (p[1] - p[0]) / chords[k]
        beams = BeamMesh.hermite(p, np.array([t, t]), [[0, 1]])
        assert beams.lengths[0] == pytest.approx(chords[k], rel=1e-15, abs=0)
        # the centreline is the straight segment, parametrised at constant speed
        eta = np.linspace(-1, 1, 5)
        np.testing.assert_allclose(beams.evaluate(0, eta), p[0] + 0.5 * (1 + eta)[:, None] * (p[1] - p[0]),
                                   rtol=0, atol=1e-14)


def test_hermite_lengths_function_matches_mesh():
    beams = quarter_circle(3)
    L = hermite_lengths(beams.positions, beams.tangents, beams.elements)
    np.testing.assert_array_equal(L, beams.lengths)


def test_lagrange_lengths():
    positions = np.array([[0, 0, 0], [3, 4, 0], [1, 1, 0]], dtype=float)
    line = BeamMesh.lagrange(positions, [[0, 1], [1, 2]])
    np.testing.assert_allclose(line.lengths, [5.0, np.hypot(2, 3)], rtol=1e-15)
    assert line.tangents is None
    # line3 with a straight, evenly spaced middle node: the chord
    pos3 = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0]], dtype=float)
    assert BeamMesh.lagrange(pos3, [[0, 1, 2]], element="line3").lengths[0] == pytest.approx(2.0, rel=1e-15)


def test_non_unit_tangents_are_normalised_with_warning():
    positions = np.array([[0, 0, 0], [1, 0, 0]], dtype=float)
    with pytest.warns(UserWarning, match="not unit vectors"):
        beams = BeamMesh.hermite(positions, [[2, 0, 0], [0.5, 0, 0]], [[0, 1]])
    np.testing.assert_array_equal(beams.tangents, [[1, 0, 0], [1, 0, 0]])
    assert beams.lengths[0] == pytest.approx(1.0, rel=1e-15)


def test_centreline_dofs_layout():
    beams = quarter_circle(2)
    q = beams.centreline_dofs()
    assert q.shape == (6 * 3,) == (beams.n_centreline_dofs,)
    np.testing.assert_array_equal(q[6 * 1: 6 * 1 + 3], beams.positions[1])
    np.testing.assert_array_equal(q[6 * 1 + 3: 6 * 2], beams.tangents[1])
    np.testing.assert_array_equal(beams.function_columns(), [[0, 1, 2, 3], [2, 3, 4, 5]])


# --------------------------------------------------------------------------------------------
# bad input -> MeshError naming the problem and the offending ids
# --------------------------------------------------------------------------------------------
def test_mesh_error_is_value_error():
    assert issubclass(MeshError, ValueError)
    assert format_ids(range(12), limit=3) == "0, 1, 2 (and 9 more)"


def test_valid_meshes_pass():
    points, cells = two_hexes()
    solid = SolidMesh(points, {"hexahedron": cells})
    assert solid.n_elements == 2 and solid.n_nodes == 12
    SolidMesh(TET_POINTS, {"tetra": [[0, 1, 2, 3]]})


def test_unknown_solid_element_type():
    with pytest.raises(MeshError, match="unknown solid element type 'pyramid'"):
        SolidMesh(HEX_POINTS, {"pyramid": np.arange(5)[None]})


def test_unknown_beam_element_type():
    with pytest.raises(MeshError, match="unknown Lagrange beam element 'line4'; use 'line' or 'line3'"):
        BeamMesh.lagrange(HEX_POINTS[:2], [[0, 1]], element="line4")
    # Hermite interpolates tangents too: not a Lagrange element
    with pytest.raises(MeshError, match="unknown Lagrange beam element 'hermite'"):
        BeamMesh.lagrange(HEX_POINTS[:2], [[0, 1]], element="hermite")


def test_unknown_beam_element_type_direct_constructor():
    with pytest.raises(MeshError, match="unknown beam element type 'line4'"):
        BeamMesh("line4", HEX_POINTS[:2], [[0, 1]])


@pytest.mark.parametrize("points, cells, match", [
    (HEX_POINTS[:, :2], {"hexahedron": np.arange(8)[None]}, r"solid points: expected shape \(n, 3\), got \(8, 2\)"),
    (HEX_POINTS.ravel(), {"hexahedron": np.arange(8)[None]}, r"solid points: expected shape \(n, 3\), got \(24,\)"),
    (HEX_POINTS, {"hexahedron": np.arange(7)[None]}, r"'hexahedron': expected shape \(m, 8\), got \(1, 7\)"),
    (HEX_POINTS, {"hexahedron": np.arange(8)}, r"'hexahedron': expected shape \(m, 8\), got \(8,\)"),
    (HEX_POINTS, {"tetra": np.arange(8)[None]}, r"'tetra': expected shape \(m, 4\), got \(1, 8\)"),
    (HEX_POINTS, {"hexahedron": np.arange(8)[None] + 0.5}, "node ids must be integers"),
    (HEX_POINTS, {}, "non-empty dict"),
    (HEX_POINTS, [np.arange(8)], "non-empty dict"),
    (HEX_POINTS, {"hexahedron": np.zeros((0, 8), dtype=int)}, "no elements"),
    ([["a", "b", "c"]], {"hexahedron": np.arange(8)[None]}, "cannot convert"),
])
def test_wrong_solid_shapes(points, cells, match):
    with pytest.raises(MeshError, match=match):
        SolidMesh(points, cells)


def test_ragged_connectivity():
    with pytest.raises(MeshError, match="hexahedron"):
        SolidMesh(HEX_POINTS, {"hexahedron": [[0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 2]]})


def test_wrong_beam_shapes():
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    tan = np.tile([1.0, 0, 0], (3, 1))
    with pytest.raises(MeshError, match=r"beam positions: expected shape \(n, 3\), got \(3, 2\)"):
        BeamMesh.hermite(pos[:, :2], tan, [[0, 1]])
    with pytest.raises(MeshError, match=r"beam elements \(hermite\): expected shape \(m, 2\), got \(1, 3\)"):
        BeamMesh.hermite(pos, tan, [[0, 1, 2]])
    with pytest.raises(MeshError, match=r"beam elements \(line3\): expected shape \(m, 3\), got \(1, 2\)"):
        BeamMesh.lagrange(pos, [[0, 1]], element="line3")
    with pytest.raises(MeshError, match=r"beam tangents: expected shape \(3, 3\), got \(2, 3\)"):
        BeamMesh.hermite(pos, tan[:2], [[0, 1]])
    with pytest.raises(MeshError, match="line beams take no tangents"):
        BeamMesh("line", pos, [[0, 1]], tangents=tan)
    with pytest.raises(MeshError, match="no elements"):
        BeamMesh.lagrange(pos, np.zeros((0, 2), dtype=int))
    with pytest.raises(MeshError, match="n_elements must be >= 1"):
        BeamMesh.from_curve(lambda t: [t, 0, 0], lambda t: [1, 0, 0], 0, 1, 0)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_coordinates(value):
    points = HEX_POINTS.copy()
    points[5, 1] = value
    with pytest.raises(MeshError, match=r"solid points: NaN or infinite coordinates at rows 5$"):
        SolidMesh(points, {"hexahedron": np.arange(8)[None]})
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], dtype=float)
    pos[[1, 3], 2] = value
    with pytest.raises(MeshError, match=r"beam positions: NaN or infinite coordinates at rows 1, 3$"):
        BeamMesh.lagrange(pos, [[0, 1], [1, 2], [2, 3]])
    tan = np.tile([1.0, 0, 0], (4, 1))
    tan[2, 0] = value
    with pytest.raises(MeshError, match=r"beam tangents: NaN or infinite coordinates at rows 2$"):
        BeamMesh.hermite(np.arange(12.0).reshape(4, 3), tan, [[0, 1], [1, 2], [2, 3]])


def test_node_ids_out_of_range():
    points, cells = two_hexes()
    bad = cells.copy()
    bad[1, 3] = 12
    with pytest.raises(MeshError, match=r"out of range \[0, 12\) in elements 1$"):
        SolidMesh(points, {"hexahedron": bad})
    bad = cells.copy()
    bad[0, 0] = -1
    with pytest.raises(MeshError, match=r"in elements 0$"):
        SolidMesh(points, {"hexahedron": bad})
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    with pytest.raises(MeshError, match=r"beam elements \(line\): node ids out of range \[0, 3\) in elements 1$"):
        BeamMesh.lagrange(pos, [[0, 1], [1, 3]])


def test_inverted_hex8():
    points, cells = two_hexes()
    bad = cells.copy()
    bad[1, [0, 1]] = bad[1, [1, 0]]
    with pytest.raises(MeshError, match=r"inverted hexahedron elements .*: 1$"):
        SolidMesh(points, {"hexahedron": bad})
    # mirrored node order (bottom <-> top): every Jacobian negative
    bad = cells[:, [4, 5, 6, 7, 0, 1, 2, 3]]
    with pytest.raises(MeshError, match=r"inverted hexahedron elements .*: 0, 1$"):
        SolidMesh(points, {"hexahedron": bad})


def test_inverted_tet4():
    points = np.vstack([TET_POINTS, [[1, 1, 1]]])
    # tet (1, 2, 3, 4) is positively oriented; swapping two nodes inverts it
    assert SolidMesh(points, {"tetra": [[0, 1, 2, 3], [1, 2, 3, 4]]}).n_elements == 2
    with pytest.raises(MeshError, match=r"inverted tetra elements .*: 1$"):
        SolidMesh(points, {"tetra": [[0, 1, 2, 3], [1, 3, 2, 4]]})
    with pytest.raises(MeshError, match=r"inverted tetra elements .*: 0, 1$"):
        SolidMesh(points, {"tetra": [[0, 2, 1, 3], [2, 1, 3, 4]]})


def test_inverted_element_ids_are_global_across_blocks():
    points = np.vstack([HEX_POINTS, [[2, 0, 0]]])
    with pytest.raises(MeshError, match=r"inverted tetra elements .*: 1$"):
        SolidMesh(points, {"hexahedron": np.arange(8)[None], "tetra": [[1, 8, 5, 2]]})


def test_degenerate_flat_tet():
    points = np.vstack([TET_POINTS, [[0.3, 0.3, 0.0]]])
    with pytest.raises(MeshError, match=r"degenerate tetra elements .*: 1$"):
        SolidMesh(points, {"tetra": [[0, 1, 2, 3], [0, 1, 2, 4]]})
    # also when the flat tet is far from the origin and tiny (relative criterion)
    points = 1e-4 * np.vstack([TET_POINTS, [[0.3, 0.3, 0.0]]]) + 1e3
    with pytest.raises(MeshError, match=r"degenerate tetra elements .*: 1$"):
        SolidMesh(points, {"tetra": [[0, 1, 2, 3], [0, 1, 2, 4]]})
    # a valid tiny tet in the same place is accepted
    SolidMesh(points, {"tetra": [[0, 1, 2, 3]]})


def test_degenerate_flat_hex():
    points = HEX_POINTS.copy()
    points[4:, 2] = 0.0    # top face collapsed onto the bottom one (distinct nodes, same positions)
    with pytest.raises(MeshError, match=r"degenerate hexahedron elements .*: 0$"):
        SolidMesh(points, {"hexahedron": np.arange(8)[None]})


def _mirror(reference_nodes):
    """A reflection of the reference element onto itself, as the node permutation it induces:
    ξ_3 -> -ξ_3 where the element is symmetric about ξ_3 = 0 (hexahedra), else ξ_1 <-> ξ_2."""
    for mirrored in (reference_nodes * [1, 1, -1], reference_nodes[:, [1, 0, 2]]):
        match = (np.abs(reference_nodes[None, :, :] - mirrored[:, None, :]) < 1e-12).all(axis=2)
        if (match.sum(axis=1) == 1).all():
            return match.argmax(axis=1)
    raise AssertionError("no reflection maps the reference nodes onto themselves")


@pytest.mark.parametrize("element", list(dispatch.NODAL_ELEMENTS))
def test_inverted_and_degenerate_every_element_type(element):
    box = generate.box((0, 0, 0), (1, 1, 1), (2, 1, 1), element)
    ids = re.escape(format_ids(range(box.n_elements)))              # "0, 1, ... 9 (and 2 more)" for 12 tets
    # mirrored (x -> -x, same node order): every element turned inside out
    with pytest.raises(MeshError, match=rf"inverted {element} elements .*: {ids}$"):
        SolidMesh(box.points * [-1.0, 1.0, 1.0], box.cells)
    # squashed flat (z -> 1e-14 z): distinct nodes, zero volume relative to the element size
    with pytest.raises(MeshError, match=rf"degenerate {element} elements .*: {ids}$"):
        SolidMesh(box.points * [1.0, 1.0, 1e-14], box.cells)
    # the last element's nodes listed as its mirror image (ξ_3 -> -ξ_3 for hexahedra, ξ_1 <-> ξ_2 for
    # tetrahedra): that element alone is inverted
    perm = _mirror(dispatch.SOLID_ELEMENTS[element].reference_nodes)
    cells = box.cells[element].copy()
    cells[-1] = cells[-1][perm]
    with pytest.raises(MeshError, match=rf"inverted {element} elements .*: {box.n_elements - 1}$"):
        SolidMesh(box.points, {element: cells})


def test_zero_length_beam_element():
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    with pytest.raises(MeshError, match=r"zero-length beam elements: 1$"):
        BeamMesh.lagrange(pos, [[0, 1], [1, 2], [2, 3]])
    tan = np.tile([1.0, 0, 0], (4, 1))
    with pytest.raises(MeshError, match=r"zero-length beam elements: 1$"):
        BeamMesh.hermite(pos, tan, [[0, 1], [1, 2], [2, 3]])


def test_zero_tangent():
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    tan = np.tile([1.0, 0, 0], (3, 1))
    tan[2] = 0.0
    with pytest.raises(MeshError, match=r"zero beam tangents at nodes 2$"):
        BeamMesh.hermite(pos, tan, [[0, 1], [1, 2]])
    with pytest.raises(MeshError, match="zero beam tangents"):
        BeamMesh.hermite(pos, np.zeros((3, 3)), [[0, 1], [1, 2]])
    # an unused node may have a zero tangent
    assert BeamMesh.hermite(pos, tan, [[0, 1]]).n_elements == 1


def test_missing_tangents_for_hermite():
    pos = np.array([[0, 0, 0], [1, 0, 0]], dtype=float)
    with pytest.raises(MeshError, match="Hermite beams need one tangent per node"):
        BeamMesh.hermite(pos, None, [[0, 1]])


def test_repeated_node_in_element():
    points, cells = two_hexes()
    bad = cells.copy()
    bad[1, 5] = bad[1, 4]
    with pytest.raises(MeshError, match=r"'hexahedron': elements 1 use the same node twice"):
        SolidMesh(points, {"hexahedron": bad})
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    with pytest.raises(MeshError, match=r"beam elements \(line3\): elements 0 use the same node twice"):
        BeamMesh.lagrange(pos, [[0, 2, 0]], element="line3")
    with pytest.raises(MeshError, match=r"elements 1 use the same node twice"):
        BeamMesh.hermite(pos, np.tile([1.0, 0, 0], (3, 1)), [[0, 1], [2, 2]])


# --------------------------------------------------------------------------------------------
# meshio round trip, mixed blocks
# --------------------------------------------------------------------------------------------
def test_from_meshio_round_trip_skips_triangles():
    points, cells = two_hexes()
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    mesh = meshio.Mesh(points, [("hexahedron", cells[:1]), ("triangle", triangles), ("hexahedron", cells[1:])],
                       point_sets={"bottom": np.array([0, 1, 2, 3])})
    with pytest.warns(UserWarning, match="skipped lower-dimensional cells 2 triangle"):
        solid = SolidMesh.from_meshio(mesh)
    assert solid.n_elements == 2
    np.testing.assert_array_equal(solid.points, points)
    np.testing.assert_array_equal(solid.cells["hexahedron"], cells)
    np.testing.assert_array_equal(solid.point_sets["bottom"], [0, 1, 2, 3])
    out = solid.to_meshio()
    assert [b.type for b in out.cells] == ["hexahedron"]
    np.testing.assert_array_equal(out.points, points)
    np.testing.assert_array_equal(out.cells[0].data, cells)
    # and back again, without warnings this time
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = SolidMesh.from_meshio(out)
    np.testing.assert_array_equal(again.connectivity, solid.connectivity)
    np.testing.assert_array_equal(again.element_codes, solid.element_codes)


def test_from_meshio_hexahedron_and_wedge_sharing_a_face():
    from mortar1d3d.physics.surface import boundary_faces
    points = np.vstack([HEX_POINTS, [[2, 0, 0], [2, 0, 1]]])
    mesh = meshio.Mesh(points, [("hexahedron", np.arange(8)[None]), ("wedge", [[1, 8, 2, 5, 9, 6]])])
    solid = SolidMesh.from_meshio(mesh)
    assert solid.n_elements == 2 and list(solid.cells) == ["hexahedron", "wedge"]
    # the hexahedron's face x = 1 is the wedge's face ξ1 = 0: interior, on neither boundary list
    faces = boundary_faces(solid)
    assert len(faces) == 5 + 4
    on_boundary = {(int(e), int(f)) for e, f in zip(faces["element"], faces["face"])}
    assert (0, 1) not in on_boundary and (1, 4) not in on_boundary


def test_from_meshio_rejects_pyramids():
    points = np.vstack([HEX_POINTS, [[0.5, 0.5, 2.0]]])
    mesh = meshio.Mesh(points, [("hexahedron", np.arange(8)[None]), ("pyramid", [[4, 5, 6, 7, 8]])])
    with pytest.raises(MeshError, match="unsupported cell type 'pyramid'"):
        SolidMesh.from_meshio(mesh)


def test_from_meshio_without_solid_cells():
    mesh = meshio.Mesh(HEX_POINTS, [("triangle", [[0, 1, 2]])])
    with pytest.warns(UserWarning, match="1 triangle"):
        with pytest.raises(MeshError, match="no supported 3D cells"):
            SolidMesh.from_meshio(mesh)


def _hex_and_tets():
    """A unit hex [0,1]^3 and two tets glued to its x = 1 face (nodes shared)."""
    points = np.vstack([HEX_POINTS, [[2.0, 0.5, 0.5]]])
    tets = np.array([[1, 2, 5, 8], [2, 6, 5, 8]])
    return points, np.arange(8)[None], tets


def test_mixed_blocks_numbered_block_by_block():
    points, hexes, tets = _hex_and_tets()
    solid = SolidMesh(points, {"hexahedron": hexes, "tetra": tets})
    assert solid.n_elements == 3
    hex_code = dispatch.SOLID_ELEMENTS["hexahedron"].code
    tet_code = dispatch.SOLID_ELEMENTS["tetra"].code
    np.testing.assert_array_equal(solid.element_codes, [hex_code, tet_code, tet_code])
    assert solid.element_codes.dtype == np.int64 and solid.connectivity.dtype == np.int64
    assert solid.connectivity.shape == (3, 8)        # as wide as the mesh's largest element
    np.testing.assert_array_equal(solid.connectivity[0, :8], hexes[0])
    np.testing.assert_array_equal(solid.connectivity[1:, :4], tets)
    assert np.all(solid.connectivity[0, 8:] == -1) and np.all(solid.connectivity[1:, 4:] == -1)
    np.testing.assert_array_equal(solid.element_nodes(2), tets[1])
    np.testing.assert_array_equal(solid.element_nodes(0), hexes[0])
    assert "1 hexahedron" in repr(solid) and "2 tetra" in repr(solid)
    # the dict order decides the numbering
    swapped = SolidMesh(points, {"tetra": tets, "hexahedron": hexes})
    np.testing.assert_array_equal(swapped.element_codes, [tet_code, tet_code, hex_code])
    np.testing.assert_array_equal(swapped.element_nodes(2), hexes[0])
    # meshio round trip keeps the blocks
    out = swapped.to_meshio()
    assert [b.type for b in out.cells] == ["tetra", "hexahedron"]
    back = SolidMesh.from_meshio(out)
    np.testing.assert_array_equal(back.connectivity, swapped.connectivity)


def test_mixed_quadratic_blocks():
    # a hexahedron27 and a tetra10 built from the reference nodes (affine maps, valid elements)
    d27 = dispatch.SOLID_ELEMENTS["hexahedron27"]
    d10 = dispatch.SOLID_ELEMENTS["tetra10"]
    points = np.vstack([d27.reference_nodes, d10.reference_nodes + [2.0, 0, 0]])
    solid = SolidMesh(points, {"hexahedron27": np.arange(27)[None], "tetra10": 27 + np.arange(10)[None]})
    np.testing.assert_array_equal(solid.element_codes, [d27.code, d10.code])
    assert np.all(solid.connectivity[1, 10:] == -1)
    np.testing.assert_array_equal(solid.element_nodes(1), 27 + np.arange(10))
    # an inverted tetra10 in the second block is reported with its global id
    bad = 27 + np.arange(10)[[0, 2, 1, 3, 6, 5, 4, 7, 9, 8]]
    with pytest.raises(MeshError, match=r"inverted tetra10 elements .*: 1$"):
        SolidMesh(points, {"hexahedron27": np.arange(27)[None], "tetra10": bad[None]})
