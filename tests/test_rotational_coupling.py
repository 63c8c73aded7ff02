"""Issue 18 item 4: rotational coupling of Simo–Reissner beams to the solid (penalty).

A straight fibre along the axis of a block whose every node is prescribed by a finite twist (and
bend) field carries the torsion the solid imposes with rotational coupling and none without it;
both solid triads are objective, vanish in the reference and under rigid motions, reproduce a
constant rotation exactly; the tangent matches central differences; the two triads and the two
rotational multiplier types are compared on coarse and fine solid meshes."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mortar1d3d as m13
from mortar1d3d import SceneError
from mortar1d3d.model import Model, plan
from mortar1d3d.physics import rotational_coupling_kernel as kernel
from mortar1d3d.physics.rotational_coupling import RotationalCoupling
from mortar1d3d.solvers.newton import solve_load_steps

SECTION = {"E": 2e11, "nu": 0.3, "radius": 0.01}
TAU = 0.2            # twist rate of the prescribed solid field (rad per unit length)
ALL = {"inside": [[-1, -1, -1], [2, 1, 1]]}


def twist_bend(X, tau, k):
    """Positions of the block's points after a twist about the x axis (rate tau), then a bend in
    the x-z plane with curvature k (the axis becomes a circular arc of radius 1/k)."""
    x, y, z = X.T
    c, s = np.cos(tau * x), np.sin(tau * x)
    y, z = c * y - s * z, s * y + c * z
    if k == 0.0:
        return np.column_stack([x, y, z])
    R = 1.0 / k
    return np.column_stack([(R - z) * np.sin(k * x), y, R - (R - z) * np.cos(k * x)])


def block(n, beam_elements, rotational, support=False, beams=None):
    """A block [0, 1] × [-0.1, 0.1]² with n × 3 × 3 hex8 cells, a straight fibre on its axis."""
    coupling = {} if rotational is None else {"rotational": rotational}
    dirichlet = [{"on": ALL}] + ([{"on": "beam:0:start", "rotation": [0, 0, 0]}] if support else [])
    return m13.Scene(solid={"mesh": {"box": [[0, -0.1, -0.1], [1, 0.1, 0.1]], "cells": [n, 3, 3]},
                            "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=beams or [{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": beam_elements,
                                      "model": "simo_reissner", "section": SECTION}],
                     coupling=coupling, dirichlet=dirichlet, analysis={"kinematics": "nonlinear", "steps": 2})


def solve_prescribed(scene, positions):
    """Solve with every solid node prescribed at ``positions(X)``; returns the model, the
    displacement unknowns and the Newton iterations per step."""
    model = Model(scene).prepare()
    X = model.solid_mesh.points
    nS = X.size
    assert np.array_equal(model.fixed_dofs[:nS], np.arange(nS))
    model.fixed_values[:nS] = (positions(X) - X).ravel()
    z, records, _ = solve_load_steps(model, np.zeros(model.n_unknowns), 2, rtol=1e-10, increment_rtol=1e-10)
    return model, z[:model.n_displacement_dofs], [r.iterations for r in records]


def moments(model, d, eta=(-0.5, 0.0, 0.5)):
    """Material moments (GI_T K1, EI2 K2, EI3 K3) of the fibre at ``eta`` of every element (n_el, k, 3)."""
    g = model.groups[0]
    return g.physics.sample(d[g.dofs.slice], d[g.rotations.slice].reshape(-1, 3), np.array(eta))["M"]


def middle(M):
    """The samples of the middle half of the fibre (away from its free ends)."""
    n = len(M)
    return M[n // 4: n - n // 4].reshape(-1, 3)


def errors(n, beam_elements, triad, lm, k=0.0):
    """Torsion and bending moment errors in the middle half of the fibre, relative to GI_T τ and EI k."""
    rotational = None if triad is None else {"triad": triad, "lm": lm}
    model, d, _ = solve_prescribed(block(n, beam_elements, rotational, support=triad is None),
                                   lambda X: twist_bend(X, TAU, k))
    section = model.groups[0].physics.sections[0]
    M = middle(moments(model, d))
    torsion = np.abs(M[:, 0] / (section.GI_T * TAU) - 1.0).max()
    bending = np.abs(np.hypot(M[:, 1], M[:, 2]) / (section.EI2 * k) - 1.0).max() if k else np.nan
    return torsion, bending


# -- the fibre twisted with the solid ----------------------------------------------------------

def test_fibre_twisted_with_the_solid_carries_its_torsion_only_with_rotational_coupling():
    section = None
    results = {}
    for n in (4, 8):
        model, d, iterations = solve_prescribed(block(n, 2 * n, {"triad": "polar"}),
                                                lambda X: twist_bend(X, TAU, 0.0))
        section = model.groups[0].physics.sections[0]
        M = moments(model, d)
        results[n] = np.abs(middle(M)[:, 0] / (section.GI_T * TAU) - 1.0).max()
        assert np.abs(M[..., 1:]).max() < 1e-8 * section.GI_T * TAU       # no bending
        assert max(iterations) <= 3
        assert model.counts["coupling.rotational_penalty"] > 0
    # measured: 2.5e-3 (solid 4 cells / beam 8 elements), 1.2e-4 (8 / 16)
    assert results[4] < 4e-3 and results[8] < 3e-4 and results[8] < 0.1 * results[4]
    # without rotational coupling (a rotation support instead) the fibre does not twist at all
    model, d, _ = solve_prescribed(block(4, 8, None, support=True), lambda X: twist_bend(X, TAU, 0.0))
    assert np.abs(moments(model, d)).max() < 1e-10 * section.GI_T * TAU


def test_line3_rotational_multipliers_beat_line2_on_the_twisted_fibre():
    """line2 multipliers constrain fewer rotations than the line3 triads have, so the fibre's
    twist keeps a mesh-scale oscillation. Torsion errors in the middle half (solid 4 cells),
    measured: line2 4.6e-2 / 9.9e-3 with 8 / 16 beam elements, line3 2.5e-3 / 3.5e-4."""
    line2 = [errors(4, b, "polar", "line2")[0] for b in (8, 16)]
    line3 = [errors(4, b, "polar", "line3")[0] for b in (8, 16)]
    assert line2[0] > 0.03 and line2[1] < 0.5 * line2[0]
    assert line3[0] < 0.1 * line2[0] and line3[1] < 0.1 * line2[1]


def test_comparison_of_the_solid_triads_on_coarse_and_fine_solid_meshes():
    """Twist (0.2 rad per unit length) and bend (curvature 0.5) of the solid; a fibre of 4
    elements; solid of 4 and 16 cells along it. Measured (torsion error, bending error) in the
    middle half, relative to GI_T τ and EI k (2 / 8 cells: polar 1.0e-2, 1.00 / 9.5e-3, 3.7e-2;
    deformation_gradient 9.1e-3, 1.28 / 9.2e-3, 6.2e-2):

    ========================  =================  =================
    triad (lm = line3)        solid 4 cells      solid 16 cells
    ========================  =================  =================
    polar                     9.9e-3, 0.111      9.4e-3, 1.87e-2
    deformation_gradient      8.7e-3, 0.208      9.4e-3, 2.47e-2
    none (rotation support)   1 (no torsion), 0.136   1, 0.135
    ========================  =================  =================

    The torsion error is the 4-element fibre's own (its free ends); the bending error falls with
    the solid's refinement with either triad, by 1.2 to 2 times less with the polar one, while
    without rotational coupling it stays at the fibre's discretisation error.
    """
    table = {triad: [errors(n, 4, triad, "line3", k=0.5) for n in (4, 16)] for triad in ("polar", "deformation_gradient")}
    plain = [errors(n, 4, None, None, k=0.5) for n in (4, 16)]
    polar, gradient = table["polar"], table["deformation_gradient"]
    for torsion, _ in polar + gradient:
        assert torsion < 1.2e-2
    assert polar[1][1] < 0.025 and gradient[1][1] < 0.035
    assert polar[0][1] < 0.7 * gradient[0][1] and polar[1][1] < 0.9 * gradient[1][1]      # polar bends better
    assert polar[1][1] < 0.2 * polar[0][1]
    assert min(plain[0][1], plain[1][1]) > 0.1 and plain[0][0] == pytest.approx(1.0)


# -- triads, constraint, tangent ------------------------------------------------------------------

SYMMETRIC_SHEAR_ANGLE = 0.2380675563      # measured; polar 0.245, deformation_gradient 0.232


def _triad(kind, F, L0):
    L = np.empty((3, 3))
    assert kernel.solid_triad(kernel.TRIADS[kind], np.ascontiguousarray(F), L0, L, np.empty((4, 3, 3))) == kernel.OK
    return L


@pytest.mark.parametrize("kind", ["polar", "deformation_gradient", "deformation_gradient_symmetric"])
def test_solid_triads_are_objective_rotations_and_exact_for_rigid_rotations(kind):
    rng = np.random.default_rng(3)
    L0 = Rotation.from_rotvec([0.4, -0.2, 1.1]).as_matrix()
    Q = Rotation.from_rotvec([-0.7, 0.5, 0.3]).as_matrix()
    for _ in range(5):
        F = np.eye(3) + 0.3 * rng.standard_normal((3, 3))
        L = _triad(kind, F, L0)
        assert np.abs(L.T @ L - np.eye(3)).max() < 1e-14 and np.linalg.det(L) > 0
        assert np.abs(_triad(kind, Q @ F, L0) - Q @ L).max() < 1e-14             # objective
        # a stretch along the reference base vectors does not turn the triad (the symmetric triad:
        # only an equal one, since it is built about the mean direction of the stretched vectors)
        S = L0 @ np.diag(rng.uniform(0.5, 2.0, 3) if kind != "deformation_gradient_symmetric"
                         else np.full(3, rng.uniform(0.5, 2.0))) @ L0.T
        assert np.abs(_triad(kind, Q @ S, L0) - Q @ L0).max() < 1e-14
    # the triads differ under shear in the section plane (polar turns, the bisector stays)
    shear = L0 @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.0, 0.0, 1.0]]) @ L0.T
    angle = np.linalg.norm(Rotation.from_matrix(_triad(kind, shear, L0) @ L0.T).as_rotvec())
    assert angle == pytest.approx({"polar": 0.2449786631, "deformation_gradient": 0.2318238045,
                                   "deformation_gradient_symmetric": SYMMETRIC_SHEAR_ANGLE}[kind], rel=1e-8)


def test_symmetric_triad_is_the_even_tripod_about_the_mean_direction():
    """4C's deformation_gradient_3d_general: unit vectors at acos(1/√3) from d = Σ a_i / |Σ a_i|,
    spread by 2π/3 about d, turned so that their mean angular offset from the a_i's projections
    vanishes; the identity on the reference; unlike the others it turns under an unequal stretch."""
    L0 = Rotation.from_rotvec([0.4, -0.2, 1.1]).as_matrix()
    np.testing.assert_allclose(_triad("deformation_gradient_symmetric", np.eye(3), L0), L0, atol=1e-15)
    F = np.eye(3) + 0.3 * np.random.default_rng(7).standard_normal((3, 3))
    L = _triad("deformation_gradient_symmetric", F, L0)
    a = F @ L0
    d = a.sum(axis=1) / np.linalg.norm(a.sum(axis=1))
    np.testing.assert_allclose(L.T @ d, np.full(3, 1 / np.sqrt(3)), atol=1e-14)
    p = a - np.outer(d, d @ a)
    p /= np.linalg.norm(p, axis=0)
    q = L - np.outer(d, d @ L)
    q /= np.linalg.norm(q, axis=0)
    offsets = [np.arctan2(d @ np.cross(q[:, k], p[:, k]), q[:, k] @ p[:, k]) for k in range(3)]
    assert abs(sum(offsets)) < 1e-13 and max(map(abs, offsets)) > 1e-3
    stretch = L0 @ np.diag([2.0, 1.0, 1.0]) @ L0.T
    assert np.abs(_triad("deformation_gradient_symmetric", stretch, L0) - L0).max() > 0.1


def coupled_rod(element="hexahedron"):
    """A straight fibre in a 3 × 2 × 2 block, skew to its axes."""
    return m13.Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [3, 2, 2], "element": element},
                            "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=[{"curve": {"line": [[0.05, 0.4, 0.55], [0.95, 0.6, 0.45]]}, "elements": 3,
                             "model": "simo_reissner", "section": SECTION}],
                     dirichlet=[{"on": "solid:x_min"}], coupling={"rotational": {}},
                     analysis={"kinematics": "nonlinear"})


def rod_coupling(kind, element="hexahedron", **options):
    """The model of :func:`coupled_rod`, its beam group and a RotationalCoupling of it."""
    model = Model(coupled_rod(element)).prepare()
    g = model.groups[0]
    return model, g, RotationalCoupling(g.operators, g.physics, model.solid_mesh, g.rotations.start,
                                        model.n_displacement_dofs, triad=kind, **options)


def _spin(psi, theta):
    """Rotation vectors after the multiplicative update exp(θ) exp(ψ) (rows)."""
    return np.array([(Rotation.from_rotvec(t) * Rotation.from_rotvec(p)).as_rotvec() for p, t in zip(psi, theta)])


@pytest.mark.parametrize("kind, element", [("polar", "hexahedron"), ("deformation_gradient", "hexahedron"),
                                           ("polar", "tetra"), ("deformation_gradient", "hexahedron27"),
                                           ("deformation_gradient_symmetric", "hexahedron")])
def test_constraint_vanishes_in_the_reference_and_under_rigid_motions(kind, element):
    model, g, rc = rod_coupling(kind, element, penalty=1e4)
    X = model.solid_mesh.points
    n_rot = g.physics.n_rotation_nodes
    assert np.abs(rc.relative_rotations(np.zeros(X.size), np.zeros((n_rot, 3)))).max() < 1e-14     # round-off
    Q = Rotation.from_rotvec([0.9, -1.3, 0.6])
    u = (Q.apply(X) + [0.3, -2.0, 5.0] - X).ravel()
    psi = np.tile(Q.as_rotvec(), (n_rot, 1))
    assert np.abs(rc.relative_rotations(u, psi)).max() < 1e-14
    r, _ = rc.evaluate(u, psi, tangent=False)
    assert np.abs(r).max() < 1e-9                                       # penalty 1e4 × ψ ~ 1e-15
    # a deformed state and the same state rigidly rotated: the same energy (objective measure)
    rng = np.random.default_rng(5)
    ud = 0.03 * rng.standard_normal(X.size)
    psid = 0.2 * rng.standard_normal((n_rot, 3))
    uq = (Q.apply(X + ud.reshape(-1, 3)) - X).ravel()
    assert rc.energy(uq, _spin(psid, np.tile(Q.as_rotvec(), (n_rot, 1)))) == pytest.approx(rc.energy(ud, psid),
                                                                                           rel=1e-12)


@pytest.mark.parametrize("kind, element", [("polar", "hexahedron"), ("deformation_gradient", "hexahedron"),
                                           ("polar", "tetra"), ("deformation_gradient", "hexahedron27"),
                                           ("deformation_gradient_symmetric", "hexahedron")])
def test_tangent_matches_central_differences(kind, element):
    model, g, rc = rod_coupling(kind, element, penalty=1e3, lm="line2")
    worst_r, worst_K = _central_differences(model, g, rc)
    assert worst_r < 1e-8 and worst_K < 1e-8          # measured 7e-11, 6e-11 (polar, hexahedron)


def _central_differences(model, g, rc):
    """Largest deviations of the residual from the energy's and of the tangent from the residual's
    central differences (relative to the largest entry) at a random state."""
    nS, n_rot = 3 * model.n_solid_nodes, g.physics.n_rotation_nodes
    rng = np.random.default_rng(1)
    u, psi = 0.03 * rng.standard_normal(nS), 0.2 * rng.standard_normal((n_rot, 3))
    r, K = rc.evaluate(u, psi)
    h = 1e-6
    columns = [int(c) for c in rng.choice(nS, 6, replace=False)] + list(g.rotations.start + np.arange(0, 3 * n_rot, 2))
    worst_r = worst_K = 0.0
    for c in columns:
        states = []
        for s in (h, -h):
            uu, pp = u.copy(), psi.copy()
            if c < nS:
                uu[c] += s
            else:
                k, i = divmod(c - g.rotations.start, 3)
                theta = np.zeros((n_rot, 3))
                theta[k, i] = s
                pp = _spin(psi, theta)
            states.append((uu, pp))
        fd = (rc.energy(*states[0]) - rc.energy(*states[1])) / (2 * h)
        worst_r = max(worst_r, abs(fd - r[c]) / np.abs(r).max())
        column = (rc.evaluate(*states[0], tangent=False)[0] - rc.evaluate(*states[1], tangent=False)[0]) / (2 * h)
        worst_K = max(worst_K, np.abs(column - K[:, c].toarray().ravel()).max() / abs(K).max())
    return worst_r, worst_K


@pytest.mark.parametrize("kind", ["polar", "deformation_gradient_symmetric"])
def test_gauss_point_constraint_is_the_point_wise_penalty(kind):
    """``constraint = "gauss_point"`` (4C's gauss_point_to_segment rotational coupling): the energy
    is ε/2 Σ_p w_p |ψ_p|², its residual and tangent match central differences, it differs from
    the mortar constraint's energy, and the reported line moments are the lumped projection
    κ_j⁻¹ Σ_p Φ_j w_p ε ψ_p."""
    model, g, rc = rod_coupling(kind, penalty=1e3, lm="line2", constraint="gauss_point")
    mortar = rod_coupling(kind, penalty=1e3, lm="line2")[2]
    rng = np.random.default_rng(4)
    u, psi = 0.03 * rng.standard_normal(3 * model.n_solid_nodes), 0.2 * rng.standard_normal((g.physics.n_rotation_nodes, 3))
    psi_p = rc.relative_rotations(u, psi)
    assert rc.energy(u, psi) == pytest.approx(0.5e3 * np.sum(rc.weight * np.sum(psi_p ** 2, axis=1)), rel=1e-13)
    assert abs(rc.energy(u, psi) / mortar.energy(u, psi) - 1.0) > 1e-3
    lumped = rc.kappa_inverse[:, None] * (rc.Phi @ (rc.weight[:, None] * 1e3 * psi_p))
    np.testing.assert_allclose(rc.line_moment(u, psi), lumped, rtol=1e-13, atol=1e-13 * np.abs(lumped).max())
    worst_r, worst_K = _central_differences(model, g, rc)
    assert worst_r < 1e-8 and worst_K < 1e-8
    with pytest.raises(ValueError, match="penalty only"):
        rod_coupling(kind, constraint="gauss_point", enforcement="lagrange")


def _state(model, g, scale, seed=2):
    rng = np.random.default_rng(seed)
    return (scale * 0.03 * rng.standard_normal(3 * model.n_solid_nodes),
            scale * 0.2 * rng.standard_normal((g.physics.n_rotation_nodes, 3)))


def test_fourc_forces_are_the_documented_formula_and_close_to_the_variational_ones():
    """``forces = "fourc"``: the solid's share is the exact gradient's, the beam's on the spins of
    rotation node k is Σ_p w_p L_k(η_p) T(ψ_p)⁻¹ λ_p (T the library's left Jacobian, inverted here
    with numpy); the difference to the variational forces is of the order of ψ times the moment
    (a state scaled by 1/10 shrinks it relative to the forces by about 10)."""
    from mortar1d3d.physics.rotations import jacobian
    model, g, rc = rod_coupling("deformation_gradient_symmetric", penalty=1e3, lm="line2", forces="fourc")
    variational = rod_coupling("deformation_gradient_symmetric", penalty=1e3, lm="line2")[2]
    nS = 3 * model.n_solid_nodes
    relative = []
    for scale in (1.0, 0.1):
        u, psi = _state(model, g, scale)
        r, _ = rc.evaluate(u, psi, tangent=False)
        rv, _ = variational.evaluate(u, psi, tangent=False)
        np.testing.assert_allclose(r[:nS], rv[:nS], rtol=0, atol=1e-13 * np.abs(rv).max())
        psi_p = rc.relative_rotations(u, psi)
        lam_p = rc.Phi.T @ (1e3 * rc.kappa_inverse[:, None] * (rc.Phi @ (rc.weight[:, None] * psi_p)))
        expected = np.zeros(rc.n_dofs)
        for p in range(rc.n_points):
            T = np.empty((3, 3))
            jacobian(psi_p[p], T)
            f = rc.weight[p] * np.linalg.solve(T, lam_p[p])
            for k in range(3):
                start = rc.rotation_offset + 3 * rc.rotation_nodes[rc.beam_element[p], k]
                expected[start: start + 3] += rc.lag[p, k] * f
        np.testing.assert_allclose(r[nS:], expected[nS:], rtol=0, atol=1e-13 * np.abs(expected).max())
        relative.append(np.abs(r - rv).max() / np.abs(rv).max())
    assert relative[0] > 1e-2 and 5 < relative[0] / relative[1] < 20     # measured 5.5e-2, ratio 11.1


def test_fourc_forces_have_their_own_consistent_tangent():
    model, g, rc = rod_coupling("deformation_gradient_symmetric", penalty=1e3, lm="line2", forces="fourc")
    worst_r, worst_K = _central_differences(model, g, rc)
    assert worst_r > 1e-3                   # not the gradient of the penalty energy (measured 3.6e-2)
    assert worst_K < 1e-8                   # but its tangent is the derivative of its forces (2e-11)


def test_polar_triad_is_4c_polar_decomposition_2d_in_the_y_z_plane():
    """4C's polar_decomposition_2d: Λ_S = exp((θ_R + |ψ0|) e_x), θ_R the angle of the rotation of
    the 2D polar decomposition of F's y-z block, ψ0 = a e_x (a ≥ 0) the beam's reference rotation.
    For an F that keeps the y-z plane that is the library's polar triad R Λ0 (an independent
    2D polar decomposition by the SVD here)."""
    rng = np.random.default_rng(11)
    for a in (0.0, 0.5235987756, 2.0):
        L0 = Rotation.from_rotvec([a, 0.0, 0.0]).as_matrix()
        for _ in range(4):
            F2 = np.eye(2) + 0.4 * rng.standard_normal((2, 2))
            if np.linalg.det(F2) <= 0.1:
                continue
            F = np.zeros((3, 3))
            F[0, 0], F[1:, 1:] = rng.uniform(0.5, 1.5), F2
            U, _, Vt = np.linalg.svd(F2)
            R2 = U @ Vt
            theta = np.arctan2(R2[1, 0], R2[0, 0])
            expected = Rotation.from_rotvec([theta + a, 0.0, 0.0]).as_matrix()
            assert np.abs(_triad("polar", F, L0) - expected).max() < 1e-14


def _assert_jacobian_in_F_matches_differences(kind, F, L0, triads, lag, h=1e-6, bound=1e-8):
    """The complex-step ∂ψ/∂F of ``point_jacobian`` against central differences of ``point_psi``."""
    psi, J = np.empty(3), np.empty((3, 18))
    code = kernel.TRIADS[kind]
    assert kernel.point_jacobian(code, F, L0, triads, lag, psi, J) == kernel.OK
    for c in range(9):
        Fp, Fm = F.copy(), F.copy()
        Fp[c // 3, c % 3] += h
        Fm[c // 3, c % 3] -= h
        pp, pm = np.empty(3), np.empty(3)
        kernel.point_psi(code, Fp, L0, triads, lag, pp, np.empty((8, 3, 3)))
        kernel.point_psi(code, Fm, L0, triads, lag, pm, np.empty((8, 3, 3)))
        assert np.abs((pp - pm) / (2 * h) - J[:, c]).max() < bound


@pytest.mark.parametrize("k", [1, 2, 3])
def test_local_triads_keep_one_deformed_base_vector(k):
    """4C's deformation_gradient_3d_local_k: the deformed base vector a_k = F g_k kept, the next one
    (cyclically) along a_{k-1} × a_k, the third completing the right-handed triad (an independent
    construction with numpy here); the reference triad at F = I, objective, and a Jacobian equal to
    central differences."""
    kind = f"deformation_gradient_local_{k}"
    rng = np.random.default_rng(20 + k)
    L0 = Rotation.from_rotvec([0.4, -0.2, 1.1]).as_matrix()
    Q = Rotation.from_rotvec([-0.7, 0.5, 0.3]).as_matrix()
    assert np.abs(_triad(kind, np.eye(3), L0) - L0).max() < 1e-15
    for _ in range(4):
        F = np.eye(3) + 0.3 * rng.standard_normal((3, 3))
        a = F @ L0
        i, j, m = k - 1, k % 3, (k + 1) % 3
        e = np.empty((3, 3))
        e[:, i] = a[:, i] / np.linalg.norm(a[:, i])
        e[:, j] = np.cross(a[:, m], a[:, i])
        e[:, j] /= np.linalg.norm(e[:, j])
        e[:, m] = np.cross(e[:, i], e[:, j])
        L = _triad(kind, F, L0)
        assert np.abs(L - e).max() < 1e-14 and np.linalg.det(L) > 0
        assert np.abs(_triad(kind, Q @ F, L0) - Q @ L).max() < 1e-14
    F = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
    triads = np.stack([Rotation.from_rotvec(v).as_matrix() for v in ([0.4, -0.2, 1.1], [0.45, -0.2, 1.0],
                                                                     [0.4, -0.15, 1.1])])
    lag = np.array([0.2, 0.3, 0.5])
    _assert_jacobian_in_F_matches_differences(kind, F, L0, triads, lag)


@pytest.mark.parametrize("kind", ["plane_y", "plane_z", "plane_average"])
def test_plane_triads_turn_the_reference_about_x_by_fs_angle(kind):
    """4C's deformation_gradient_{y,z,average}_2d: Λ_S = exp(θ e_x) Λ0 with θ the angle by which F
    turns the y axis (atan2(F_zy, F_yy)), the z axis (atan2(F_zz, F_yz) − π/2) or their mean; their
    complex-step Jacobian equals central differences of ψ."""
    rng = np.random.default_rng(5)
    L0 = Rotation.from_rotvec([0.7, 0.0, 0.0]).as_matrix()
    for _ in range(4):
        F = np.zeros((3, 3))
        F[0, 0], F[1:, 1:] = rng.uniform(0.5, 1.5), np.eye(2) + 0.4 * rng.standard_normal((2, 2))
        ty = np.arctan2(F[2, 1], F[1, 1])
        tz = np.arctan2(F[2, 2], F[1, 2]) - np.pi / 2
        theta = {"plane_y": ty, "plane_z": tz, "plane_average": 0.5 * (ty + tz)}[kind]
        expected = Rotation.from_rotvec([theta, 0.0, 0.0]).as_matrix() @ L0
        assert np.abs(_triad(kind, F, L0) - expected).max() < 1e-14
    # a pure rotation about x is reproduced by all three; a shear in the y-z plane tells them apart
    Q = Rotation.from_rotvec([0.9, 0.0, 0.0]).as_matrix()
    assert np.abs(_triad(kind, Q, L0) - Q @ L0).max() < 1e-14
    shear = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.0, 0.0, 1.0]])
    angle = Rotation.from_matrix(_triad(kind, shear, L0) @ L0.T).as_rotvec()[0]
    assert angle == pytest.approx({"plane_y": 0.0, "plane_z": np.arctan2(1.0, 0.5) - np.pi / 2,
                                   "plane_average": 0.5 * (np.arctan2(1.0, 0.5) - np.pi / 2)}[kind], abs=1e-14)
    # the Jacobian (complex step through the half-angle form) against central differences
    F = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
    triads = np.stack([Rotation.from_rotvec(v).as_matrix() for v in ([0.7, 0.05, 0.0], [0.72, 0.0, 0.03],
                                                                     [0.71, 0.0, 0.0])])
    lag = np.array([0.2, 0.3, 0.5])
    _assert_jacobian_in_F_matches_differences(kind, F, L0, triads, lag)


@pytest.mark.parametrize("kind, constraint, forces", [
    ("polar", "mortar", "variational"), ("deformation_gradient", "mortar", "variational"),
    ("deformation_gradient_symmetric", "mortar", "variational"), ("polar", "gauss_point", "variational"),
    ("deformation_gradient_symmetric", "mortar", "fourc")])
def test_a_constant_rotation_of_the_solid_is_reproduced_exactly(kind, constraint, forces):
    """The solid rigidly turned by 0.8 rad: the free fibre's triads all become Q Λ0 (consistency)."""
    Q = Rotation.from_rotvec([0.2, 0.5, -0.6])
    model, d, iterations = solve_prescribed(block(2, 4, {"triad": kind, "constraint": constraint,
                                                         "forces": forces}), lambda X: Q.apply(X))
    g = model.groups[0]
    psi = d[g.rotations.slice].reshape(-1, 3)
    assert np.abs(psi - Q.as_rotvec()).max() < 1e-10
    assert np.abs(moments(model, d)).max() < 1e-6


# -- scene, plan, mechanism check -----------------------------------------------------------------

def test_rotational_coupling_holds_the_free_twist_and_is_planned_only_when_asked():
    scene = block(2, 4, {"triad": "deformation_gradient", "penalty": 5e3})
    names = [e.name for e in plan(scene)]
    assert "coupling.rotational_penalty" in names
    effect = next(e for e in plan(scene) if e.name == "coupling.rotational_penalty")
    assert "deformation_gradient" in effect.detail and "5000" in effect.detail
    model = Model(scene).prepare()                          # no twist mechanism: no rotation support needed
    assert model.zero_energy_modes == []
    assert model.groups[0].rotational.penalty == 5e3
    assert "coupling.rotational_penalty" not in [e.name for e in plan(block(2, 4, None, support=True))]
    with pytest.raises(SceneError, match=r"zero-energy mode .*or tie the cross-sections to the solid "
                                         r"\(coupling.rotational\)"):
        Model(block(2, 4, None)).prepare()
    # default: 1e3 GI_T / h² with the mean element length h = 0.25
    model = Model(block(2, 4, {})).prepare()
    rc = model.groups[0].rotational
    assert rc.penalty == pytest.approx(1e3 * model.groups[0].physics.sections[0].GI_T / 0.25 ** 2)
    assert (rc.triad, rc.lm) == ("polar", "line3")


@pytest.mark.parametrize("model_name", ["truss", "torsion_free"])
def test_rotational_coupling_needs_beams_with_rotations(model_name):
    beams = [{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "model": model_name,
              "section": {"E": 2e11, "radius": 0.01}}]
    with pytest.raises(SceneError, match=rf"^coupling.rotational: beams\[0\] is a {model_name} beam, which has no "
                                         "cross-section rotations"):
        block(2, 2, {}, beams=beams)


@pytest.mark.parametrize("change, message", [
    ({"enforcement": "nitsche"}, r"^coupling.rotational.enforcement: unknown value 'nitsche'"),
    ({"triad": "gram_schmidt"}, r"^coupling.rotational.triad: unknown value 'gram_schmidt'"),
    ({"lm": "line4"}, r"^coupling.rotational.lm: unknown value 'line4'"),
    ({"penalty": -1.0}, r"^coupling.rotational.penalty"),
    ({"tirad": "polar"}, r"^coupling.rotational.tirad: unknown key"),
])
def test_bad_rotational_coupling_keys(change, message):
    with pytest.raises(SceneError, match=message):
        block(2, 2, change)


def test_rotational_coupling_from_a_toml_scene(tmp_path):
    path = tmp_path / "fibre.toml"
    path.write_text("""
[solid]
mesh = { box = [[0, -0.1, -0.1], [1, 0.1, 0.1]], cells = [2, 3, 3] }
material = { model = "linear_elastic", E = 1e9, nu = 0.3 }

[[beams]]
curve = { line = [[0, 0, 0], [1, 0, 0]] }
elements = 4
model = "simo_reissner"
section = { E = 2e11, nu = 0.3, radius = 0.01 }

[coupling.rotational]
triad = "deformation_gradient"
lm = "line2"
penalty = 2e4

[[dirichlet]]
on = "solid:x_min"

[[load]]
type = "traction"
on = "solid:x_max"
value = [0, 0, -1e5]

[analysis]
kinematics = "linear"
""", encoding="utf-8")
    scene = m13.Scene.from_toml(path)
    assert scene.coupling["rotational"] == {"triad": "deformation_gradient", "enforcement": "penalty",
                                            "lm": "line2", "penalty": 2e4, "constraint": "mortar",
                                            "forces": "variational"}
    result = m13.solve(path)               # no rotation support: the rotational coupling holds the twist
    assert result.model.counts["coupling.rotational_penalty"] >= 2
    g = result.model.groups[0]
    u_beam = np.linalg.norm(result.beam_displacement, axis=1).max()
    u_solid = np.linalg.norm(result.solid_displacement, axis=1).max()
    assert 0.5 * u_solid < u_beam < u_solid
    assert g.rotational.triad == "deformation_gradient"


@pytest.mark.parametrize("rotational", [{"forces": "fourc", "constraint": "gauss_point"},
                                        {"forces": "fourc", "enforcement": "lagrange"}])
def test_fourc_forces_are_for_the_mortar_penalty_pair_only(rotational):
    with pytest.raises(SceneError, match=r"^coupling.rotational.forces: 'fourc' is 4C's force form of the mortar "
                                         r"constraint with penalty enforcement"):
        block(2, 2, rotational)
