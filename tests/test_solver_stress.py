"""Solver stress (issue 6 part 4): penalty sweep 1e0..1e12 E against the Lagrange solution with a
conditioning estimate, nearly incompressible Neo-Hooke, a soft solid with very stiff fibres, a
90° rigid rotation of an embedded fibre bundle, load-step cutting, and the failure message.

Small meshes only: every scene here solves in well under a second once compiled.
"""
import math
import warnings

import numpy as np
import pytest
import scipy.optimize
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from mortar1d3d.errors import AccuracyWarning
from mortar1d3d.mesh import SolidMesh
from mortar1d3d.model import PENALTY_ROUNDOFF_LIMIT
from mortar1d3d.physics.materials import material
from mortar1d3d.physics.solid import SolidModel
from mortar1d3d.scene import Scene
from mortar1d3d.solvers.newton import ConvergenceError

# --------------------------------------------------------------------------------------------
# penalty sweep
# --------------------------------------------------------------------------------------------
E_SOFT = 1e3


def rebar_scene(enforcement, penalty=None, load=1.0, steps=1, E_beam=100 * E_SOFT, **analysis):
    """Cantilever 1 × 0.2 × 0.2 (4 hex8) with an eccentric embedded rebar, clamped at x = 0
    (solid face and bar start), bent by a dead traction on x = 1 (tip deflection ~5 % of L)."""
    data = {"solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1], "element": "hexahedron"},
                      "material": {"model": "saint_venant_kirchhoff", "E": E_SOFT, "nu": 0.3}},
            "beams": [{"curve": {"line": [[0, 0.1, 0.06], [1, 0.1, 0.06]]}, "elements": 6,
                       "section": {"E": E_beam, "radius": 0.02}}],
            "coupling": {"enforcement": enforcement},
            "dirichlet": [{"on": "solid:x_min"}, {"on": "beam:0:start"}],
            "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -load]}],
            "analysis": {"steps": steps, **analysis}}
    if penalty is not None:
        data["coupling"]["penalty"] = penalty
    return Scene.from_dict(data)


def condition_estimate(result):
    """1-norm condition number estimate of the reduced tangent at the solution (Hager/Higham
    estimator on A and on A⁻¹ applied through one sparse LU factorisation)."""
    model = result.model
    _, K = model.residual(result.z, 1.0)
    A = K[model.free][:, model.free].tocsc()
    lu = spla.splu(A)
    inverse = spla.LinearOperator(A.shape, matvec=lu.solve, rmatvec=lambda x: lu.solve(x, trans="T"))
    return spla.onenormest(A) * spla.onenormest(inverse)


def test_penalty_sweep_converges_to_lagrange_until_the_round_off_floor():
    """ε = 1e0 … 1e12 × E_solid. Measured (max |u − u_Lagrange|, tip deflection 0.046):
    1.1e-3, 3.4e-4, 6.2e-5, 6.9e-6, 7.0e-7, 7.0e-8 (ε = 1e5 E), 6.4e-9 (1e6 E, best), then
    round-off: 2.1e-8, 1.7e-7, 1.9e-6, 5.0e-6, 8.0e-5, 1.1e-3 (1e12 E). cond₁(K) ≈ 1.48 ε/E × 1e4
    for ε >= 1e2 E (1.5e6 … 1.4e16). Newton: 5-6 iterations at every ε, no cut (at ε >= 1e7 E
    it stops at the round-off floor of the penalty forces)."""
    exact = m13.solve(rebar_scene("lagrange"))
    scale = np.abs(exact.solid_displacement).max()
    assert 0.03 < scale < 0.06
    errors, conditions = [], []
    for k in range(13):
        eps = 10.0 ** k * E_SOFT
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = m13.solve(rebar_scene("penalty", penalty=eps))
        accuracy = [w for w in caught if issubclass(w.category, AccuracyWarning)]
        assert bool(accuracy) == (eps > PENALTY_ROUNDOFF_LIMIT * E_SOFT), (k, [str(w.message) for w in caught])
        if accuracy:
            assert "coupling.penalty" in str(accuracy[0].message) and "lagrange" in str(accuracy[0].message)
        step = result.steps[-1]
        assert len(result.steps) == 1 and step.cuts == 0 and step.iterations <= 8, (k, step)
        errors.append(np.abs(result.solid_displacement - exact.solid_displacement).max() / scale)
        conditions.append(condition_estimate(result))
    errors, conditions = np.array(errors), np.array(conditions)
    # the penalty error falls like 1/ε in the asymptotic range (1e2 .. 1e5 E)
    ratios = errors[2:5] / errors[3:6]
    assert ((ratios > 8.0) & (ratios < 12.0)).all(), (errors, ratios)
    # the floor: best accuracy around 1e6 E, about 1e-7 relative
    best = int(np.argmin(errors))
    assert 5 <= best <= 8 and errors[best] < 1e-6, errors
    # past the floor round-off grows again: 1e12 E is much worse than the best, yet not garbage
    assert errors[12] > 100.0 * errors[best] and errors[12] < 0.1, errors
    # conditioning grows linearly with ε once the penalty dominates the stiffness
    growth = conditions[3:] / conditions[2:-1]
    assert ((growth > 7.0) & (growth < 13.0)).all(), conditions
    assert conditions[0] < 1e7 and conditions[-1] > 1e15, conditions


# --------------------------------------------------------------------------------------------
# nearly incompressible Neo-Hooke
# --------------------------------------------------------------------------------------------
def uniaxial_neo_hooke(P, E, nu):
    """Stretches (a, b) of F = diag(a, b, b) under a dead uniaxial first Piola–Kirchhoff stress P
    for W = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)² (lateral stress zero)."""
    mat = material("neo_hooke", E, nu)
    lam, mu = mat.lam, mat.mu

    def equations(x):
        a, b = x
        log_j = math.log(a * b * b)
        return [mu * (a - 1.0 / a) + lam * log_j / a - P,          # P_11
                mu * (b * b - 1.0) + lam * log_j]                    # b² S_22 = 0

    a, b = scipy.optimize.fsolve(equations, [1.0 + P / E, 1.0 - nu * P / E], xtol=1e-14)
    assert np.abs(equations([a, b])).max() < 1e-12 * E
    return a, b


def test_nearly_incompressible_neo_hooke_matches_the_homogeneous_solution():
    """ν = 0.49, 20 % stretch under a dead traction; rollers make the exact solution homogeneous,
    so every node must sit at diag(a, b, b) X with (a, b) from the two scalar equations; an
    embedded oblique fibre whose ends follow the same field carries no coupling load.
    Measured: a = 1.2444, b = 0.8982, volume ratio J = a b² = 1.0040 (small-strain estimate
    (1 − 2ν) ε = 0.5 %)."""
    E, nu, P = 1.0, 0.49, 0.2
    a, b = uniaxial_neo_hooke(P, E, nu)
    F = np.diag([a, b, b])
    start, end = np.array([0.1, 0.2, 0.15]), np.array([0.9, 0.75, 0.85])
    scene = Scene(
        solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [2, 2, 2]},
               "material": {"model": "neo_hooke", "E": E, "nu": nu}},
        beams=[{"curve": {"line": [start.tolist(), end.tolist()]}, "elements": 3,
                "section": {"EA": 0.05, "EI": 1e-4}}],
        dirichlet=[{"on": "solid:x_min", "components": ["x"]}, {"on": "solid:y_min", "components": ["y"]},
                   {"on": "solid:z_min", "components": ["z"]},
                   {"on": "beam:0:start", "value": ((F - np.eye(3)) @ start).tolist()},
                   {"on": "beam:0:end", "value": ((F - np.eye(3)) @ end).tolist()}],
        load=[{"type": "traction", "on": "solid:x_max", "value": [P, 0, 0]}],
        analysis={"steps": 2})
    result = m13.solve(scene)
    assert all(s.cuts == 0 and s.iterations <= 8 for s in result.steps)
    model = result.model
    X = model.solid_mesh.points
    assert np.abs(result.solid_displacement - X @ (F - np.eye(3)).T).max() < 1e-9
    X_B = model.groups[0].mesh.positions
    assert np.abs(result.beam_displacement - X_B @ (F - np.eye(3)).T).max() < 1e-9
    assert np.abs(result.line_load).max() < 1e-7 * 0.05 * (a - 1.0)
    # volume: the deformed hex8 mesh's volume against J = a b²
    deformed = SolidMesh(X + result.solid_displacement, model.solid_mesh.cells)
    volume = SolidModel(deformed, material("neo_hooke", E, nu)).volume()
    assert volume == pytest.approx(a * b * b, rel=1e-9)
    assert 1.0 < volume < 1.006 and a > 1.2


# --------------------------------------------------------------------------------------------
# soft solid, very stiff fibres
# --------------------------------------------------------------------------------------------
def test_soft_solid_with_very_stiff_fibre_keeps_the_fibre_nearly_inextensible():
    """E_beam / E_solid = 1e6, pulled along the bar (bar clamped at x = 0). Measured: the plain
    block's end moves by 0.295 (30 % strain); with the bar its strain is 1.272e-6 = F/EA_bar
    (1.273e-6) to 0.1 %: the bar takes the whole load, and the solid moves at most 2.7e-4 (local
    deformation at the loaded face)."""
    force = 0.01     # traction × area on x_max
    pulled = {"load": [{"type": "traction", "on": "solid:x_max", "value": [force / 0.04, 0, 0]}]}

    def scene(with_bar):
        data = {"solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1]},
                          "material": {"model": "neo_hooke", "E": 1.0, "nu": 0.3}},
                "dirichlet": [{"on": "solid:x_min"}], "analysis": {"steps": 2}, **pulled}
        if with_bar:
            data["beams"] = [{"curve": {"line": [[0, 0.1, 0.1], [1, 0.1, 0.1]]}, "elements": 4,
                              "section": {"E": 1e6, "radius": 0.05}}]
            data["dirichlet"].append({"on": "beam:0:start"})
        return Scene.from_dict(data)

    plain = m13.solve(scene(False))
    plain_strain = plain.solid_displacement[:, 0].max()    # L = 1
    assert 0.2 < plain_strain < 0.4
    reinforced = m13.solve(scene(True))
    assert all(s.cuts == 0 for s in reinforced.steps)
    bar_strain = reinforced.beam_displacement[-1, 0] - reinforced.beam_displacement[0, 0]
    EA = 1e6 * math.pi * 0.05 ** 2
    assert 0.0 < bar_strain < 1e-4 * plain_strain, (bar_strain, plain_strain)
    assert bar_strain == pytest.approx(force / EA, rel=0.01)
    # the solid follows the bar: its x-displacements stay at the bar's scale
    assert np.abs(reinforced.solid_displacement[:, 0]).max() < 1e-3 * plain_strain


# --------------------------------------------------------------------------------------------
# large rotation of an embedded fibre bundle
# --------------------------------------------------------------------------------------------
def rotation_about_x(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rotated_bundle_scene(steps, max_iterations=25, max_cuts=6):
    """Unit block (2×2×2 hex8, Neo-Hooke) with three oblique embedded fibres; the nodes of x = 0 are
    moved to their place after a 90° rotation about the block's x axis (straight-line paths,
    so the intermediate states are strained); everything else must follow through Newton."""
    R, centre = rotation_about_x(math.pi / 2), np.array([0.0, 0.5, 0.5])
    dirichlet = []
    for y in (0.0, 0.5, 1.0):
        for z in (0.0, 0.5, 1.0):
            X = np.array([0.0, y, z])
            u = R @ (X - centre) + centre - X
            dirichlet.append({"on": {"inside": [[-1e-3, y - 1e-3, z - 1e-3], [1e-3, y + 1e-3, z + 1e-3]]},
                              "value": u.tolist()})
    fibres = [[[0.05, 0.2, 0.3], [0.95, 0.8, 0.6]], [[0.1, 0.9, 0.1], [0.9, 0.15, 0.85]],
              [[0.02, 0.5, 0.5], [0.98, 0.45, 0.55]]]
    return Scene(
        solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [2, 2, 2]},
               "material": {"model": "neo_hooke", "E": 1.0, "nu": 0.3}},
        beams=[{"curve": {"line": f}, "elements": 3, "section": {"EA": 2.0, "EI": 0.05}} for f in fibres],
        dirichlet=dirichlet,
        analysis={"steps": steps, "max_iterations": max_iterations, "max_cuts": max_cuts}), R, centre


def test_embedded_fibre_bundle_rotates_rigidly_by_90_degrees():
    """Measured: 5 Newton iterations per step, positions exact to 2e-13, |λ| 4e-13."""
    scene, R, centre = rotated_bundle_scene(steps=6)
    result = m13.solve(scene)
    model = result.model
    X = model.solid_mesh.points
    exact = (X - centre) @ R.T + centre - X
    assert np.abs(result.solid_displacement - exact).max() < 1e-8
    X_B = np.vstack([g.mesh.positions for g in model.groups])
    assert np.abs(result.beam_displacement - ((X_B - centre) @ R.T + centre - X_B)).max() < 1e-8
    T = model.groups[0].mesh.tangents
    assert np.abs(result.beam_tangent_displacement - T @ (R - np.eye(3)).T).max() < 1e-8
    # zero strain energy and no coupling load in the rotated state
    n = 3 * model.n_solid_nodes
    assert abs(model.solid_physics.energy(result.z[:n])) < 1e-16
    g = model.groups[0]
    assert abs(g.physics.energy(result.z[g.dof_offset: g.dof_offset + g.mesh.n_centreline_dofs])) < 1e-16
    assert np.abs(result.line_load).max() < 1e-8
    # the intermediate states were strained (straight-line paths): the steps did real work
    assert max(s.iterations for s in result.steps) >= 3


# --------------------------------------------------------------------------------------------
# step cutting and the failure message
# --------------------------------------------------------------------------------------------
def test_step_cutting_recovers_from_a_too_large_step():
    """The 90° rotation in one step with at most 8 iterations fails twice; measured: steps to load
    factors 0.25 (2 cuts), 0.5 (1 cut), 1.0; the result equals 16 uncut steps to 3.7e-12."""
    big, R, centre = rotated_bundle_scene(steps=1, max_iterations=8)
    cut = m13.solve(big)
    assert sum(s.cuts for s in cut.steps) > 0 and len(cut.steps) > 1
    assert cut.steps[-1].load_factor == 1.0
    small = m13.solve(rotated_bundle_scene(steps=16)[0])
    assert all(s.cuts == 0 for s in small.steps)
    assert np.abs(cut.z - small.z).max() < 1e-9


def test_a_run_that_cannot_converge_says_what_failed_and_what_to_try():
    scene, _, _ = rotated_bundle_scene(steps=1, max_iterations=2, max_cuts=1)
    with pytest.raises(ConvergenceError) as info:
        m13.solve(scene)
    message = str(info.value)
    assert "Newton's method gave up at load factor 0.5 (last converged: 0)" in message
    assert "after 1 step cuts" in message and "no convergence in 2 iterations" in message
    for advice in ("Try more load steps ([analysis] steps)", "supports fix every rigid-body motion",
                   "lower the penalty"):
        assert advice in message
