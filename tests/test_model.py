"""The nonlinear beam-in-solid model end to end: patch test, rebar, penalty vs Lagrange,
Newton, supports, what runs (counts), and output."""
import math
import subprocess
import sys

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.errors import CouplingWarning
from mortar1d3d.model import Model
from mortar1d3d.scene import Scene, SceneError

# --------------------------------------------------------------------------------------------
# uniform-strain patch test
# --------------------------------------------------------------------------------------------
STRAIN = 2e-3
E_SOLID = 1e3


def affine(x):
    x = np.asarray(x, dtype=float)
    return np.array([STRAIN * x[0], 0.0, 0.0])


def patch_scene(constraint, integration, enforcement, element="hexahedron", kinematics="nonlinear"):
    """Block (ν = 0) stretched along x by a dead traction with rollers on three faces, and an oblique
    straight beam whose ends follow the same affine field. Uniform strain is the exact solution
    for solid and beam; the beam's axial force is constant and taken by its end supports, so the
    coupling line load must vanish."""
    start, end = np.array([0.1, 0.2, 0.15]), np.array([0.9, 0.75, 0.85])
    stretch = 1.0 + STRAIN
    # dead traction = first Piola–Kirchhoff stress of the uniform stretch (SVK, ν = 0: S = E E_GL)
    P = stretch * E_SOLID * (STRAIN + 0.5 * STRAIN ** 2) if kinematics == "nonlinear" else E_SOLID * STRAIN
    return Scene(
        solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [3, 3, 3], "element": element},
               "material": {"model": "saint_venant_kirchhoff", "E": E_SOLID, "nu": 0.0}},
        beams=[{"curve": {"line": [start.tolist(), end.tolist()]}, "elements": 4,
                "section": {"EA": 5.0, "EI": 0.01}}],
        coupling={"constraint": constraint, "integration": integration, "enforcement": enforcement,
                  "penalty": 1e3 * E_SOLID, "n_gauss": 4},
        dirichlet=[{"on": "solid:x_min", "components": ["x"]}, {"on": "solid:y_min", "components": ["y"]},
                   {"on": "solid:z_min", "components": ["z"]},
                   {"on": "beam:0:start", "value": affine(start).tolist()},
                   {"on": "beam:0:end", "value": affine(end).tolist()}],
        load=[{"type": "traction", "on": "solid:x_max", "value": [P, 0, 0]}],
        analysis={"kinematics": kinematics, "steps": 1})


VARIANTS = [("mortar", "segment", "penalty"), ("mortar", "element", "penalty"),
            ("mortar", "segment", "lagrange"), ("mortar", "element", "lagrange"),
            ("gauss_point", "segment", "penalty"), ("gauss_point", "element", "penalty"),
            ("mortar", "auto", "penalty")]


@pytest.mark.parametrize("constraint, integration, enforcement", VARIANTS)
def test_uniform_strain_patch_every_coupling_variant(constraint, integration, enforcement):
    result = m13.solve(patch_scene(constraint, integration, enforcement))
    model = result.model
    exact_solid = np.array([affine(x) for x in model.solid_mesh.points])
    g = model.groups[0]
    exact_beam = np.array([affine(x) for x in g.mesh.positions])
    assert np.abs(result.solid_displacement - exact_solid).max() <= 1e-10 * STRAIN
    assert np.abs(result.beam_displacement - exact_beam).max() <= 1e-10 * STRAIN
    # the deformed tangent is the affine image of the reference tangent
    F = np.diag([1.0 + STRAIN, 1.0, 1.0])
    assert np.abs(result.beam_tangent_displacement - g.mesh.tangents @ (F - np.eye(3)).T).max() <= 1e-10 * STRAIN
    # λ = 0: the coupling transfers nothing (scale: the beam's axial force over its length)
    axial = 5.0 * STRAIN
    assert np.abs(result.line_load).max() <= 1e-8 * axial
    assert result.steps[-1].iterations <= 4


@pytest.mark.parametrize("element", ["tetra", "hexahedron27", "wedge"])
def test_uniform_strain_patch_other_elements_linear(element):
    result = m13.solve(patch_scene("mortar", "segment", "penalty", element=element, kinematics="linear"))
    exact = np.array([affine(x) for x in result.model.solid_mesh.points])
    assert np.abs(result.solid_displacement - exact).max() <= 1e-10 * STRAIN
    assert np.abs(result.line_load).max() <= 1e-8 * 5.0 * STRAIN


WEDGE_SCENE = """
[solid]
mesh = { box = [[0, 0, 0], [1, 1, 1]], cells = [2, 3, 3], element = "wedge" }
material = { model = "saint_venant_kirchhoff", E = 1e3, nu = 0.0 }

[[beams]]
curve = { line = [[0.1, 0.2, 0.15], [0.9, 0.75, 0.85]] }
elements = 4
section = { EA = 5.0, EI = 0.01 }

[coupling]
constraint = "mortar"
integration = "segment"
enforcement = "lagrange"
n_gauss = 4

[[dirichlet]]
on = "solid:x_min"
components = ["x"]

[[dirichlet]]
on = "solid:y_min"
components = ["y"]

[[dirichlet]]
on = "solid:z_min"
components = ["z"]

[[dirichlet]]
on = "beam:0:start"
value = [0, 0, START]

[[dirichlet]]
on = "beam:0:end"
value = [0, 0, END]

[[load]]
type = "traction"
on = "solid:z_max"
value = [0, 0, TRACTION]

[analysis]
kinematics = "nonlinear"
steps = 2
"""


def test_wedge_scene_file_stretched_through_its_triangle_faces(tmp_path):
    """A scene file with a wedge mesh, solved: the uniform stretch along z (dead traction on z_max, whose
    faces are the wedges' triangles) is the exact solution of solid and beam, and λ = 0."""
    stretch = 1.0 + STRAIN
    P = stretch * E_SOLID * (STRAIN + 0.5 * STRAIN ** 2)
    path = tmp_path / "wedges.toml"
    text = WEDGE_SCENE.replace("START", repr(STRAIN * 0.15)).replace("END", repr(STRAIN * 0.85))
    path.write_text(text.replace("TRACTION", repr(P)))
    result = m13.solve(Scene.from_toml(path))
    model = result.model
    assert list(model.solid_mesh.cells) == ["wedge"] and model.solid_mesh.n_elements == 2 * 18
    exact = lambda X: STRAIN * np.column_stack([0 * X[:, 0], 0 * X[:, 1], X[:, 2]])    # noqa: E731
    assert np.abs(result.solid_displacement - exact(model.solid_mesh.points)).max() <= 1e-10 * STRAIN
    assert np.abs(result.beam_displacement - exact(model.groups[0].mesh.positions)).max() <= 1e-10 * STRAIN
    assert np.abs(result.line_load).max() <= 1e-8 * 5.0 * STRAIN
    assert result.steps[-1].iterations <= 4


# --------------------------------------------------------------------------------------------
# eccentric rebar: transformed-section beam theory
# --------------------------------------------------------------------------------------------
def rebar_scene(cells, with_rebar, element="hexahedron20", enforcement="lagrange", penalty=None, load=1.0,
                kinematics="linear", steps=1):
    L, b, h = 1.0, 0.1, 0.1
    scene = {
        "solid": {"mesh": {"box": [[0, 0, 0], [L, b, h]], "cells": list(cells), "element": element},
                  "material": {"model": "saint_venant_kirchhoff", "E": 30e9, "nu": 0.0}},
        "dirichlet": [{"on": "solid:x_min"}],
        "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -load * 1e5]}],
        "analysis": {"kinematics": kinematics, "steps": steps},
    }
    if with_rebar:
        scene["beams"] = [{"curve": {"line": [[0, b / 2, h / 2 - 0.025], [L, b / 2, h / 2 - 0.025]]},
                           "elements": 2 * cells[0], "section": {"E": 200e9, "radius": 0.008}}]
        scene["coupling"] = {"enforcement": enforcement, "integration": "segment"}
        if penalty is not None:
            scene["coupling"]["penalty"] = penalty
        scene["dirichlet"].append({"on": "beam:0:start"})
    return Scene.from_dict(scene)


def tip_deflection(result):
    X = result.model.solid_mesh.points
    tip = np.isclose(X[:, 0], X[:, 0].max())
    return -result.solid_displacement[tip, 2].mean()


def transformed_section_ratio():
    b = h = 0.1
    n = 200e9 / 30e9
    r, e = 0.008, 0.025
    A_c, I_c = b * h, b * h ** 3 / 12
    A_s, I_s = math.pi * r ** 2, math.pi * r ** 4 / 4
    # the embedded bar adds to the solid (the solid is not cut away): extra area n A_s at -e
    shift = n * A_s * e / (A_c + n * A_s)
    I_t = I_c + A_c * shift ** 2 + n * A_s * (e - shift) ** 2 + n * I_s
    return I_t / I_c


def test_eccentric_rebar_stiffens_like_the_transformed_section():
    """Tip deflection ratio (plain / reinforced) against transformed-section beam theory.

    Measured: hex8 (10,2,2) -2.6 %, (20,4,4) -0.64 %; hex20 (4,1,1) -0.09 % (the rest is the
    3D/shear difference between the solid and Euler–Bernoulli theory).
    """
    expected = transformed_section_ratio()
    assert expected > 1.08                      # the rebar matters
    errors = []
    for cells in ((10, 2, 2), (20, 4, 4)):
        plain = tip_deflection(m13.solve(rebar_scene(cells, False, element="hexahedron")))
        reinforced = tip_deflection(m13.solve(rebar_scene(cells, True, element="hexahedron")))
        errors.append(abs(plain / reinforced / expected - 1.0))
    assert errors[0] < 0.05 and errors[1] < 0.01 and errors[1] < errors[0] / 2, errors
    plain = tip_deflection(m13.solve(rebar_scene((4, 1, 1), False)))
    reinforced = tip_deflection(m13.solve(rebar_scene((4, 1, 1), True)))
    assert abs(plain / reinforced / expected - 1.0) < 3e-3


def test_penalty_converges_to_lagrange_like_one_over_epsilon():
    cells = (8, 1, 1)
    exact = m13.solve(rebar_scene(cells, True, element="hexahedron", enforcement="lagrange"))
    errors = []
    # measured: errors 1.5e-8, 1.5e-9, 1.6e-10 (ratios 9.6, 9.9); below ε = 100 E pre-asymptotic,
    # above 1e5 E round-off of the penalty system dominates
    for eps in (3e12, 3e13, 3e14):
        pen = m13.solve(rebar_scene(cells, True, element="hexahedron", enforcement="penalty", penalty=eps))
        errors.append(np.abs(pen.solid_displacement - exact.solid_displacement).max())
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(8.5 < q < 11.5 for q in ratios), (errors, ratios)


def test_nonlinear_equals_linear_for_small_loads():
    # tip deflection ~1e-7 of the length: geometric nonlinearity ~1e-7 relative
    lin = m13.solve(rebar_scene((8, 1, 1), True, element="hexahedron", load=1e-4))
    non = m13.solve(rebar_scene((8, 1, 1), True, element="hexahedron", load=1e-4, kinematics="nonlinear"))
    scale = np.abs(lin.solid_displacement).max()
    assert 0 < scale < 1e-6
    assert np.abs(non.solid_displacement - lin.solid_displacement).max() <= 1e-5 * scale
    assert np.abs(non.beam_displacement - lin.beam_displacement).max() <= 1e-5 * scale


def test_newton_converges_quadratically():
    result = m13.solve(rebar_scene((8, 1, 1), True, element="hexahedron", load=300.0, kinematics="nonlinear",
                                   enforcement="penalty", penalty=3e12))
    res = np.array(result.steps[0].residuals)
    r = res / res[0]
    assert result.steps[0].iterations >= 3 and r[-1] < 1e-8
    # quadratic: once in the basin, each relative residual is at most ~ the square of the previous
    tail = [(a, b) for a, b in zip(r[1:-1], r[2:]) if a < 1e-1 and b > 1e-9]     # above the round-off floor
    assert tail, r
    assert all(b <= 50.0 * a * a for a, b in tail), r


# --------------------------------------------------------------------------------------------
# beams alone through the scene layer
# --------------------------------------------------------------------------------------------
def test_cantilever_rolls_up_into_a_circle_through_a_scene():
    L, EI = 1.0, 2.0
    scene = Scene(beams=[{"curve": {"line": [[0, 0, 0], [L, 0, 0]]}, "elements": 16,
                          "section": {"EA": 1e7, "EI": EI}}],
                  dirichlet=[{"on": "beam:0:start", "clamp": True}],
                  load=[{"type": "moment", "on": "beam:0:end", "value": [0, 0, 2 * math.pi * EI / L]}],
                  analysis={"steps": 8})
    result = m13.solve(scene)
    tip = np.array([L, 0, 0]) + result.beam_displacement[-1]
    assert np.linalg.norm(tip) < 1e-3 * L
    t_tip = np.array([1.0, 0, 0]) + result.beam_tangent_displacement[-1]
    assert np.allclose(t_tip / np.linalg.norm(t_tip), [1, 0, 0], atol=1e-3)
    # the beam passes through (0, 2R, 0) at mid-length: the top of the circle of radius L / 2π
    mid = np.array([L / 2, 0, 0]) + result.beam_displacement[8]
    assert np.allclose(mid, [0, L / math.pi, 0], atol=1e-3)


# --------------------------------------------------------------------------------------------
# supports, counts, output
# --------------------------------------------------------------------------------------------
def test_free_rigid_body_motion_is_reported_before_solving(monkeypatch):
    data = dict(solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 1]},
                       "material": {"model": "neo_hooke", "E": 1.0, "nu": 0.3}},
                dirichlet=[{"on": "solid:x_min", "components": ["x"]}],
                load=[{"type": "body", "value": [1, 0, 0]}])
    calls = []
    monkeypatch.setattr(Model, "solve_linear", lambda *a, **k: calls.append(1))
    with pytest.raises(SceneError, match=r"the solid can move freely \(3 rigid-body mode\(s\) not fixed: "
                                         r"translation in y, translation in z, rotation about x\)"):
        m13.solve(Scene(**data))
    assert not calls
    # a beam outside the solid is not coupled and, unsupported, floats
    data["dirichlet"] = [{"on": "solid:x_min"}]
    data["beams"] = [{"curve": {"line": [[2, 0, 0], [3, 0, 0]]}, "elements": 2, "section": {"EA": 1, "EI": 1}}]
    with pytest.raises(SceneError, match=r"beam 0 \(outside the solid, so not coupled\) can move freely"), \
            pytest.warns(CouplingWarning, match=r"beams\[0\]: no part of this beam lies inside the solid"):
        m13.solve(Scene(**data))


def test_scenes_run_only_what_they_declare(monkeypatch):
    import mortar1d3d.model.model as model_module
    calls = []
    real = model_module.assemble_mortar
    monkeypatch.setattr(model_module, "assemble_mortar", lambda *a, **k: calls.append(1) or real(*a, **k))

    # no beams: no search, segmentation or coupling at all
    solid_only = Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1]},
                              "material": {"model": "saint_venant_kirchhoff", "E": 1e3, "nu": 0.3}},
                       dirichlet=[{"on": "solid:x_min"}],
                       load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1]}],
                       analysis={"steps": 3})
    result = m13.solve(solid_only)
    assert not calls
    assert not any(k.startswith(("mortar.", "coupling.", "beam")) for k in result.counts)
    planned = {e.name for e in m13.plan(solid_only)}
    assert set(result.counts) <= planned
    iterations = sum(s.iterations for s in result.steps)
    assert result.counts["solid.tangent"] == result.counts["solid.internal_force"] == iterations + len(result.steps)
    assert "load.pressure_tangent" not in result.counts

    # linear kinematics: one stiffness, one linear solve, no Newton loop
    linear = rebar_scene((4, 1, 1), True, element="hexahedron", enforcement="penalty", penalty=3e11)
    result = m13.solve(linear)
    assert calls == [1]
    assert result.counts["solver.linear"] == 1 and "solver.newton" not in result.counts
    assert result.counts["solid.stiffness"] == 1 and result.counts["beam.stiffness"] == 1
    assert result.counts["linear_solver.direct"] == 1
    assert set(result.counts) <= {e.name for e in m13.plan(linear)}

    # nonlinear, several steps: the coupling is assembled once and reused
    calls.clear()
    nonlinear = rebar_scene((4, 1, 1), True, element="hexahedron", enforcement="penalty", penalty=3e11,
                            kinematics="nonlinear", steps=3)
    result = m13.solve(nonlinear)
    assert calls == [1] and result.counts["mortar.assembly"] == 1 and len(result.steps) == 3
    assert result.counts["solid.tangent"] > 3
    assert set(result.counts) <= {e.name for e in m13.plan(nonlinear)}

    # follower pressure: its tangent is computed only when a pressure load exists
    data = {"solid": solid_only.solid, "dirichlet": [{"on": "solid:x_min"}],
            "load": [{"type": "pressure", "on": "solid:z_max", "value": 0.5}], "analysis": {"steps": 2}}
    data["solid"] = {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1]},
                     "material": {"model": "saint_venant_kirchhoff", "E": 1e3, "nu": 0.3}}
    result = m13.solve(Scene(**data))
    assert result.counts["load.pressure_tangent"] == result.counts["solid.tangent"] > 0
    assert result.model.pressures[0].n_tangents == result.counts["load.pressure_tangent"]


def test_model_tangent_matches_finite_differences():
    """Whole-model Jacobian (solid + beam + penalty coupling + follower pressure + end moment)."""
    scene = Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 0.3, 0.3]], "cells": [2, 1, 1]},
                         "material": {"model": "neo_hooke", "E": 10.0, "nu": 0.3}},
                  beams=[{"curve": {"line": [[0.1, 0.1, 0.12], [0.9, 0.2, 0.17]]}, "elements": 2,
                          "section": {"EA": 3.0, "EI": 0.2}},
                         {"curve": {"line": [[1.2, 0.0, 0.0], [1.5, 0.0, 0.0]]}, "elements": 1,
                          "section": {"EA": 3.0, "EI": 0.2}}],
                  coupling={"penalty": 50.0},
                  dirichlet=[{"on": "solid:x_min"}, {"on": "beam:1:start", "clamp": True}],
                  load=[{"type": "pressure", "on": "solid:z_max", "value": 0.7},
                        {"type": "moment", "on": "beam:1:end", "value": [0.0, 0.3, 0.1]}])
    with pytest.warns(CouplingWarning, match=r"beams\[1\]"):      # beam 1 lies outside on purpose
        model = Model(scene).prepare()
    rng = np.random.default_rng(3)
    z = 0.02 * rng.standard_normal(model.n_unknowns)
    r, K = model.residual(z, 0.8)
    K = K.toarray()
    h = 1e-6
    worst = 0.0
    for j in range(0, model.n_unknowns, 3):
        e = np.zeros_like(z)
        e[j] = h
        fd = (model.residual(z + e, 0.8, tangent=False)[0] - model.residual(z - e, 0.8, tangent=False)[0]) / (2 * h)
        worst = max(worst, np.abs(fd - K[:, j]).max() / max(np.abs(K).max(), 1e-300))
    assert worst < 1e-7


def test_failed_run_leaves_no_output(tmp_path):
    scene = tmp_path / "fails.toml"
    scene.write_text("""
[solid]
mesh = { box = [[0, 0, 0], [1, 0.1, 0.1]], cells = [4, 1, 1] }
material = { model = "neo_hooke", E = 1.0, nu = 0.3 }
[[dirichlet]]
on = "solid:x_min"
[[load]]
type = "traction"
on = "solid:x_max"
value = [0, 0, -1e6]
[analysis]
steps = 1
max_iterations = 2
max_cuts = 1
""")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "run", str(scene), "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 3
    assert "Newton's method gave up" in proc.stderr and "Try more load steps" in proc.stderr
    assert not out.exists() and not list(tmp_path.glob(".out*"))


def test_write_failure_leaves_no_partial_files(tmp_path, monkeypatch):
    result = m13.solve(rebar_scene((2, 1, 1), True, element="hexahedron", enforcement="penalty", penalty=3e11))
    import mortar1d3d.io.vtu as vtu

    def broken(*args, **kwargs):
        raise OSError("disk full")
    monkeypatch.setattr(vtu, "write_pvd", broken)
    with pytest.raises(OSError, match="disk full"):
        result.write(tmp_path / "out")
    assert not (tmp_path / "out").exists() and not list(tmp_path.iterdir())


def test_cli_run_writes_a_paraview_series(tmp_path):
    import meshio
    from pathlib import Path
    example = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "rebar_cantilever.toml"
    out = tmp_path / "rebar"
    proc = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "run", str(example), "--out", str(out)],
                          capture_output=True, text=True, check=True)
    assert proc.stdout.count("load factor") == 4
    pvd = (out / "result.pvd").read_text()
    assert pvd.count("<DataSet") == 5 * 4          # steps 0..4 × (solid, beams, segments, points)
    solid = meshio.read(out / "solid_0004.vtu")
    assert solid.point_data["displacement"][:, 2].min() < 0
    assert solid.cell_data["cauchy_stress"][0].shape[1] == 9
    beams = meshio.read(out / "beams_0004.vtu")
    for key in ("displacement", "axial_force", "curvature", "line_load"):
        assert key in beams.point_data
    quiet = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "run", str(example), "--out",
                            str(tmp_path / "q"), "--quiet"], capture_output=True, text=True, check=True)
    assert quiet.stdout == ""


def test_rigid_body_modes_are_in_the_kernel_of_the_reference_tangent():
    """Solid + oblique Hermite beam + penalty coupling: K(0) R = 0 for the six modes, tangent rows included.

    The tangent DOFs must turn with the same scale as the positions (ω × t), otherwise the
    rotation columns are not rigid motions of the beam and the support check and the AMG near
    null space would be fed wrong vectors.
    """
    scene = Scene(solid={"mesh": {"box": [[0, 0, 0], [2.0, 0.6, 0.6]], "cells": [3, 1, 1]},
                         "material": {"model": "saint_venant_kirchhoff", "E": 10.0, "nu": 0.3}},
                  # straight (the torsion-free beam refuses curved ones, issue 16), along no axis, so that
                  # every rotation turns its tangents
                  beams=[{"curve": {"line": [[0.2, 0.1, 0.15], [1.8, 0.5, 0.45]]},
                          "elements": 4, "section": {"EA": 3.0, "EI": 0.2}}],
                  coupling={"penalty": 50.0},
                  dirichlet=[{"on": "solid:x_min"}])
    model = Model(scene).prepare()
    R = model.rigid_body_modes()
    _, K = model.internal(np.zeros(model.n_displacement_dofs))
    scale = abs(K).max() * np.abs(R).max()
    for k in range(6):
        assert np.abs(K @ R[:, k]).max() < 1e-12 * scale, k
    # the beam's rotation columns are not trivially zero on the tangent rows
    first = model.groups[0].dof_offset
    tangent_rows = np.concatenate([first + 6 * i + np.arange(3, 6) for i in range(model.groups[0].mesh.n_nodes)])
    assert np.abs(R[tangent_rows, 3:]).max() > 0.1 * np.abs(R[:, 3:]).max()
