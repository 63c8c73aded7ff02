"""Fibre-reinforced material (S, C and element tangent against finite differences, closed-form
stretch, scene hook) and the composite plate example (explicit fibres vs homogenised model)."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.physics.fibre_material import FibreField, fibre_family, fibre_stress_tangent
from mortar1d3d.physics.materials import VOIGT, material
from mortar1d3d.physics.solid import SolidModel
from mortar1d3d.scene import Scene, SceneError

RNG = np.random.default_rng(7)
FAMILIES = np.array([fibre_family(RNG.normal(size=3), 500.0, 0.3), fibre_family(RNG.normal(size=3), 800.0, 0.2)])


def _material_at(name, H):
    m = material(name, 100.0, 0.3)
    S, C = np.empty((3, 3)), np.empty((6, 6))
    W = fibre_stress_tangent(m.code, m.lam, m.mu, FAMILIES, 0, len(FAMILIES), H, S, C)
    return W, S, C


@pytest.mark.parametrize("name", ["saint_venant_kirchhoff", "neo_hooke"])
def test_fibre_material_stress_and_tangent_match_finite_differences(name):
    H = 0.08 * RNG.uniform(-1, 1, (3, 3))
    W, S, C = _material_at(name, H)
    F = np.eye(3) + H
    h = 1e-6
    P = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            dH = np.zeros((3, 3))
            dH[i, j] = h
            P[i, j] = (_material_at(name, H + dH)[0] - _material_at(name, H - dH)[0]) / (2 * h)
    # ∂W/∂F = P = F S
    assert np.abs(P - F @ S).max() <= 1e-7 * np.abs(S).max()
    # dS = C : dE with dE = sym(Fᵀ dH), Voigt with engineering shear
    for _ in range(3):
        dH = RNG.uniform(-1, 1, (3, 3))
        dS = (_material_at(name, H + h * dH)[1] - _material_at(name, H - h * dH)[1]) / (2 * h)
        dE = 0.5 * (F.T @ dH + dH.T @ F)
        dE_voigt = np.array([dE[I, J] * (1.0 if I == J else 2.0) for I, J in VOIGT])
        predicted = C @ dE_voigt
        assert np.abs(predicted - np.array([dS[I, J] for I, J in VOIGT])).max() <= 1e-6 * np.abs(C).max()
    assert np.abs(C - C.T).max() <= 1e-12 * np.abs(C).max()


def test_fibre_stretch_closed_form():
    """Stretch λ along a single fibre family at ν = 0: S_aa = (E + k) E_aa, W = ½ (E + k) E_aa²."""
    a = np.array([1.0, 2.0, 2.0]) / 3.0
    row = fibre_family(a * 7.0, 200.0, 0.25)           # not unit on input: normalised
    assert np.allclose(row[:3], a) and row[3] == 50.0
    stretch = 1.1
    H = (stretch - 1.0) * np.outer(a, a)               # F = I + (λ - 1) a⊗a
    m = material("saint_venant_kirchhoff", 10.0, 0.0)
    S, C = np.empty((3, 3)), np.empty((6, 6))
    W = fibre_stress_tangent(m.code, m.lam, m.mu, row[None, :], 0, 1, H, S, C)
    E_aa = 0.5 * (stretch ** 2 - 1.0)
    assert np.allclose(S, 60.0 * E_aa * np.outer(a, a), rtol=1e-13, atol=1e-13)
    assert W == pytest.approx(0.5 * 60.0 * E_aa ** 2, rel=1e-13)


def _fibre_box(element, kinematics):
    mesh = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (2, 1, 1), element), amplitude=0.05, seed=3)
    # family 0 everywhere, family 1 on element 0 only: two non-empty sets
    field = FibreField(mesh.n_elements, [(FAMILIES[0], None), (FAMILIES[1], [0])])
    return SolidModel(mesh, material("saint_venant_kirchhoff", 100.0, 0.3), kinematics, fibres=field)


@pytest.mark.parametrize("element", ["hexahedron", "tetra"])
def test_element_forces_and_tangent_with_fibres_match_finite_differences(element):
    model = _fibre_box(element, "nonlinear")
    assert model.fibres.element_families(0).shape == (2, 4)
    u = 0.04 * np.random.default_rng(2).uniform(-1, 1, model.n_dofs)
    f, K = model.evaluate(u)
    h = 1e-6
    K_fd = np.empty((model.n_dofs, model.n_dofs))
    f_fd = np.empty(model.n_dofs)
    for j in range(model.n_dofs):
        e = np.zeros(model.n_dofs)
        e[j] = h
        K_fd[:, j] = (model.evaluate(u + e, False)[0] - model.evaluate(u - e, False)[0]) / (2 * h)
        f_fd[j] = (model.energy(u + e) - model.energy(u - e)) / (2 * h)
    scale = np.abs(K_fd).max()
    assert np.abs(K.toarray() - K_fd).max() <= 1e-6 * scale
    assert np.abs(f - f_fd).max() <= 1e-6 * np.abs(f).max()
    # the fibres are really there: without them the forces differ by far more than round-off
    bare = SolidModel(model.mesh, model.material, "nonlinear")
    assert np.abs(bare.evaluate(u, False)[0] - f).max() > 0.1 * np.abs(f).max()


def test_linear_kinematics_with_fibres_is_the_linearisation():
    linear, nonlinear = _fibre_box("hexahedron", "linear"), _fibre_box("hexahedron", "nonlinear")
    u = np.random.default_rng(4).uniform(-1, 1, linear.n_dofs)
    K_lin = linear.evaluate(u)[1].toarray()
    K0 = nonlinear.evaluate(np.zeros(nonlinear.n_dofs))[1].toarray()
    assert np.abs(K_lin - K0).max() <= 1e-12 * np.abs(K0).max()
    # energy ½ uᵀK u, and the cell stress of a uniform strain includes the fibres
    assert linear.energy(u) == pytest.approx(0.5 * u @ K_lin @ u, rel=1e-12)
    eps = np.array([[1e-3, 0, 0], [0, 0, 0], [0, 0, 0]])
    sigma = linear.cell_fields((linear.mesh.points @ eps.T).reshape(-1))["cauchy_stress"]
    m = linear.material
    expected = np.zeros((3, 3))
    expected[0, 0] = (m.lam + 2 * m.mu) * 1e-3
    expected[1, 1] = expected[2, 2] = m.lam * 1e-3
    for e in range(2):
        rows = linear.fibres.element_families(e)
        expected_e = expected + sum(r[3] * r[0] ** 2 * 1e-3 * np.outer(r[:3], r[:3]) for r in rows)
        assert np.allclose(sigma[e], expected_e, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("kinematics", ["linear", "nonlinear"])
def test_scene_fibres_uniaxial_tension(kinematics):
    """A bar (ν = 0) with fibres along x: uniaxial E_GL = P / (λ (E + k)) exactly."""
    E, k = 1e3, 0.4 * 5e3
    scene = Scene(solid={"mesh": {"box": [[0, 0, 0], [2, 1, 1]], "cells": [2, 1, 1]},
                         "material": {"model": "saint_venant_kirchhoff", "E": E, "nu": 0.0,
                                      "fibres": [{"direction": [2, 0, 0], "E": 5e3, "volume_fraction": 0.4}]}},
                  dirichlet=[{"on": "solid:x_min", "components": ["x"]}, {"on": "solid:y_min", "components": ["y"]},
                             {"on": "solid:z_min", "components": ["z"]}],
                  load=[{"type": "traction", "on": "solid:x_max", "value": [30.0, 0, 0]}],
                  analysis={"kinematics": kinematics})
    assert "1 fibre families" in str(m13.plan(scene))
    result = m13.solve(scene)
    ux = result.solid_displacement[np.isclose(result.model.solid_mesh.points[:, 0], 2.0), 0]
    if kinematics == "linear":
        strain = 30.0 / (E + k)
    else:   # P = λ S = λ (E + k) (λ² - 1)/2
        from scipy.optimize import brentq
        strain = brentq(lambda s: (1 + s) * (E + k) * ((1 + s) ** 2 - 1) / 2 - 30.0, 0.0, 0.1)
    assert np.allclose(ux, 2.0 * strain, rtol=1e-9)


def test_scene_fibre_validation_and_regions():
    base = {"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 2]}}

    def scene(fibre):
        return Scene(solid={**base, "material": {"model": "saint_venant_kirchhoff", "E": 1.0, "nu": 0.3,
                                                 "fibres": [fibre]}}, dirichlet=[{"on": "solid:z_min"}])
    good = {"direction": [0, 1, 0], "E": 10.0, "volume_fraction": 0.5}
    for key, value, text in (("direction", [0, 0, 0], "must not be zero"), ("volume_fraction", 1.5, "<= 1"),
                             ("E", -1.0, "> 0")):
        with pytest.raises(SceneError, match=rf"solid\.material\.fibres\[0\]\.{key}: .*{text}"):
            scene({**good, key: value})
    with pytest.raises(SceneError, match=r"fibres\[0\]\.colour"):
        scene({**good, "colour": 1})
    # a region: only the upper element (centroid z = 0.75) is reinforced
    model = m13.Model(scene({**good, "inside": [[0, 0, 0.5], [1, 1, 1]]})).prepare()
    field = model.solid_physics.fibres
    assert [len(field.element_families(e)) for e in range(2)] == [0, 1]
    assert np.allclose(field.element_families(1), [[0, 1, 0, 5.0]])
    with pytest.raises(SceneError, match=r"fibres\[0\]\.inside: no element centroid"):
        m13.Model(scene({**good, "inside": [[2, 2, 2], [3, 3, 3]]})).prepare()


# --------------------------------------------------------------------------------------------
# the composite plate example, coarse
# --------------------------------------------------------------------------------------------
def _example():
    path = Path(__file__).resolve().parents[1] / "examples" / "composite_plate.py"
    spec = importlib.util.spec_from_file_location("composite_plate_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# measured with this test's settings (8 × 2 × 4 hexahedron20, nonlinear, see the example's docstring)
PINNED = {("tension", 1): 0.0218, ("tension", 2): 0.0059, ("bending", 1): -0.0422, ("bending", 2): -0.0120}


@pytest.mark.parametrize("load", ["tension", "bending"])
def test_composite_plate_explicit_fibres_approach_homogenised(load):
    example = _example()
    _, homogenised_scene = example.plate_scenes(1, load, cells=(8, 2))
    homogenised = m13.solve(homogenised_scene)
    differences = {}
    for level in (1, 2):
        explicit_scene, _ = example.plate_scenes(level, load, cells=(8, 2))
        explicit = m13.solve(explicit_scene)
        row = example.compare(explicit, homogenised, load)
        differences[level] = row
        assert row["tip"] == pytest.approx(PINNED[load, level], abs=5e-4)
    # the difference shrinks like 1/level² (fibre discreteness) and is small for the finer fibres
    assert abs(differences[2]["tip"]) < 0.35 * abs(differences[1]["tip"])
    assert abs(differences[2]["tip"]) < 0.015 and differences[2]["field"] < 0.015
    # deflections are real: tension ~1e-3 strain, bending ~1 % of the length
    assert differences[2]["tip_homogenised"] > (4e-4 if load == "tension" else 5e-3)
