"""Supports (issue 16, part 5): clamps fix the tangent's direction in a rotated basis, rigidly moved
scenes give rotated results, free rigid-body motions are counted and named from the null space of
the supports, and a linear solve warns when its displacements are large against the body."""
import math
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mortar1d3d as m13
from mortar1d3d.errors import LargeDeformationWarning
from mortar1d3d.model import LINEAR_DISPLACEMENT_LIMIT, Model
from mortar1d3d.scene import Scene, SceneError

from clamped_scenes import clamped_scene, rotation_error

Q = Rotation.from_rotvec([0.4, -0.7, 0.5]).as_matrix()      # a general rotation (no axis is kept)
SHIFT = np.array([3.0, -5.0, 7.0])


# --------------------------------------------------------------------------------------------
# clamps
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kinematics", ["linear", "nonlinear"])
@pytest.mark.parametrize("direction", [[1.0, 0.0, 0.0], [1.0, -2.0, 0.5]], ids=["along_x", "oblique"])
def test_a_clamp_fixes_the_tangent_direction_not_the_stretch(direction, kinematics):
    """Clamped bar pulled along its axis: uniform strain P/EA, so every nodal tangent, the clamped
    one included, stretches to (1 + P/EA) d and the tip moves by P L / EA along d.

    Before: the clamp fixed two tangent components of a bar along x but all three of an oblique
    bar, which pinned its stretch at the clamp (Δt = 0 there, the tip 3 % short here)."""
    d = np.asarray(direction) / np.linalg.norm(direction)
    L, EA, P = 1.5, 40.0, 2.0
    scene = Scene(beams=[{"curve": {"line": [[0.3, 0.2, 0.1], (np.array([0.3, 0.2, 0.1]) + L * d).tolist()]},
                          "elements": 4, "section": {"EA": EA, "EI": 0.5}}],
                  dirichlet=[{"on": "beam:0:start", "clamp": True}],
                  load=[{"type": "point", "on": "beam:0:end", "value": (P * d).tolist()}],
                  analysis={"kinematics": kinematics, "rtol": 1e-12})
    result = m13.solve(scene)
    strain = P / EA
    assert np.abs(result.beam_tangent_displacement - strain * d).max() <= 1e-12 * strain
    assert np.abs(result.beam_displacement[-1] - strain * L * d).max() <= 1e-12 * strain * L
    assert np.abs(result.beam_displacement[0]).max() == 0.0


@pytest.mark.parametrize("kinematics, enforcement, solver", [
    ("linear", "penalty", "direct"), ("nonlinear", "penalty", "direct"), ("linear", "lagrange", "direct"),
    ("linear", "penalty", "amg")])
def test_a_rigidly_moved_clamped_scene_gives_rotated_results(kinematics, enforcement, solver):
    """The same clamped scene along x and rotated by a general rotation (plus a translation):
    displacements, tangent changes, line load and reactions rotate with it to round-off
    (measured at most 5e-10, on λ of the saddle-point solve; the rest 1e-11).

    Before: displacements 1e-2 apart, tangent changes 3e-2 and λ by 5 times its largest value (the
    rotated clamp also fixed the stretch)."""
    reference = m13.solve(clamped_scene(kinematics=kinematics, enforcement=enforcement, solver=solver))
    moved = m13.solve(clamped_scene(Q, SHIFT, kinematics=kinematics, enforcement=enforcement, solver=solver))
    errors = rotation_error(reference, moved, Q)
    assert max(errors.values()) <= 1e-8, errors
    # the clamped tangent stretched (the axial traction pulls the bar), in both orientations
    t0 = reference.beam_tangent_displacement[0]
    assert abs(t0[0]) > 1e-3 * np.abs(reference.beam_tangent_displacement).max()
    assert np.allclose(moved.beam_tangent_displacement[0], Q @ t0, rtol=0, atol=1e-8 * abs(t0[0]))


def test_clamped_tangents_live_in_rotated_frames_for_every_solver_input():
    """Residual, tangent, rigid-body modes and the auxiliary-space prolongation all use the
    basis in which the clamp is two fixed DOFs: the two fixed components of a clamped triplet are
    e1·Δt and e2·Δt, the tangent maps the rigid-body modes to zero, a rotation mode turns the
    clamped tangent within the frame, and the prolongation's row of the clamped tangent is its
    free component t0·Δt."""
    model = Model(clamped_scene(Q, SHIFT)).prepare()
    g = model.groups[0]
    start = g.dof_offset + 3                              # the clamped node's tangent triplet
    frame = model.basis.frames[list(model.basis.starts).index(start)]
    t0 = Q @ np.array([1.0, 0.0, 0.0])
    assert np.allclose(frame[2], t0, atol=1e-15) and np.allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    assert {start, start + 1} <= set(model.fixed.tolist()) and start + 2 in model.free

    R = model.rigid_body_modes()
    _, K = model.residual(np.zeros(model.n_unknowns), 0.0)
    assert np.abs(K @ R).max() <= 1e-12 * abs(K).max() * np.abs(R).max()
    # the rotated triplet of a rotation mode: ω × t0 in the frame, no component along t0
    omega = np.array([0.3, -0.2, 0.9])
    size = float(np.ptp(model.reference().reshape(-1, 3)[: model.n_solid_nodes], axis=0).max())
    rotation = R[:, 3:] @ omega * size
    assert np.allclose(rotation[start: start + 3], frame @ np.cross(omega, t0), atol=1e-14)

    # the prolongation (beam DOFs following the solid) gives the clamped tangent's free DOF as
    # the t0 component of the tangent that the physical follow operator gives
    from mortar1d3d.physics.coupling import follow_operator
    split, free = model._follow_split(), model.free
    nS = 3 * model.n_solid_nodes
    u = np.zeros(nS)
    u[free[split["solid"]]] = np.random.default_rng(5).standard_normal(len(split["solid"]))
    physical = follow_operator(g.operators, g.mesh) @ u
    clamped = int(np.flatnonzero(free[split["beam"]] == start + 2)[0])
    expected = t0 @ physical[start - nS: start - nS + 3]
    assert abs(expected) > 0.1 * np.abs(physical).max()
    assert abs((split["prolongation"] @ u[free[split["solid"]]])[clamped] - expected) <= 1e-14 * np.abs(physical).max()


def test_a_clamp_on_a_truss_is_an_error_naming_the_entry():
    scene = Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "model": "truss",
                          "section": {"EA": 1.0}}],
                  dirichlet=[{"on": "beam:0:start", "clamp": True}, {"on": "beam:0:end"}])
    with pytest.raises(SceneError, match=r"^dirichlet\[0\]\.clamp: beam 'beam:0:start' has no tangent DOFs"):
        m13.plan(scene)


# --------------------------------------------------------------------------------------------
# free rigid-body motions
# --------------------------------------------------------------------------------------------
def _free_motions(scene):
    with pytest.raises(SceneError) as info:
        Model(scene).prepare()
    return str(info.value)


def test_free_motions_are_counted_and_named_from_the_null_space_of_the_supports():
    """Before: an unsupported oblique beam was reported as '5 rigid-body mode(s) not fixed' followed
    by all six names (the turn about its own axis moves nothing, but no single-axis rotation is
    that turn); a block pinned at one corner gave '3 combination(s) of rigid-body motions'."""
    oblique = Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 1, 0]]}, "elements": 2, "section": {"EA": 1, "EI": 1}}])
    assert ("beam 0 can move freely (5 rigid-body mode(s) not fixed: translation in x, translation in y, "
            "translation in z, rotation about (0.707, -0.707, 0), rotation about z)") in _free_motions(oblique)

    block = {"mesh": {"box": [[0, 0, 0], [2, 1, 1]], "cells": [2, 1, 1]},
             "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}}
    corner = Scene(solid=block, dirichlet=[{"on": {"inside": [[0, 0, 0], [0, 0, 0]]}}])
    # each axis through the pinned corner, named by its point nearest to the centroid (1, 0.5, 0.5)
    assert ("the solid can move freely (3 rigid-body mode(s) not fixed: rotation about x through (1, 0, 0), "
            "rotation about y through (0, 0.5, 0), rotation about z through (0, 0, 0.5))") in _free_motions(corner)

    # an edge held in y and z: the turn about that edge (a line through no centroid) and the slide along it
    edge = Scene(solid=block, dirichlet=[{"on": {"inside": [[0, 1, 1], [2, 1, 1]]}, "components": ["y", "z"]}])
    assert ("(2 rigid-body mode(s) not fixed: translation in x, rotation about x through (1, 1, 1))"
            in _free_motions(edge))


# --------------------------------------------------------------------------------------------
# large displacements in a linear analysis
# --------------------------------------------------------------------------------------------
def _concrete_cantilever(E, kinematics="linear"):
    """A 2 m concrete cantilever in SI units under a 20 kN tip load."""
    return Scene(solid={"mesh": {"box": [[0, 0, 0], [2, 0.2, 0.2]], "cells": [8, 1, 1]},
                        "material": {"model": "linear_elastic", "E": E, "nu": 0.2}},
                 dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -5e5]}],
                 analysis={"kinematics": kinematics})


def test_a_linear_solve_warns_when_the_body_moves_by_a_tenth_of_its_size():
    """E of concrete given in MPa in an SI scene: the tip moves by tens of metres on a 2 m beam.
    Before: no warning."""
    with pytest.warns(LargeDeformationWarning) as record:
        result = m13.solve(_concrete_cantilever(30e3))
    umax = np.linalg.norm(result.solid_displacement, axis=1).max()
    size = math.sqrt(2.0 ** 2 + 0.2 ** 2 + 0.2 ** 2)
    assert umax > 10 * size
    message = str(record[0].message)
    assert message.startswith(f"analysis.kinematics: the solid moves by up to {umax:.3g}, {umax / size:.3g} "
                              f"times its size {size:.3g}")
    assert "E in Pa, not MPa" in message and 'kinematics = "nonlinear"' in message
    # the same beam with E in Pa moves by 4e-3 of its size: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", LargeDeformationWarning)
        small = m13.solve(_concrete_cantilever(30e9))
    assert np.linalg.norm(small.solid_displacement, axis=1).max() < LINEAR_DISPLACEMENT_LIMIT * size
