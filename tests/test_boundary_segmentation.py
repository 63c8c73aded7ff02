"""``integration = "element_boundary"``: element-based integration points, except on the beam
elements that cross the solid's boundary, which get Gauss points on their part inside only."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.scene import Scene


def _beam(x0, length, elements, y=0.5, z=0.5):
    return generate.straight_beams([[[x0, y, z], [x0 + length, y, z]]], elements)


def _dense(ops):
    return ops.D.toarray(), ops.M.toarray(), ops.kappa


def test_exact_integrals_of_a_beam_that_leaves_the_solid():
    """One unit hex8, a straight beam of two elements from x = 0.2 to 1.4: the second element
    leaves at x = 1 (η = -1/3). Line2 multipliers: κ = ∫Φ ds over the part inside, in closed form
    (0.3, 0.3 + 0.2 - 0.2²/1.2, 0.2²/1.2); D and M equal segment-based integration, which is
    exact here (polynomial integrands in one affine element)."""
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams = _beam(0.2, 1.2, 2)
    ops = m13.assemble_mortar(beams, solid, integration="element_boundary", lm="line2")
    np.testing.assert_allclose(ops.kappa, [0.3, 0.5 - 0.04 / 1.2, 0.04 / 1.2], rtol=1e-14)
    assert ops.embedded_length == pytest.approx(0.8, rel=1e-14)
    assert ops.diagnostics["boundary_segmented_elements"] == 1
    for got, exact in zip(_dense(ops), _dense(m13.assemble_mortar(beams, solid, integration="segment", lm="line2"))):
        np.testing.assert_allclose(got, exact, rtol=0, atol=1e-15)
    # the inside element keeps its element-based points (6 on the whole element)
    p = ops.points
    np.testing.assert_allclose(p["eta"][p["beam_element"] == 0], np.polynomial.legendre.leggauss(6)[0], atol=1e-15)
    # plain element-based integration drops the points outside and so misses the integral
    plain = m13.assemble_mortar(beams, solid, integration="element", lm="line2")
    assert abs(plain.kappa[2] - 0.04 / 1.2) > 1e-3


@pytest.mark.parametrize("cells", [(1, 1, 1), (2, 2, 2)])
def test_continuous_as_the_beam_is_shifted_across_the_boundary(cells):
    """A beam of two elements (0.3 each) slid along x out of the unit cube: the embedded length
    is exact for every shift, and D, M, κ change by O(shift) between neighbouring shifts, also
    where the boundary passes between the outermost Gauss point and the element's end (4C's own
    criterion, a Gauss point outside, switches there; a point test on the ends as well keeps it
    continuous). Plain element-based integration jumps by a Gauss weight there."""
    solid = generate.box((0, 0, 0), (1, 1, 1), cells)
    shifts = np.linspace(0.2, 0.9, 141)
    step = shifts[1] - shifts[0]
    for integration, continuous in (("element_boundary", True), ("element", False)):
        previous, jumps = None, []
        for x0 in shifts:
            ops = m13.assemble_mortar(_beam(x0, 0.6, 2, y=0.3, z=0.35), solid, integration=integration, lm="line2")
            now = _dense(ops)
            if continuous:
                assert ops.embedded_length == pytest.approx(min(x0 + 0.6, 1.0) - x0, rel=1e-13, abs=1e-15)
            if previous is not None:
                jumps.append(max(np.abs(a - b).max() for a, b in zip(now, previous)))
            previous = now
        if continuous:
            assert max(jumps) < 2.5 * step
        else:
            assert max(jumps) > 5 * step


def test_inside_beams_keep_the_element_based_points():
    """Nothing leaves the solid: the points are those of element-based integration, bit for bit."""
    solid = generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2)), amplitude=0.05)
    beams = generate.random_curved_beams(3, 4, seed=3, lower=(0.2, 0.2, 0.2), upper=(0.8, 0.8, 0.8))
    ops = m13.assemble_mortar(beams, solid, integration="element_boundary")
    ref = m13.assemble_mortar(beams, solid, integration="element")
    assert ops.diagnostics["boundary_segmented_elements"] == 0
    for a, b in zip(_dense(ops), _dense(ref)):
        np.testing.assert_array_equal(a, b)


def test_scene_accepts_element_boundary_and_plans_the_segmentation():
    data = {"solid": {"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 1]},
                      "material": {"model": "saint_venant_kirchhoff", "E": 1.0, "nu": 0.3}},
            "beams": [{"curve": {"line": [[0.2, 0.5, 0.5], [1.4, 0.5, 0.5]]}, "elements": 2,
                       "section": {"E": 1.0, "radius": 0.01}}],
            "dirichlet": [{"on": "solid:x_min"}],
            "coupling": {"constraint": "gauss_point", "integration": "element_boundary", "penalty": 10.0}}
    details = {e.name: e.detail for e in m13.plan(Scene.from_dict(data))}
    assert "cross the solid's boundary" in details["mortar.segmentation"]
