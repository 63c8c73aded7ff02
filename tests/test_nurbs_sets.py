"""Sets by position on NURBS solids select points of the body, not control points (issue 19): the
control points of the corners, edges, faces and elements whose body lies in the region."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.model.build import build
from mortar1d3d.scene import SceneError

RI, RO, L = 0.1, 0.2, 0.1


def sets(mesh):
    scene = m13.Scene(solid={"mesh": mesh, "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}})
    return build(scene)


def pipe(n):
    return {"pipe": {"r_inner": RI, "r_outer": RO, "length": L, "elements": [1, n, 1]}}


def test_a_radial_line_selects_the_edge_on_it():
    b = sets(pipe(4))
    _, nodes = b.sets.select({"inside": [[RI, 0, 0], [RO, 0, 0]]}, "on")
    X = b.solid_mesh.points[nodes]
    assert len(nodes) == 3 and np.allclose(X[:, 1:], 0.0) and np.allclose(np.sort(X[:, 0]), [RI, 0.15, RO])


def test_x_min_of_a_pipe_is_the_body_line_not_the_arc_control_points():
    b = sets(pipe(4))
    _, nodes = b.sets.select("solid:x_min", "on")
    X = b.solid_mesh.points[nodes]
    # the outer line at 180°: three nodes along z; the arcs' middle control points at (−RO, ±RO) have the
    # same x but lie off the body
    assert len(nodes) == 3 and np.allclose(X[:, :2], [-RO, 0.0])
    assert (np.abs(b.solid_mesh.points[:, 0] + RO) < 1e-12).sum() == 9


def test_a_box_around_a_whole_element_takes_its_bulging_control_points():
    b = sets(pipe(3))                                     # 120° arcs: middle control points at 2 r
    box = [[-0.5 * RO - 1e-12, 0, 0], [RO, RO, L]]          # the body of the span 0° … 120°
    _, nodes = b.sets.select({"inside": box}, "on")
    X = b.solid_mesh.points[nodes]
    assert len(nodes) == 27
    assert (X[:, 1] > RO + 1e-9).sum() == 6               # arc middles (r, √3 r), r = 0.15, 0.2: outside the box
    # a box around part of that span holds only what lies wholly in it: the radial edges at 0°
    _, part = b.sets.select({"inside": [[0, 0, 0], [RO, 0.05, L]]}, "on")
    assert len(part) == 9 and np.allclose(b.solid_mesh.points[part][:, 1], 0.0)


def test_a_region_without_a_whole_entity_selects_nothing():
    b = sets(pipe(3))                                     # x_min: a line in the middle of a 120° face
    with pytest.raises(SceneError, match="selects no node"):
        b.sets.select("solid:x_min", "dirichlet[0].on")


def test_brick_faces_by_position_are_its_face_sets():
    b = sets({"brick": {"lower": [0, 0, 0], "upper": [2, 1, 1], "elements": [2, 1, 1]}})
    for name in ("x_min", "x_max", "y_min", "z_max"):
        _, nodes = b.sets.select(f"solid:{name}", "on")
        assert np.array_equal(nodes, np.sort(b.solid_mesh.point_sets[name]))


def test_fibre_regions_test_the_body_centre_of_a_thick_curved_element():
    """``fibres[].inside`` on NURBS: the centroid of a 90° span's control points lies at 0.94 r_mid
    (the arc's middle control points bulge out to √2 r, the ends lie on r), the body centre at r_mid.
    A box around the body centre (r_mid = 0.15 at 45°: x = y = 0.1061) but not the control-point
    centroid (x = y = 0.1) selects that element and no other one."""
    b = sets(pipe(4))
    centre = 0.15 * np.sqrt(0.5)
    lo, hi = np.array([centre - 0.003, centre - 0.003, 0.0]), np.array([centre + 0.003, centre + 0.003, L])
    X = b.solid_mesh.points[b.solid_mesh.connectivity]
    cp_centroid = X.mean(axis=1)
    assert not ((cp_centroid >= lo) & (cp_centroid <= hi)).all(axis=1).any()    # the old rule found nothing
    elements, = b.sets.fibre_regions([{"inside": (lo, hi)}])
    assert elements.tolist() == [True, False, False, False]
    # a box around the control-point centroids only (off the body's centre) selects nothing
    with pytest.raises(SceneError, match=r"fibres\[0\]\.inside: no element centroid"):
        b.sets.fibre_regions([{"inside": (np.array([0.098, 0.098, 0.0]), np.array([0.102, 0.102, L]))}])
