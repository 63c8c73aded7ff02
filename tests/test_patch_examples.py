"""examples/patch_test.py as regression tests: segment-based coupling passes the force and the
boundary-value patch tests to round-off, element-based integration fails them; every variant
passes the displacement patch test."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import mortar1d3d as m13

_path = Path(__file__).resolve().parent.parent / "examples" / "patch_test.py"
_spec = importlib.util.spec_from_file_location("patch_test_example", _path)
patch = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(patch)


def test_the_line_crosses_a_node_and_an_edge():
    # t = 0: grid node (1, 1, 1); t = 1: the interior edge u_x = 2, u_y = 3
    assert np.allclose(patch.P + 0 * patch.Q, [1, 1, 1])
    assert np.allclose((patch.P + patch.Q)[:2], [2, 3]) and 1 < (patch.P + patch.Q)[2] < 2
    assert patch.T0 < 0 < 1 < patch.T1


def test_exact_forces_are_consistent():
    """Independent integrator: total force = ∫λ ds and the first moment = ∫λ x ds (affine basis)."""
    beams, t_nodes = patch.beam_mesh()
    for kind in ("hexahedron", "tetra"):
        solid, _ = patch.solid_mesh(kind)
        a, b = patch.LOADS["linear"]
        fs, fb = patch.exact_forces(kind, a, b, t_nodes, solid.n_nodes)
        length = beams.length
        total = (a + 0.5 * b) * length
        assert np.allclose(-fs.sum(axis=0), total * patch.DIRECTION, rtol=1e-13)
        # Σ_a N_a x_a = x on the line: first moment ∫ λ x ds, with x linear in τ
        x0, x1 = beams.positions[0], beams.positions[-1]
        moment = length * (a * (x0 + x1) / 2 + b * (x0 / 6 + x1 / 3))
        assert np.allclose(-(fs[:, 0:1] / patch.DIRECTION[0] * solid.points).sum(axis=0), moment, rtol=1e-12)
        assert np.allclose(fb[:, :3].sum(axis=0), total * patch.DIRECTION, rtol=1e-13)


@pytest.mark.parametrize("kind", ["hexahedron", "tetra"])
def test_force_patch_segment_exact_element_not(kind):
    beams, t_nodes = patch.beam_mesh()
    solid, _ = patch.solid_mesh(kind)
    seg = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=6)
    # measured: hex8 1.9e-16 / 2.4e-16, tet4 ~6e-16 (solid); beam ~1e-16
    element_errors = {}
    for load, (a, b) in patch.LOADS.items():
        exact = patch.exact_forces(kind, a, b, t_nodes, solid.n_nodes)
        es, eb = patch.force_errors(seg, kind, a, b, t_nodes, exact)
        assert es < 1e-14 and eb < 1e-14, (load, es, eb)
        element_errors[load] = [patch.force_errors(
            m13.assemble_mortar(beams, solid, integration="element", n_gauss=n), kind, a, b, t_nodes, exact)[0]
            for n in (2, 8, 32)]
    # element-based: far from round-off, falling slowly with the number of Gauss points
    # (measured hex8 constant: 6.0e-2, 7.4e-3, 4.9e-4; tet4: 2.5e-2, 3.6e-3, 1.2e-4)
    for load, e in element_errors.items():
        assert e[0] > 1e-2 and e[2] > 1e-5, (load, e)
        assert e[0] > e[1] > e[2], (load, e)


def test_displacement_patch_every_variant():
    rows = patch.displacement_patch_test(elements=("hexahedron", "tetra", "hexahedron27"))
    assert len(rows) == 3 * 2 * 4
    worst = max(rows.values())
    assert worst < 1e-14, rows          # measured max 5.5e-16


@pytest.mark.parametrize("kind", ["hexahedron", "tetra"])
def test_boundary_value_patch_segment_exact_element_fails(kind):
    seg = patch.boundary_value_patch_test(kind, "segment", 6)
    # measured: hex8 solid 1.2e-14, beam 2.4e-14, λ 7e-12; tet4 3e-15, 1.4e-14, 5e-12
    assert seg["solid"] < 1e-12 and seg["beam"] < 1e-12 and seg["lambda"] < 1e-9, seg
    el = patch.boundary_value_patch_test(kind, "element", 6)
    # measured: hex8 solid 5.7e-5, λ 7.2e-3; tet4 2.0e-5, 3.3e-3
    assert el["solid"] > 1e-6 and el["lambda"] > 1e-4, el
