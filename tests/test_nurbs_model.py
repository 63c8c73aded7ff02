"""The solid model on NURBS patches (issue 19 item 4, without the scene): a thick-walled pipe under
internal pressure against Lamé's plane-strain solution, and the rational Gauss-point data.
"""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from mortar1d3d import nurbs
from mortar1d3d.nurbs.solid import NurbsSolidModel
from mortar1d3d.physics.materials import material

A, B, H = 0.1, 0.2, 0.05          # radii and height of the quarter pipe
E, NU, P = 1000.0, 0.3, 1.0


def lame_radial(r):
    """u_r(r) of a thick-walled pipe, inner pressure P, plane strain: σ_r = c - d/r², σ_θ = c + d/r²."""
    c = P * A * A / (B * B - A * A)
    d = P * A * A * B * B / (B * B - A * A)
    return (1 + NU) / E * ((1 - 2 * NU) * c * r + d / r)


def quarter_pipe_solution(n):
    """n × n × 1 elements (radial, circumferential, axial). One circumferential element is exact for the
    geometry and even holds the solution, but 3³ Gauss points integrate a 90° span's rational
    stiffness only to ~1e-3: the circumferential refinement removes that error too."""
    solid = nurbs.hollow_cylinder(A, B, H, angle=90.0, elements=(n, n, 1))
    model = NurbsSolidModel(solid, material("linear_elastic", E, NU), kinematics="linear")
    _, K = model.evaluate(np.zeros(model.n_dofs))
    f = model.pressure(0, "u0_min", P)
    fixed = np.zeros(model.n_dofs, dtype=bool)
    # symmetry planes y = 0 (θ = 0) and x = 0 (θ = 90°), plane strain (both ends held axially)
    for face, component in (("u1_min", 1), ("u1_max", 0), ("u2_min", 2), ("u2_max", 2)):
        fixed[3 * solid.face_control(0, face) + component] = True
    free = np.flatnonzero(~fixed)
    u = np.zeros(model.n_dofs)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), f[free])
    return model, u


def radial_errors(model, u):
    """Largest |u_r - Lamé| on the inner and the outer surface (sampled), relative to u_r(A)."""
    x0 = model.sample(points=5)
    x1 = model.sample(u, points=5)
    r = np.hypot(x0[..., 0], x0[..., 1])
    ur = ((x1 - x0)[..., 0] * x0[..., 0] + (x1 - x0)[..., 1] * x0[..., 1]) / r
    out = []
    for radius in (A, B):
        on = np.abs(r - radius) < 1e-12
        out.append(np.abs(ur[on] - lame_radial(radius)).max() / lame_radial(A))
    return out


def test_pressure_resultant_and_volume():
    solid = nurbs.hollow_cylinder(A, B, H, angle=90.0, elements=(2, 2, 1))
    model = NurbsSolidModel(solid, material("linear_elastic", E, NU), kinematics="linear")
    # the inner quarter surface pushed outwards: resultant P A H along (1, 1, 0); n dA is rational, the
    # Gauss rule converges exponentially
    for n_gauss, tol in ((4, 1e-7), (10, 1e-13)):
        f = model.pressure(0, "u0_min", P, n_gauss=n_gauss).reshape(-1, 3)
        assert np.abs(f.sum(axis=0) - [P * A * H, P * A * H, 0.0]).max() < tol * P * A * H
    volume = np.pi / 4 * (B * B - A * A) * H
    assert abs(model.solid.volume() - volume) < 1e-6 * volume     # 3 × 3 × 3 Gauss points, det J rational


def test_lame_pipe_converges_under_h_refinement():
    errors = []
    for n in (1, 2, 4):
        model, u = quarter_pipe_solution(n)
        errors.append(radial_errors(model, u))
    errors = np.array(errors)                        # [level, (inner, outer)]
    rates = np.log2(errors[:-1] / errors[1:])
    # measured: inner 9.5e-3, 1.0e-3, 7.1e-5 (n = 1, 2, 4; 4.3e-6 at n = 8), outer 8.3e-3, 5.3e-4, 3.5e-5
    assert errors[-1].max() < 1e-4
    # quadratic NURBS: the surface displacement error falls faster than h³ (measured h⁴ from n = 2)
    assert (rates > 3.0).all(), (errors, rates)


def test_vtu_of_sampled_spans(tmp_path):
    import meshio

    model, u = quarter_pipe_solution(1)
    path = model.write_vtu(str(tmp_path / "pipe.vtu"), u)
    mesh = meshio.read(path)
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    assert mesh.cells_dict["hexahedron27"].shape == (1, 27)
    assert np.abs(r[[0, 3, 4, 7, 11, 15]] - A).max() < 1e-15           # the inner face's corners and edge middles
    d = mesh.point_data["displacement"]
    assert np.abs(d[0] - [lame_radial(A), 0, 0]).max() < 0.02 * lame_radial(A)
