"""The preconditioner kept across the linear solves of a nonlinear analysis (issue 22, item 3)."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.model import Model
from mortar1d3d.solvers._common import LinearSolverError
from mortar1d3d.solvers.reuse import REBUILD_GROWTH, REBUILD_SLACK, ReusedPreconditioner


class FakeSolver:
    """A linear solve that records the preconditioner it was given and reports set iterations."""

    def __init__(self):
        self.given, self.built = [], 0
        self.iterations, self.fail_with_kept = 10, False

    def __call__(self, kept):
        self.given.append(kept)
        if kept is None:
            self.built += 1
            return np.zeros(2), {"iterations": self.iterations, "preconditioner": f"P{self.built}"}
        if self.fail_with_kept:
            raise LinearSolverError("did not converge")
        return np.zeros(2), {"iterations": self.iterations}


def test_kept_preconditioner_is_reused_until_it_serves_badly():
    solver, reuse = FakeSolver(), ReusedPreconditioner()
    _, info = reuse.solve(solver)
    assert solver.given == [None] and info["reused"] is False and "preconditioner" not in info
    _, info = reuse.solve(solver)
    assert solver.given[-1] == "P1" and info["reused"] is True
    # one iteration beyond the limit: used this time, dropped for the next solve
    solver.iterations = int(REBUILD_GROWTH * 10 + REBUILD_SLACK) + 1
    reuse.solve(solver)
    assert solver.given[-1] == "P1" and reuse.current is None
    reuse.solve(solver)
    assert solver.given[-1] is None and reuse.current == "P2"
    assert (reuse.builds, reuse.reuses) == (2, 2)


def test_solve_failing_with_the_kept_preconditioner_is_repeated_with_a_new_one():
    solver, reuse = FakeSolver(), ReusedPreconditioner()
    reuse.solve(solver)
    solver.fail_with_kept = True
    _, info = reuse.solve(solver)
    assert solver.given == [None, "P1", None] and info["reused"] is False and reuse.current == "P2"


def _bent_cube(solver, enforcement):
    beams, solid = m13.generate.fibre_cube(4, 60, 8)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.01}}],
                     coupling={"enforcement": enforcement},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -2e7]}],
                     analysis={"kinematics": "nonlinear", "steps": 2, "solver": solver})


@pytest.mark.parametrize("enforcement, solver", [("penalty", "amg"), ("lagrange", "block")])
def test_newton_keeps_the_preconditioner_and_reaches_the_direct_solution(enforcement, solver):
    """fibre_cube(4, 60, 8) bent in 2 nonlinear steps: one set-up serves every Newton iteration
    (measured: 1 set-up for 9 solves with penalty, for 10 with Lagrange multipliers, where the direct
    solver takes 9 Newton iterations), and the result is the direct one."""
    result = m13.solve(_bent_cube(solver, enforcement))
    direct = m13.solve(_bent_cube("direct", enforcement))
    kept = result.model._preconditioner
    newton = sum(s.iterations for s in result.steps)
    assert newton <= sum(s.iterations for s in direct.steps) + 2      # inexact solves: maybe one more
    assert kept.builds + kept.reuses == newton and kept.builds <= 2 and kept.reuses >= newton - 2
    u, u_dir = result.solid_displacement, direct.solid_displacement
    assert np.abs(u - u_dir).max() <= 1e-7 * np.abs(u_dir).max()     # measured 4e-12, 2e-13
    # switched off: a set-up per solve, the same solution to the tolerance
    Model.reuse_preconditioner = False
    try:
        fresh = m13.solve(_bent_cube(solver, enforcement))
    finally:
        Model.reuse_preconditioner = True
    assert fresh.model._preconditioner is None
    assert np.abs(fresh.solid_displacement - u_dir).max() <= 1e-7 * np.abs(u_dir).max()
