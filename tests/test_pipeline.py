"""The one-way pipeline (scene → build → Model → solvers.newton → Result) and the beam-type
registry: DOF map blocks, mesh readers, beam types as descriptors, the vectorised beam functions
and the linear step of the Newton module."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.elements.beam import BEAM_ELEMENTS, MAX_FUNCTIONS, deriv, evaluate, shape
from mortar1d3d.mesh import BeamMesh
from mortar1d3d.model import READERS, Block, BuiltScene, DofMap, Model, build
from mortar1d3d.physics.beam import BeamModel
from mortar1d3d.physics.beam_types import BEAM_TYPES, PLANNED_BEAM_TYPES, beam_type
from mortar1d3d.scene import BEAM_MODELS, IMPLEMENTED_BEAM_MODELS, Scene, SceneError
from mortar1d3d.solvers.newton import solve_linear_step


def coupled_scene(**analysis):
    """Two beam types in one solid: a torsion-free beam and two trusses (two groups)."""
    return Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 0.4, 0.4]], "cells": [3, 1, 1]},
                        "material": {"model": "linear_elastic", "E": 100.0, "nu": 0.3}},
                 beams=[{"curve": {"line": [[0.1, 0.2, 0.2], [0.9, 0.2, 0.2]]}, "elements": 3,
                         "section": {"EA": 5.0, "EI": 0.1}},
                        {"curve": {"line": [[0.1, 0.1, 0.1], [0.9, 0.3, 0.3]]}, "elements": 2, "model": "truss",
                         "section": {"EA": 2.0}},
                        {"curve": {"line": [[0.1, 0.3, 0.1], [0.9, 0.1, 0.3]]}, "elements": 4, "model": "truss",
                         "section": {"EA": 3.0}}],
                 dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -0.1]}],
                 analysis={"kinematics": "linear", **analysis})


# --------------------------------------------------------------------------------------------
# DOF map
# --------------------------------------------------------------------------------------------
def test_dof_map_blocks_are_contiguous_and_in_order():
    built = build(coupled_scene())
    dm = built.dofmap
    assert [b.kind for b in dm.blocks] == ["solid", "centreline", "centreline", "rotations", "rotations",
                                           "multipliers"]
    n_solid = built.solid_mesh.n_nodes
    assert (dm.solid.start, dm.solid.stop, dm.solid.dofs_per_node) == (0, 3 * n_solid, 3)
    hermite, truss = dm.centreline
    assert (hermite.start, hermite.size, hermite.dofs_per_node) == (3 * n_solid, 6 * 4, 6)
    assert (truss.start, truss.size, truss.dofs_per_node) == (hermite.stop, 3 * (3 + 5), 3)
    assert [b.size for b in dm.rotations] == [0, 0] and dm.multipliers.size == 0
    assert dm.n_displacement == dm.n_unknowns == truss.stop
    # the groups hold their blocks; DOFs per node come from the centreline element type
    for g, block, rotations in zip(built.groups, dm.centreline, dm.rotations):
        assert g.dofs is block and g.dof_offset == block.start and g.rotations is rotations
        assert block.dofs_per_node == g.type.dofs_per_node == g.mesh.element_type.dofs_per_node
        assert block.size == g.mesh.n_centreline_dofs
    # a node range of a block is a contiguous range of unknowns (what a distributed run would own)
    assert truss.node_range(2, 5) == (truss.start + 6, truss.start + 15)
    np.testing.assert_array_equal(truss.dofs([2, 4], [0, 2]), truss.start + np.array([6, 8, 12, 14]))
    # multipliers are appended once their number is known
    grown = dm.with_multipliers(7)
    assert grown.multipliers.start == dm.n_displacement and grown.n_unknowns == dm.n_displacement + 7
    assert grown.blocks[:-1] == dm.blocks[:-1]


def test_dof_map_refuses_gaps_and_wrong_order():
    solid, _, rotations, multipliers = DofMap.layout(2, [(6, 0, 3)]).blocks
    with pytest.raises(ValueError, match="contiguous"):
        DofMap((solid, rotations, multipliers))                     # a gap where the beams were
    with pytest.raises(ValueError, match="one per beam group"):
        DofMap((solid, Block("centreline", 6, 24, 6), Block("multipliers", 24, 24, 1)))
    with pytest.raises(ValueError, match="in this order"):
        DofMap((Block("rotations", 0, 0, 3), Block("solid", 0, 6, 3), Block("multipliers", 6, 6, 1)))


def test_model_numbering_follows_the_dof_map():
    model = Model(coupled_scene()).prepare()
    assert model.n_displacement_dofs == model.dofmap.n_displacement
    assert model.n_unknowns == model.dofmap.n_displacement + model.n_multipliers
    lagrange = coupled_scene()
    lagrange.coupling["enforcement"] = "lagrange"
    model = Model(lagrange).prepare()
    assert model.n_multipliers > 0
    assert model.n_unknowns == model.dofmap.n_displacement + model.n_multipliers


# --------------------------------------------------------------------------------------------
# build → Model
# --------------------------------------------------------------------------------------------
def test_model_of_a_built_scene_equals_model_of_the_scene():
    scene = coupled_scene()
    built = build(scene)
    assert isinstance(built, BuiltScene) and built.scene is scene
    a, b = Model(built).prepare(), Model(scene).prepare()
    z = np.linspace(-1e-3, 1e-3, a.n_unknowns)
    ra, Ka = a.residual(z, 1.0)
    rb, Kb = b.residual(z, 1.0)
    assert ra.tobytes() == rb.tobytes()
    assert (Ka != Kb).nnz == 0
    np.testing.assert_array_equal(a.fixed, b.fixed)
    with pytest.raises(TypeError, match="expected a Scene"):
        Model({"solid": None})
    with pytest.raises(TypeError, match="expected a Scene"):
        build(42)


def test_beams_are_grouped_by_type_in_order_of_first_appearance():
    built = build(coupled_scene())
    assert [g.model for g in built.groups] == ["torsion_free", "truss"]
    assert [g.entries for g in built.groups] == [[0], [1, 2]]
    assert [g.type for g in built.entry_group] == [BEAM_TYPES["torsion_free"], BEAM_TYPES["truss"],
                                                   BEAM_TYPES["truss"]]
    assert built.groups[1].entry_elements == [(0, 2), (2, 6)]


def test_linear_step_of_the_newton_module_solves_the_linear_system():
    model = Model(coupled_scene()).prepare()
    z0 = np.zeros(model.n_unknowns)
    z, record, r = solve_linear_step(model, z0)
    r0, K0 = model.residual(z0, 1.0)            # the system linearised at z0
    free = model.free
    assert r.tobytes() == (r0 + K0 @ z).tobytes()      # z0 = 0
    assert np.linalg.norm(r[free]) <= 1e-9 * record.residuals[0]
    np.testing.assert_array_equal(z[model.fixed], model.prescribed(1.0))
    assert record.iterations == 1 and record.load_factor == 1.0
    # solve() takes the same step: bit for bit
    result = m13.solve(coupled_scene())
    assert result.z.tobytes() == model.basis.to_physical(z).tobytes()
    assert result.steps[0].residuals == record.residuals


# --------------------------------------------------------------------------------------------
# mesh readers
# --------------------------------------------------------------------------------------------
def test_every_mesh_file_goes_through_a_registered_reader(tmp_path, monkeypatch):
    import meshio
    solid = m13.generate.box((0, 0, 0), (1, 1, 1), (2, 1, 1))
    path = tmp_path / "block.vtu"
    meshio.write(path, meshio.Mesh(solid.points, [(d.name, c) for d, c in solid.blocks]))
    calls = []

    class Recording(type(READERS[0])):
        def accepts(self, p):
            calls.append(p)
            return True

    monkeypatch.setattr("mortar1d3d.model.readers.READERS", (Recording(),))
    scene = Scene(solid={"mesh": str(path), "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                  dirichlet=[{"on": "solid:x_min"}])
    built = build(scene)
    assert calls == [path]
    np.testing.assert_array_equal(built.solid_mesh.points, solid.points)


# --------------------------------------------------------------------------------------------
# beam types
# --------------------------------------------------------------------------------------------
def test_beam_types_take_their_dofs_from_the_element_type():
    from mortar1d3d.physics.beam3eb import Beam3ebModel
    from mortar1d3d.physics.simo_reissner import SimoReissnerBeam
    for t in BEAM_TYPES.values():
        assert t.dofs_per_node == t.element.dofs_per_node
        assert t.element is BEAM_ELEMENTS[t.element.name]
        assert t.physics_class() is (SimoReissnerBeam if t.triads else Beam3ebModel if t.name == "beam3eb"
                                     else BeamModel)
    assert BEAM_TYPES["torsion_free"].element.has_tangents and not BEAM_TYPES["truss"].element.has_tangents
    # rotation nodes: none without triads; line3 triads: the mesh's nodes, then one middle node per element
    beams = BeamMesh.hermite([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[1, 0, 0]] * 3, [[0, 1], [1, 2]])
    assert BEAM_TYPES["torsion_free"].rotation_nodes(beams).shape == (2, 0)
    assert BEAM_TYPES["torsion_free"].n_rotation_nodes(beams) == 0
    assert BEAM_TYPES["simo_reissner"].rotation_nodes(beams).tolist() == [[0, 1, 3], [1, 2, 4]]
    assert BEAM_TYPES["simo_reissner"].n_rotation_nodes(beams) == 5
    # the scene validates against the registry (planned types are named, not run)
    assert IMPLEMENTED_BEAM_MODELS == tuple(BEAM_TYPES)
    assert BEAM_MODELS == tuple(BEAM_TYPES) + PLANNED_BEAM_TYPES
    with pytest.raises(ValueError, match="unknown beam model 'cable'; known models: torsion_free, truss, simo_reissner"):
        beam_type("cable")


def test_a_clamp_needs_an_element_with_tangents():
    scene = Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "model": "truss",
                          "section": {"EA": 1.0}}],
                  dirichlet=[{"on": "beam:0:start", "clamp": True}])
    with pytest.raises(SceneError, match=r"dirichlet\[0\].clamp: beam 'beam:0:start' has no tangent DOFs \(truss\)"):
        Model(scene)


# --------------------------------------------------------------------------------------------
# vectorised beam functions (VTU output, arc lengths)
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(BEAM_ELEMENTS))
def test_vectorised_beam_functions_have_the_kernels_bits(name):
    element = BEAM_ELEMENTS[name]
    eta = np.array([[-1.0, -0.7310, -0.2], [0.0, 0.3331, 1.0]])
    length = 0.8173
    for derivative, kernel in ((False, shape), (True, deriv)):
        values = evaluate(element, eta, length, derivative=derivative)
        assert values.shape == eta.shape + (MAX_FUNCTIONS,) and values.flags.c_contiguous
        for index in np.ndindex(eta.shape):
            H = np.zeros(MAX_FUNCTIONS)
            kernel(element.code, eta[index], length, H)
            assert values[index].tobytes() == H.tobytes()


# --------------------------------------------------------------------------------------------
# one way
# --------------------------------------------------------------------------------------------
def test_the_pipeline_modules_import_only_earlier_stages():
    """scene → build → Model → solve: each module of ``mortar1d3d.model`` imports (at module level
    or inside a function) only the stages before it, so walking ``solve`` never climbs back."""
    import ast
    from pathlib import Path

    import mortar1d3d.model as package
    stages = [{"curves", "dofmap", "sets", "tangent"}, {"readers"}, {"build"}, {"checks"}, {"model"}, {"effects", "solve"}]
    rank = {name: k for k, names in enumerate(stages) for name in names}
    for path in Path(package.__file__).parent.glob("*.py"):
        if path.stem == "__init__":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                names = [node.module] if node.module else [a.name for a in node.names]
                for name in names:
                    assert rank[name] < rank[path.stem], f"{path.stem} imports {name}"


# --------------------------------------------------------------------------------------------
# one place for every exception and warning
# --------------------------------------------------------------------------------------------
def test_every_public_exception_and_warning_is_defined_in_errors_py():
    import ast
    from pathlib import Path

    from mortar1d3d import errors
    package = Path(m13.__file__).parent
    elsewhere = []
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.ClassDef) and not node.name.startswith("_")
                    and any(getattr(b, "id", getattr(b, "attr", "")).endswith(("Error", "Warning", "Exception"))
                            for b in node.bases)):
                if path.name != "errors.py":
                    elsewhere.append(f"{path.relative_to(package)}:{node.name}")
    assert elsewhere == []
    # the modules that raise them still export them under the names users import
    from mortar1d3d.physics.solid import InvertedElementsError
    from mortar1d3d.solvers.linear import LinearSolverError
    from mortar1d3d.solvers.newton import ConvergenceError
    assert (SceneError, LinearSolverError, ConvergenceError, InvertedElementsError) == (
        errors.SceneError, errors.LinearSolverError, errors.ConvergenceError, errors.InvertedElementsError)
    assert set(errors.__all__) >= {"MeshError", "AccuracyWarning", "CouplingWarning", "LargeDeformationWarning"}
