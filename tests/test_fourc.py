"""4C input files: the reader (node orders, conditions, errors), the beam3eb beam, line loads, and
4C's own regression files where the folder of them exists (``MORTAR1D3D_4C_INPUTS`` or
``shared/4c-inputs`` beside the repository's folder; skipped with the reason otherwise)."""
import subprocess
import sys
import warnings

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.io import fourc
from mortar1d3d.io.fourc import FourCError, read_4c, scene_from_4c
from mortar1d3d.mesh import BeamMesh
from mortar1d3d.physics.beam import BeamModel, line_force
from mortar1d3d.physics.beam3eb import Beam3ebModel
from mortar1d3d.scene import Scene, SceneError

FOLDER = fourc.input_folder()
needs_inputs = pytest.mark.skipif(FOLDER is None, reason=f"no 4C input files: set {fourc.ENV_VAR} or provide "
                                                         "shared/4c-inputs beside the repository's folder")
EB = "beam3eb_static_beam_to_solid_volume_meshtying_"


# -- a small 4C file written here: a 2 × 1 × 1 hex8 block with a BEAM3EB fibre along x ------------
def tiny_file(tmp_path, coupling=None, extra="", funct="t", elements=None):
    """A self-made 4C input file (not one of 4C's): block [0, 2] × [0, 1] × [0, 1], clamped at
    x = 0, pulled at x = 2, a beam of two elements at y = z = 0.5 with a line load."""
    X = [(x, y, z) for x in (0.0, 1.0, 2.0) for y in (0.0, 1.0) for z in (0.0, 1.0)]
    node = {p: i + 1 for i, p in enumerate(X)}

    def hexa(x0):
        c = [(x0, 0, 0), (x0 + 1, 0, 0), (x0 + 1, 1, 0), (x0, 1, 0), (x0, 0, 1), (x0 + 1, 0, 1), (x0 + 1, 1, 1),
             (x0, 1, 1)]
        return " ".join(str(node[tuple(float(v) for v in p)]) for p in c)
    beam = [(0.2, 0.5, 0.5), (1.0, 0.5, 0.5), (1.8, 0.5, 0.5)]
    lines = [f'  - "NODE {i + 1} COORD {p[0]} {p[1]} {p[2]}"' for i, p in enumerate(X + beam)]
    elements = elements or [f'  - "1 SOLID HEX8 {hexa(0)} MAT 1 KINEM nonlinear"',
                            f'  - "2 SOLID HEX8 {hexa(1)} MAT 1 KINEM nonlinear"',
                            '  - "3 BEAM3EB LINE2 13 14 MAT 2"', '  - "4 BEAM3EB LINE2 14 15 MAT 2"']
    x0 = [f'  - "NODE {node[p]} DSURFACE 1"' for p in X if p[0] == 0.0]
    x2 = [f'  - "NODE {node[p]} DSURFACE 2"' for p in X if p[0] == 2.0]
    coupling = coupling or ("  CONTACT_DISCRETIZATION: mortar\n  CONSTRAINT_STRATEGY: penalty\n"
                            "  MORTAR_SHAPE_FUNCTION: line2\n  PENALTY_PARAMETER: 100\n")
    text = f"""\
PROBLEM TYPE:
  PROBLEMTYPE: "Structure"
STRUCTURAL DYNAMIC:
  DYNAMICTYPE: "Statics"
  TIMESTEP: 0.5
  NUMSTEP: 2
  MAXTIME: 1
BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING:
{coupling}MATERIALS:
  - MAT: 1
    MAT_Struct_StVenantKirchhoff:
      YOUNG: 100
      NUE: 0.3
      DENS: 0
  - MAT: 2
    MAT_BeamKirchhoffTorsionFreeElastHyper:
      YOUNG: 1000
      DENS: 0
      CROSSAREA: 0.01
      MOMIN: 1.0e-05
FUNCT1:
  - SYMBOLIC_FUNCTION_OF_SPACE_TIME: "{funct}"
DESIGN SURF DIRICH CONDITIONS:
  - E: 1
    NUMDOF: 3
    ONOFF: [1, 1, 1]
    VAL: [0, 0, 0]
    FUNCT: [0, 0, 0]
DESIGN SURF NEUMANN CONDITIONS:
  - E: 2
    NUMDOF: 3
    ONOFF: [1, 0, 1]
    VAL: [2, 0, -1]
    FUNCT: [1, 0, 1]
DESIGN LINE NEUMANN CONDITIONS:
  - E: 1
    NUMDOF: 6
    ONOFF: [0, 1, 0, 0, 0, 0]
    VAL: [0, 0.5, 0, 0, 0, 0]
    FUNCT: [0, 1, 0, 0, 0, 0]
BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE:
  - E: 1
    COUPLING_ID: 1
BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING VOLUME:
  - E: 1
    COUPLING_ID: 1
{extra}RESULT DESCRIPTION:
  - STRUCTURE:
      DIS: "structure"
      NODE: 15
      QUANTITY: "dispx"
      VALUE: 0.0
      TOLERANCE: 1e-10
  - STRUCTURE:
      SPECIAL: true
      QUANTITY: "num_iter_step_1"
      VALUE: 3
      TOLERANCE: 1e-08
DSURF-NODE TOPOLOGY:
{chr(10).join(x0 + x2)}
DLINE-NODE TOPOLOGY:
  - "NODE 13 DLINE 1"
  - "NODE 14 DLINE 1"
  - "NODE 15 DLINE 1"
DVOL-NODE TOPOLOGY:
{chr(10).join(f'  - "NODE {i + 1} DVOL 1"' for i in range(len(X)))}
NODE COORDS:
{chr(10).join(lines)}
STRUCTURE ELEMENTS:
{chr(10).join(elements)}
"""
    path = tmp_path / "tiny.4C.yaml"
    path.write_text(text)
    return path


def test_tiny_file_becomes_the_scene_written_by_hand(tmp_path):
    scene, nodes = scene_from_4c(tiny_file(tmp_path))
    assert scene.analysis["steps"] == 2 and scene.solid["material"] == {"model": "saint_venant_kirchhoff",
                                                                         "E": 100.0, "nu": 0.3}
    assert [b["model"] for b in scene.beams] == ["beam3eb"]
    assert scene.beams[0]["section"]["EA"] == pytest.approx(10.0) and scene.beams[0]["section"]["EI"] == 1e-2
    assert scene.coupling["penalty"] == 100.0 and scene.coupling["lm"] == "line2"
    assert scene.coupling["search_points"] == 6 and scene.coupling["n_gauss"] == 6
    assert [d["on"] for d in scene.dirichlet] == ["solid:dsurf1"]
    loads = {item["type"]: item for item in scene.loads}
    np.testing.assert_array_equal(loads["traction"]["value"], [2.0, 0.0, -1.0])
    np.testing.assert_array_equal(loads["line"]["value"], [0.0, 0.5, 0.0])
    assert loads["line"]["on"] == "beam:0"
    assert nodes[15] == ("beam", 2) and nodes[12][0] == "solid"
    assert "load.line" in str(m13.plan(scene))
    # the same model written as a scene by hand gives the same bits
    solid = scene.solid["mesh"]
    hand = Scene(solid={"mesh": solid, "material": {"model": "saint_venant_kirchhoff", "E": 100, "nu": 0.3}},
                 beams=[{"curve": {"line": [[0.2, 0.5, 0.5], [1.8, 0.5, 0.5]]}, "elements": 2, "model": "beam3eb",
                         "section": {"EA": 1000 * 0.01, "EI": 1000 * 1e-5}}],
                 coupling={"penalty": 100},
                 dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "traction", "on": "solid:x_max", "value": [2, 0, -1]},
                       {"type": "line", "on": "beam:0", "value": [0, 0.5, 0]}],
                 analysis={"steps": 2, "solver": "direct"})
    a, b = m13.solve(scene), m13.solve(hand)
    np.testing.assert_array_equal(a.z, b.z)
    assert np.abs(a.beam_displacement).max() > 1e-3


def test_check_reports_special_entries_as_not_comparable(tmp_path):
    report = fourc.check(tiny_file(tmp_path))
    statuses = [r.status for r in report.rows]
    assert statuses[1] == "not comparable"
    # the file's made-up value 0 for dispx of node 15 is wrong: the check must say so
    assert statuses[0] == "FAIL" and report.rows[0].deviation > 1e-4 and not report.passed
    assert "not comparable" in report.table()


def test_cli_check_exit_codes(tmp_path):
    path = tiny_file(tmp_path)
    out = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "check", str(path), "--quiet"],
                         capture_output=True, text=True)
    assert out.returncode == 1 and "FAIL" in out.stdout and "not comparable" in out.stdout
    bad = tiny_file(tmp_path, funct="t*t")
    out = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "check", str(bad), "--quiet"],
                         capture_output=True, text=True)
    assert out.returncode == 2 and "FUNCT1.SYMBOLIC_FUNCTION_OF_SPACE_TIME" in out.stderr


@pytest.mark.parametrize("coupling, extra, key", [
    ("  CONTACT_DISCRETIZATION: mortar\n  CONSTRAINT_STRATEGY: lagrange\n  LAGRANGE_FORMULATION: mixed\n"
     "  MORTAR_SHAPE_FUNCTION: line2\n", "", "LAGRANGE_FORMULATION: 'mixed' is not supported"),
    ("  CONTACT_DISCRETIZATION: mortar\n  CONSTRAINT_STRATEGY: penalty\n  MORTAR_SHAPE_FUNCTION: line2\n"
     "  PENALTY_PARAMETER: 1\n  ROTATION_COUPLING: fix_triad_2d\n", "",
     "ROTATION_COUPLING: 'fix_triad_2d' is not supported"),
    ("  CONTACT_DISCRETIZATION: mortar\n  CONSTRAINT_STRATEGY: penalty\n  MORTAR_SHAPE_FUNCTION: line2\n"
     "  PENALTY_PARAMETER: 1\n  GEOMETRY_PAIR_STRATEGY: gauss_point_projection_cross_section\n", "",
     "GEOMETRY_PAIR_STRATEGY: 'gauss_point_projection_cross_section'"),
    (None, "BEAM CONTACT/BEAM TO BEAM CONTACT:\n  STRATEGY: penalty\n", "BEAM CONTACT/BEAM TO BEAM CONTACT: section"),
    (None, "DESIGN SURF NEUMANN CONDITIONS:\n  - E: 2\n    NUMDOF: 3\n    ONOFF: [1, 0, 0]\n    VAL: [1, 0, 0]\n"
           "    FUNCT: [1, 0, 0]\n    TYPE: pseudo_orthopressure\n", "TYPE: 'pseudo_orthopressure'"),
])
def test_unsupported_keys_are_errors_naming_key_and_value(tmp_path, coupling, extra, key):
    with pytest.raises(FourCError) as info:
        scene_from_4c(tiny_file(tmp_path, coupling=coupling, extra=extra))
    assert key in str(info.value)
    assert isinstance(info.value, SceneError)


def test_nurbs27_without_knots_and_constant_load_are_errors(tmp_path):
    nurbs = ['  - "1 SOLID NURBS27 ' + " ".join(str(i) for i in range(1, 13)) + ' MAT 1 KINEM nonlinear"']
    with pytest.raises(FourCError, match="STRUCTURE KNOTVECTORS: missing"):
        scene_from_4c(tiny_file(tmp_path, elements=nurbs))
    with pytest.raises(FourCError, match=r"FUNCT1.*'2\*t\*t'"):
        scene_from_4c(tiny_file(tmp_path, funct="2*t*t"))


def test_node_permutations_match_the_library_reference_nodes():
    from mortar1d3d.elements.solid.dispatch import solid_element
    for name, (lib, ref4c) in fourc.FOURC_SOLID_NODES.items():
        perm = fourc._permutation(name)
        np.testing.assert_array_equal(ref4c[perm], solid_element(lib).reference_nodes)
    # 4C's TET10: node 5 halves edge 1-2, 6 edge 2-3, 7 edge 3-1, 8 edge 1-4, 9 edge 2-4, 10 edge 3-4
    tet = fourc.FOURC_SOLID_NODES["TET10"][1]
    for k, (i, j) in enumerate([(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]):
        np.testing.assert_array_equal(tet[4 + k], 0.5 * (tet[i] + tet[j]))


@needs_inputs
def test_hex27_node_order_of_4c_files_is_the_geometry():
    """Every node of the bar's HEX27 elements sits where its 4C reference coordinate maps to under
    the trilinear map of the element's corners (the bricks are straight-sided): the table of 4C's
    node order is right."""
    fc = read_4c(FOLDER / f"{EB}mortar_penalty_line3.4C.yaml")
    ref = fourc.FOURC_SOLID_NODES["HEX27"][1]
    corners = ref[:8]
    # trilinear functions at the 27 reference points
    N = np.prod(1.0 + ref[:, None, :] * corners[None, :, :], axis=2) / 8.0
    for _, kind, ids, _ in fc.solids:
        X = np.array([fc.nodes[n] for n in ids])
        np.testing.assert_allclose(N @ X[:8], X, atol=1e-12)


# -- beam3eb ----------------------------------------------------------------------------------------
def _bent_beam(n=3):
    beams = BeamMesh.hermite(np.column_stack([np.linspace(0, 1.2, n + 1), np.zeros(n + 1), np.zeros(n + 1)]),
                             np.tile([1.0, 0, 0], (n + 1, 1)), np.column_stack([np.arange(n), np.arange(1, n + 1)]))
    rng = np.random.default_rng(3)
    d = 0.05 * rng.standard_normal(6 * (n + 1))
    return beams, d


def test_beam3eb_tangent_is_the_derivative_of_its_force():
    beams, d = _bent_beam()
    model = Beam3ebModel(beams, EA=50.0, EI=0.3)
    f, K = model.evaluate(d)
    K = K.toarray()
    h = 1e-6
    fd = np.column_stack([(model.evaluate(d + h * e, tangent=False)[0] - model.evaluate(d - h * e, tangent=False)[0])
                          / (2 * h) for e in np.eye(len(d))])
    assert np.abs(fd - K).max() < 1e-6 * np.abs(K).max()
    # the ANS axial term is not variational: the tangent is not symmetric
    assert np.abs(K - K.T).max() > 1e-4 * np.abs(K).max()


def test_beam3eb_bending_force_is_the_gradient_of_4c_bending_energy():
    beams, d = _bent_beam()
    model = Beam3ebModel(beams, EA=1e-30, EI=0.3)
    f, _ = model.evaluate(d, tangent=False)
    h = 1e-6
    grad = np.array([(model.energy(d + h * e) - model.energy(d - h * e)) / (2 * h) for e in np.eye(len(d))])
    np.testing.assert_allclose(f, grad, atol=1e-7 * np.abs(f).max())


def test_beam3eb_differs_from_torsion_free_at_second_order_only():
    beams, d = _bent_beam()
    eb, tf = Beam3ebModel(beams, EA=50.0, EI=0.3), BeamModel(beams, EA=50.0, EI=0.3)
    # the same stiffness at the reference state: 3 sampled strains interpolate the quadratic linear
    # strain exactly, as the 3-point axial rule of torsion_free integrates it exactly
    Ka, Kb = eb.evaluate(np.zeros_like(d))[1].toarray(), tf.evaluate(np.zeros_like(d))[1].toarray()
    assert np.abs(Ka - Kb).max() < 1e-12 * np.abs(Kb).max()
    # the forces then differ at second order in the displacement
    diff = [np.abs(eb.evaluate(s * d, tangent=False)[0] - tf.evaluate(s * d, tangent=False)[0]).max()
            for s in (1e-3, 1e-4)]
    assert diff[1] > 0.0 and diff[0] / diff[1] == pytest.approx(100.0, rel=0.02)


def test_line_force_sums_to_load_times_length():
    beams, _ = _bent_beam(4)
    dofs, f = line_force(beams, np.arange(4), [0.0, 2.0, -1.0])
    total = np.zeros(beams.n_centreline_dofs)
    np.add.at(total, dofs, f)
    per_node = total.reshape(-1, 6)
    np.testing.assert_allclose(per_node[:, :3].sum(axis=0), [0.0, 2.4, -1.2], rtol=1e-14)
    # the tangent shares cancel between neighbouring elements except at the ends: ±q L²/12 there
    np.testing.assert_allclose(per_node[0, 3:], [0.0, 2.0 * 0.3 ** 2 / 12, -0.3 ** 2 / 12], rtol=1e-12)
    np.testing.assert_allclose(per_node[1:-1, 3:], 0.0, atol=1e-15)


def test_line_load_needs_a_whole_beam():
    with pytest.raises(SceneError, match=r"load\[0\].on: a line load acts along a whole beam"):
        Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "section": {"EA": 1, "EI": 1}}],
              load=[{"type": "line", "on": "beam:0:end", "value": [0, 0, 1]}])


# -- 4C's files -------------------------------------------------------------------------------------
@needs_inputs
@pytest.mark.parametrize("name", ["mortar_penalty_line3", "mortar_lagrange_saddlepoint_line3",
                                  "mortar_lagrange_regularized_line3"])
def test_4c_beam3eb_line3_bar_passes(name):
    report = fourc.check(FOLDER / f"{EB}{name}.4C.yaml")
    assert report.passed, report.table()
    assert report.max_deviation < 1e-10


R = "beam3r_herm2line3_static_beam_to_solid_volume_meshtying_"


@needs_inputs
@pytest.mark.parametrize("name", ["beam_in_solid_column_gauss_point_projection_without_boundary_segmentation",
                                  "beam_along_solid_boundary_gauss_point_projection_without_boundary_segmentation",
                                  "beam_in_solid_column_gauss_point_projection_boundary_segmentation",
                                  "beam_along_solid_boundary_gauss_point_projection_boundary_segmentation"])
def test_4c_beam3r_gauss_point_projection_files_pass(name):
    """With 4C's Gauss–Lobatto force rule the BEAM3R files reproduce 4C (measured 1.7e-13 and
    1.1e-13 against the tolerance 1e-8; with the 3-point Gauss force rule they missed by 7e-3 and 1e-2).
    The boundary-segmentation pair runs with ``integration = "element_boundary"`` (4.4e-13, 1.2e-13;
    4C's values for the two strategies differ by 5e-3 and 1.9e-2)."""
    report = fourc.check(FOLDER / f"{R}{name}.4C.yaml")
    assert report.passed, report.table()
    assert report.max_deviation < 1e-11


@needs_inputs
@pytest.mark.parametrize("name", ["mortar_penalty_line2", "mortar_penalty_line3", "mortar_penalty_line4",
                                  "mortar_penalty_line3_element_based_integration",
                                  "mortar_lagrange_saddlepoint_line3"])
def test_4c_beam3r_mortar_files_pass_with_the_twist_gauge(name):
    """The spin about global z held at the start of a beam along x only removes the beam's free
    twist: read as a twist support, with a note (measured 1.8e-11, 3.7e-11, 2.0e-11, 3.9e-11 and
    3.5e-12 against the tolerance 1e-10). The same code gave 5.003e-11 for line3 on another machine
    (AMD EPYC; OpenBLAS chooses its kernels by CPU): the deviations move with the machine, presumably
    the round-off of a stiff penalty solve (not measured further), so the bound below leaves 1.5x
    room over the largest seen, still below the files' 1e-10."""
    with pytest.warns(UserWarning, match=r"rotation components \[5\] .* read as twist = true"):
        scene, _ = scene_from_4c(FOLDER / f"{R}{name}.4C.yaml")
    twist = [d for d in scene.dirichlet if d["twist"]]
    assert len(twist) == 1 and twist[0]["on"] == "beam:0:start" and twist[0]["components"] == []
    assert not any(d["rotation"] is not None for d in scene.dirichlet)
    with pytest.warns(UserWarning):
        report = fourc.check(FOLDER / f"{R}{name}.4C.yaml")
    assert report.passed, report.table()
    assert report.max_deviation < 7.5e-11
    assert "note: DESIGN POINT DIRICH CONDITIONS[0]: rotation components [5]" in report.table()


@needs_inputs
@pytest.mark.parametrize("change, message", [
    (("VAL: [0, 0, 0, 0, 0, 0, 0, 0, 0]\n    FUNCT: [0, 0, 0, 0, 0, 0, 0, 0, 0]",
      "VAL: [0, 0, 0, 0, 0, 1, 0, 0, 0]\n    FUNCT: [0, 0, 0, 0, 0, 1, 0, 0, 0]"),
     r"VAL: rotation components \[5\] with values \[1.0\]: a nonzero rotation"),
    (("MOMIN3: 4.9087385212340526e-06", "MOMIN3: 5.0e-06"), r"ONOFF: .*section is not the same about g2 and g3"),
    # x and z: a real constraint of the bending rotation once the beam bends
    (("ONOFF: [0, 0, 0, 0, 0, 1, 0, 0, 0]", "ONOFF: [0, 0, 0, 1, 0, 1, 0, 0, 0]"),
     r"ONOFF: rotation components \[3, 5\] .*two spin components hold the bending rotation"),
    (("  PENALTY_PARAMETER: 10\n", "  PENALTY_PARAMETER: 10\n  ROTATION_COUPLING: deformation_gradient_3d_general\n"
      "  ROTATION_COUPLING_PENALTY_PARAMETER: 10\n  ROTATION_COUPLING_MORTAR_SHAPE_FUNCTION: line2\n"),
     r"ONOFF: .*with ROTATION_COUPLING the cross-sections are tied to the solid"),
])
def test_4c_single_rotation_components_that_are_not_a_gauge_are_errors(tmp_path, change, message):
    text = (FOLDER / f"{R}mortar_penalty_line2.4C.yaml").read_text()
    assert text.count(change[0]) == 1
    text = text.replace(change[0], change[1], 1)
    path = tmp_path / "changed.4C.yaml"
    path.write_text(text)
    with pytest.raises(FourCError, match=message):
        scene_from_4c(path)


POLAR_2D = f"{R}rotational_coupling_gpts_polar_decomposition_2d.4C.yaml"


@needs_inputs
def test_4c_polar_decomposition_2d_file_passes():
    """Line moments on the BEAM3R beam (about its axis x), the Gauss-point rotational coupling and
    4C's polar_decomposition_2d, which in the file's y-z plane is the polar triad (measured 3.4e-12
    against the tolerance 1e-10)."""
    scene = Scene.from_4c(FOLDER / POLAR_2D)
    assert scene.coupling["rotational"]["triad"] == "polar"
    assert scene.coupling["rotational"]["constraint"] == "gauss_point"
    assert [item["type"] for item in scene.loads] == ["line_moment"]
    report = fourc.check(FOLDER / POLAR_2D)
    assert report.passed, report.table()
    assert report.max_deviation < 1e-11


@needs_inputs
def test_4c_polar_decomposition_2d_needs_rotations_about_x(tmp_path):
    text = (FOLDER / POLAR_2D).read_text()
    triads = "TRIADS 0.523598775598 0 0 0.523598775598 0 0 0.523598775598 0 0"
    assert text.count(triads) == 1
    path = tmp_path / "tilted.4C.yaml"
    path.write_text(text.replace(triads, "TRIADS 0.523598775598 0.1 0 0.523598775598 0.1 0 0.523598775598 0.1 0"))
    with pytest.raises(FourCError, match="ROTATION_COUPLING: 'polar_decomposition_2d' needs reference triads"):
        scene_from_4c(path)


@needs_inputs
def test_4c_point_wise_rotational_coupling_in_3d_is_an_error(tmp_path):
    """The library's variational forces are 4C's point-wise ones only in the plane problem of
    polar_decomposition_2d; a three-dimensional triad there is refused, not approximated."""
    text = (FOLDER / POLAR_2D).read_text()
    assert text.count("ROTATION_COUPLING: polar_decomposition_2d") == 1
    path = tmp_path / "three_d.4C.yaml"
    path.write_text(text.replace("ROTATION_COUPLING: polar_decomposition_2d",
                                 "ROTATION_COUPLING: deformation_gradient_3d_general"))
    with pytest.raises(FourCError, match="ROTATION_COUPLING: 'deformation_gradient_3d_general' with "
                                         "CONTACT_DISCRETIZATION gauss_point_to_segment"):
        scene_from_4c(path)


@needs_inputs
@pytest.mark.parametrize("lm", ["line2_line2", "line4_line3"])
def test_4c_rotational_mortar_files_pass(lm):
    """With 4C's rotational force form (coupling.rotational.forces = "fourc") and BEAM3R's Lagrange
    virtual spins (virtual_spins = "lagrange") both files reproduce 4C to round-off (measured
    1.1e-15 and 5.0e-16 against the tolerance 1e-10; with the exact spin variation 2.2e-6 and
    9.4e-8, with the variational coupling forces 7.7e-4 and 1.1e-4)."""
    name = f"{R}rotational_coupling_mortar_{lm}_deformation_gradient_3d_general.4C.yaml"
    scene = Scene.from_4c(FOLDER / name)
    assert scene.coupling["rotational"]["forces"] == "fourc" and scene.beams[0]["virtual_spins"] == "lagrange"
    report = fourc.check(FOLDER / name)
    assert report.passed, report.table()
    assert report.max_deviation < 1e-13
    assert max(s.iterations for s in report.result.steps) <= 6


@needs_inputs
def test_4c_rotation_coupling_triads(tmp_path):
    """4C's deformation_gradient_3d_general is the symmetric triad, its 3d_base_1 the library's
    deformation_gradient triad (built from the first base vector)."""
    name = f"{R}rotational_coupling_mortar_line4_line3_deformation_gradient_3d_general.4C.yaml"
    assert Scene.from_4c(FOLDER / name).coupling["rotational"]["triad"] == "deformation_gradient_symmetric"
    text = (FOLDER / name).read_text()
    assert text.count("ROTATION_COUPLING: deformation_gradient_3d_general") == 1
    path = tmp_path / "base_1.4C.yaml"
    path.write_text(text.replace("ROTATION_COUPLING: deformation_gradient_3d_general",
                                 "ROTATION_COUPLING: deformation_gradient_3d_base_1"))
    assert Scene.from_4c(path).coupling["rotational"]["triad"] == "deformation_gradient"


@needs_inputs
def test_4c_regularized_lagrange_is_the_penalty_method():
    """4C's regularised Lagrange formulation is the penalty method: its reference values equal the
    penalty file's, and the reader maps it to penalty coupling."""
    scene = Scene.from_4c(FOLDER / f"{EB}mortar_lagrange_regularized_line3.4C.yaml")
    assert scene.coupling["enforcement"] == "penalty" and scene.coupling["penalty"] == 10.0
    a = read_4c(FOLDER / f"{EB}mortar_lagrange_regularized_line3.4C.yaml").results
    b = read_4c(FOLDER / f"{EB}mortar_penalty_line3.4C.yaml").results
    assert [r.value for r in a] == [r.value for r in b]


@needs_inputs
def test_4c_beam3r_files_become_simo_reissner_scenes():
    name = ("beam3r_herm2line3_static_beam_to_solid_volume_meshtying_beam_in_solid_column_gauss_point_projection_"
            "without_boundary_segmentation.4C.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")               # 4C's element formulation: no accuracy warning
        scene, nodes = scene_from_4c(FOLDER / name)
    beam = scene.beams[0]
    assert beam["model"] == "simo_reissner" and beam["mesh"].n_elements == 4
    assert beam["force_rule"] == "lobatto3"         # 4C's rule of the force term of a Hermite BEAM3R
    assert beam["virtual_spins"] == "lagrange"      # and its spin rows (Jelenić & Crisfield's eq. (4.3))
    # the elements' TRIADS (all the same rotation vector) give the reference triads, g1 the tangents
    triads = np.array(beam["triads"])
    np.testing.assert_allclose(triads[:, :, 0], np.tile(beam["mesh"].tangents[0], (len(triads), 1)), atol=1e-12)
    rotation = [d for d in scene.dirichlet if d["rotation"] is not None]
    assert len(rotation) == 1 and rotation[0]["components"] == [0, 1, 2]
    assert scene.coupling["constraint"] == "gauss_point" and scene.coupling["integration"] == "element"


def test_missing_material_parameter_is_an_error_naming_it(tmp_path):
    path = tiny_file(tmp_path)
    path.write_text(path.read_text().replace("      MOMIN: 1.0e-05\n", ""))
    with pytest.raises(FourCError, match=r"MATERIALS\[1\].*MOMIN: missing"):
        scene_from_4c(path)


@needs_inputs
def test_beam3r_shear_modulus_may_be_given_instead_of_poisson_ratio(tmp_path):
    """4C's beam materials take exactly one of SHEARMOD and POISSONRATIO."""
    name = ("beam3r_herm2line3_static_beam_to_solid_volume_meshtying_beam_in_solid_column_gauss_point_projection_"
            "without_boundary_segmentation.4C.yaml")
    text = (FOLDER / name).read_text()
    assert text.count("POISSONRATIO: 0.3") == 1
    path = tmp_path / "shear.4C.yaml"
    path.write_text(text.replace("POISSONRATIO: 0.3", "SHEARMOD: 384615384.6153846"))     # E / (2 (1 + ν))
    by_G = scene_from_4c(path)[0].beams[0]["section"]
    by_nu = scene_from_4c(FOLDER / name)[0].beams[0]["section"]
    assert by_G.keys() == by_nu.keys()
    for key in by_nu:
        assert by_G[key] == pytest.approx(by_nu[key], rel=1e-14), key
    assert by_nu["GA2"] == pytest.approx(384615384.6153846 * 7.853981634e-05, rel=1e-14)
    path.write_text(text.replace("POISSONRATIO: 0.3", "POISSONRATIO: 0.3\n      SHEARMOD: 1.0"))
    with pytest.raises(FourCError, match="exactly one of SHEARMOD and POISSONRATIO"):
        scene_from_4c(path)


def test_input_folder_follows_the_environment_variable(tmp_path, monkeypatch):
    monkeypatch.setenv(fourc.ENV_VAR, str(tmp_path))
    assert fourc.input_folder() == tmp_path
    monkeypatch.setenv(fourc.ENV_VAR, str(tmp_path / "absent"))
    assert fourc.input_folder() is None


# -- NURBS27 (STRUCTURE KNOTVECTORS, CP lines) -------------------------------------------------------
def nurbs_file(tmp_path, solid, elements=None, name="nurbs.4C.yaml"):
    """A self-made 4C input file of a :class:`~mortar1d3d.nurbs.NurbsSolid` (quadratic patches): knot
    vectors, control points as CP lines (4C ids = global ids + 1), NURBS27 elements numbered patch after
    patch with the first direction fastest and their control points listed first direction fastest (4C's
    layout), the patches' z = 0 faces clamped. ``elements`` overrides the element lines."""
    knots, lines = ['  - "NURBS_DIMENSION 3"'], []
    for k, patch in enumerate(solid.patches):
        knots += ['  - "BEGIN NURBSPATCH"', f'  - "ID {k + 1}"']
        for U, p in zip(patch.knots, patch.degrees):
            knots += [f'  - "NUMKNOTS {len(U)}"', f'  - "DEGREE {p}"', '  - "TYPE Interpolated"']
            knots += [f'  - "{float(u)!r}"' for u in U]
        knots.append('  - "END NURBSPATCH"')
        ids = solid.patch_ids[k].reshape(patch.shape) + 1
        n0, n1, n2 = (n - 2 for n in patch.shape)
        for m in range(n2):
            for j in range(n1):
                for i in range(n0):
                    listed = ids[i:i + 3, j:j + 3, m:m + 3].transpose(2, 1, 0).ravel()
                    lines.append(" ".join(map(str, listed)))
    cps = [f'  - "CP {c + 1} COORD {x!r} {y!r} {z!r} {w!r}"' for c, ((x, y, z), w) in
           enumerate(zip(solid.control.tolist(), solid.weights.tolist()))]
    bottom = np.flatnonzero(np.abs(solid.control[:, 2]) < 1e-12) + 1
    elements = elements or [f'  - "{e + 1} SOLID NURBS27 {ids} MAT 1 KINEM nonlinear"' for e, ids in enumerate(lines)]
    text = f"""\
PROBLEM TYPE:
  PROBLEMTYPE: "Structure"
  SHAPEFCT: "Nurbs"
STRUCTURAL DYNAMIC:
  DYNAMICTYPE: "Statics"
  TIMESTEP: 1
  NUMSTEP: 1
  MAXTIME: 1
MATERIALS:
  - MAT: 1
    MAT_Struct_StVenantKirchhoff:
      YOUNG: 100
      NUE: 0.3
      DENS: 0
DESIGN SURF DIRICH CONDITIONS:
  - E: 1
    NUMDOF: 3
    ONOFF: [1, 1, 1]
    VAL: [0, 0, 0]
    FUNCT: [0, 0, 0]
DSURF-NODE TOPOLOGY:
{chr(10).join(f'  - "NODE {c} DSURF 1"' for c in bottom)}
STRUCTURE KNOTVECTORS:
{chr(10).join(knots)}
NODE COORDS:
{chr(10).join(cps)}
STRUCTURE ELEMENTS:
{chr(10).join(elements)}
"""
    path = tmp_path / name
    path.write_text(text)
    return path


def three_patch_pipe():
    """A closed pipe (radii 0.2 / 0.3, height 1) as three 120° patches of one element each: the NURBS
    layout of 4C's NURBS27 file, here generated."""
    from mortar1d3d import nurbs
    parts = [nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=120.0, start=120.0 * k, elements=(1, 1, 1)).patches[0]
             for k in range(3)]
    return nurbs.NurbsSolid(parts)


def test_nurbs27_file_becomes_the_bezier_mesh_of_its_patches(tmp_path):
    from mortar1d3d.nurbs.mesh import element_values
    solid = three_patch_pipe()
    assert solid.n_control == 54                     # 3 × 27, the 3 × 9 seam points shared
    scene, nodes = scene_from_4c(nurbs_file(tmp_path, solid))
    mesh = scene.solid["mesh"]
    assert mesh.blocks[0][0].name == "nurbs27" and mesh.n_elements == 3 and mesh.n_nodes == 54
    rows = np.array([nodes[c + 1][1] for c in range(54)])
    assert np.array_equal(mesh.points[rows], solid.control)          # each CP is the node of its 4C id
    assert np.array_equal(mesh.weights[rows], solid.weights)
    assert len(mesh.point_sets["dsurf1"]) == 18               # 3 × 9 on z = 0, 3 × 3 on the seams shared
    # the exact cylinder: points of every element at the exact radii
    s = np.linspace(-1.0, 1.0, 5)
    xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), axis=-1).reshape(-1, 3)
    x = element_values(mesh, xi, mesh.points).reshape(-1, 3)
    r = np.hypot(x[:, 0], x[:, 1])
    on_surface = (np.abs(r - 0.2) < 1e-9) | (np.abs(r - 0.3) < 1e-9)
    assert on_surface.sum() == 3 * 2 * 25 and (r > 0.2 - 1e-12).all() and (r < 0.3 + 1e-12).all()


def test_nurbs27_elements_that_do_not_match_their_span_are_errors_naming_them(tmp_path):
    from mortar1d3d import nurbs
    from mortar1d3d.io.fourc_nurbs import nurbs_mesh, nurbs_solid
    # one patch of two elements along u: element 2 lists a control point of its span wrongly
    solid = nurbs.brick([0, 0, 0], [2, 1, 1], elements=(2, 1, 1))
    path = nurbs_file(tmp_path, solid)
    text = path.read_text()
    line = next(l for l in text.splitlines() if l.startswith('  - "2 SOLID'))
    ids = line.split()[4:31]
    wrong = line.replace(f" {ids[0]} {ids[1]} ", f" {ids[1]} {ids[0]} ", 1)
    path.write_text(text.replace(line, wrong))
    with pytest.raises(FourCError, match=r"element 2: its control points do not match span \(1, 0, 0\) of patch 1"):
        nurbs_solid(read_4c(path))
    # a smooth two-element patch is read, but scenes would solve on a larger space than 4C's
    with pytest.raises(FourCError, match=r"patch 1, direction 0: interior knots of multiplicity below"):
        nurbs_mesh(read_4c(nurbs_file(tmp_path, solid)))
    # one element listed with u and w swapped: mirrored, so det J < 0, named by the mesh check
    pipe = three_patch_pipe()
    path = nurbs_file(tmp_path, pipe)
    text = path.read_text()
    line = next(l for l in text.splitlines() if l.startswith('  - "3 SOLID'))
    ids = np.array(line.split()[4:31]).reshape(3, 3, 3)
    path.write_text(text.replace(line, line.replace(" ".join(ids.ravel()), " ".join(ids.transpose(2, 1, 0).ravel()))))
    with pytest.raises(FourCError, match=r"STRUCTURE ELEMENTS: inverted nurbs27 elements \(negative Jacobian "
                                         r"determinant at a corner"):
        scene_from_4c(path)
    # an element beyond those the knot vectors give is named, not ignored
    path = nurbs_file(tmp_path, pipe)
    text = path.read_text()
    line = next(l for l in text.splitlines() if l.startswith('  - "3 SOLID'))
    path.write_text(text.replace(line, line + "\n" + line.replace('"3 SOLID', '"99 SOLID', 1)))
    with pytest.raises(FourCError, match=r"STRUCTURE ELEMENTS: NURBS element\(s\) \[99\] lie beyond the"):
        scene_from_4c(path)


def test_nurbs27_knot_section_errors_name_the_key(tmp_path):
    from mortar1d3d.io.fourc_nurbs import parse_knotvectors
    with pytest.raises(FourCError, match=r"STRUCTURE KNOTVECTORS: 'ID x' at entry 2: expected an integer"):
        parse_knotvectors(["NURBS_DIMENSION 3", "BEGIN NURBSPATCH", "ID x"])
    with pytest.raises(FourCError, match="STRUCTURE KNOTVECTORS: expected 'NURBS_DIMENSION 3'"):
        parse_knotvectors(["NURBS_DIMENSION 2"])
    lines = ["NURBS_DIMENSION 3", "BEGIN NURBSPATCH", "ID 1"] + \
            ["NUMKNOTS 6", "DEGREE 2", "TYPE Periodic"] + ["0", "0", "0", "1", "1", "1"]
    with pytest.raises(FourCError, match=r"patch 1, direction 0: TYPE 'Periodic' is not supported"):
        parse_knotvectors(lines)
    path = nurbs_file(tmp_path, three_patch_pipe())
    path.write_text(path.read_text().replace("STRUCTURE KNOTVECTORS:", "STRUCTURE KNOTS:"))
    with pytest.raises(FourCError, match="STRUCTURE KNOTS: section not supported"):
        scene_from_4c(path)


@needs_inputs
def test_4c_nurbs27_file_passes():
    """4C's NURBS27 file (three 120° patches of a hollow cylinder, two Simo–Reissner beams, mortar
    line4 penalty) passes: with the multiplier nodes of negative κ coupled as in 4C (the reader's
    ``negative_kappa = "keep"``; 3.9e-3 with them dropped) and BEAM3R's Lagrange virtual spins
    (``virtual_spins = "lagrange"``; 1.3e-6 with the exact spin variation) it comes to 4.4e-11 of
    4C's values (tolerance 1e-10): see docs/fourc.md, NURBS27."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene, nodes = scene_from_4c(FOLDER / f"{R}nurbs27_mortar_penalty_line4.4C.yaml")
        mesh = scene.solid["mesh"]
        assert mesh.n_elements == 3 and mesh.n_nodes == 54 and sorted(mesh.point_sets) == \
            ["dsurf1", "dsurf2", "dsurf3", "dvol1"]
        report = fourc.check(FOLDER / f"{R}nurbs27_mortar_penalty_line4.4C.yaml")
    assert scene.coupling["negative_kappa"] == "keep"
    assert all(beam["virtual_spins"] == "lagrange" for beam in scene.beams)
    assert report.passed, report.table()
    assert report.max_deviation < 6e-11


def test_negative_kappa_keep_couples_the_multipliers_that_drop_leaves_out():
    """A line4 beam with a short piece in the solid: one multiplier node gets κ < 0. ``drop`` (the
    library's default) leaves it uncoupled; ``keep`` (4C's rule, set by the reader) adds its penalty
    with the negative weight ε / κ_j."""
    from mortar1d3d.generate import box
    from mortar1d3d.physics.coupling import Coupling
    solid = box([0, 0, 0], [1, 1, 1], [1, 1, 1])
    beam = BeamMesh("hermite", [[0.7, 0.5, 0.5], [1.7, 0.5, 0.5]], [[0, 1]], tangents=[[1, 0, 0], [1, 0, 0]])
    ops = m13.assemble_mortar(beam, solid, lm="line4")
    assert np.allclose(ops.kappa, [0.1243875, 0.0136125, 0.2298375, -0.0678375], rtol=0, atol=1e-12)
    n_S = 3 * solid.n_nodes
    args = (ops, beam, solid, n_S, n_S + beam.n_centreline_dofs)
    drop, keep = Coupling(*args, penalty=10.0), Coupling(*args, penalty=10.0, negative_kappa="keep")
    assert drop.coupled.tolist() == [True, True, True, False] and keep.coupled.all()
    B3 = keep.B[9:12]
    assert abs(keep.K - drop.K - 10.0 / ops.kappa[3] * (B3.T @ B3)).max() < 1e-12 * abs(keep.K).max()
    with pytest.raises(SceneError, match="coupling.negative_kappa"):
        Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 1]},
                     "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
              beams=[{"mesh": beam, "section": {"E": 1.0, "radius": 0.01}}],
              coupling={"enforcement": "lagrange", "negative_kappa": "keep"})


@pytest.mark.parametrize("old, new, key, message", [
    ('BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE:\n  - E: 1\n',
     'BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE:\n  - E: 2\n', "MESHTYING LINE.E",
     "design line 2 leaves out 1 beam nodes"),
    ('  - "NODE 12 DVOL 1"\n', "", "MESHTYING VOLUME.E", "design vol 1 leaves out 1 solid nodes")])
def test_coupling_sets_must_hold_every_beam_and_solid_node(tmp_path, old, new, key, message):
    """The library ties every beam to the whole solid, so a coupling condition on part of the beams
    (design line 2: nodes 13 and 14 of the beam 13-14-15) or of the solid is an error naming the
    condition (it would be coupled wholly otherwise)."""
    path = tiny_file(tmp_path)
    text = path.read_text(encoding="utf-8").replace('  - "NODE 15 DLINE 1"\n',
                                                    '  - "NODE 15 DLINE 1"\n  - "NODE 13 DLINE 2"\n'
                                                    '  - "NODE 14 DLINE 2"\n')
    assert old in text
    path.write_text(text.replace(old, new), encoding="utf-8")
    with pytest.raises(FourCError, match=f"{key}: {message}"):
        fourc.scene_from_4c(path)
