"""Every scene file in examples/scenes/ is valid and plans (its sets resolve, its supports hold);
the small ones also solve to the figures their comments describe."""
import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13

SCENES = sorted((Path(__file__).resolve().parent.parent / "examples" / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_scene_file_plans(path):
    effects = m13.plan(m13.Scene.from_toml(path))
    assert any(e.name == "solid.mesh" for e in effects)


def test_pullout_line_load_grows_towards_the_loaded_end():
    result = m13.solve(m13.Scene.from_toml(SCENES[0].parent / "lagrange_pullout.toml"))
    lam = result.line_load[:, 0]
    # 7 LM nodes; the last lies outside the block (κ = 0): λ = 0 there. Measured λ_x:
    # 2857, -48, 976, 1144, 1347, 8524, 0 N/m: growing towards the loaded end, a peak at each end
    assert lam[-1] == 0.0 and lam[5] == pytest.approx(8524, rel=1e-3) and lam[0] == pytest.approx(2857, rel=1e-3)
    assert lam[2] < lam[3] < lam[4] < lam[5]
    # the multipliers carry the whole pull-out force: ∫ λ ds = Σ κ_j λ_j = 1e3 N
    kappa = result.model.groups[0].operators.kappa
    assert float(kappa @ lam) == pytest.approx(1e3, rel=1e-9)


def end_twist(result):
    """Rotation about x of the free end's corner (1, 0.1, 0.1) of the twisted_fibre block."""
    X, u = result.model.solid_mesh.points, result.solid_displacement
    corner = np.flatnonzero(np.all(np.isclose(X, [1.0, 0.1, 0.1]), axis=1))[0]
    x = X[corner] + u[corner]
    return float(np.arctan2(x[2], x[1]) - np.pi / 4)


def test_twisted_fibre_carries_torsion_only_with_rotational_coupling():
    """examples/scenes/twisted_fibre.toml against the same scene without [coupling.rotational]
    (a rotation support at the fibre's start instead). Measured: end twist 0.12637 rad against
    0.25331 rad; the fibre's torque in its middle 0.67 kN m of the 1.2 kN m applied; the line
    moments (rotational multipliers) integrate to zero over the fibre (no moment acts on it from
    outside the block), peaking at its ends (45.2 and -30.0 kN m/m)."""
    path = SCENES[0].parent / "twisted_fibre.toml"
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    result = m13.solve(m13.Scene.from_dict(data, base_dir=path.parent))
    assert result.counts["coupling.rotational_lagrange"] > 0
    assert end_twist(result) == pytest.approx(0.12637, rel=1e-4)
    g = result.model.groups[0]
    torque = g.physics.sample(result.z[g.dofs.slice], result.z[g.rotations.slice].reshape(-1, 3),
                              np.array([0.0]))["M"][:, 0, 0]
    assert np.all((torque[:6] > 660.0) & (torque[:6] < 680.0))
    lam = result.line_moment
    assert lam.shape == (17, 3) and lam[0, 0] == pytest.approx(45177, rel=1e-3)
    assert lam[8, 0] == pytest.approx(-29963, rel=1e-3)
    assert abs(g.rotational.kappa @ lam[:, 0]) < 1e-9 * np.abs(lam).max()
    plain = copy.deepcopy(data)
    del plain["coupling"]["rotational"]
    plain["dirichlet"].append({"on": "beam:0:start", "rotation": [0, 0, 0]})
    without = m13.solve(m13.Scene.from_dict(plain, base_dir=path.parent))
    assert end_twist(without) == pytest.approx(0.25331, rel=1e-4)
    assert without.line_moment.shape == (0, 3)
