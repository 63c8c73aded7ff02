"""Issue 18: Simo–Reissner beams through the public ``solve``: benchmarks against closed forms and
published values, coupling to a solid, supports, moments, output and scene errors."""
import math

import meshio
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import SceneError
from mortar1d3d.model import Model

from test_mechanisms import SOLID, arc


def cantilever(elements, load, steps, section=None, dirichlet=None, length=1.0, rule=None):
    """A straight Simo–Reissner cantilever along x, clamped at x = 0 (position, tangent, triad)."""
    section = section or {"EA": 1e4, "GA2": 1e4, "GA3": 1e4, "GI_T": 1.0, "EI2": 1.0, "EI3": 1.0}
    beam = {"curve": {"line": [[0, 0, 0], [length, 0, 0]]}, "elements": elements, "model": "simo_reissner",
            "section": section}
    if rule is not None:
        beam["force_rule"] = rule
    return m13.Scene(beams=[beam],
                     dirichlet=dirichlet or [{"on": "beam:0:start", "clamp": True}], load=load,
                     analysis={"steps": steps})


def tip_positions(result, length=1.0):
    """Tip position after every load step (physical components)."""
    model = result.model
    g = model.groups[0]
    return [model.basis.to_physical(z)[g.dofs.slice].reshape(-1, 6)[-1, :3] + [length, 0, 0] for z in result.history]


# -- roll-up -------------------------------------------------------------------------------------

def roll_up(elements):
    """End moment M = 2π EI/L in 8 steps: after step k the beam is an arc of angle φ = 2πk/8."""
    result = m13.solve(cantilever(elements, [{"type": "moment", "on": "beam:0:end", "value": [0, 0, 2 * math.pi]}],
                                  steps=8))
    errors = []
    for step, tip in zip(result.steps, tip_positions(result)):
        phi = 2 * math.pi * step.load_factor
        exact = np.array([math.sin(phi) / phi, (1 - math.cos(phi)) / phi, 0.0])
        errors.append(float(np.linalg.norm(tip - exact)))
    return result, np.array(errors)


def test_end_moment_rolls_the_cantilever_into_a_full_circle():
    fine, errors = roll_up(16)
    # the exact circle at every load step: tip (L/φ) sin φ, (L/φ)(1 - cos φ); measured 5.9e-9 at φ = π/4
    # growing to 5.9e-5 L at the full circle (16 elements)
    assert errors.max() < 1.2e-4
    assert errors[0] < 1e-8
    # full circle: the tip is back at the clamp and its triad is the identity (ψ = 0); measured |ψ| = 3.6e-4
    assert np.linalg.norm(fine.beam_displacement[-1] + [1.0, 0, 0]) < 1.2e-4
    assert np.linalg.norm(fine.beam_rotation[-1]) < 1e-3
    # Newton stays quadratic: 4 iterations per step (measured), the residual at round-off after them
    assert max(s.iterations for s in fine.steps) <= 5
    assert all(s.cuts == 0 for s in fine.steps)
    # convergence under refinement: measured 2.9e-3 with 8 elements, 49 times the error of 16
    _, coarse = roll_up(8)
    assert coarse[-1] / errors[-1] > 30


def test_newton_with_spatial_rotations_converges_quadratically():
    """Tip moment with a torsion part and an out-of-plane force: rotations about changing axes, where
    only the multiplicative update matches the tangent (an additive ψ update stalls here)."""
    result = m13.solve(cantilever(8, [{"type": "moment", "on": "beam:0:end", "value": [1.5, 0, 3.0]},
                                      {"type": "point", "on": "beam:0:end", "value": [0, 0, 2.0]}],
                                  steps=4, section={"EA": 1e4, "GA2": 1e4, "GA3": 1e4, "GI_T": 0.7, "EI2": 1.0,
                                                    "EI3": 1.0}))
    assert [s.iterations for s in result.steps] == [7, 11, 12, 10]        # measured; no step cut
    for s in result.steps:
        r = np.array(s.residuals) / s.residuals[0]
        # the last iterations contract quadratically: r_k+1 <= 1e3 r_k² once r_k < 1e-2
        small = np.flatnonzero(r[:-1] < 1e-2)
        assert len(small) and all(r[k + 1] <= max(1e3 * r[k] ** 2, 1e-10) for k in small)
    # equilibrium: the tip's triad carries the applied moment, tip moved out of plane
    assert result.beam_displacement[-1, 2] > 0.5


# -- large-deflection cantilever ------------------------------------------------------------------

#: Bisshopp & Drucker, Q Appl Math 3 (1945) 272-275: tip deflection of an inextensible cantilever
#: under a dead transverse tip load, α = PL²/EI → vertical deflection / L, horizontal shortening / L
#: (the elliptic-integral solution; a shooting solution of θ'' = -α cos θ gives the same 5 digits)
BISSHOPP_DRUCKER = {1.0: (0.30172, 0.05643), 2.0: (0.49346, 0.16064), 3.0: (0.60325, 0.25442)}


def test_large_deflection_cantilever_matches_bisshopp_drucker():
    stiff = {"EA": 1e6, "GA2": 1e6, "GA3": 1e6, "GI_T": 1.0, "EI2": 1.0, "EI3": 1.0}      # inextensible, no shear
    result = m13.solve(cantilever(16, [{"type": "point", "on": "beam:0:end", "value": [0, -3.0, 0]}], steps=3,
                                  section=stiff))
    for step, tip in zip(result.steps, tip_positions(result)):
        vertical, shortening = BISSHOPP_DRUCKER[round(3 * step.load_factor, 6)]
        # measured |error| 1.6e-6 .. 4.6e-5 L (16 elements)
        assert abs(-tip[1] - vertical) < 1e-4
        assert abs((1.0 - tip[0]) - shortening) < 1e-4


def test_prescribed_end_rotation_bends_the_beam_into_an_arc():
    """A rotation support at the free end (positions free): pure bending into a quarter circle."""
    theta = math.pi / 2
    scene = cantilever(16, [], steps=2, dirichlet=[{"on": "beam:0:start", "clamp": True},
                                                    {"on": "beam:0:end", "rotation": [0, 0, theta]}])
    result = m13.solve(scene)
    tip = tip_positions(result)[-1]
    assert np.linalg.norm(tip - [math.sin(theta) / theta, (1 - math.cos(theta)) / theta, 0]) < 1e-5
    np.testing.assert_allclose(result.beam_rotation[-1], [0, 0, theta], atol=1e-14)
    # the reaction moment of the support is EI θ / L (the rotation row of the residual)
    g = result.model.groups[0]
    end = g.rotations.dofs([g.mesh.n_nodes - 1], [0, 1, 2])
    np.testing.assert_allclose(result.model.last_residual[end], [0, 0, theta], rtol=1e-4, atol=1e-8)


# -- twist support --------------------------------------------------------------------------------

def pinned(support, load, kinematics="nonlinear", steps=2):
    """Beam along x: start position fixed plus ``support``, end held in y and z (no rigid motion
    but the twist, which ``support`` removes)."""
    return m13.Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 4, "model": "simo_reissner",
                             "section": {"EA": 1e4, "GA2": 1e4, "GA3": 1e4, "GI_T": 2.0, "EI2": 1.0, "EI3": 1.0}}],
                     dirichlet=[{"on": "beam:0:start"}, support, {"on": "beam:0:end", "components": ["y", "z"]}],
                     load=load, analysis={"steps": steps, "kinematics": kinematics})


def test_twist_support_holds_the_twist_and_nothing_else():
    torque = [{"type": "moment", "on": "beam:0:end", "value": [1.5, 0, 0]}]
    twist = m13.solve(pinned({"on": "beam:0:start", "twist": True}, torque))
    whole = m13.solve(pinned({"on": "beam:0:start", "rotation": [0, 0, 0]}, torque))
    # a torque turns the sections about the axis only: the tip turns by M L / GI_T, with either support
    np.testing.assert_allclose(twist.beam_rotation[-1], [1.5 / 2.0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(twist.beam_displacement, whole.beam_displacement, atol=1e-14)
    np.testing.assert_allclose(twist.beam_rotation, whole.beam_rotation, atol=1e-12)
    # an end moment bends the simply supported beam: the twist support leaves the start free to turn
    # (M L / 6 EI there, M L / 3 EI at the loaded end), a whole-rotation support would clamp it
    bend = [{"type": "moment", "on": "beam:0:end", "value": [0, 0, 1e-3]}]
    result = m13.solve(pinned({"on": "beam:0:start", "twist": True}, bend, kinematics="linear"))
    np.testing.assert_allclose(result.beam_rotation[[0, -1], 2], [-1e-3 / 6, 1e-3 / 3], rtol=1e-3)
    clamped = m13.solve(pinned({"on": "beam:0:start", "rotation": [0, 0, 0]}, bend, kinematics="linear"))
    assert abs(clamped.beam_rotation[0, 2]) < 1e-12


def test_twist_support_at_a_node_that_turns_far():
    """Roll-up to a quarter circle with the twist of the tip held: the tip turns by π/2 about z,
    normal to its reference tangent, so the support changes nothing; Newton stays quadratic (the
    unknowns of the held node are its rotation vector, additive, with the exact Jacobian)."""
    load = [{"type": "moment", "on": "beam:0:end", "value": [0, 0, math.pi / 2]}]
    free = m13.solve(cantilever(8, load, steps=2))
    held = m13.solve(cantilever(8, load, steps=2, dirichlet=[{"on": "beam:0:start", "clamp": True},
                                                             {"on": "beam:0:end", "twist": True}]))
    np.testing.assert_allclose(held.beam_rotation[-1], [0, 0, math.pi / 2], atol=1e-4)
    np.testing.assert_allclose(held.beam_rotation, free.beam_rotation, atol=1e-12)
    np.testing.assert_allclose(held.beam_displacement, free.beam_displacement, atol=1e-12)
    assert [s.iterations for s in held.steps] == [s.iterations for s in free.steps]
    # the Jacobian against central differences of the residual through the model's own update, away
    # from equilibrium (a perturbed state of load factor 1, evaluated at 0.5)
    model, z = held.model, held.model.basis.to_unknowns(held.history[-1])
    free_dofs = model.free
    model.update(z, free_dofs, 0.05 * np.random.default_rng(4).normal(size=len(free_dofs)))
    r, K = model.residual(z, 0.5)
    h, columns = 1e-6, []
    for j in range(len(free_dofs)):
        rs = []
        for sign in (1.0, -1.0):
            w = z.copy()
            step = np.zeros(len(free_dofs))
            step[j] = sign * h
            model.update(w, free_dofs, step)
            rs.append(model.residual(w, 0.5, tangent=False)[0])
        columns.append((rs[0] - rs[1]) / (2 * h))
    fd = np.array(columns).T[free_dofs]
    Kf = K.toarray()[np.ix_(free_dofs, free_dofs)]
    assert np.abs(Kf - fd).max() < 1e-6 * np.abs(Kf).max()


def test_twist_support_errors():
    tf = {"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "section": {"EA": 1.0, "EI": 1.0}}
    with pytest.raises(SceneError, match=r"^dirichlet\[0\]\.twist: the twist is held on beam sets only"):
        m13.Scene(solid=SOLID, beams=[sr_beam()], dirichlet=[{"on": "solid:x_min", "twist": True}])
    with pytest.raises(SceneError, match=r"^dirichlet\[0\]\.twist: give twist or a whole rotation"):
        m13.Scene(beams=[sr_beam()], dirichlet=[{"on": "beam:0:start", "twist": True, "rotation": [0, 0, 0]}])
    with pytest.raises(SceneError, match=r"^dirichlet\[0\]\.twist: beam 0 is a torsion_free beam"):
        m13.Scene(beams=[tf], dirichlet=[{"on": "beam:0:start", "twist": True}])
    with pytest.raises(SceneError, match=r"^dirichlet\[1\]: prescribes the whole rotation of a node whose twist"):
        Model(m13.Scene(beams=[sr_beam()], dirichlet=[{"on": "beam:0:start", "twist": True},
                                                      {"on": "beam:0", "rotation": [0, 0, 0]}]))
    # an entry with only twist fixes no positions
    assert m13.Scene(beams=[sr_beam()], dirichlet=[{"on": "beam:0:start", "twist": True}]).dirichlet[0][
        "components"] == []


# -- coupled to a solid ---------------------------------------------------------------------------

ARC_SCENE = dict(solid=SOLID, dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -5e6]}])
SECTION = {"E": 2e11, "nu": 0.3, "radius": 0.005}


@pytest.mark.parametrize("enforcement, constraint", [("penalty", "mortar"), ("lagrange", "mortar"),
                                                     ("penalty", "gauss_point")])
def test_half_circle_arc_tied_to_a_block_follows_it(enforcement, constraint):
    """The arc that the torsion-free beam refuses (tests/test_mechanisms.py) as a simo_reissner beam:
    the curvature ties its twist to its bending, so the positional coupling alone holds it."""
    scene = m13.Scene(beams=[{"mesh": arc(), "model": "simo_reissner", "section": SECTION}],
                      coupling={"enforcement": enforcement, "constraint": constraint}, **ARC_SCENE)
    result = m13.solve(scene)
    u_beam = np.linalg.norm(result.beam_displacement, axis=1).max()
    u_solid = np.linalg.norm(result.solid_displacement, axis=1).max()
    # measured 0.02275 m (0.02274 Gauss-point) in a solid that moves 0.0341 m; the truss: 0.0236 m
    assert 0.6 * u_solid < u_beam < 0.7 * u_solid
    assert np.abs(result.beam_rotation).max() < 0.05          # measured 0.036 rad
    assert result.steps[0].iterations <= 5


def test_half_circle_arc_converges_under_refinement():
    starts = []
    for n in (12, 24, 48):
        scene = m13.Scene(beams=[{"mesh": arc(elements=n), "model": "simo_reissner", "section": SECTION}],
                          coupling={"enforcement": "lagrange"}, analysis={"kinematics": "linear"}, **ARC_SCENE)
        starts.append(m13.solve(scene).beam_displacement[0])
    d1, d2 = np.linalg.norm(starts[1] - starts[0]), np.linalg.norm(starts[2] - starts[1])
    # measured 6.2e-6 then 1.4e-6 against |u| = 0.0227 m
    assert d2 < 0.5 * d1 and d1 < 1e-3 * np.linalg.norm(starts[2])


def rod(enforcement="penalty", constraint="mortar", support=True):
    """A straight simo_reissner fibre in the unit cube (positional coupling only)."""
    dirichlet = [{"on": "solid:x_min"}] + ([{"on": "beam:0:start", "rotation": [0, 0, 0]}] if support else [])
    return m13.Scene(solid=SOLID, beams=[{"curve": {"line": [[0.2, 0.45, 0.55], [0.9, 0.5, 0.5]]}, "elements": 8,
                                          "model": "simo_reissner", "section": {"E": 2e11, "nu": 0.3, "radius": 0.01}}],
                     coupling={"enforcement": enforcement, "constraint": constraint}, dirichlet=dirichlet,
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                     analysis={"kinematics": "linear"})


@pytest.mark.parametrize("enforcement, constraint", [("penalty", "mortar"), ("lagrange", "mortar"),
                                                     ("penalty", "gauss_point")])
def test_straight_fibre_tied_by_position_only_has_a_free_twist(enforcement, constraint):
    model = Model(rod(enforcement, constraint, support=False))
    with pytest.raises(SceneError, match=r"^beams\[0\]: zero-energy mode .*cross-sections turn about the centreline "
                                         r"\(a twist about its axis, nodes 0, 1, 2, 3, 4, 5, 6, 7, 8\).*Support the rotation at one node "
                                         r"\(\[\[dirichlet\]\] on = \"beam:0:start\", rotation = \[0, 0, 0\]\)"):
        model.prepare()
    (group, mechanism), = model.zero_energy_modes
    # the mode turns the triads only, and the reference tangent has no stiffness against it
    n_cl = group.mesh.n_centreline_dofs
    assert np.abs(mechanism.mode[:n_cl]).max() == 0.0 or np.abs(mechanism.mode[:n_cl]).max() < 1e-12
    w = np.zeros(model.n_displacement_dofs)
    w[group.dofs.slice] = mechanism.mode[:n_cl]
    w[group.rotations.slice] = mechanism.mode[n_cl:]
    _, K = model.internal(np.zeros(model.n_displacement_dofs))
    assert np.abs(K @ w).max() < 1e-9 * abs(K).max()
    # one rotation support fixes it; the fibre then follows the solid
    result = m13.solve(rod(enforcement, constraint))
    u_beam = np.linalg.norm(result.beam_displacement, axis=1).max()
    u_solid = np.linalg.norm(result.solid_displacement, axis=1).max()
    assert 0.7 * u_solid < u_beam < u_solid          # measured 0.00531 m in a solid moving 0.00681 m


# -- output ---------------------------------------------------------------------------------------

def test_vtu_output_has_triads_resultants_and_strains(tmp_path):
    result = m13.solve(cantilever(4, [{"type": "moment", "on": "beam:0:end", "value": [0, 0, math.pi / 2]}], steps=1))
    result.write(tmp_path / "out", samples_per_element=3)
    mesh = meshio.read(tmp_path / "out" / "beams_0001.vtu")
    data = mesh.point_data
    for key in ("displacement", "axial_force", "curvature", "g1", "g2", "g3", "n", "m", "Gamma", "K"):
        assert key in data, key
    # pure bending about z by M = π/2: moment m = (0, 0, π/2) everywhere (to the discretisation error of
    # 4 elements, measured 2e-3 relative), g3 = e_z, curvature π/2
    np.testing.assert_allclose(data["m"], np.tile([0, 0, math.pi / 2], (len(data["m"]), 1)), rtol=0, atol=5e-3)
    np.testing.assert_allclose(data["g3"], np.tile([0, 0, 1.0], (len(data["g3"]), 1)), atol=1e-12)
    np.testing.assert_allclose(data["curvature"], math.pi / 2, rtol=5e-3)
    # the tip's triad g1 has turned by π/2 into e_y
    np.testing.assert_allclose(data["g1"][-1], [0, 1, 0], atol=3e-3)         # measured 1.9e-3 off
    reference = meshio.read(tmp_path / "out" / "beams_0000.vtu").point_data
    np.testing.assert_allclose(reference["g1"], np.tile([1.0, 0, 0], (len(reference["g1"]), 1)), atol=1e-15)


# -- scene ----------------------------------------------------------------------------------------

def sr_beam(**extra):
    beam = {"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "model": "simo_reissner",
            "section": {"E": 1.0, "G": 0.4, "A": 1.0, "I2": 0.1, "I3": 0.1, "I_T": 0.2}}
    beam.update(extra)
    return beam


def test_sections_of_a_simo_reissner_beam():
    circle = m13.Scene(beams=[sr_beam(section={"E": 2e11, "nu": 0.3, "radius": 0.01})]).beams[0]["section"]
    r, E, G = 0.01, 2e11, 2e11 / 2.6
    k = 6 * 1.3 / (7 + 6 * 0.3)             # Cowper's shear correction of a solid circle
    expected = {"EA": E * math.pi * r * r, "GA2": G * k * math.pi * r * r, "GI_T": G * math.pi * r ** 4 / 2,
                "EI2": E * math.pi * r ** 4 / 4}
    for key, value in expected.items():
        assert circle[key] == pytest.approx(value, rel=1e-14)
    general = m13.Scene(beams=[sr_beam()]).beams[0]["section"]
    assert (general["EA"], general["GA3"], general["GI_T"], general["EI3"]) == (1.0, 0.4, 0.4 * 0.2, 0.1)
    given = {"EA": 1.0, "GA2": 2.0, "GA3": 3.0, "GI_T": 4.0, "EI2": 5.0, "EI3": 6.0}
    assert {k: v for k, v in m13.Scene(beams=[sr_beam(section=given)]).beams[0]["section"].items()
            if k in given} == given


@pytest.mark.parametrize("change, message", [
    (dict(section={"E": 1.0, "G": 0.4, "A": 1.0, "I2": 0.1, "I3": 0.1}), r"^beams\[0\]\.section\.I_T: missing"),
    (dict(section={"E": 1.0, "nu": 0.3, "G": 0.4, "radius": 0.1}), r"^beams\[0\]\.section\.G: give exactly one of G"),
    # G = E/4 means ν = 1: no isotropic material, so no Cowper correction (it used to fall back to k = 1 silently)
    (dict(section={"E": 1.0, "G": 0.25, "radius": 0.1}), r"^beams\[0\]\.section\.G: E/\(2G\) - 1 = 1 is not a Poisson"),
    (dict(section={"EA": 1.0, "GA2": 1.0, "GA3": 1.0, "GI_T": 1.0, "EI2": 1.0}), r"^beams\[0\]\.section\.EI3: missing"),
    (dict(section={"EA": 1.0, "GA2": 1.0, "GA3": 1.0, "GI_T": 1.0, "EI2": 1.0, "EI3": 1.0, "E": 1.0}),
     r"^beams\[0\]\.section\.E: give either the stiffnesses"),
    (dict(section={"E": 1.0, "nu": 0.3, "radius": 0.1, "I_T": 1.0}), r"^beams\[0\]\.section\.I_T: a circular section"),
    (dict(normal=[0, 0, 0]), r"^beams\[0\]\.normal: must not be zero"),
])
def test_bad_simo_reissner_sections(change, message):
    with pytest.raises(SceneError, match=message):
        m13.Scene(beams=[sr_beam(**change)])


def test_scene_errors_of_rotations_and_triads():
    clamp = [{"on": "beam:0:start", "clamp": True}]
    # a partial rotation vector, and a rotation on a beam without rotation DOFs
    with pytest.raises(SceneError, match=r"^dirichlet\[1\]\.rotation: expected the total rotation vector .*all three "
                                         r"components.*got 2 entries"):
        m13.Scene(beams=[sr_beam()], dirichlet=clamp + [{"on": "beam:0:end", "rotation": [0.1, 0.2]}])
    tf = {"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "section": {"EA": 1.0, "EI": 1.0}}
    with pytest.raises(SceneError, match=r"^dirichlet\[1\]\.rotation: beam 0 is a torsion_free beam, which has no "
                                         r"rotation DOFs"):
        m13.Scene(beams=[tf], dirichlet=clamp + [{"on": "beam:0:end", "rotation": [0, 0, 1]}])
    with pytest.raises(SceneError, match=r"^dirichlet\[0\]\.rotation: a rotation is prescribed on beam sets only"):
        m13.Scene(solid=SOLID, beams=[sr_beam()], dirichlet=[{"on": "solid:x_min", "rotation": [0, 0, 0]}])
    # a moment on a truss; a moment on all nodes of a torsion-free beam
    truss = dict(tf, model="truss", section={"EA": 1.0})
    with pytest.raises(SceneError, match=r"^load\[0\]\.on: a moment needs a beam with bending stiffness; beam 0 is a truss"):
        m13.Scene(beams=[truss], load=[{"type": "moment", "on": "beam:0:end", "value": [0, 0, 1]}])
    with pytest.raises(SceneError, match=r"^load\[0\]\.on: a moment on a torsion_free beam acts on a beam end"):
        m13.Scene(beams=[tf], load=[{"type": "moment", "on": "beam:0", "value": [0, 0, 1]}])
    with pytest.raises(SceneError, match=r"^beams\[0\]\.normal: a torsion_free beam has no material frame"):
        m13.Scene(beams=[dict(tf, normal=[0, 0, 1])])
    # given triads: checked at build (plan reports them), naming the key path and the rotation nodes
    good = np.tile(np.eye(3), (5, 1, 1))            # 3 nodes + 2 middle nodes, g1 = e_x
    m13.plan(m13.Scene(beams=[sr_beam(triads=good)], dirichlet=clamp))
    skew = good.copy()
    skew[4] = [[1, 0, 0], [0, 1, 0.1], [0, 0, 1]]
    with pytest.raises(SceneError, match=r"^beams\[0\]\.triads: reference triads are not orthonormal at rotation "
                                         r"nodes 4"):
        m13.plan(m13.Scene(beams=[sr_beam(triads=skew)], dirichlet=clamp))
    with pytest.raises(SceneError, match=r"^beams\[0\]\.triads: expected shape \(5, 3, 3\)"):
        m13.plan(m13.Scene(beams=[sr_beam(triads=good[:3])], dirichlet=clamp))
    with pytest.raises(SceneError, match=r"^beams\[0\]\.normal: .*parallel to the tangent"):
        m13.plan(m13.Scene(beams=[sr_beam(normal=[1, 0, 0])], dirichlet=clamp))


def _per_beam_option(key, default, value, wrong, what):
    """The simo_reissner beam key ``key``: an error on a torsion_free beam (which has no ``what``) and for
    the unknown name ``wrong``; ``value`` on the second of two clamped cantilevers reaches that beam's
    elements only (the first keeps ``default``)."""
    tf = {"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "section": {"EA": 1.0, "EI": 1.0}}
    with pytest.raises(SceneError, match=rf"^beams\[0\]\.{key}: a torsion_free beam has no {what}"):
        m13.Scene(beams=[dict(tf, **{key: value})])
    with pytest.raises(SceneError, match=rf"^beams\[0\]\.{key}: .*'{wrong}'"):
        m13.Scene(beams=[sr_beam(**{key: wrong})])
    other = sr_beam(curve={"line": [[0, 1, 0], [1, 1, 0]]}, **{key: value})
    model = Model(m13.Scene(beams=[sr_beam(), other], dirichlet=[{"on": "beam:0:start", "clamp": True},
                                                                 {"on": "beam:1:start", "clamp": True}]))
    model.prepare()
    assert getattr(model.groups[0].physics, key).tolist() == [default, default, value, value]


def test_force_rule_of_a_simo_reissner_beam():
    """``force_rule = "lobatto3"`` reaches the physics per beam; other models and names are errors."""
    _per_beam_option("force_rule", "gauss", "lobatto3", "lobatto", "force")
    # a tip load on a 2-element cantilever: the rules differ by the discretisation error (measured tip
    # deflection 0.2752 with the Gauss force rule, 0.2722 with Lobatto)
    load = [{"type": "point", "on": "beam:0:end", "value": [0, 0, -0.05]}]
    tips = [m13.solve(cantilever(2, load, steps=2, section=sr_beam()["section"],
                                 rule=rule)).beam_displacement[-1] for rule in (None, "lobatto3")]
    assert 0.5e-2 < tips[0][2] / tips[1][2] - 1 < 2e-2 and 0.25 < -tips[0][2] < 0.3


def test_an_unclamped_simo_reissner_cantilever_can_twist_freely():
    """Position and tangent direction fixed, the triad free: the beam turns about its own axis, a
    rigid motion that the torsion-free beam does not have (it has no triads)."""
    with pytest.raises(SceneError, match=r"rigid-body mode\(s\) not fixed: rotation about x"):
        m13.solve(cantilever(2, [], steps=1, dirichlet=[{"on": "beam:0:start"},
                                                        {"on": "beam:0:start", "components": ["y", "z"]},
                                                        {"on": "beam:0:end", "components": ["y", "z"]}]))


def test_plan_lists_the_rotations():
    effects = {e.name: e for e in m13.plan(cantilever(2, [{"type": "moment", "on": "beam:0", "value": [0, 0, 1]}],
                                                      steps=2))}
    assert "5 rotation nodes" in effects["beam.rotations"].detail
    assert "log(exp(Δθ) exp(ψ))" in effects["beam.rotation_update"].detail
    assert effects["load.moment"].when == "once"
    result = m13.solve(cantilever(2, [{"type": "moment", "on": "beam:0", "value": [0, 0, 0.1]}], steps=2))
    assert set(result.counts) <= set(effects)


def test_the_arc_in_block_example_runs(tmp_path, capsys):
    from pathlib import Path

    from mortar1d3d.cli import main
    example = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "arc_in_block.toml"
    assert main(["run", str(example), "--out", str(tmp_path / "arc")]) in (0, None)
    assert capsys.readouterr().out.count("load factor") == 2
    beams = meshio.read(tmp_path / "arc" / "beams_0002.vtu").point_data
    for key in ("g1", "g2", "g3", "n", "m", "line_load"):
        assert key in beams
    solid = meshio.read(tmp_path / "arc" / "solid_0002.vtu").point_data["displacement"]
    # the fibre follows the bent block: measured 2.44 mm in a block whose tip moves 2.87 mm
    assert 0.5 * np.abs(solid).max() < np.abs(beams["displacement"]).max() < np.abs(solid).max()


def test_nonlinear_simo_reissner_scenes_solve_directly():
    """CG and MINRES need a symmetric tangent; the Simo–Reissner tangent is not, away from the reference."""
    scene = cantilever(2, [], steps=1)
    scene.analysis["solver"] = "amg"
    with pytest.raises(SceneError, match=r"^analysis\.solver: 'amg' runs CG or MINRES.*simo_reissner beam's tangent "
                                         r"is not symmetric"):
        Model(scene)
    scene.analysis["solver"] = "auto"
    assert Model(scene).linear_solver_method(10 ** 6) == "direct"


#: the 45° bend cantilever: tip positions under the out-of-plane tip load P published by Bathe &
#: Bolourchi (Int J Numer Meth Eng 14, 1979) and Simo & Vu-Quoc (CMAME 58, 1986), both 8 elements
BEND_REFERENCE = {300.0: ((22.33, 58.84, 40.08), (22.5, 59.2, 39.5)),
                  600.0: ((15.79, 47.23, 53.37), (15.9, 47.2, 53.4))}


def test_45_degree_bend_matches_the_published_tip_positions():
    """R = 100, 45° arc in the x-y plane, clamped at the origin, P along z at the tip; E = 1e7, A = 1,
    I = 1/12, G = E/2 (GA = 5e6, GI_T = EI = 833 333); 8 elements, P up to 600."""
    from mortar1d3d import BeamMesh
    R, E = 100.0, 1e7
    mesh = BeamMesh.from_curve(lambda t: np.array([R - R * np.cos(t), R * np.sin(t), 0.0]),
                               lambda t: np.array([R * np.sin(t), R * np.cos(t), 0.0]), 0.0, math.pi / 4, 8)
    section = {"EA": E, "GA2": E / 2, "GA3": E / 2, "GI_T": E / 12, "EI2": E / 12, "EI3": E / 12}
    scene = m13.Scene(beams=[{"mesh": mesh, "model": "simo_reissner", "section": section}],
                      dirichlet=[{"on": "beam:0:start", "clamp": True}],
                      load=[{"type": "point", "on": "beam:0:end", "value": [0, 0, 600.0]}], analysis={"steps": 6})
    result = m13.solve(scene)
    g = result.model.groups[0]
    tips = {round(600 * s.load_factor, 6): result.model.basis.to_physical(z)[g.dofs.slice].reshape(-1, 6)[-1, :3]
            + mesh.positions[-1] for s, z in zip(result.steps, result.history)}
    for load, (bathe, simo) in BEND_REFERENCE.items():
        # measured (22.24, 58.79, 40.18) and (15.68, 47.17, 53.44): 0.14 from Bathe & Bolourchi's
        # positions, 0.84 and 0.23 from Simo & Vu-Quoc's (rounded to 0.1; the two references differ by 0.7)
        assert np.linalg.norm(tips[load] - bathe) < 0.2
        assert np.linalg.norm(tips[load] - simo) < 1.0


@pytest.mark.parametrize("enforcement, solver", [("penalty", "amg"), ("lagrange", "block")])
def test_linear_iterative_solvers_take_the_rotations(enforcement, solver):
    """At the stress-free reference the tangent is symmetric: CG with the auxiliary-space preconditioner
    (rotation rows of the prolongation zero) and block MINRES give the direct solution."""
    direct = m13.solve(rod(enforcement))
    scene = rod(enforcement)
    scene.analysis["solver"] = solver
    iterative = m13.solve(scene)
    assert iterative.counts[f"linear_solver.{solver}"] == 1
    scale = np.abs(direct.beam_displacement).max()
    # measured 1.5e-10 (amg) and 4.6e-11 (block) relative; rotations 3.3e-10 and 6.7e-11
    assert np.abs(iterative.beam_displacement - direct.beam_displacement).max() < 1e-5 * scale
    assert np.abs(iterative.beam_rotation - direct.beam_rotation).max() < 1e-5 * np.abs(direct.beam_rotation).max()


def test_virtual_spins_of_a_simo_reissner_beam():
    """``virtual_spins = "lagrange"`` reaches the physics per beam; other models and names are errors.
    A 3D end moment on a cantilever (bending and twist): the two forms differ by the discretisation
    error and converge to one solution as the beam is refined."""
    _per_beam_option("virtual_spins", "exact", "lagrange", "variational", "spins")

    def tip(elements, spins):
        scene = cantilever(elements, [{"type": "moment", "on": "beam:0:end", "value": [0.4, 0.3, 0.5]}], steps=2)
        scene.beams[0]["virtual_spins"] = spins
        return m13.solve(scene).beam_displacement[-1]
    gaps = [np.abs(tip(n, "lagrange") - tip(n, "exact")).max() for n in (2, 8)]
    # measured: 3.6e-4 with 2 elements, 1.4e-7 with 8 (7.7e-6 with 4, 2.2e-9 with 16)
    assert 2e-4 < gaps[0] < 6e-4 and 5e-8 < gaps[1] < 3e-7
