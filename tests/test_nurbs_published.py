"""A published number of 4C for NURBS27 (issue 19): the segment of a curved Hermite line inside a 90°
hollow-cylinder NURBS27 element.

Source (facts only; 4C, github 4C-multiphysics/4C, LGPL-3.0): the unit test
``GeometryPairLineToVolumeSegmentationTest.TestMultipleIntersectionsNurbs27`` in
``unittests/geometry_pair/4C_geometry_pair_line_to_volume_segmentation_test.cpp`` (commit 08402d47),
geometry from ``xtest_multiple_intersections_nurbs27_geometry`` in
``unittests/geometry_pair/4C_geometry_pair_line_to_volume_segmentation_geometry_functions_test.hpp``
(commit 7f7e2264):

* the solid: one NURBS27 element, knots [0, 0, 0, 1, 1, 1] in each direction, 27 control points listed
  with the first direction fastest: around the arc from (0, r) to (r, 0) (middle point (r, r), weight
  0.707107 as written there, the others 1), r = 0.1, 0.15, 0.2 in the second direction, z = 0, 0.15,
  0.3 in the third (a 90° sector of the hollow cylinder with radii 0.1 / 0.2, height 0.3);
* the line: one cubic Hermite element from (-0.05, 0.05, 0.3), unit tangent (1, 1, 1)/√3, to
  (0.45, -0.05, 0.1), unit tangent (0.8017837257372733, -0.5345224838248488, 0.2672612419124244),
  reference length 0.61920435714496047108;
* 4C's result: one segment, η from -0.40769440465702655 to -0.0090552523537554153, checked there to
  ``projection_xi_eta_tol``.
"""
import numpy as np

import mortar1d3d as m13
from mortar1d3d import nurbs
from mortar1d3d.mesh import BeamMesh

ETA_4C = (-0.40769440465702655, -0.0090552523537554153)
LENGTH_4C = 0.61920435714496047108


def sector():
    """The NURBS27 element of 4C's test as a library patch (net index [circumferential, radial, axial])."""
    arc = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0]])
    control = np.empty((3, 3, 3, 3))
    weights = np.empty((3, 3, 3))
    for a in range(3):
        for b, r in enumerate((0.1, 0.15, 0.2)):
            for c, z in enumerate((0.0, 0.15, 0.3)):
                control[a, b, c] = [r * arc[a, 0], r * arc[a, 1], z]
                weights[a, b, c] = 0.707107 if a == 1 else 1.0
    knots = (np.array([0.0, 0, 0, 1, 1, 1]),) * 3
    return nurbs.NurbsSolid([nurbs.NurbsPatch(control, weights, knots, (2, 2, 2))])


def line():
    t1 = np.array([0.8017837257372733, -0.5345224838248488, 0.2672612419124244])
    return BeamMesh("hermite", [[-0.05, 0.05, 0.3], [0.45, -0.05, 0.1]], [[0, 1]],
                    tangents=[np.full(3, 1 / np.sqrt(3)), t1])


def test_hermite_line_through_a_90_degree_nurbs27_sector_gives_4c_segment():
    beam = line()
    assert abs(beam.lengths[0] - LENGTH_4C) < 1e-12          # the same reference length (arc length)
    ops = m13.assemble_mortar(beam, nurbs.bezier_mesh(sector()).solid, lm="line2")
    assert len(ops.segments) == 1
    eta = (ops.segments["eta_start"][0], ops.segments["eta_end"][0])
    assert np.abs(np.subtract(eta, ETA_4C)).max() < 1e-10
    assert ops.embedded_length > 0 and ops.constraint_residual < 1e-12
