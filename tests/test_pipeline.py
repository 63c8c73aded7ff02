"""The one-way pipeline (scene → build → Model → solvers.newton → Result) and the beam-type
registry: DOF map blocks, mesh readers, beam types as descriptors, the vectorised beam functions
and the linear step of the Newton module."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.elements.beam import BEAM_ELEMENTS, MAX_FUNCTIONS, deriv, evaluate, shape
from mortar1d3d.model import Model
from mortar1d3d.physics.beam import BeamModel
from mortar1d3d.physics.beam_types import BEAM_TYPES, PLANNED_BEAM_TYPES, beam_type
from mortar1d3d.scene import BEAM_MODELS, IMPLEMENTED_BEAM_MODELS, Scene
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
# beam types
# --------------------------------------------------------------------------------------------
def test_beam_types_take_their_dofs_from_the_element_type():
    for t in BEAM_TYPES.values():
        assert t.dofs_per_node == t.element.dofs_per_node
        assert t.element is BEAM_ELEMENTS[t.element.name]
        assert t.physics_class() is BeamModel
    assert BEAM_TYPES["torsion_free"].element.has_tangents and not BEAM_TYPES["truss"].element.has_tangents
    # the scene validates against the registry (planned types are named, not run)
    assert IMPLEMENTED_BEAM_MODELS == tuple(BEAM_TYPES)
    assert BEAM_MODELS == tuple(BEAM_TYPES) + PLANNED_BEAM_TYPES
    with pytest.raises(NotImplementedError, match=r"'simo_reissner' is not implemented yet; use 'torsion_free' "
                                                  r"\(Hermite centreline\) or 'truss' \(line\)"):
        beam_type("simo_reissner")
    with pytest.raises(ValueError, match="unknown beam model 'cable'; known models: torsion_free, truss"):
        beam_type("cable")


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
