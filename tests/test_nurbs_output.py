"""Rational (NURBS) elements on the paths that evaluate element functions outside the engine: VTU
output samples them through their exact points; the Gauss-point and rotational couplings, which
evaluate polynomial functions only, refuse them with the key that chose them."""
import numpy as np
import pytest

from mortar1d3d import nurbs
from mortar1d3d.io.vtu import write_solid
from mortar1d3d.physics.coupling import Coupling
from mortar1d3d.physics.rotational_coupling import RotationalCoupling

A, B, H = 0.1, 0.2, 0.05


def quarter_mesh(elements=(1, 2, 1)):
    return nurbs.bezier_mesh(nurbs.hollow_cylinder(A, B, H, angle=90.0, elements=elements)).solid


def test_write_solid_samples_rational_spans(tmp_path):
    import meshio

    solid = quarter_mesh()
    # a field equal to the node positions interpolates to the exact points of the geometry
    path = write_solid(tmp_path / "s.vtu", solid, point_data={"x": solid.points, "w": solid.weights},
                       cell_data={"id": np.arange(solid.n_elements) * 10})
    mesh = meshio.read(path)
    assert mesh.cells_dict["hexahedron27"].shape == (2, 27)
    assert np.abs(mesh.point_data["x"] - mesh.points).max() < 1e-15
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    on_inner = np.abs(r - A) < 1e-9
    assert on_inner.sum() == 18                      # 9 lattice points of each span's inner face
    assert np.abs(r[on_inner] - A).max() < 1e-15     # exact circle (the control points are off it)
    assert np.abs(np.hypot(solid.points[:, 0], solid.points[:, 1]) - A).min() < 1e-15
    assert (np.abs(np.hypot(solid.points[:, 0], solid.points[:, 1]) - A) > 1e-3).sum() > 0
    assert mesh.cell_data["id"][0].tolist() == [0, 10]
    assert mesh.cell_data["solid_element"][0].tolist() == [0, 1]


def test_gauss_point_and_rotational_couplings_refuse_rational_solids():
    solid = quarter_mesh()
    with pytest.raises(ValueError, match=r"coupling\.constraint = 'gauss_point': not implemented for rational "
                                         r"elements \['nurbs27'\]"):
        Coupling(None, None, solid, 0, 0, constraint="gauss_point")
    with pytest.raises(ValueError, match=r"coupling\.rotational: not implemented for rational elements"):
        RotationalCoupling(None, None, solid, 0, 0)
