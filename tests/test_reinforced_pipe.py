"""The reinforced pipe example (issue 19 item 6), reduced: Lamé convergence of the unreinforced NURBS
pipe, the sign change of the axial strain across the netting angle, and the scene file."""
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13
from example_modules import load_example


@pytest.fixture(scope="module")
def pipe():
    return load_example("reinforced_pipe")


@pytest.fixture(scope="module")
def quick(pipe, tmp_path_factory):
    return pipe.main(["--quick", "--no-vtu", "--out", str(tmp_path_factory.mktemp("pipe"))])


def test_lame_errors_fall_at_the_quadratic_rate(quick):
    lame = np.array([row[2:4] + row[5:7] for row in quick["lame"]])      # [level, (C0 in, out, C1 in, out)]
    # measured: n = 1: 4.07e-3 | 4.58e-3 (both spaces), n = 2: 1.41e-4 | 1.52e-4 (C0), 1.40e-4 | 1.52e-4 (C1)
    assert np.allclose(lame[0], [4.07e-3, 4.58e-3, 4.07e-3, 4.58e-3], rtol=5e-3)
    assert np.allclose(lame[1], [1.41e-4, 1.52e-4, 1.40e-4, 1.52e-4], rtol=1e-2)
    assert (np.log2(lame[0] / lame[1]) > 4.5).all()


def test_lame_errors_of_cubic_spans(quick):
    """p-refinement: the same exact geometry degree-elevated to cubic (``pipe.degree = 3``, nurbs64)."""
    cubic = np.array([row[2:4] + row[5:7] for row in quick["lame_by_degree"][3]])
    quadratic = np.array([row[2:4] + row[5:7] for row in quick["lame_by_degree"][2]])
    # measured: n = 1: 4.36e-4 | 4.22e-4 (both spaces); n = 2: 5.79e-5 | 5.12e-5 (C0), 2.96e-5 | 3.09e-5 (C2),
    # with 6 × 6 points on the cubic faces' pressure (with 4 × 4: 3.10e-4 | 4.12e-4 and 7.83e-5 | 7.37e-5,
    # 4.23e-5 | 4.38e-5: the pressure's own error of about 3e-5 of the load shifted them)
    assert np.allclose(cubic[0], [4.36e-4, 4.22e-4, 4.36e-4, 4.22e-4], rtol=1e-2)
    assert np.allclose(cubic[1], [5.79e-5, 5.12e-5, 2.96e-5, 3.09e-5], rtol=1e-2)
    assert (cubic < quadratic).all()
    assert [row[1] for row in quick["lame_by_degree"][3]] == [192, 672]          # nurbs64 nodes: (3n+1)·12n·4


def test_lame_errors_of_quartic_spans(pipe, quick):
    """p-refinement to degree 4 (``pipe.degree = 4``, nurbs125 spans) on the same exact geometry."""
    rows = pipe.lame_study((1, 2), degree=4)
    quartic = np.array([row[2:4] + row[5:7] for row in rows])
    cubic = np.array([row[2:4] + row[5:7] for row in quick["lame_by_degree"][3]])
    # measured (examples/reinforced_pipe.py --lame): n = 1: 5.28e-4 | 4.92e-4 (both spaces, one span
    # radially: a little above the cubic 4.36e-4 | 4.22e-4, pre-asymptotic); n = 2: 6.82e-7 | 7.96e-7 (C0),
    # 2.43e-7 | 2.20e-7 (C3); at n = 4 and 8 the C0 errors are 4.2e-9 and 5.0e-11
    assert np.allclose(quartic[0], [5.28e-4, 4.92e-4, 5.28e-4, 4.92e-4], rtol=1e-2)
    assert np.allclose(quartic[1], [6.82e-7, 7.96e-7, 2.43e-7, 2.20e-7], rtol=2e-2)
    assert (cubic[1] / quartic[1] > 50.0).all()
    assert [row[1] for row in rows] == [400, 1440]          # nurbs125 nodes: (4n+1)·16n·5


def test_axial_strain_changes_sign_below_the_netting_angle(quick, pipe):
    rows = {r["angle"]: r for r in quick["rows"]}
    # pinned (1 × 8 × 4 spans, 4 fibres per family, E_f / E_m = 1000)
    assert rows[35]["strain"] == pytest.approx(-7.113e-4, rel=2e-3)
    assert rows[55]["strain"] == pytest.approx(1.833e-4, rel=2e-3)
    assert rows[75]["strain"] == pytest.approx(1.943e-3, rel=2e-3)
    # the fibres stiffen the hoop direction more the flatter they wind
    assert rows[35]["radial"] > rows[55]["radial"] > rows[75]["radial"]
    assert quick["plain"]["radial"] > rows[35]["radial"]
    assert quick["plain"]["strain"] > 0                         # the matrix alone lengthens the pipe
    assert all(r["coupled"] == pytest.approx(1.0, abs=1e-9) for r in quick["rows"])
    crossing = quick["crossings"][1000]
    assert crossing == pytest.approx(50.90, abs=0.05)
    assert 45.0 < crossing < pipe.NETTING_ANGLE


def test_zero_crossing_interpolation(pipe):
    assert pipe.zero_crossing([10, 20, 30], [-2.0, -1.0, 1.0]) == pytest.approx(25.0)
    assert pipe.zero_crossing([10, 20], [1.0, 2.0]) is None
    # a soft family's low-angle change (lengthening to shortening) is not the one reported
    assert pipe.zero_crossing([10, 20, 30, 40], [1.0, -1.0, -1.0, 3.0]) == pytest.approx(32.5)
    assert pipe.NETTING_ANGLE == pytest.approx(54.7356, abs=1e-4)
    assert pipe.NETTING_ANGLE_WALL == pytest.approx(56.0122, abs=1e-3)


def test_scene_file_is_the_example_at_the_netting_angle(pipe):
    path = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "reinforced_pipe.toml"
    result = m13.solve(m13.Scene.from_toml(path))
    m = pipe.measures(result, 1e9 * np.pi * pipe.FIBRE_RADIUS ** 2)
    plain = pipe.measures(m13.solve(pipe.pipe_scene(None)))
    # at the netting angle the axial strain is a small fraction of the unreinforced pipe's
    assert abs(m["strain"]) < 0.15 * plain["strain"], (m, plain)
    assert m["radial"] < 0.25 * plain["radial"]
    assert sum(result.coupled_length) == pytest.approx(sum(result.beam_length), rel=1e-9)
