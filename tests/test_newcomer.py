"""What a newcomer tripped over (issue 21, item 3): the cold-cache note, fibre ids and arc length in
the beam VTU, segments and points that move with the beams, coupled length per beam and its
warning, fibre generators and [[fibres]] arrays, the plan table, --version, the demo's overwrite
note and the patch test's closing line."""
import io
import re
from pathlib import Path

import meshio
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import _config, generate
from mortar1d3d.cli import main as cli_main
from mortar1d3d.errors import CouplingWarning
from mortar1d3d.io.vtu import beam_fibres, displacement_coefficients, write_beams, write_integration_points, \
    write_segments

from example_modules import load_example as _example


# -- first run: say that the kernels compile, only when the cache is cold ------------------------

def test_cold_cache_is_announced_once_and_only_when_cold(monkeypatch):
    monkeypatch.delenv("MORTAR1D3D_QUIET_COMPILE", raising=False)
    monkeypatch.setattr(_config, "_announced", False)
    monkeypatch.setattr(_config, "CACHE_WAS_COLD", True)
    out = io.StringIO()
    assert _config.announce_compilation(out) is True
    assert _config.announce_compilation(out) is False          # once per process
    text = out.getvalue()
    assert text.count("\n") == 1 and "compiling the Numba kernels" in text and "minutes" in text
    monkeypatch.setattr(_config, "_announced", False)
    monkeypatch.setattr(_config, "CACHE_WAS_COLD", False)
    quiet = io.StringIO()
    assert _config.announce_compilation(quiet) is False and quiet.getvalue() == ""


def test_cold_cache_is_detected_from_the_cache_directory(tmp_path):
    assert _config.cached_kernel_files(tmp_path) == 0
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "kernel-1.py311.nbi").write_bytes(b"")
    (tmp_path / "sub" / "kernel-1.py311.1.nbc").write_bytes(b"")
    assert _config.cached_kernel_files(tmp_path) == 1


def test_patch_test_mentions_compilation_only_when_something_compiled():
    line = _example("patch_test").run_time_line
    assert line(2.04, 0) == "run time 2.0 s (kernels loaded from the cache)"
    assert "compilation" not in line(2.0, 0)
    assert line(95.0, 37) == "run time 95.0 s (including Numba compilation of 37 kernels on a cold cache)"


# -- beam VTU: fibres and their arc length; segments and points with the displacement ------------

def _two_fibres():
    ends = np.array([[[0.1, 0.2, 0.3], [0.9, 0.2, 0.3]], [[0.5, 0.1, 0.1], [0.5, 0.7, 0.9]]])
    return generate.straight_beams(ends, 3), np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)


def test_beam_fibres_number_chains_and_add_up_their_lengths():
    beams, lengths = _two_fibres()
    fibre, start = beam_fibres(beams)
    assert fibre.tolist() == [0, 0, 0, 1, 1, 1]
    np.testing.assert_allclose(start, np.r_[np.arange(3) * lengths[0] / 3, np.arange(3) * lengths[1] / 3],
                               rtol=1e-14, atol=1e-15)


def test_beam_vtu_arc_length_runs_along_each_fibre(tmp_path):
    beams, lengths = _two_fibres()
    mesh = meshio.read(write_beams(tmp_path / "b.vtu", beams, 5))
    fibre, arc = mesh.point_data["fibre"], mesh.point_data["arc_length"]
    for f in (0, 1):
        a = arc[fibre == f]
        assert a[0] == 0.0 and np.all(np.diff(a) >= -1e-14)      # no restart at element ends (round-off)
        assert a[-1] == pytest.approx(lengths[f], rel=1e-13)
    assert mesh.point_data["element_arc_length"].max() == pytest.approx(lengths.max() / 3, rel=1e-13)


def test_segments_and_points_carry_the_beam_displacement(tmp_path):
    """u = A x, applied to the Hermite positions and tangents, is interpolated exactly: the written
    displacement at every segment sample and integration point is A times its reference position."""
    beams, solid = generate.fibre_cube(2, 2, 3, curved=True)
    ops = m13.assemble_mortar(beams, solid, n_gauss=3)
    A = np.array([[0.1, -0.2, 0.05], [0.3, 0.0, -0.1], [0.02, 0.4, 0.2]])
    d = np.empty((beams.n_nodes, 6))
    d[:, :3], d[:, 3:] = beams.positions @ A.T, beams.tangents @ A.T
    u = displacement_coefficients(beams, d.ravel())
    seg = meshio.read(write_segments(tmp_path / "s.vtu", beams, ops, displacement=u))
    np.testing.assert_allclose(seg.point_data["displacement"], seg.points @ A.T, atol=1e-13)
    pts = meshio.read(write_integration_points(tmp_path / "p.vtu", ops, beams=beams, displacement=u))
    np.testing.assert_allclose(pts.point_data["displacement"], pts.points @ A.T, atol=1e-13)


# -- coupled length per beam and the warning for a partly uncoupled beam -------------------------

def _scene(beams):
    return m13.Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 0.4, 0.4]], "cells": [2, 1, 1]},
                            "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                     beams=[{"curve": {"line": line}, "elements": 4, "section": {"EA": 1.0, "EI": 0.01}}
                            for line in beams],
                     dirichlet=[{"on": "solid:x_min"}], load=[{"type": "pressure", "on": "solid:x_max", "value": 1e-3}],
                     analysis={"kinematics": "linear"})


def test_a_beam_half_outside_the_solid_warns_and_reports_its_coupled_length(recwarn):
    scene = _scene([[[0.1, 0.2, 0.2], [0.9, 0.2, 0.2]], [[0.5, 0.1, 0.1], [1.5, 0.1, 0.1]]])
    result = m13.solve(scene)
    messages = [str(w.message) for w in recwarn if issubclass(w.category, CouplingWarning)]
    assert len(messages) == 1 and messages[0].startswith("beams[1]: 50.0% of this beam (0.5 of length 1)")
    np.testing.assert_allclose(result.beam_length, [0.8, 1.0], rtol=1e-13)
    np.testing.assert_allclose(result.coupled_length, [0.8, 0.5], rtol=1e-12)
    summary = result.coupling_summary()
    assert summary[0].startswith("beams[1]: coupled length 0.5 of 1 (50.0%)")
    assert summary[-1] == "all 2 beams: coupled length 1.3 of 1.8 (72.2%); 1 partly or not coupled"


def test_cli_summary_lists_the_coupled_length(tmp_path, capsys):
    path = tmp_path / "half.toml"
    path.write_text("""
[solid]
mesh = { box = [[0, 0, 0], [1, 0.4, 0.4]], cells = [2, 1, 1] }
material = { model = "linear_elastic", E = 1.0, nu = 0.3 }
[[beams]]
curve = { line = [[0.5, 0.1, 0.1], [1.5, 0.1, 0.1]] }
elements = 4
section = { EA = 1.0, EI = 0.01 }
[[dirichlet]]
on = "solid:x_min"
[[load]]
type = "point"
on = "beam:0:end"
value = [0, 0, -1e-3]
[analysis]
kinematics = "linear"
""")
    with pytest.warns(CouplingWarning, match=r"beams\[0\]: 50.0% of this beam"):
        assert cli_main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "beams[0]: coupled length 0.5 of 1 (50.0%)" in capsys.readouterr().out
    files = sorted(p.name for p in (tmp_path / "out").iterdir())
    # segments and points at every step (reference state and the one step), so they move with the beams
    assert {"segments_0000.vtu", "segments_0001.vtu", "points_0000.vtu", "points_0001.vtu"} <= set(files)
    beams = meshio.read(tmp_path / "out" / "beams_0001.vtu")
    assert set(np.unique(beams.point_data["beam"])) == {0}
    assert beams.point_data["arc_length"].max() == pytest.approx(1.0, rel=1e-12)
    seg = meshio.read(tmp_path / "out" / "segments_0001.vtu")
    assert np.abs(seg.point_data["displacement"]).max() > 0.0


# -- generators ----------------------------------------------------------------------------------

def test_fibres_in_box_respect_box_lengths_orientation_and_spacing():
    lower, upper = np.array([1.0, -1.0, 0.0]), np.array([3.0, 0.0, 0.5])
    ends = generate.fibres_in_box(40, lower, upper, length={"uniform": [0.2, 0.4]},
                                  orientation={"direction": [1, 1, 0], "spread": 20.0}, min_spacing=0.03, seed=7)
    assert ends.shape == (40, 2, 3)
    assert (ends >= lower).all() and (ends <= upper).all()
    d = ends[:, 1] - ends[:, 0]
    L = np.linalg.norm(d, axis=1)
    assert L.min() >= 0.2 and L.max() <= 0.4
    cos = d @ np.array([1, 1, 0]) / (L * np.sqrt(2))
    assert cos.min() >= np.cos(np.radians(20.0)) - 1e-12
    s = np.linspace(0, 1, 201)
    samples = ends[:, :1] + s[None, :, None] * d[:, None]              # (40, 201, 3)
    for i in range(40):
        others = np.delete(samples, i, axis=0).reshape(-1, 3)
        assert np.linalg.norm(others[:, None] - samples[i][None], axis=2).min() >= 0.03 - 1e-12
    again = generate.fibres_in_box(40, lower, upper, length={"uniform": [0.2, 0.4]},
                                   orientation={"direction": [1, 1, 0], "spread": 20.0}, min_spacing=0.03, seed=7)
    assert np.array_equal(ends, again)


def test_fibres_in_box_say_when_they_do_not_fit():
    with pytest.raises(ValueError, match=r"placed \d+ of 50 fibres"):
        generate.fibres_in_box(50, [0, 0, 0], [1, 1, 1], length=0.9, orientation=[1, 0, 0], min_spacing=0.3,
                               max_attempts=20)


def test_segment_distances_against_sampling():
    rng = np.random.default_rng(3)
    s = np.linspace(0, 1, 1001)
    for k in range(40):
        p, q, a, b = rng.normal(size=(4, 3))
        if k % 4 == 0:
            b = a + 0.5 * (q - p)                                        # parallel
        brute = np.linalg.norm((p + s[:, None] * (q - p))[:, None] - (a + s[:, None] * (b - a))[None], axis=2).min()
        d = generate.segment_distances(p, q, a[None], b[None])[0]
        # sampling overestimates by at most half a sample spacing of each segment
        assert d <= brute + 1e-12 and brute - d < 5e-4 * (np.linalg.norm(q - p) + np.linalg.norm(b - a))
    # exact cases: crossing skew segments, a parallel offset, collinear end-to-end, a T
    p, q = np.array([-1.0, 0, 0]), np.array([1.0, 0, 0])
    a = np.array([[0.0, -1, 1], [-0.5, 0.3, 0.4], [1.5, 0, 0], [3.0, 2, 0]])
    b = np.array([[0.0, 1, 1], [0.5, 0.3, 0.4], [2.5, 0, 0], [3.0, -2, 0]])
    np.testing.assert_allclose(generate.segment_distances(p, q, a, b), [1.0, 0.5, 0.5, 2.0], rtol=1e-15)


def test_helices_on_a_cylinder_share_it_and_split_the_phase():
    helices = generate.helices_on_cylinder(4, [0.5, 0.5, 0.5], [0, 0, 2], 0.2, 0.8, 1.5, phase=0.1)
    np.testing.assert_allclose([h["phase"] for h in helices], 0.1 + np.arange(4) * np.pi / 2)
    beams = generate.helix_beams(helices, 12)
    radial = np.linalg.norm(beams.positions[:, :2] - 0.5, axis=1)
    np.testing.assert_allclose(radial, 0.2, rtol=1e-14)
    assert beams.n_elements == 48 and beams.positions[:, 2].min() == pytest.approx(0.1)


FIBRE_SCENE = """
[solid]
mesh = { box = [[0, 0, 0], [1, 1, 1]], cells = [2, 2, 2] }
material = { model = "neo_hooke", E = 1.0, nu = 0.3 }
[[beams]]
curve = { line = [[0.1, 0.5, 0.5], [0.9, 0.5, 0.5]] }
elements = 2
section = { E = 10.0, radius = 0.01 }
[[fibres]]
count = 50
box = [[0.1, 0.1, 0.1], [0.9, 0.9, 0.9]]
length = { normal = [0.3, 0.05] }
orientation = "isotropic"
min_spacing = 0.01
seed = 4
elements = 2
section = { E = 10.0, radius = 0.01 }
[[fibres]]
count = 3
cylinder = { centre = [0.5, 0.5, 0.5], axis = [0, 0, 1], radius = 0.3, length = 0.8, turns = 1 }
elements = 8
model = "truss"
section = { E = 10.0, radius = 0.01 }
"""


def test_fibres_in_a_scene_file_are_one_beam_each(tmp_path):
    path = tmp_path / "fibres.toml"
    path.write_text(FIBRE_SCENE)
    scene = m13.Scene.from_toml(path)
    assert len(scene.beams) == 54 and "54 beam(s)" in repr(scene)
    assert scene.fibres == [(1, 50), (51, 3)]
    assert all("line" in b["curve"] for b in scene.beams[1:51])
    assert [b["curve"]["helix"]["phase"] for b in scene.beams[51:]] == pytest.approx([0, 2 * np.pi / 3, 4 * np.pi / 3])
    assert m13.Scene.from_toml(path).beams[20]["curve"]["line"].tolist() == scene.beams[20]["curve"]["line"].tolist()
    effects = m13.plan(scene)
    assert [e.detail for e in effects if e.name == "beams.mesh"] == [
        "torsion_free: 51 beam(s), 102 hermite elements", "truss: 3 beam(s), 24 line elements"]


@pytest.mark.parametrize("change, message", [
    ("count = 0", "fibres[0].count: expected an integer in [1, 100000], got 0"),
    ("cylinder = { centre = [0, 0, 0], axis = [0, 0, 1], radius = 1, length = 1, turns = 1 }",
     "fibres[0]: give exactly one of box (random straight fibres) or cylinder (helices)"),
    ("length = { uniform = [0.4, 0.2] }", "fibres[0].length.uniform: expected 0 < a <= b"),
    ("orientation = \"random\"", "fibres[0].orientation: unknown value 'random'"),
    ("min_spacing = 0.5", "fibres[0]: fibres_in_box: placed"),
    ("section = { E = -1.0, radius = 0.01 }", "fibres[0].section.E: expected a number > 0"),
])
def test_fibre_array_errors_name_the_key(change, message):
    table = {"count": 20, "box": [[0, 0, 0], [1, 1, 1]], "elements": 2, "section": {"E": 1.0, "radius": 0.01}}
    import tomllib
    extra = tomllib.loads(change)
    table.update(extra)
    with pytest.raises(m13.SceneError) as info:
        m13.Scene(fibres=[table])
    assert str(info.value).startswith(message)


# -- plan table, --version, demo's overwrite note ------------------------------------------------

def test_plan_prints_as_a_table():
    effects = m13.plan(_scene([[[0.1, 0.2, 0.2], [0.9, 0.2, 0.2]]]))
    lines = str(effects).splitlines()
    assert re.fullmatch(r"effect +when +detail", lines[0]) and set(lines[1]) == {"-", " "}
    assert len(lines) == len(effects) + 2
    column = lines[0].index("when")
    for line, e in zip(lines[2:], effects):
        assert line.startswith(e.name) and line[column:].startswith(e.when)
    assert effects == list(effects)                     # still a list of Effect


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        cli_main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"mortar1d3d {m13.__version__}"


def test_demo_says_when_it_overwrites(tmp_path):
    note = _example("fibre_cube_demo").overwrite_note
    assert note(str(tmp_path / "new")) == f"writing to {tmp_path / 'new'}/"
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "fibre_cube.png").write_bytes(b"")
    assert "overwriting the 1 files of an earlier run" in note(str(tmp_path / "old"))


def test_the_scene_reference_fibres_example_builds():
    text = (Path(__file__).resolve().parent.parent / "docs" / "scene_reference.md").read_text()
    section = text[text.index("## `[[fibres]]`"):]
    block = section[section.index("```toml") + 7: section.index("```", section.index("```toml") + 7)]
    import tomllib
    data = tomllib.loads(block)
    scene = m13.Scene.from_dict({"solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [10, 2, 2]},
                                           "material": {"model": "linear_elastic", "E": 30e9, "nu": 0.2}}, **data})
    assert len(scene.beams) == 206 and scene.fibres == [(0, 200), (200, 6)]
