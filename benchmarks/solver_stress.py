"""The figures behind tests/test_solver_stress.py (issue 6 part 4), printed instead of asserted.

    .venv/bin/python benchmarks/solver_stress.py

Uses the test module's scenes, so the numbers are those the tests judge:

- penalty sweep ε = 1e0 … 1e12 × E_solid on the eccentric-rebar cantilever: Newton iterations and
  step cuts, max |u − u_Lagrange| over the tip deflection, and the 1-norm condition estimate of
  the reduced tangent at the solution;
- ν = 0.49 Neo-Hooke under uniaxial traction: the exact stretches (a, b) and J = a b², and the
  largest nodal deviation of the finite element solution from the homogeneous field;
- a fibre 1e6 stiffer than the solid: its strain against F/EA;
- step cutting on the 90° rotation of the fibre bundle: the load factors and cuts of the steps,
  and the difference to 16 uncut steps.
"""
import math
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import mortar1d3d as m13                                   # noqa: E402
import test_solver_stress as stress                        # noqa: E402


def penalty_sweep():
    exact = m13.solve(stress.rebar_scene("lagrange"))
    scale = np.abs(exact.solid_displacement).max()
    print(f"penalty sweep (E_solid = {stress.E_SOFT:g}; tip deflection {scale:.3g})")
    print(f"  {'eps/E':>6s} {'its':>4s} {'cuts':>4s} {'max err / tip':>14s} {'cond_1 est.':>12s}")
    for k in range(13):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = m13.solve(stress.rebar_scene("penalty", penalty=10.0 ** k * stress.E_SOFT))
        step = result.steps[-1]
        error = np.abs(result.solid_displacement - exact.solid_displacement).max() / scale
        print(f"  {'1e%d' % k:>6s} {step.iterations:4d} {sum(s.cuts for s in result.steps):4d} {error:14.2e} "
              f"{stress.condition_estimate(result):12.3g}")


def nearly_incompressible():
    E, nu, P = 1.0, 0.49, 0.2
    a, b = stress.uniaxial_neo_hooke(P, E, nu)
    print(f"nu = {nu} Neo-Hooke, P = {P}: a = {a:.4f}, b = {b:.4f}, J = {a * b * b:.4f}")


def stiff_fibre():
    force, EA = 0.01, 1e6 * math.pi * 0.05 ** 2
    data = {"solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [4, 1, 1]},
                      "material": {"model": "neo_hooke", "E": 1.0, "nu": 0.3}},
            "beams": [{"curve": {"line": [[0, 0.1, 0.1], [1, 0.1, 0.1]]}, "elements": 4,
                       "section": {"E": 1e6, "radius": 0.05}}],
            "dirichlet": [{"on": "solid:x_min"}, {"on": "beam:0:start"}], "analysis": {"steps": 2},
            "load": [{"type": "traction", "on": "solid:x_max", "value": [force / 0.04, 0, 0]}]}
    result = m13.solve(m13.Scene.from_dict(data))
    strain = result.beam_displacement[-1, 0] - result.beam_displacement[0, 0]
    print(f"fibre E ratio 1e6: strain {strain:.4g} against F/EA = {force / EA:.4g}")


def step_cutting():
    cut = m13.solve(stress.rotated_bundle_scene(steps=1, max_iterations=8)[0])
    small = m13.solve(stress.rotated_bundle_scene(steps=16)[0])
    steps = ", ".join(f"{s.load_factor:g} ({s.cuts} cuts, {s.iterations} its)" for s in cut.steps)
    print(f"90° rotation in one step, <= 8 iterations: steps to {steps}; "
          f"max |z - z_16 steps| = {np.abs(cut.z - small.z).max():.2g}")


if __name__ == "__main__":
    penalty_sweep()
    nearly_incompressible()
    stiff_fibre()
    step_cutting()
