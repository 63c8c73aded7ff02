"""The assembled operators against a slow point-by-point reference (tests/naive.py)."""
import numpy as np
import pytest

import mortar1d3d as m13
from naive import operators_from_points


@pytest.mark.parametrize("lm", ["line2", "line3", "line4"])
@pytest.mark.parametrize("integration", ["segment", "element"])
@pytest.mark.parametrize("element", ["hexahedron", "tetra10"])
def test_operators_equal_naive_sum(lm, integration, element):
    beams, _ = m13.generate.fibre_cube(3, 4, 6, curved=True)
    solid = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), element), 0.1, seed=3)
    ops = m13.assemble_mortar(beams, solid, integration=integration, lm=lm, n_gauss=8)
    D, M, kappa = operators_from_points(beams, solid, ops)
    Dd, Md = ops.D.toarray(), ops.M.toarray()
    for i in range(3):
        # every scalar entry is a 3×3 identity block: rows 3j+i, columns 3c+i
        np.testing.assert_allclose(Dd[i::3, i::3], D, rtol=0, atol=1e-15)
        np.testing.assert_allclose(Md[i::3, i::3], M, rtol=0, atol=1e-15)
        for k in range(3):
            if k != i:
                assert not Dd[i::3, k::3].any() and not Md[i::3, k::3].any()
    np.testing.assert_allclose(ops.kappa, kappa, rtol=0, atol=1e-15)
    if integration == "segment":
        # Σκ integrates |r0'| with 8 points per segment; L uses 10 points per element
        assert ops.embedded_length == pytest.approx(ops.beam_length, rel=1e-6)
        assert ops.diagnostics["points_outside_element"] == 0
