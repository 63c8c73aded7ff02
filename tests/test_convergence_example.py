"""examples/convergence.py, reduced: levels h_S = 1/4, 1/8, 1/16 (reference 1/32 would take longer).

Asserts the measured convergence of mortar coupling (both integrations agree and converge at
rate > 1.3 in the solid and on the beam for every ratio h_B/h_S), and the stiffening of
point-wise (Gauss-point) penalty coupling when beam elements are long compared with solid
elements (h_B/h_S >= 1 here: six penalty points per segment on a linear beam over-constrain
the trilinear solid).
"""
import importlib.util
from pathlib import Path

import numpy as np

_path = Path(__file__).resolve().parent.parent / "examples" / "convergence.py"
_spec = importlib.util.spec_from_file_location("convergence_example", _path)
conv = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(conv)


def test_reduced_convergence_rates_and_point_wise_stiffening():
    out = conv.run(levels=(4, 8, 16), ratios=(0.5, 2.0), variants=("mortar segment", "mortar element",
                                                                    "gauss-point penalty"), verbose=False)
    for ratio in (0.5, 2.0):
        seg = out["errors"][("mortar segment", ratio)]
        el = out["errors"][("mortar element", ratio)]
        for k in (0, 1):                        # solid, beam centreline
            rate = np.log2(seg[k][0] / seg[k][1])
            assert 1.3 < rate < 2.5, (ratio, k, seg)
            # element-based integration is not exact but converges the same way
            assert np.allclose(el[k], seg[k], rtol=2e-2), (ratio, k, seg, el)
    # measured (reference h_S = 1/16): mortar rates 1.58 / 1.56 (h_B/h_S = 1/2), 1.73 / 1.70 (2);
    # Gauss-point penalty errors twice as large, rates 0.93 and 0.71
    for ratio in (0.5, 2.0):
        seg = out["errors"][("mortar segment", ratio)]
        gp = out["errors"][("gauss-point penalty", ratio)]
        assert (gp[0] > 1.8 * seg[0]).all() and np.log2(gp[0][0] / gp[0][1]) < np.log2(seg[0][0] / seg[0][1]) - 0.4
    # tip deflection at h_S = 1/8: mortar hardly depends on the ratio; Gauss-point penalty with
    # long beam elements is stiffer than with short ones
    mortar = [out["tip"][("mortar segment", r, 8)] for r in (0.5, 2.0)]
    point = [out["tip"][("gauss-point penalty", r, 8)] for r in (0.5, 2.0)]
    assert abs(mortar[0] / mortar[1] - 1) < 0.05, mortar
    assert point[1] < 0.97 * mortar[1], (point, mortar)
