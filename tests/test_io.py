"""VTU/PVD output: files read back with meshio hold exactly the meshes, samples and operator data."""
import os
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements.beam import hermite
from mortar1d3d.io import (sample_beams, write_beams, write_integration_points, write_mortar, write_pvd,
                           write_segments, write_solid)
from mortar1d3d.mesh import BeamMesh, SolidMesh

from naive import adaptive_arc_length

SAMPLES = 8


@pytest.fixture(scope="module")
def scene():
    return generate.fibre_cube(3, 4, 3)


@pytest.fixture(scope="module", params=["segment", "element"])
def ops(request, scene):
    beams, solid = scene
    return m13.assemble_mortar(beams, solid, integration=request.param)


@pytest.fixture(scope="module")
def hex27():
    return generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), element="hexahedron27")


def cell_block(mesh, kind):
    blocks = [i for i, b in enumerate(mesh.cells) if b.type == kind]
    assert len(blocks) == 1
    return blocks[0], mesh.cells[blocks[0]].data


# -- solid ---------------------------------------------------------------------------------------
def test_write_solid_hex8_with_data(tmp_path, scene):
    _, solid = scene
    u = solid.points * [1.0, 2.0, 3.0]
    stress = np.arange(solid.n_elements, dtype=float) ** 2
    path = write_solid(tmp_path / "solid.vtu", solid, point_data={"u": u}, cell_data={"stress": stress})
    assert path == tmp_path / "solid.vtu"
    mesh = meshio.read(path)
    np.testing.assert_array_equal(mesh.points, solid.points)
    i, conn = cell_block(mesh, "hexahedron")
    np.testing.assert_array_equal(conn, solid.cells["hexahedron"])
    np.testing.assert_array_equal(mesh.point_data["u"], u)
    np.testing.assert_array_equal(mesh.cell_data["stress"][i], stress)
    np.testing.assert_array_equal(mesh.cell_data["solid_element"][i], np.arange(27))
    assert sorted(os.listdir(tmp_path)) == ["solid.vtu"]       # no temporary file left


def test_write_solid_hex27_is_a_quadratic_vtk_cell(tmp_path, hex27):
    path = write_solid(tmp_path / "hex27.vtu", hex27)
    assert 'NumberOfPoints="125"' in path.read_text(errors="replace")
    mesh = meshio.read(path)
    assert mesh.points.shape == (125, 3)
    np.testing.assert_array_equal(mesh.points, hex27.points)
    _, conn = cell_block(mesh, "hexahedron27")
    assert conn.shape == (8, 27)
    np.testing.assert_array_equal(conn, hex27.cells["hexahedron27"])
    # meshio maps VTK type 29 (VTK_TRIQUADRATIC_HEXAHEDRON) back to hexahedron27
    assert SolidMesh.from_meshio(mesh).n_elements == 8


def test_write_solid_wedges_read_back_as_wedges(tmp_path):
    wedges = generate.box((0.0, 0.0, 0.0), (1.0, 2.0, 1.0), (2, 1, 2), element="wedge")
    mesh = meshio.read(write_solid(tmp_path / "wedges.vtu", wedges))
    np.testing.assert_array_equal(mesh.points, wedges.points)
    _, conn = cell_block(mesh, "wedge")                            # VTK_WEDGE (13)
    np.testing.assert_array_equal(conn, wedges.cells["wedge"])
    again = SolidMesh.from_meshio(mesh)
    np.testing.assert_array_equal(again.connectivity, wedges.connectivity)
    np.testing.assert_array_equal(again.element_codes, wedges.element_codes)


def test_write_solid_mixed_blocks_and_global_cell_data(tmp_path):
    hexes = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1), "hexahedron")
    tets = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1), "tetra")
    np.testing.assert_array_equal(hexes.points, tets.points)       # same lattice numbering
    solid = SolidMesh(hexes.points, {"hexahedron": hexes.cells["hexahedron"][:1],
                                     "tetra": tets.cells["tetra"][6:]})
    values = 10.0 * np.arange(7)
    mesh = meshio.read(write_solid(tmp_path / "mixed.vtu", solid,
                                   cell_data={"a": values, "b": [np.array([1]), np.arange(6)]}))
    assert [b.type for b in mesh.cells] == ["hexahedron", "tetra"]
    np.testing.assert_array_equal(mesh.cells[1].data, tets.cells["tetra"][6:])
    np.testing.assert_array_equal(mesh.cell_data["a"][0], [0.0])
    np.testing.assert_array_equal(mesh.cell_data["a"][1], values[1:])
    np.testing.assert_array_equal(mesh.cell_data["b"][1], np.arange(6))
    np.testing.assert_array_equal(np.concatenate(mesh.cell_data["solid_element"]), np.arange(7))


def test_write_solid_rejects_wrong_sizes(tmp_path, scene):
    _, solid = scene
    with pytest.raises(ValueError, match="point_data"):
        write_solid(tmp_path / "s.vtu", solid, point_data={"u": np.zeros((3, 3))})
    with pytest.raises(ValueError, match="cell_data"):
        write_solid(tmp_path / "s.vtu", solid, cell_data={"c": np.zeros(26)})
    with pytest.raises(ValueError, match="compression"):
        write_solid(tmp_path / "s.vtu", solid, compression="gzip")
    assert os.listdir(tmp_path) == []


# -- beams ---------------------------------------------------------------------------------------
def test_write_beams_samples_equal_evaluate(tmp_path, scene):
    beams, _ = scene
    m = beams.n_elements
    mesh = meshio.read(write_beams(tmp_path / "beams.vtu", beams, samples_per_element=SAMPLES))
    assert mesh.points.shape == (m * SAMPLES, 3)
    _, lines = cell_block(mesh, "line")
    assert lines.shape == (m * (SAMPLES - 1), 2)
    np.testing.assert_array_equal(lines[:, 1] - lines[:, 0], 1)
    eta = np.linspace(-1.0, 1.0, SAMPLES)
    np.testing.assert_array_equal(mesh.point_data["eta"], np.tile(eta, m))
    np.testing.assert_array_equal(mesh.point_data["beam_element"], np.repeat(np.arange(m), SAMPLES))
    np.testing.assert_array_equal(mesh.cell_data["beam_element"][0], np.repeat(np.arange(m), SAMPLES - 1))
    points = mesh.points.reshape(m, SAMPLES, 3)
    for e in range(m):
        np.testing.assert_allclose(points[e], beams.evaluate(e, eta), rtol=0, atol=1e-15)
    # straight fibres: tangent = the fibre direction, arc length proportional to η
    tangent = mesh.point_data["tangent"].reshape(m, SAMPLES, 3)
    np.testing.assert_allclose(tangent, np.broadcast_to(beams.tangents[beams.elements[:, 0]][:, None],
                                                        tangent.shape), rtol=0, atol=1e-14)
    arc = mesh.point_data["element_arc_length"].reshape(m, SAMPLES)
    np.testing.assert_allclose(arc, 0.5 * (eta + 1.0) * beams.lengths[:, None], rtol=0, atol=1e-15)
    np.testing.assert_allclose(beams.lengths, 0.1, rtol=1e-14)                  # L = 0.3, 3 elements


def test_sample_beams_curved_tangents_and_arc_lengths():
    beams, _ = generate.fibre_cube(2, 3, 4, curved=True)
    s = sample_beams(beams, 5)
    m = beams.n_elements
    eta = np.linspace(-1.0, 1.0, 5)
    for e in range(m):
        np.testing.assert_allclose(s.points[5 * e:5 * e + 5], beams.evaluate(e, eta), rtol=0, atol=1e-15)
    # tangent: r'/|r'| from the package's Hermite derivative functions
    Q = beams.coefficients()
    dH = np.empty(4)
    for e in range(m):
        for i, x in enumerate(eta):
            hermite.deriv.py_func(x, beams.lengths[e], dH)
            d = dH @ Q[e]
            np.testing.assert_allclose(s.tangent[5 * e + i], d / np.linalg.norm(d), rtol=0, atol=1e-13)
    # and the direction of a central difference of evaluate in the interior
    h = 1e-5
    d = beams.evaluate(0, eta[1:-1] + h) - beams.evaluate(0, eta[1:-1] - h)
    np.testing.assert_allclose(s.tangent[1:4], d / np.linalg.norm(d, axis=1, keepdims=True), rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(s.tangent, axis=1), 1.0, rtol=1e-15)
    # nodal tangents are the given unit tangents (Hermite interpolation condition)
    np.testing.assert_allclose(s.tangent[0::5], beams.tangents[beams.elements[:, 0]], rtol=0, atol=1e-14)
    np.testing.assert_allclose(s.tangent[4::5], beams.tangents[beams.elements[:, 1]], rtol=0, atol=1e-14)
    arc = s.arc_length.reshape(m, 5)
    assert (arc[:, 0] == 0).all() and (np.diff(arc, axis=1) > 0).all()
    # arc lengths are accurate integrals of |r'| (here half a helix turn per element, where the
    # 10-point rule of BeamMesh.lengths is off by 3e-9 relative)
    for e in (0, 5):
        for i in (2, 4):
            np.testing.assert_allclose(arc[e, i], adaptive_arc_length(beams, e, -1.0, eta[i]), rtol=1e-14)
    np.testing.assert_allclose(arc[:, -1], beams.lengths, rtol=1e-8)


@pytest.mark.parametrize("element", ["line", "line3"])
def test_write_beams_lagrange(tmp_path, element):
    t = np.linspace(0.0, 1.0, 7)
    positions = np.column_stack([np.cos(t), np.sin(t), t * t])
    if element == "line":
        elements = np.column_stack([np.arange(6), np.arange(1, 7)])
    else:
        elements = np.array([[0, 2, 1], [2, 4, 3], [4, 6, 5]])
    beams = BeamMesh.lagrange(positions, elements, element=element)
    mesh = meshio.read(write_beams(tmp_path / "lagrange.vtu", beams, samples_per_element=4))
    eta = np.linspace(-1.0, 1.0, 4)
    points = mesh.points.reshape(beams.n_elements, 4, 3)
    for e in range(beams.n_elements):
        np.testing.assert_allclose(points[e], beams.evaluate(e, eta), rtol=0, atol=1e-15)
    np.testing.assert_allclose(mesh.point_data["element_arc_length"].reshape(-1, 4)[:, -1], beams.lengths, rtol=1e-13)


def test_write_beams_extra_point_data(tmp_path, scene):
    beams, _ = scene
    m = beams.n_elements
    per_element = np.arange(m) * 1.5
    per_point = np.arange(m * 3)[:, None] * np.ones(3)
    mesh = meshio.read(write_beams(tmp_path / "b.vtu", beams, samples_per_element=3,
                                   point_data={"e": per_element, "p": per_point}))
    np.testing.assert_array_equal(mesh.point_data["e"], np.repeat(per_element, 3))
    np.testing.assert_array_equal(mesh.point_data["p"], per_point)
    with pytest.raises(ValueError, match="point_data"):
        write_beams(tmp_path / "c.vtu", beams, point_data={"bad": np.zeros(5)})
    with pytest.raises(ValueError, match="samples_per_element"):
        write_beams(tmp_path / "c.vtu", beams, samples_per_element=1)
    assert not (tmp_path / "c.vtu").exists()


def test_write_beams_20000_elements(tmp_path):
    """Large output is complete and exact (its speed is measured in benchmarks/test_io_speed.py)."""
    beams, _ = generate.fibre_cube(2, 1000, 20, curved=True)
    assert beams.n_elements == 20000
    path = write_beams(tmp_path / "big.vtu", beams)
    mesh = meshio.read(path)
    assert mesh.points.shape == (20000 * 8, 3)
    e = 12345
    np.testing.assert_allclose(mesh.points[8 * e:8 * e + 8], beams.evaluate(e, np.linspace(-1, 1, 8)),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(mesh.point_data["element_arc_length"][7::8], beams.lengths, rtol=1e-13)


# -- segments and integration points --------------------------------------------------------------
def test_write_segments(tmp_path, scene, ops):
    beams, _ = scene
    k = 4
    seg = ops.segments
    n = len(seg)
    mesh = meshio.read(write_segments(tmp_path / "segments.vtu", beams, ops, samples_per_segment=k))
    assert mesh.points.shape == (n * k, 3)
    _, lines = cell_block(mesh, "line")
    assert lines.shape == (n * (k - 1), 2)
    owner = np.repeat(np.arange(n), k - 1)
    np.testing.assert_array_equal(mesh.cell_data["segment"][0], owner)
    np.testing.assert_array_equal(mesh.cell_data["beam_element"][0], seg["beam_element"][owner])
    np.testing.assert_array_equal(mesh.cell_data["solid_element"][0], seg["solid_element"][owner])
    eta = mesh.point_data["eta"].reshape(n, k)
    np.testing.assert_array_equal(eta[:, 0], seg["eta_start"])
    np.testing.assert_array_equal(eta[:, -1], seg["eta_end"])
    points = mesh.points.reshape(n, k, 3)
    for i in range(n):
        np.testing.assert_allclose(points[i], beams.evaluate(seg["beam_element"][i], eta[i]), rtol=0, atol=1e-15)
    # straight fibres: the segment length is (η_b - η_a)/2 L
    length = mesh.cell_data["length"][0][::k - 1]
    expected = 0.5 * (seg["eta_end"] - seg["eta_start"]) * beams.lengths[seg["beam_element"]]
    np.testing.assert_allclose(length, expected, rtol=1e-13, atol=1e-16)
    if ops.integration == "segment":
        # the fibres lie inside the cube: the segments of every element add up to its length
        per_element = np.bincount(seg["beam_element"], weights=length, minlength=beams.n_elements)
        np.testing.assert_allclose(per_element, beams.lengths, rtol=1e-13)
        np.testing.assert_allclose(length.sum(), ops.embedded_length, rtol=1e-13)


def test_write_integration_points(tmp_path, scene, ops):
    beams, _ = scene
    p = ops.points
    assert len(p) > 0
    mesh = meshio.read(write_integration_points(tmp_path / "points.vtu", ops))
    _, vertices = cell_block(mesh, "vertex")
    np.testing.assert_array_equal(vertices[:, 0], np.arange(len(p)))
    np.testing.assert_array_equal(mesh.points, p["position"])
    for name in ("weight", "eta", "xi", "beam_element", "solid_element", "status"):
        np.testing.assert_array_equal(mesh.point_data[name], p[name])
    assert mesh.point_data["xi"].shape == (len(p), 3)
    np.testing.assert_allclose(mesh.point_data["weight"].sum(), ops.embedded_length, rtol=1e-13)
    for q in range(0, len(p), 7):
        np.testing.assert_allclose(mesh.points[q], beams.evaluate(p["beam_element"][q], p["eta"][q])[0],
                                   rtol=0, atol=1e-14)


def test_empty_operators_write_valid_empty_files(tmp_path, scene):
    beams, solid = scene
    outside = BeamMesh.hermite(beams.positions + 5.0, beams.tangents, beams.elements)
    ops = m13.assemble_mortar(outside, solid)
    assert len(ops.segments) == 0 and len(ops.points) == 0
    for path in (write_segments(tmp_path / "s.vtu", outside, ops),
                 write_integration_points(tmp_path / "p.vtu", ops)):
        piece = ET.parse(path).getroot().find("UnstructuredGrid/Piece")
        assert piece.get("NumberOfPoints") == "0" and piece.get("NumberOfCells") == "0"


# -- collections -------------------------------------------------------------------------------------
def read_pvd(path):
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), int(d.get("part")), d.get("file")) for d in root.iter("DataSet")]


@pytest.mark.parametrize("integration", ["segment", "element"])
@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27"])
def test_write_mortar(tmp_path, scene, hex27, integration, element):
    beams, solid = scene
    if element == "hexahedron27":
        solid = hex27
    ops = m13.assemble_mortar(beams, solid, integration=integration)
    directory = tmp_path / "out" / "nested"
    paths = write_mortar(directory, beams, solid, ops, prefix="run")
    names = ["run_solid.vtu", "run_beams.vtu", "run_segments.vtu", "run_points.vtu", "run.pvd"]
    assert paths == [directory / n for n in names]
    assert sorted(os.listdir(directory)) == sorted(names)
    entries = read_pvd(directory / "run.pvd")
    assert entries == [(0.0, i, n) for i, n in enumerate(names[:4])]
    for _, _, file in entries:
        assert (directory / file).is_file()
    solid_out, beams_out, segments_out, points_out = (meshio.read(directory / f) for _, _, f in entries)
    assert solid_out.cells[0].type == element and len(solid_out.points) == solid.n_nodes
    assert len(beams_out.points) == 8 * beams.n_elements
    assert len(segments_out.points) == 4 * len(ops.segments)
    np.testing.assert_array_equal(points_out.points, ops.points["position"])
    np.testing.assert_array_equal(points_out.point_data["weight"], ops.points["weight"])


def test_write_pvd_time_series(tmp_path):
    entries = [(t, part, f"series/step_{i:03d}_{part}.vtu")
               for i, t in enumerate([0.0, 0.1, 1.0 / 3.0]) for part in (0, 1)]
    path = write_pvd(tmp_path / "series.pvd", entries)
    assert path == tmp_path / "series.pvd"
    assert read_pvd(path) == entries                    # timesteps round-trip exactly
    with pytest.raises(ValueError, match="relative"):
        write_pvd(tmp_path / "bad.pvd", [(0.0, 0, tmp_path / "a.vtu")])
    with pytest.raises(ValueError, match="part"):
        write_pvd(tmp_path / "bad.pvd", [(0.0, -1, "a.vtu")])
    with pytest.raises(ValueError, match="tuples"):
        write_pvd(tmp_path / "bad.pvd", [(0.0, "a.vtu")])
    assert sorted(os.listdir(tmp_path)) == ["series.pvd"]


def test_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, scene, monkeypatch):
    beams, solid = scene
    path = write_solid(tmp_path / "solid.vtu", solid)
    before = path.read_bytes()

    def broken(filename, *args, **kwargs):
        with open(filename, "w") as f:
            f.write("<VTKFile half-writ")
        raise RuntimeError("disk full")

    monkeypatch.setattr(meshio, "write", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        write_solid(path, solid)
    with pytest.raises(RuntimeError, match="disk full"):
        write_beams(tmp_path / "beams.vtu", beams)
    assert sorted(os.listdir(tmp_path)) == ["solid.vtu"]
    assert path.read_bytes() == before
