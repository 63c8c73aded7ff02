"""Every scene file in examples/scenes/ is valid and plans (its sets resolve, its supports hold);
the two small ones also solve to the figures their comments describe."""
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
