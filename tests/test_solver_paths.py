"""Round-off far from the origin (issue 16, part 4)."""
import tomllib
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.mesh import BeamMesh
from mortar1d3d.physics.beam import BeamModel
from mortar1d3d.scene import Scene

EPS = np.finfo(float).eps
SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"


def _rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


# --------------------------------------------------------------------------------------------
# far from the origin
# --------------------------------------------------------------------------------------------
def test_beam_forces_do_not_see_the_distance_from_the_origin():
    """Forces at a rigidly translated state equal those at the original state: to 5e-14 at the
    origin and (formerly 7e-11, r'' from absolute positions) 1e5 away from it."""
    direction = np.array([1.0, 2.0, 2.0]) / 3
    diffs = []
    for shift in (0.0, 1e5):
        points = shift + np.outer(np.linspace(0, 1, 9), direction)
        mesh = BeamMesh.hermite(points, np.tile(direction, (9, 1)), np.column_stack([np.arange(8), np.arange(1, 9)]))
        beam = BeamModel(mesh, EA=1e8, EI=1e2)
        d = 1e-4 * np.random.default_rng(0).standard_normal(beam.n_dofs)
        moved = d.copy()
        moved.reshape(-1, 6)[:, :3] += [0.3, -0.2, 0.1]           # positions move, tangents do not
        f, _ = beam.evaluate(d)
        g, _ = beam.evaluate(moved)
        diffs.append(np.abs(g - f).max() / np.abs(f).max())
    assert diffs[1] <= 10 * diffs[0]


@pytest.mark.parametrize("enforcement", ["lagrange", "penalty"])
def test_nonlinear_cantilever_far_from_the_origin_converges_as_at_the_origin(enforcement):
    """examples/scenes/rebar_cantilever.toml moved by 1e5 m: Lagrange multipliers stalled at a
    residual of 8.5e-5 (target 1.2e-6) and gave up. Now every step converges as at the origin and
    the answers differ by what representing the coordinates costs (eps 1e5 / h = 2.2e-10)."""
    base = tomllib.loads((SCENES / "rebar_cantilever.toml").read_text())
    results = []
    for shift in (0.0, 1e5):
        data = tomllib.loads((SCENES / "rebar_cantilever.toml").read_text())
        data["solid"]["mesh"]["box"] = [[v + shift for v in p] for p in base["solid"]["mesh"]["box"]]
        data["beams"][0]["curve"]["line"] = [[v + shift for v in p] for p in base["beams"][0]["curve"]["line"]]
        data["coupling"]["enforcement"] = enforcement
        results.append(m13.solve(Scene.from_dict(data)))
    near, far = results
    h = 0.1
    scale = EPS * 1e5 / h
    assert len(far.steps) == len(near.steps) == 4 and all(s.cuts == 0 for s in far.steps)
    assert [s.iterations for s in far.steps] == [s.iterations for s in near.steps]
    assert _rel(far.solid_displacement, near.solid_displacement) < 10 * scale       # measured 0.4x
    assert _rel(far.beam_displacement, near.beam_displacement) < 10 * scale         # measured 0.3x
    assert _rel(far.line_load, near.line_load) < 100 * scale                        # measured 10x
