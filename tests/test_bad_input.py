"""Bad input (issue 6 part 5): malformed and adversarial scene files must stop with the library's
:class:`SceneError` naming the key path (or the node / element ids), never with a KeyError,
TypeError, ZeroDivisionError, OverflowError or a numpy warning; ``mortar1d3d run`` exits with
code 2 and writes nothing; no run can loop without bound.

Scenes are written as TOML text to a temporary directory and read back with
:meth:`Scene.from_toml`, as the command line does.
"""
import copy
import json
import math
import re
import subprocess
import sys
import warnings

import meshio
import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.cli import main as cli_main
from mortar1d3d.errors import CouplingWarning
from mortar1d3d.model import Model
from mortar1d3d.scene import MAX_MAGNITUDE, Scene, SceneError
from mortar1d3d.solvers.newton import ConvergenceError

# A valid scene: 2 hex8, one embedded torsion-free bar clamped at its start.
BASE = {
    "solid": {"mesh": {"box": [[0.0, 0.0, 0.0], [1.0, 0.2, 0.2]], "cells": [2, 1, 1], "element": "hexahedron"},
              "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
    "beams": [{"curve": {"line": [[0.05, 0.1, 0.1], [0.95, 0.1, 0.1]]}, "elements": 2, "model": "torsion_free",
               "section": {"E": 2e11, "radius": 0.01}}],
    "coupling": {"enforcement": "penalty", "penalty": 1e12, "n_gauss": 4},
    "dirichlet": [{"on": "solid:x_min", "value": [0.0, 0.0, 0.0]}, {"on": "beam:0:start", "clamp": True}],
    "load": [{"type": "traction", "on": "solid:x_max", "value": [0.0, 0.0, -1e5]}],
    "analysis": {"steps": 2, "max_iterations": 10, "max_cuts": 2},
}
# an error message starts with the key path of the entry it is about
KEY_PATH = re.compile(r"^(solid|beams|coupling|dirichlet|load|analysis|scene)(\[\d+\])?[.:\[ ]")


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------
def toml_value(value):
    """Inline TOML for the plain data of a scene (no TOML writer is a dependency)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{json.dumps(str(k))} = {toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML for {value!r}")


def write_scene(directory, data, name="scene"):
    path = directory / f"{name}.toml"
    path.write_text("".join(f"{json.dumps(k)} = {toml_value(v)}\n" for k, v in data.items()))
    return path


def expect_scene_error(path, match):
    """Read and solve a scene file: it must raise SceneError whose message matches ``match``,
    with numpy warnings turned into errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(SceneError, match=match) as info:
            m13.solve(path)
    return str(info.value)


def leaves(node, path=()):
    """Key paths (tuples) of every entry of nested dicts/lists, interior entries included."""
    if isinstance(node, dict):
        for key, value in node.items():
            yield from leaves(value, path + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from leaves(value, path + (i,))
    if path:
        yield path


def dotted(path):
    """("beams", 0, "section", "E") -> "beams[0].section.E" (the library's key-path spelling)."""
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else key)
    return out


def test_the_base_scene_is_valid_and_solves(tmp_path):
    result = m13.solve(write_scene(tmp_path, BASE))
    assert np.isfinite(result.z).all() and result.solid_displacement[:, 2].min() < 0


# --------------------------------------------------------------------------------------------
# malformed TOML
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("text", [
    "[solid\nmesh = 1\n",                                   # unterminated table header
    "[analysis]\nsteps = 2\nsteps = 3\n",                   # duplicate key
    "[analysis]\nsteps = \n",                               # missing value
    "beams = [{ curve = { line = [[0, 0, 0], [1, 0, 0]] }\n",  # unterminated inline table
    "solid = { E = 1e9 } }\n",                              # stray brace
    "\x00\x01binary",                                       # not text at all
])
def test_invalid_toml_is_a_scene_error_and_the_cli_exits_2(tmp_path, text, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match="not valid TOML"):
        Scene.from_toml(path)
    out = tmp_path / "out"
    assert cli_main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert "error:" in capsys.readouterr().err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


# --------------------------------------------------------------------------------------------
# every number of the scene rejects values that cannot be computed with
# --------------------------------------------------------------------------------------------
def _numeric_paths():
    out = []
    for path in leaves(BASE):
        node = BASE
        for key in path:
            node = node[key]
        if isinstance(node, (int, float)) and not isinstance(node, bool):
            out.append(path)
    return out


@pytest.mark.parametrize("bad", [1e308, -1e308, math.inf, -math.inf, math.nan, 10 ** 400, 1e-308],
                         ids=["1e308", "-1e308", "inf", "-inf", "nan", "10^400", "1e-308"])
def test_every_number_rejects_unusable_values_naming_its_key_path(tmp_path, bad):
    """Before the magnitude bounds, 1e308 in a coordinate or load overflowed to numpy
    RuntimeWarnings, a radius of 1e308 raised OverflowError (r**4), E = 1e308 a ValueError
    from the beam model, 1e-308 a singular factorisation."""
    paths = _numeric_paths()
    assert len(paths) == 31
    for path in paths:
        data = copy.deepcopy(BASE)
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = bad
        scene = write_scene(tmp_path, data)
        message = expect_scene_error(scene, None)
        assert message.startswith(dotted(path) + ":"), (path, message)


@pytest.mark.parametrize("path, value, message", [
    ("solid.material.E", -2e9, r"solid\.material\.E: expected a number > 0"),
    ("beams.0.section.radius", -0.01, r"beams\[0\]\.section\.radius: expected a number > 0"),
    ("beams.0.section.E", 0, r"beams\[0\]\.section\.E: expected a number > 0"),
    ("solid.mesh.cells", [0, 1, 1], r"solid\.mesh\.cells\[0\]: expected an integer in \[1"),
    ("solid.mesh.box", [[0, 0, 0], [0, 0.2, 0.2]], r"solid\.mesh\.box: the upper corner must be greater"),
    ("beams.0.curve", {"polyline": [[0.1, 0.1, 0.1], [0.5, 0.1, 0.1], [0.5, 0.1, 0.1], [0.9, 0.1, 0.1]]},
     r"beams\[0\]\.curve\.polyline: consecutive points coincide"),
    ("coupling.penalty", -1.0, r"coupling\.penalty: expected a number > 0"),
    ("analysis.max_iterations", 10 ** 9, r"analysis\.max_iterations: expected an integer in \[1, 1000\]"),
    ("analysis.steps", 1.5, r"analysis\.steps: expected an integer"),
    ("solid.mesh.cells", [2000, 2000, 2000], r"solid\.mesh\.cells: \[2000, 2000, 2000\] gives 8000000000 cells"),
    ("beams.0.elements", 10 ** 12, r"beams\[0\]\.elements: expected an integer in \[1, 1000000\]"),
    ("load.0.value", "down", r"load\[0\]\.value: expected a list of 3 numbers"),
    ("beams", {"curve": 1}, r"beams: expected a list"),
])
def test_adversarial_values_name_the_key_path(tmp_path, path, value, message):
    data = copy.deepcopy(BASE)
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    node = data
    for key in keys[:-1]:
        node = node[key]
    node[keys[-1]] = value
    expect_scene_error(write_scene(tmp_path, data), "^" + message)


# --------------------------------------------------------------------------------------------
# mesh files
# --------------------------------------------------------------------------------------------
def _box():
    return generate.box((0, 0, 0), (1, 0.2, 0.2), (2, 1, 1), "hexahedron")


def _duplicated_face():
    """The two hexes of the box, the second one on copies of the shared face's nodes (a crack)."""
    box = _box()
    points, cells = box.points.copy(), box.cells["hexahedron"].copy()
    shared = np.intersect1d(cells[0], cells[1])
    copies = {int(n): len(points) + i for i, n in enumerate(shared)}
    points = np.vstack([points, box.points[shared]])
    cells[1] = [copies.get(int(n), n) for n in cells[1]]
    return meshio.Mesh(points, [("hexahedron", cells)])


def _mesh_file_cases():
    box = _box()
    hexes = box.cells["hexahedron"]
    nan_points = box.points.copy()
    nan_points[3, 1] = np.nan
    return {
        "empty": (meshio.Mesh(np.zeros((0, 3)), []), r"solid\.mesh: cannot read mesh file .*empty\.vtu"),
        "boundary_only": (meshio.Mesh(box.points, [("quad", hexes[:, :4])]),
                          r"solid\.mesh: meshio mesh has no supported 3D cells"),
        "duplicate_nodes": (_duplicated_face(),
                            r"solid\.mesh: duplicate nodes at the same position: 1 and 12, 4 and 13, 7 and 14, "
                            r"10 and 15; the elements on either side are not connected"),
        "unused_node": (meshio.Mesh(np.vstack([box.points, [[5.0, 5.0, 5.0]]]), [("hexahedron", hexes)]),
                        r"solid\.mesh: nodes not used by any element: 12"),
        "nan_point": (meshio.Mesh(nan_points, [("hexahedron", hexes)]),
                      r"solid\.mesh: solid points: NaN or infinite coordinates at rows 3"),
        "inverted": (meshio.Mesh(box.points, [("hexahedron", np.vstack([hexes[0, [4, 5, 6, 7, 0, 1, 2, 3]], hexes[1]]))]),
                     r"solid\.mesh: inverted hexahedron elements .*: 0$"),
        "node_out_of_range": (meshio.Mesh(box.points, [("hexahedron", np.vstack([hexes[0], [0, 1, 2, 3, 4, 5, 6, 99]]))]),
                              r"solid\.mesh: solid cells 'hexahedron': node ids out of range \[0, 12\) in elements 1"),
    }


@pytest.mark.parametrize("case", ["empty", "boundary_only", "duplicate_nodes", "unused_node", "nan_point",
                                  "inverted", "node_out_of_range"])
def test_bad_solid_mesh_files(tmp_path, case):
    """Before: an empty .vtu raised numpy's ValueError from meshio; duplicate nodes (a crack
    between the two hexes) ran into a ConvergenceError after six cuts; an unused node made the
    error blame load[0].on ('solid:x_max' had no boundary face, the box was now the stray node's)."""
    mesh, message = _mesh_file_cases()[case]
    meshio.write(tmp_path / f"{case}.vtu", mesh)
    data = copy.deepcopy(BASE)
    data["solid"]["mesh"] = f"{case}.vtu"
    if case == "boundary_only":
        with pytest.warns(UserWarning, match="skipped lower-dimensional cells 2 quad"):
            expect_scene_error(write_scene(tmp_path, data), message)
    else:
        expect_scene_error(write_scene(tmp_path, data), message)


@pytest.mark.parametrize("content, suffix, message", [
    ("<VTKFile broken", ".vtu", r"solid\.mesh: cannot read mesh file .* \(malformed \.vtu file\)"),
    ("hello", ".xyz", r"solid\.mesh: cannot read mesh file .*ReadError"),
    ("", ".msh", r"solid\.mesh: cannot read mesh file"),
])
def test_unreadable_mesh_files(tmp_path, content, suffix, message):
    """meshio's XML reader calls sys.exit(1) on a malformed .vtu: before the fix the CLI process
    simply exited with code 1 (and pytest stopped)."""
    (tmp_path / f"mesh{suffix}").write_text(content)
    data = copy.deepcopy(BASE)
    data["solid"]["mesh"] = f"mesh{suffix}"
    expect_scene_error(write_scene(tmp_path, data), message)


@pytest.mark.parametrize("model, points, cells, message", [
    ("torsion_free", [[0.1, 0.1, 0.1], [0.1, 0.1, 0.1]], [[0, 1]],
     r"beams\[0\]: beam elements of zero length \(consecutive nodes coincide\): 0"),
    ("truss", [[0.1, 0.1, 0.1], [0.1, 0.1, 0.1]], [[0, 1]], r"beams\[0\]: zero-length beam elements: 0"),
    ("torsion_free", [[0.1, 0.1, 0.1], [0.5, 0.1, 0.1], [0.5, 0.1, 0.1], [0.9, 0.1, 0.1]], [[0, 1], [2, 3]],
     r"beams\[0\]: .* the line cells must form one chain"),
])
def test_bad_beam_mesh_files(tmp_path, model, points, cells, message):
    """Before: a zero-length element of a Hermite beam file divided by zero (numpy warning)."""
    meshio.write(tmp_path / "beam.vtu", meshio.Mesh(np.array(points, float), [("line", np.array(cells))]))
    data = copy.deepcopy(BASE)
    data["beams"][0] = {"mesh": "beam.vtu", "model": model, "section": {"E": 2e11, "radius": 0.01}}
    if model == "truss":
        data["dirichlet"][1] = {"on": "beam:0"}
    expect_scene_error(write_scene(tmp_path, data), message)


@pytest.mark.parametrize("kinematics", ["linear", "nonlinear"])
@pytest.mark.parametrize("model", ["torsion_free", "truss"])
@pytest.mark.parametrize("case, points, cells, message", [
    ("unused_node", [[0.05, 0.1, 0.1], [0.5, 0.1, 0.1], [0.95, 0.1, 0.1], [0.5, 0.15, 0.1]], [[0, 1], [1, 2]],
     r"nodes not used by any element: 3 \(remove them\)"),
    ("split_chain", [[0.05, 0.1, 0.1], [0.5, 0.1, 0.1], [0.5, 0.1, 0.1], [0.95, 0.1, 0.1]], [[0, 1], [2, 3]],
     r"beam ends at the same position: 1 and 2; the elements on either side are not connected"),
])
def test_beam_mesh_files_are_checked_like_solid_ones(tmp_path, case, points, cells, message, model, kinematics):
    """Before: an unused node ended the linear solve in scipy's 'Factor is exactly singular' and the
    nonlinear one in a ConvergenceError; a chain split at two coincident nodes was solved as two
    separate bars."""
    tangent = {"tangent": np.tile([1.0, 0.0, 0.0], (len(points), 1))}      # so that a split chain can be read
    meshio.write(tmp_path / "beam.vtu", meshio.Mesh(np.array(points, float), [("line", np.array(cells))],
                                                    point_data=tangent))
    data = copy.deepcopy(BASE)
    data["beams"][0] = {"mesh": "beam.vtu", "model": model, "section": {"E": 2e11, "radius": 0.01}}
    data["dirichlet"][1] = {"on": "beam:0:start"}
    data["analysis"]["kinematics"] = kinematics
    expect_scene_error(write_scene(tmp_path, data), r"^beams\[0\]\.mesh '.*beam\.vtu': " + message)


def test_fibres_crossing_at_a_node_are_not_duplicates(tmp_path):
    """Coincident nodes inside two chains are separate fibres crossing on purpose, not a split beam."""
    points = [[0.05, 0.1, 0.1], [0.5, 0.1, 0.1], [0.95, 0.1, 0.1], [0.5, 0.02, 0.1], [0.5, 0.1, 0.1], [0.5, 0.18, 0.1]]
    meshio.write(tmp_path / "cross.vtu", meshio.Mesh(np.array(points), [("line", np.array([[0, 1], [1, 2], [3, 4],
                                                                                            [4, 5]]))]))
    data = copy.deepcopy(BASE)
    data["beams"][0] = {"mesh": "cross.vtu", "model": "truss", "section": {"E": 2e11, "radius": 0.01}}
    data["dirichlet"][1] = {"on": "beam:0"}
    model = Model(Scene.from_dict(data, base_dir=tmp_path))
    assert model.groups[0].mesh.n_nodes == 6


# --------------------------------------------------------------------------------------------
# units mix-up: the bar given in millimetres, the solid in metres
# --------------------------------------------------------------------------------------------
def test_beam_outside_the_solid_because_of_units_warns_naming_the_beam(tmp_path):
    """Decision: a beam with no part inside the solid gets a CouplingWarning naming it (and
    suggesting the units), not an error, because a beam may legitimately lie outside (its own
    supports, or coupled later); if it is then unsupported the existing support check fails with
    a SceneError naming it. Either way nothing is solved silently."""
    data = copy.deepcopy(BASE)
    data["beams"][0]["curve"]["line"] = [[50.0, 100.0, 100.0], [950.0, 100.0, 100.0]]   # mm
    data["dirichlet"][1] = {"on": "beam:0:end"}        # a pinned end: the bar can still rotate
    path = write_scene(tmp_path, data)
    with pytest.warns(CouplingWarning, match=r"^beams\[0\]: no part of this beam lies inside the solid.*units"):
        with pytest.raises(SceneError, match=r"^dirichlet: beam 0 \(outside the solid, so not coupled\) can "
                                             r"move freely"):
            m13.solve(path)
    out = tmp_path / "out"
    with pytest.warns(CouplingWarning):
        assert cli_main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    # clamped, the stray bar is a valid (uncoupled) structure: solved, with the warning
    data["dirichlet"][1] = {"on": "beam:0:start", "clamp": True}
    with pytest.warns(CouplingWarning, match=r"beams\[0\]"):
        result = m13.solve(write_scene(tmp_path, data))
    assert np.abs(result.beam_displacement).max() < 1e-30 and np.abs(result.line_load).max() == 0.0


def test_a_beam_inside_the_solid_does_not_warn(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", CouplingWarning)
        m13.plan(write_scene(tmp_path, BASE))
        Model(Scene.from_dict(BASE)).prepare()


# --------------------------------------------------------------------------------------------
# nothing hangs: every run is bounded by steps, cuts and iterations
# --------------------------------------------------------------------------------------------
def test_a_hopeless_run_stops_after_a_bounded_number_of_iterations(tmp_path, monkeypatch):
    data = copy.deepcopy(BASE)
    data["load"][0]["value"] = [0.0, 0.0, -1e29]      # valid number, impossible load
    data["analysis"] = {"steps": 3, "max_iterations": 7, "max_cuts": 4}
    calls = []
    real = Model.residual
    monkeypatch.setattr(Model, "residual", lambda self, *a, **k: calls.append(1) or real(self, *a, **k))
    with pytest.raises(ConvergenceError, match="Try more load steps"):
        m13.solve(write_scene(tmp_path, data))
    # at most (cuts + 1) attempts of (max_iterations + 1) residuals per step
    assert 0 < len(calls) <= 3 * (4 + 1) * (7 + 1)


def test_cli_run_of_a_bad_scene_exits_2_and_writes_nothing(tmp_path):
    data = copy.deepcopy(BASE)
    data["beams"][0]["section"]["radius"] = -0.01
    path = write_scene(tmp_path, data)
    out = tmp_path / "results"
    proc = subprocess.run([sys.executable, "-m", "mortar1d3d.cli", "run", str(path), "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("error: beams[0].section.radius: expected a number > 0")
    assert "Traceback" not in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


# --------------------------------------------------------------------------------------------
# fuzzed scene files (hypothesis, bounded derandomized profile in make test)
# --------------------------------------------------------------------------------------------
PATHS = list(leaves(BASE))
BAD_VALUES = [1e308, -1e308, math.inf, -math.inf, math.nan, 10 ** 400, 1e-308, -1, 0, -0.5, "", "x",
              [], {}, True, [1.0, 2.0], {"box": 1}]


@st.composite
def mutated_scenes(draw):
    """BASE with 1-3 mutations: drop an entry, replace it with an adversarial value, negate a
    number, duplicate a list entry, or move the bar's coordinates to millimetres."""
    data = copy.deepcopy(BASE)
    done = []
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(PATHS))
        node = data
        try:
            for key in path[:-1]:
                node = node[key]
            node[path[-1]]
        except (KeyError, IndexError, TypeError):
            continue            # an earlier mutation removed or replaced this entry
        action = draw(st.sampled_from(["drop", "replace", "negate", "duplicate", "millimetres"]))
        value = node[path[-1]]
        if action == "drop":
            del node[path[-1]]
        elif action == "replace":
            node[path[-1]] = copy.deepcopy(draw(st.sampled_from(BAD_VALUES)))
        elif action == "negate" and isinstance(value, (int, float)) and not isinstance(value, bool):
            node[path[-1]] = -value
        elif action == "duplicate" and isinstance(node, list):
            node.insert(path[-1], copy.deepcopy(value))
        elif action == "millimetres" and "beams" in data and isinstance(data["beams"], list) and data["beams"] \
                and isinstance(data["beams"][0], dict) and "curve" in data["beams"][0]:
            line = data["beams"][0]["curve"].get("line")
            if isinstance(line, list) and all(isinstance(p, list) for p in line):
                data["beams"][0]["curve"]["line"] = [[1000.0 * c if isinstance(c, float) else c for c in p]
                                                     for p in line]
        else:
            continue
        done.append((action, dotted(path)))
    return data, done


@settings(max_examples=max(settings.default.max_examples, 40))
@given(mutated_scenes())
def test_fuzzed_scene_files_fail_cleanly(tmp_path_factory, case):
    data, mutations = case
    directory = tmp_path_factory.mktemp("fuzz")
    path = write_scene(directory, data)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("ignore", CouplingWarning)
        try:
            result = m13.solve(path)
        except SceneError as exc:
            assert KEY_PATH.match(str(exc)), (mutations, str(exc))
            event(f"SceneError at {KEY_PATH.match(str(exc)).group(1)}")
            return
        except ConvergenceError as exc:       # a valid but unsolvable scene (e.g. a negated support value)
            assert "Try more load steps" in str(exc), (mutations, str(exc))
            event("ConvergenceError")
            return
    assert np.isfinite(result.z).all(), mutations
    event("solved")


def test_magnitude_bound_is_documented_in_the_message(tmp_path):
    data = copy.deepcopy(BASE)
    data["solid"]["material"]["E"] = 1e31
    message = expect_scene_error(write_scene(tmp_path, data), r"^solid\.material\.E: ")
    assert f"{MAX_MAGNITUDE:g}" in message and "check the units" in message
