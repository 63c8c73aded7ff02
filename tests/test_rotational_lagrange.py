"""Issue 18 item 4: rotational coupling enforced with Lagrange multipliers, and the rotational
line moments in the Result and the beam VTU.

The fibre on the axis of a block whose nodes follow a twist (tests/test_rotational_coupling.py):
Lagrange enforcement is the limit of penalty enforcement (the difference falls like 1/ε), carries
the torsion GI_T τ, its multipliers are line moments whose integral over the fibre's half is the
torque the fibre carries there, and dependent rotational rows are found and left out like
positional ones."""
import warnings

import meshio
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import SceneError
from mortar1d3d.errors import CouplingWarning
from mortar1d3d.model import Model, plan
from mortar1d3d.result import Result
from mortar1d3d.solvers.newton import solve_linear_step, solve_load_steps

from test_rotational_coupling import ALL, SECTION, TAU, middle, moments, twist_bend


def scene(rotational, n=4, beam_elements=8, kinematics="nonlinear", coupling=None, solver="auto"):
    """The block [0, 1] × [-0.1, 0.1]² (n × 3 × 3 hex8 cells) with a fibre on its axis, all solid
    nodes prescribed (their values are set by the caller)."""
    coupling = dict(coupling or {}, rotational=rotational)
    return m13.Scene(solid={"mesh": {"box": [[0, -0.1, -0.1], [1, 0.1, 0.1]], "cells": [n, 3, 3]},
                            "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": beam_elements,
                             "model": "simo_reissner", "section": SECTION}],
                     coupling=coupling, dirichlet=[{"on": ALL}],
                     analysis={"kinematics": kinematics, "steps": 2, "solver": solver})


def twisted(sc):
    """Solve ``sc`` (nonlinear) with the solid twisted by τ about the x axis; all unknowns."""
    model = Model(sc).prepare()
    X = model.solid_mesh.points
    model.fixed_values[:X.size] = (twist_bend(X, TAU, 0.0) - X).ravel()
    z, records, history = solve_load_steps(model, np.zeros(model.n_unknowns), 2, rtol=1e-10, increment_rtol=1e-10)
    return model, z, records, history


def twisted_linear(sc):
    """Solve ``sc`` (linear) with the solid given the infinitesimal twist u = τ x (0, -z, y)."""
    model = Model(sc).prepare()
    X = model.solid_mesh.points
    x, y, z = X.T
    model.fixed_values[:X.size] = np.column_stack([0 * x, -TAU * x * z, TAU * x * y]).ravel()
    z, record, residual = solve_linear_step(model, np.zeros(model.n_unknowns))
    model.last_residual = residual
    return model, z, [record], [z.copy()]


def torsion_error(model, z):
    section = model.groups[0].physics.sections[0]
    M = middle(moments(model, z[:model.n_displacement_dofs]))
    return np.abs(M[:, 0] / (section.GI_T * TAU) - 1.0).max(), np.abs(M[:, 1:]).max() / (section.GI_T * TAU)


def line_moment(model, z):
    return Result(model, z, [], []).line_moment


# -- Lagrange against penalty ---------------------------------------------------------------------

def test_lagrange_rotational_coupling_carries_the_torsion_and_is_planned():
    sc = scene({"enforcement": "lagrange"})
    assert "coupling.rotational_lagrange" in [e.name for e in plan(sc)]
    assert "coupling.rotational_penalty" not in [e.name for e in plan(sc)]
    model, z, records, _ = twisted(sc)
    rc = model.groups[0].rotational
    assert rc.enforcement == "lagrange" and model.n_multipliers == rc.n_multipliers == 3 * 17   # line3: 2·8 + 1
    assert model.counts["coupling.rotational_lagrange"] > 0 and model.counts["coupling.rotational_penalty"] == 0
    assert max(r.iterations for r in records) <= 3
    torsion, bending = torsion_error(model, z)
    # measured 1.6e-4 (penalty at its default ε: 2.5e-3)
    assert torsion < 3e-4 and bending < 1e-9
    # the constraint holds: the weighted relative rotations vanish (the pointwise ones do not: more
    # integration points than LM nodes; measured 2.4e-7 rad at most)
    u, psi = z[:3 * model.n_solid_nodes], z[model.groups[0].rotations.slice].reshape(-1, 3)
    assert np.abs(rc.weighted_gap(u, psi)).max() < 1e-14
    assert 1e-7 < np.abs(rc.relative_rotations(u, psi)).max() < 1e-6


def test_penalty_tends_to_lagrange_like_one_over_the_penalty():
    """Line moments and beam rotations of penalty runs, ε = 1e8, 1e9, 1e10, against the Lagrange
    run. Measured, line moments (relative to their largest value): 4.5e-2, 4.8e-3, 4.8e-4; beam
    rotations 2.5e-4, 2.6e-5, 2.7e-6 rad."""
    model, z, _, _ = twisted(scene({"enforcement": "lagrange"}))
    lam, rot = line_moment(model, z), z[model.groups[0].rotations.slice]
    moment_error, rotation_error = [], []
    for eps in (1e8, 1e9, 1e10):
        model_p, z_p, _, _ = twisted(scene({"penalty": eps}))
        moment_error.append(np.abs(line_moment(model_p, z_p) - lam).max() / np.abs(lam).max())
        rotation_error.append(np.abs(z_p[model_p.groups[0].rotations.slice] - rot).max())
    for e in (moment_error, rotation_error):
        ratio = np.array(e[:-1]) / np.array(e[1:])
        assert np.all((ratio > 8.5) & (ratio < 11.0)), e           # rate 1/ε
    assert 4e-2 < moment_error[0] < 5e-2 and 2e-4 < rotation_error[0] < 3e-4


def test_linear_analysis_lagrange_is_exact_for_an_infinitesimal_twist_and_penalty_tends_to_it():
    """Linear kinematics, u = τ x (0, -z, y): the linearised constraint asks for the twist τ
    exactly, which the fibre's line3 triads represent: GI_T τ to round-off (measured 1e-14).
    Penalty line moments (linearised gap) differ by 4.8e-3, 4.8e-4, 4.8e-5 at ε = 1e9, 1e10, 1e11."""
    model, z, _, _ = twisted_linear(scene({"enforcement": "lagrange"}, kinematics="linear"))
    torsion, bending = torsion_error(model, z)
    assert torsion < 1e-11 and bending < 1e-11
    assert model.counts["linear_solver.direct"] == 1
    lam = line_moment(model, z)
    errors = []
    for eps in (1e9, 1e10, 1e11):
        model_p, z_p, _, _ = twisted_linear(scene({"penalty": eps}, kinematics="linear"))
        errors.append(np.abs(line_moment(model_p, z_p) - lam).max() / np.abs(lam).max())
    assert 4e-3 < errors[0] < 6e-3 and all(8.5 < a / b < 11.0 for a, b in zip(errors, errors[1:]))


def test_positional_and_rotational_multipliers_together():
    """Both couplings by multipliers: the positional rows first, then the rotational ones; the
    same torsion as rotational multipliers with a penalty-tied centreline (1e-6 relative: the
    centreline follows the axis in both)."""
    model, z, _, _ = twisted(scene({"enforcement": "lagrange"}, coupling={"enforcement": "lagrange"}))
    rc, pc = model.groups[0].rotational, model.groups[0].coupling
    assert model.n_multipliers == pc.n_multipliers + rc.n_multipliers and pc.n_multipliers > 0
    model_p, z_p, _, _ = twisted(scene({"enforcement": "lagrange"}))
    np.testing.assert_allclose(line_moment(model, z), line_moment(model_p, z_p), rtol=0,
                               atol=1e-6 * np.abs(line_moment(model_p, z_p)).max())
    result = Result(model, z, [], [])
    assert result.line_load.shape == (pc.n_lm, 3) and result.line_moment.shape == (rc.n_lm, 3)


def test_dependent_rotational_rows_are_found_and_left_out():
    """Two integration points per beam element (element-based integration, n_gauss = 2) against
    three line3 rotational LM functions per element: 2·8 points for 17 LM nodes, so one LM node's
    three rows depend on the others. They are named and left out; the constraint still holds at
    every integration point."""
    sc = scene({"enforcement": "lagrange"}, coupling={"integration": "element", "n_gauss": 2})
    with pytest.warns(CouplingWarning, match=r"coupling.rotational.lm: the coupling rows of beams\[0\] rotational "
                                             r"LM nodes 1 \(x, y, z\) are combinations of the other rows.*integration points "
                                             r"along the beam \(n_gauss\)"):
        model, z, _, _ = twisted(sc)
    assert list(model._dependent.rows) == [3, 4, 5]
    rc = model.groups[0].rotational
    psi = rc.relative_rotations(z[:3 * model.n_solid_nodes], z[model.groups[0].rotations.slice].reshape(-1, 3))
    assert np.abs(psi).max() < 1e-12
    assert torsion_error(model, z)[0] < 5e-4           # measured 2.4e-4
    # the default segment integration (3 or more points per element) has no dependent rows
    with warnings.catch_warnings():
        warnings.simplefilter("error", CouplingWarning)
        model, _, _, _ = twisted(scene({"enforcement": "lagrange"}))
    assert len(model._dependent) == 0


@pytest.mark.parametrize("solver", ["amg", "block"])
def test_iterative_solvers_with_rotational_multipliers_are_refused(solver):
    with pytest.raises(SceneError, match=rf"^analysis.solver: '{solver}' is not implemented with "
                                         r"coupling.rotational.enforcement = \"lagrange\""):
        Model(scene({"enforcement": "lagrange"}, kinematics="linear", solver=solver,
                    coupling={"enforcement": "lagrange"} if solver == "block" else None))


# -- output: line moments ---------------------------------------------------------------------------

@pytest.mark.parametrize("enforcement", ["lagrange", "penalty"])
def test_line_moments_integrate_to_the_torque_the_fibre_carries(enforcement, tmp_path):
    """Equilibrium of the fibre's left half: its line moments integrate (Σ κ_j λ_j over the LM
    nodes left of the middle; the middle node's λ is 0 by symmetry) to the torque GI_T K1 at the
    middle, and over the whole fibre to zero. The beam VTU carries them per step."""
    model, z, records, history = twisted(scene({"enforcement": enforcement}))
    rc = model.groups[0].rotational
    result = Result(model, z, records, history)
    lam = result.line_moment
    assert lam.shape == (rc.n_lm, 3) and rc.n_lm == 17
    section = model.groups[0].physics.sections[0]
    torque = moments(model, z[:model.n_displacement_dofs], eta=(1.0,))[3, 0, 0]       # end of element 3: x = 0.5
    assert torque == pytest.approx(section.GI_T * TAU, rel=5e-3)
    # line3 LM nodes of element e: e, e + 1 (its ends), 9 + e (its middle)
    assert rc.lm_index[3, :3].tolist() == [3, 4, 12]
    left = np.r_[0:4, 9:13]                           # x < 0.5
    assert abs(lam[4, 0]) < 1e-9 * abs(torque)        # the middle node (x = 0.5)
    left = rc.kappa[left] @ lam[left, 0]
    # λ is the moment the beam puts on the solid (−λ on the beam): at the free end the torque is 0,
    # so the solid's moment on the left half, −∫λ, balances the torque −GI_T K1 at its cut.
    # Measured 1.7e-3 (lagrange), 7e-4 (penalty): the moment sampled at the element end is
    # not exactly the discrete equilibrium one
    assert left == pytest.approx(torque, rel=3e-3)
    assert abs(rc.kappa @ lam[:, 0]) < 1e-9 * abs(torque)
    assert np.abs(lam[:, 1:]).max() < 1e-8 * np.abs(lam[:, 0]).max()
    # per step: the first of two steps carries half the twist (a little less: finite rotations)
    np.testing.assert_allclose(result.line_moments(-1), lam, rtol=0, atol=0)
    first = result.line_moments(0)
    assert rc.kappa[np.r_[0:4, 9:13]] @ first[np.r_[0:4, 9:13], 0] == pytest.approx(0.5 * left, rel=1e-2)
    result.write(tmp_path / "out", samples_per_element=3)
    for k, step in ((0, None), (1, 0), (2, 1)):
        data = meshio.read(tmp_path / "out" / f"beams_{k:04d}.vtu").point_data["line_moment"]
        assert data.shape == (8 * 3, 3)
        expected = 0.0 if step is None else result.line_moments(step)
        # the first sample of element e is the value at its start node e
        ends = np.zeros((8, 3)) if step is None else expected[0:8]
        np.testing.assert_allclose(data[0::3], ends, rtol=1e-12, atol=1e-10 * np.abs(lam).max())


def test_line_moment_is_absent_without_rotational_coupling():
    sc = m13.Scene(solid={"mesh": {"box": [[0, -0.1, -0.1], [1, 0.1, 0.1]], "cells": [2, 2, 2]},
                          "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                   beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2, "model": "torsion_free",
                           "section": {"E": 2e11, "radius": 0.01}}],
                   dirichlet=[{"on": "solid:x_min"}], load=[{"type": "traction", "on": "solid:x_max",
                                                             "value": [0, 0, -1e5]}])
    result = m13.solve(sc)
    assert result.line_moment.shape == (0, 3)


def test_coupling_tangent_does_not_depend_on_the_thread_count():
    """The second-derivative kernel runs chunks of points in parallel; each point by the same
    serial code: bit-identical tangents with 1 thread and with all."""
    import numba
    model, z, _, _ = twisted(scene({"enforcement": "lagrange"}))
    g = model.groups[0]
    u, psi = z[:3 * model.n_solid_nodes], z[g.rotations.slice].reshape(-1, 3)
    lam = z[model.n_displacement_dofs:]
    assert g.rotational.n_points > 2 * 8                       # more than two chunks of points
    threads = numba.get_num_threads()
    if threads < 2:
        pytest.skip("one Numba thread: nothing to compare with")
    try:
        numba.set_num_threads(1)
        one = g.rotational.constraint(u, psi, lam)
        numba.set_num_threads(threads)
        many = g.rotational.constraint(u, psi, lam)
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(one[0], many[0]) and np.array_equal(one[3].toarray(), many[3].toarray())
    assert np.abs(one[3].toarray()).max() > 0
