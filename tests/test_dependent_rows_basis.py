"""The check of prescribed values against dependent multiplier rows works in the basis of the
unknowns, where clamped tangents are rotated (issue 16, part 4; commit "Dependent-row check
compares prescribed values with the constraint rows in the unknowns' basis").

With Lagrange multipliers richer than the solid mesh resolves (``lm = "line4"`` on a bar one hex8
thick), some constraint rows are combinations ``C`` of the others. Prescribed values ``v`` of the
fixed DOFs must then satisfy ``C B_f v = 0`` (``B_f``: the constraint columns of the fixed DOFs),
or no multiplier can hold them and ``Model._dependent_multipliers`` raises ``SceneError``. The
fixed DOFs and their values live in the basis of the unknowns (``z = T z̃``): at a clamped node of a
torsion-free beam the tangent's components are ``e1·Δt, e2·Δt, t0·Δt`` (``mortar1d3d.supports``),
so the columns have to be those of ``B T``, not of ``B``.

No scene reaches the difference today, which is why this test sets the prescribed values
directly, as a prescribed turn of a clamp would: ``T`` differs from the identity only on the
tangent triplets of clamped nodes, so ``B`` and ``B T`` differ only in those columns; a
``[[dirichlet]]`` entry prescribes positions only (``Model._set_dofs`` never selects tangents),
and a clamp prescribes ``e1·Δt = e2·Δt = 0``. Every prescribed value on a rotated DOF is 0, so
``B_f v`` and ``|B_f| |v|`` come out the same in either basis.

Whether a prescription is consistent is decided here without the library's combinations: by a
dense least-squares solve for the free DOFs (``B_u z = -B_f v`` must have a solution).
"""
import numpy as np
import pytest

from mortar1d3d.errors import CouplingWarning
from mortar1d3d.model import Model
from mortar1d3d.scene import Scene, SceneError

# a bar one hex8 thick, the beam oblique to every axis (so that the clamp's frame is not a
# permutation of the coordinate axes: with the beam along x, B and B T differ only by renaming and
# sign of columns the dependent rows do not involve, and the old check gave the same answers)
LINE = [[0.0, 0.03, 0.04], [1.0, 0.07, 0.06]]


def clamped_bar():
    return Scene.from_dict({
        "solid": {"mesh": {"box": [[0, 0, 0], [1, 0.1, 0.1]], "cells": [2, 1, 1], "element": "hexahedron"},
                  "material": {"model": "saint_venant_kirchhoff", "E": 30e9, "nu": 0.2}},
        "beams": [{"curve": {"line": LINE}, "elements": 2, "section": {"E": 200e9, "radius": 0.01}}],
        "coupling": {"enforcement": "lagrange", "lm": "line4"},
        "dirichlet": [{"on": "solid:x_min"}, {"on": "beam:0:start", "clamp": True}],
        "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e5]}],
        "analysis": {"kinematics": "linear"}})


def constraint_blocks(model):
    """B of the multiplier rows in the basis of the unknowns: its free primal columns (as
    Model.solve_linear passes them), the positions of the beam columns among those, and its
    columns of the fixed DOFs."""
    n = model.n_displacement_dofs
    _, K = model.residual(np.zeros(model.n_unknowns), 1.0)           # [[K, Bᵀ], [B, 0]], rotated
    rows = model.free[model.free >= n]
    free = model.free[model.free < n]
    B_free = K[rows][:, free]
    B_fixed = K[rows][:, model.fixed_dofs]
    beam = np.flatnonzero(free >= 3 * model.n_solid_nodes)
    return B_free, beam, B_fixed


def consistent(B_free, B_fixed, v):
    """Whether B_free z = -B_fixed v has a solution z (dense least squares)."""
    rhs = -(B_fixed @ v)
    z = np.linalg.lstsq(B_free.toarray(), rhs, rcond=None)[0]
    return np.linalg.norm(B_free @ z - rhs) <= 1e-10 * np.linalg.norm(rhs)


def prescriptions(model):
    """Values of the fixed DOFs, each non-zero on the clamped tangent's rotated DOFs: the three
    rigid rotations (consistent: the coupling moves with a rigid body), the clamped tangent turned
    alone towards e1 and towards e2, and random values."""
    fixed = model.fixed_dofs
    rotated = np.isin(fixed, model.basis.starts[:, None] + np.arange(3))
    R = model.rigid_body_modes()[fixed]
    out = {f"rigid rotation about {'xyz'[k]}": R[:, 3 + k] for k in range(3)}
    for k, name in enumerate(("e1", "e2")):
        v = np.zeros(len(fixed))
        v[np.flatnonzero(rotated)[k]] = 1.0
        out[f"clamped tangent turned towards {name}"] = v
    out["random"] = np.random.default_rng(3).uniform(-1, 1, len(fixed))
    for name, v in out.items():
        assert np.abs(v[rotated]).max() > 0.01, name
    return out


@pytest.mark.parametrize("name", ["rigid rotation about x", "rigid rotation about y", "rigid rotation about z",
                                  "clamped tangent turned towards e1", "clamped tangent turned towards e2",
                                  "random"])
def test_prescribed_values_on_rotated_dofs_are_checked_in_the_unknowns_basis(name):
    """Consistent prescriptions (found by least squares) are accepted with the warning about the
    dependent rows; the others stop the run.

    Measured: without the allowance for the rows' round-off, the rigid rotation about z and the
    tangent turned towards e1 were rejected (one combination sees, on the fixed DOFs, only entries
    of about 1e-17 that vanish in exact arithmetic: gap/size 0.027 and 0.90). With the columns of
    ``B`` instead of ``B T`` (the check before the commit named above) this scene gives the same six
    answers: its dependent combinations annihilate all three tangent columns of the clamped node,
    so no scene we could build tells the two bases apart; the test checks the answers against an
    independent least-squares solve."""
    model = Model(clamped_bar()).prepare()
    frame = model.basis.frames[0]                       # the clamp's (e1, e2, t0): not a permuted identity
    assert len(model.basis.starts) == 1 and np.abs(frame).max(axis=1).min() < 0.9999
    B_free, beam, B_fixed = constraint_blocks(model)
    v = prescriptions(model)[name]
    expected = name != "random"
    assert consistent(B_free, B_fixed, v) == expected
    model.fixed_values = v
    if expected:
        with pytest.warns(CouplingWarning, match=r"coupling.lm: the coupling rows of beams\[0\] LM nodes"):
            dependent = model._dependent_multipliers(B_free, beam)
        assert len(dependent) == 3
    else:
        with pytest.raises(SceneError, match=r"^dirichlet: the prescribed values contradict the coupling"):
            model._dependent_multipliers(B_free, beam)
