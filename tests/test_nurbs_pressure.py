"""Pressure on NURBS patch faces (issue 19 item 4): the follower load and its tangent, dead pressure,
Dirichlet conditions on the control points of a patch face."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from mortar1d3d import nurbs
from mortar1d3d.nurbs.solid import NurbsSolidModel, patch_face_set
from mortar1d3d.physics.materials import material
from mortar1d3d.physics.surface import Pressure, boundary_faces

A, B, H, P = 0.1, 0.2, 0.05, 1.0


def quarter_model(elements=(2, 2, 1), kinematics="nonlinear"):
    solid = nurbs.hollow_cylinder(A, B, H, angle=90.0, elements=elements)
    return NurbsSolidModel(solid, material("neo_hooke", 1000.0, 0.3), kinematics=kinematics)


def test_follower_tangent_matches_differences_of_the_force():
    model = quarter_model()
    load = model.pressure_load(0, "u0_min", P)
    rng = np.random.default_rng(3)
    u = 0.01 * rng.standard_normal(model.n_dofs)
    f, K = load.evaluate(u)
    h = 1e-6
    for _ in range(3):
        du = rng.standard_normal(model.n_dofs)
        fd = (load.evaluate(u + h * du, False)[0] - load.evaluate(u - h * du, False)[0]) / (2 * h)
        # measured 1e-13 against |K du| ~ 3e-2
        assert np.abs(fd - K @ du).max() < 1e-9 * np.abs(K @ du).max()
    # a follower load: it changes with u (a dead load would have K = 0)
    assert np.abs(K.toarray()).max() > 0.1 * P * H


def test_follower_force_turns_with_a_rigid_rotation():
    """f(x) on the rotated surface R X + c is R f(X): the load follows the current normal."""
    model = quarter_model()
    load = model.pressure_load(0, "u0_min", P)
    X = model.nurbs.control
    angle = 0.7
    R = np.array([[np.cos(angle), 0.0, np.sin(angle)], [0.0, 1.0, 0.0], [-np.sin(angle), 0.0, np.cos(angle)]])
    u = (X @ R.T + [0.3, -0.2, 0.1] - X).ravel()
    f0, _ = load.evaluate(None, tangent=False)
    f1, _ = load.evaluate(u, tangent=False)
    assert np.abs(f1.reshape(-1, 3) - f0.reshape(-1, 3) @ R.T).max() < 1e-13 * np.abs(f0).max()


def test_dead_pressure_resultants():
    model = quarter_model(kinematics="linear")
    # quarter inner surface pushed outwards: resultant P A H (1, 1, 0); n dA is rational, so the Gauss
    # rule converges but is not exact (measured 6e-8 relative with 4 points, 5e-16 with 10)
    for n_gauss, tol in ((4, 1e-7), (10, 1e-13)):
        f = model.pressure(0, "u0_min", P, n_gauss=n_gauss).reshape(-1, 3)
        assert np.abs(f.sum(axis=0) - [P * A * H, P * A * H, 0.0]).max() < tol * P * A * H
    # a closed pipe: the inner pressure has no resultant; an end cap pushes along -z on z = 0
    pipe = NurbsSolidModel(nurbs.hollow_cylinder(A, B, H, elements=(1, 4, 1)), material("linear_elastic", 1.0, 0.3))
    f = pipe.pressure(0, "u0_min", P).reshape(-1, 3)
    assert np.abs(f.sum(axis=0)).max() < 1e-14
    f = pipe.pressure(0, "u2_min", P).reshape(-1, 3)
    # four 90° spans: 4 × 4 points integrate the rational area element to 4e-6 (measured)
    assert np.abs(f.sum(axis=0) - [0.0, 0.0, P * np.pi * (B * B - A * A)]).max() < 1e-5 * P * np.pi * B * B


def test_patch_face_sets_are_boundary_faces():
    mesh = quarter_model().mesh
    every = boundary_faces(mesh.solid)
    found = np.concatenate([patch_face_set(mesh, 0, f"u{a}_{s}") for a in range(3) for s in ("min", "max")])
    assert len(found) == len(every) == len(np.unique(found[["element", "face"]]))
    key = lambda fs: sorted(zip(fs["element"].tolist(), fs["face"].tolist()))        # noqa: E731
    assert key(found) == key(every)
    with pytest.raises(ValueError, match="face 'u3_min'"):
        patch_face_set(mesh, 0, "u3_min")


def test_rational_faces_fail_loudly_with_the_polynomial_tables():
    """The per-face tables are what make the load right. Σ_a f_a · X_a = -p ∫ x · n dA, which on the
    inner quarter surface (x · n = -A) is p A times its area π A H / 2; with unit weights (the
    polynomial tables' functions) the surface is not the circle and the sum is far off. (The
    resultant would not tell: on an open surface it depends on the boundary curve only.)"""
    model = quarter_model(elements=(1, 1, 1))
    faces = model.face_set(0, "u0_min")
    solid = model.mesh.solid
    exact = P * A * np.pi * A * H / 2
    right = Pressure(solid, faces, P).evaluate(None, False)[0].reshape(-1, 3)
    unit = type(solid)(solid.points, {"nurbs27": solid.connectivity[:, :27]}, weights=np.ones(solid.n_nodes))
    wrong = Pressure(unit, faces, P).evaluate(None, False)[0].reshape(-1, 3)
    assert abs(np.sum(right * solid.points) - exact) < 1e-5 * exact
    assert abs(np.sum(wrong * solid.points) - exact) > 1e-2 * exact


def test_face_control_points_fix_the_whole_face():
    model = quarter_model(elements=(2, 3, 2))
    solid = model.nurbs
    rng = np.random.default_rng(0)
    for face in ("u0_min", "u1_max", "u2_min"):
        u = rng.standard_normal((solid.n_control, 3))
        u[solid.face_control(0, face)] = 0.0
        x0 = model.sample(points=4)
        x1 = model.sample(u.ravel(), points=4)
        r = np.hypot(x0[..., 0], x0[..., 1])
        on = {"u0_min": np.abs(r - A) < 1e-13, "u1_max": np.abs(x0[..., 0]) < 1e-13,
              "u2_min": np.abs(x0[..., 2]) < 1e-13}[face]
        assert on.sum() > 20
        assert np.abs(x1 - x0)[on].max() < 1e-14
        assert np.abs(x1 - x0)[~on].max() > 1e-2


def test_newton_with_follower_pressure_converges_quadratically():
    """Quarter pipe, neo-Hooke, large inner follower pressure (u_r ≈ 13 % of A): the consistent tangent
    (solid + load stiffness) gives quadratic convergence."""
    model = quarter_model(elements=(1, 2, 1))
    load = model.pressure_load(0, "u0_min", 60.0)
    solid = model.nurbs
    fixed = np.zeros(model.n_dofs, dtype=bool)
    for face, component in (("u1_min", 1), ("u1_max", 0), ("u2_min", 2), ("u2_max", 2)):
        fixed[3 * solid.face_control(0, face) + component] = True
    free = np.flatnonzero(~fixed)
    u = np.zeros(model.n_dofs)
    norms = []
    for _ in range(8):
        f_int, K = model.evaluate(u)
        f_ext, K_load = load.evaluate(u)
        r = (f_int - f_ext)[free]
        norms.append(np.linalg.norm(r))
        if norms[-1] < 1e-10 * norms[0]:
            break
        u[free] -= spla.spsolve((K - K_load)[free][:, free].tocsc(), r)
    assert norms[-1] < 1e-10 * norms[0] and len(norms) <= 6, norms
    # quadratic: each of the last steps squares the relative residual (up to a modest constant)
    rel = np.array(norms) / norms[0]
    assert rel[-1] < 1e2 * rel[-2] ** 2, rel
    ur = np.hypot(*model.sample(u, points=3)[0, 0, :2]) - A
    assert 0.1 * A < ur < 0.2 * A          # measured 0.134 A


def test_cubic_face_rule_follows_the_degree_and_converges():
    """Pressure resultant on the inner face of a cubic (``nurbs64``) 90° pipe span against the closed form
    P A H (1, 1, 0). The integrand with unit weights has degree 3p − 1 = 8 per direction (5 points are
    exact for it); the default is 6 × 6 points on cubic faces (one more for the rational weight) and
    4 × 4 on quadratic ones. Measured relative errors with n = 3 … 8 points: 6.6e-4, 3.4e-5, 1.7e-6,
    7.9e-8, 3.6e-9, 1.6e-10."""
    from mortar1d3d.physics.rational_surface import rational_face_points

    assert (rational_face_points(2), rational_face_points(3)) == (4, 6)
    model = NurbsSolidModel(nurbs.hollow_cylinder(A, B, H, angle=90.0, elements=(1, 1, 1), degree=3),
                            material("linear_elastic", 1.0, 0.3), kinematics="linear")
    assert model.mesh.solid.blocks[0][0].name == "nurbs64"
    exact = np.array([P * A * H, P * A * H, 0.0])

    def error(n_gauss):
        f = model.pressure(0, "u0_min", P, n_gauss=n_gauss).reshape(-1, 3)
        return np.abs(f.sum(axis=0) - exact).max() / (P * A * H)

    errors = [error(n) for n in range(3, 9)]
    assert all(b < 0.1 * a for a, b in zip(errors, errors[1:])), errors      # converging with the rule
    assert errors[-1] < 1e-9
    assert error(None) == errors[3] < 1e-7                                   # the default is the 6-point rule
