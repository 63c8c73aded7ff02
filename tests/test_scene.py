"""Scene validation (key paths in every error), sets, and plans (no physics needed)."""
import copy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.model import Model
from mortar1d3d.scene import Scene, SceneError

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "rebar_cantilever.toml"

BASE = {
    "solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1]},
              "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
    "beams": [{"curve": {"line": [[0.05, 0.1, 0.1], [0.95, 0.1, 0.1]]}, "elements": 3,
               "section": {"E": 2e11, "radius": 0.01}}],
    "dirichlet": [{"on": "solid:x_min"}],
    "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e5]}],
    "analysis": {"steps": 2},
}


def scene_with(path, value):
    data = copy.deepcopy(BASE)
    node = data
    keys = path.split(".")
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    last = keys[-1]
    if value is KeyError:
        del node[last]
    elif isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    return data


@pytest.mark.parametrize("path, value, message", [
    ("solid.colour", "red", "solid.colour: unknown key"),
    ("solid.material", KeyError, "solid.material: missing"),
    ("solid.material.E", "hard", "solid.material.E: expected a number"),
    ("solid.material.nu", 0.5, "solid.material.nu: expected a number < 0.5"),
    ("solid.material.model", "rubber", "solid.material.model: unknown value 'rubber'"),
    ("solid.mesh.cells", [4, 1], "solid.mesh.cells: expected 3 entries"),
    ("solid.mesh.element", "pyramid", "solid.mesh.element: unknown value 'pyramid'"),
    ("beams.0.section.radius", -0.01, "beams[0].section.radius: expected a number > 0"),
    ("beams.0.section", {"E": 2e11}, "beams[0].section.radius: missing"),
    ("beams.0.section", {"E": 2e11, "radius": 0.1, "EA": 1.0}, "beams[0].section: give either"),
    ("beams.0.elements", 2.5, "beams[0].elements: expected an integer"),
    ("beams.0.model", "kirchhoff", "beams[0].model: unknown value 'kirchhoff'"),
    ("beams.0.curve", {"line": [[0, 0, 0], [0, 0, 0]]}, "beams[0].curve.line: the two points coincide"),
    ("beams.0.curve", {"spiral": 1}, "beams[0].curve.spiral: unknown key"),
    ("dirichlet.0.on", "solid:top", None),        # unknown set: found when the model is built
    ("dirichlet.0.on", "wall", "dirichlet[0].on: 'wall': expected"),
    # before: beam:-1 selected the last beam (or failed with a bare ValueError), " 0" and "1_0" passed int()
    ("dirichlet.0.on", "beam:-1:start", "dirichlet[0].on: 'beam:-1:start': expected beam:<index>[:start|end] with "
                                        "<index> = 0, 1, ..."),
    ("dirichlet.0.on", "beam:x:end", "dirichlet[0].on: 'beam:x:end': expected beam:<index>[:start|end]"),
    ("dirichlet.0.on", "beam: 0:end", "dirichlet[0].on: 'beam: 0:end': expected beam:<index>[:start|end]"),
    ("dirichlet.0.on", "beam:1_0", "dirichlet[0].on: 'beam:1_0': expected beam:<index>[:start|end]"),
    ("dirichlet.0.on", "beam:7:middle", "dirichlet[0].on: 'beam:7:middle': expected beam:<index>:start or"),
    ("load.0", {"type": "point", "on": "beam:-1:end", "value": [0, 0, 1]},
     "load[0].on: 'beam:-1:end': expected beam:<index>[:start|end]"),
    ("dirichlet.0.components", ["x", "w"], "dirichlet[0].components[1]: unknown value 'w'"),
    ("load.0.type", "wind", "load[0].type: unknown value 'wind'"),
    ("load.0.value", [1, 2], "load[0].value: expected a list of 3 numbers, got 2 entries"),
    ("analysis.steps", 0, "analysis.steps: expected an integer in [1"),
    ("analysis.kinematics", "quadratic", "analysis.kinematics: unknown value"),
    ("analysis.tolerance", 1e-3, "analysis.tolerance: unknown key"),
])
def test_invalid_scene_names_key_path(path, value, message):
    data = scene_with(path, value)
    if message is None:
        with pytest.raises(SceneError, match=r"dirichlet\[0\]\.on: unknown solid set 'top'"):
            m13.plan(Scene.from_dict(data))
        return
    with pytest.raises(SceneError) as info:
        Scene.from_dict(data)
    assert str(info.value).startswith(message), str(info.value)


def test_unknown_top_level_key_and_bad_toml(tmp_path):
    with pytest.raises(SceneError, match="^solver: unknown key"):
        Scene.from_dict({**BASE, "solver": {}})
    bad = tmp_path / "bad.toml"
    bad.write_text("[solid\nmesh = 1\n")
    with pytest.raises(SceneError, match="not valid TOML"):
        Scene.from_toml(bad)
    with pytest.raises(SceneError, match="does not exist"):
        Scene.from_toml(tmp_path / "missing.toml")


@pytest.mark.parametrize("on, message", [
    ({"inside": [[5, 5, 5], [6, 6, 6]]}, r"dirichlet\[0\]\.on: the box .* contains no solid node"),
    ("beam:3:end", r"dirichlet\[0\]\.on: beam 3 does not exist"),
])
def test_sets_that_select_nothing(on, message):
    data = scene_with("dirichlet.0.on", on)
    with pytest.raises(SceneError, match=message):
        m13.plan(Scene.from_dict(data))


def _fibre_solid(inside):
    solid = copy.deepcopy(BASE["solid"])
    solid["material"]["fibres"] = [{"direction": [1, 0, 0], "E": 1e10, "volume_fraction": 0.1, "inside": inside}]
    return solid


@pytest.mark.parametrize("key, value, message", [
    ("load", [{"type": "point", "on": "beam:3:end", "value": [0, 0, 1]}], r"^load\[0\]\.on: beam 3 does not exist "
                                                                          r"\(the scene has 1 beam\)"),
    ("load", [{"type": "point", "on": "solid:top", "value": [0, 0, 1]}], r"^load\[0\]\.on: unknown solid set 'top'"),
    ("load", [{"type": "point", "on": {"inside": [[5, 5, 5], [6, 6, 6]]}, "value": [0, 0, 1]}],
     r"^load\[0\]\.on: the box .* contains no solid node"),
    ("load", [{"type": "moment", "on": "beam:2:end", "value": [0, 0, 1]}], r"^load\[0\]\.on: beam 2 does not exist"),
    ("solid", _fibre_solid([[5, 5, 5], [6, 6, 6]]), r"^solid\.material\.fibres\[0\]\.inside: no element centroid"),
])
def test_plan_resolves_every_set_that_solve_would(key, value, message):
    """Before: plan() resolved only the Dirichlet sets; these passed plan and failed in solve."""
    data = scene_with(key, value)
    with pytest.raises(SceneError, match=message):
        m13.plan(Scene.from_dict(data))


def test_plan_reports_a_surface_load_on_a_set_without_boundary_faces():
    box = m13.generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "hexahedron")
    centre = np.flatnonzero(np.all(box.points == 0.5, axis=1))
    solid = m13.SolidMesh(box.points, box.cells, point_sets={"centre": centre})
    data = copy.deepcopy(BASE)
    data["solid"]["mesh"] = solid
    data["load"] = [{"type": "traction", "on": "solid:centre", "value": [0, 0, 1]}]
    with pytest.raises(SceneError, match=r"^load\[0\]\.on: 'solid:centre' contains no boundary face of the solid"):
        m13.plan(Scene.from_dict(data))


def test_conflicting_dirichlet_values():
    data = copy.deepcopy(BASE)
    data["dirichlet"].append({"on": "solid:z_min", "value": [0, 0, 1e-3]})
    with pytest.raises(SceneError, match="prescribed twice with different values"):
        Model(Scene.from_dict(data))


def test_sets_resolve_to_the_right_nodes():
    model = Model(Scene.from_dict(BASE))
    X = model.solid_mesh.points
    _, nodes = model.select("solid:x_max", "t")
    assert np.allclose(X[nodes, 0], 1.0) and len(nodes) == 2 * 2
    _, nodes = model.select({"inside": [[0.4, -1, -1], [0.6, 1, 1]]}, "t")
    assert np.allclose(X[nodes, 0], 0.5)
    _, g, nodes = model.select("beam:0:end", "t")
    assert np.allclose(g.mesh.positions[nodes[0]], [0.95, 0.1, 0.1])
    _, g, nodes = model.select("beam:0", "t")
    assert len(nodes) == 4
    # Dirichlet DOFs: x_min has 4 solid nodes × 3 components
    assert len(model.fixed_dofs) == 12 and (model.fixed_dofs < 3 * model.n_solid_nodes).all()


def test_plan_lists_only_what_the_scene_declares():
    names = [e.name for e in m13.plan(Scene.from_dict(BASE))]
    assert names[:2] == ["solid.mesh", "beams.mesh"]
    for expected in ("mortar.search", "mortar.segmentation", "mortar.assembly", "coupling.mortar_penalty",
                     "solid.tangent", "beam.tangent", "load.traction", "solver.newton", "linear_solver.direct"):
        assert expected in names
    assert not any(n.startswith("load.pressure") for n in names)

    solid_only = {k: v for k, v in BASE.items() if k != "beams"}
    names = [e.name for e in m13.plan(Scene.from_dict(solid_only))]
    assert not any(n.startswith(("mortar.", "coupling.", "beam")) for n in names)

    linear = scene_with("analysis", {"kinematics": "linear"})
    names = [e.name for e in m13.plan(Scene.from_dict(linear))]
    assert "solver.linear" in names and "solver.newton" not in names and "solid.stiffness" in names

    element = scene_with("coupling", {"integration": "element"})
    names = [e.name for e in m13.plan(Scene.from_dict(element))]
    assert "mortar.segmentation" not in names and "mortar.integration_points" in names

    auto = scene_with("coupling", {"integration": "auto"})
    effects = {e.name: e for e in m13.plan(Scene.from_dict(auto))}
    assert "only beam elements that cross" in effects["mortar.segmentation"].detail
    assert "auto-based" in effects["mortar.integration_points"].detail

    pressure = scene_with("load", [{"type": "pressure", "on": "solid:x_max", "value": 1e5}])
    names = [e.name for e in m13.plan(Scene.from_dict(pressure))]
    assert "load.pressure" in names and "load.pressure_tangent" in names


def test_solver_choice_must_fit_enforcement():
    with pytest.raises(SceneError, match="analysis.solver: 'block'"):
        Model(Scene.from_dict(scene_with("analysis", {"solver": "block"})))
    data = scene_with("coupling", {"enforcement": "lagrange"})
    data["analysis"] = {"solver": "amg"}
    with pytest.raises(SceneError, match="analysis.solver: Lagrange"):
        Model(Scene.from_dict(data))


def test_cli_plan_prints_the_effects():
    out = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "plan", str(EXAMPLE)],
                         capture_output=True, text=True, check=True).stdout
    assert "mortar.segmentation" in out and "solver.newton" in out and "4 load steps" in out


@pytest.mark.parametrize("on", ["beam:-1:start", "beam:5:end", "solid:top"])
def test_cli_plan_of_a_bad_set_prints_an_error_not_a_traceback(tmp_path, on, capsys):
    """Before: 'beam:-1:start' ended `mortar1d3d plan` in a ValueError traceback."""
    from mortar1d3d.cli import main
    text = EXAMPLE.read_text().replace('on = "beam:0:start"', f'on = "{on}"')
    assert f'on = "{on}"' in text
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    assert main(["plan", str(scene)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: dirichlet[1].on: ") and "Traceback" not in err


def test_unreadable_scene_files_are_scene_errors(tmp_path):
    """Before: a directory raised IsADirectoryError, a file that is not UTF-8 UnicodeDecodeError."""
    with pytest.raises(SceneError, match=r"scene file .* cannot be read: Is a directory"):
        Scene.from_toml(tmp_path)
    latin1 = tmp_path / "latin1.toml"
    latin1.write_bytes('[analysis]\n# Stahlbeton, Träger\n'.encode("latin-1"))
    with pytest.raises(SceneError, match=r"latin1\.toml: not valid TOML: 'utf-8' codec can't decode"):
        Scene.from_toml(latin1)


def test_cli_prints_warnings_as_one_line_without_source(tmp_path):
    """Before: a warning printed the library's file, line number and source line."""
    scene = tmp_path / "stiff.toml"
    scene.write_text(EXAMPLE.read_text().replace("penalty = 3e13", "penalty = 3e19"))
    proc = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "plan", str(scene)],
                          capture_output=True, text=True, check=True)
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: AccuracyWarning: coupling.penalty: 3e+19 is 1.0e+09 × "
                                                   "solid.material.E"), proc.stderr
    assert ".py:" not in proc.stderr


def test_cli_plan_into_a_closed_pipe_exits_quietly(tmp_path):
    """`mortar1d3d plan scene.toml | head` with the reader gone before the first line: the command
    stops without a traceback, with the status of a process ended by SIGPIPE (141). The pipe's
    read end is closed before the process starts, so every write fails: no race.
    Before: a BrokenPipeError traceback and status 1."""
    import os
    read, write = os.pipe()
    os.close(read)
    try:
        proc = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "plan", str(EXAMPLE)], stdout=write,
                              stderr=subprocess.PIPE, text=True)
    finally:
        os.close(write)
    assert proc.stderr == "" and proc.returncode == 141


def test_truss_by_radius_has_no_bending_stiffness_and_no_warning():
    # a truss given by E and radius must not carry the derived EI (which BeamModel would
    # reject with an "EI is ignored" warning the user never asked for)
    import warnings
    data = copy.deepcopy(BASE)
    data["beams"][0]["model"] = "truss"
    scene = Scene.from_dict(data)
    section = scene.beams[0]["section"]
    assert section["EI"] == 0.0 and section["EA"] == pytest.approx(2e11 * np.pi * 1e-4, rel=1e-15)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Model(scene).prepare()
