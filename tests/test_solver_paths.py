"""Every linear-solver path through the public ``solve``, Lagrange multipliers through the block
solver, dependent multiplier rows, Krylov tolerances and breakdowns, and round-off far from the
origin (issue 16, part 4)."""
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import mortar1d3d as m13
from mortar1d3d.errors import CouplingWarning
from mortar1d3d.mesh import BeamMesh
from mortar1d3d.model import Model
from mortar1d3d.physics.beam import BeamModel
from mortar1d3d.scene import Scene, SceneError
from mortar1d3d.solvers.direct import DIRECT_MAX_DOFS
from mortar1d3d.solvers.linear import LinearSolverError, solve_linear, solve_saddle
from test_linear_solvers import coupled_problem, penalty_matrix

EPS = np.finfo(float).eps
SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"


def _rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def _reduced_saddle(model):
    """(K, B, kappa, b, c, solid, beam) of the first linear solve of a Lagrange model."""
    r0, K0 = model.residual(np.zeros(model.n_unknowns), 1.0)
    free = model.free
    A, rhs = K0[free][:, free], -r0[free]
    primal = free < model.n_displacement_dofs
    p, q = np.flatnonzero(primal), np.flatnonzero(~primal)
    kappa = np.concatenate([np.repeat(g.operators.kappa[g.coupling.coupled], 3) for g in model.groups])
    solid = np.flatnonzero(free[p] < 3 * model.n_solid_nodes)
    return A[p][:, p], A[q][:, p], kappa, rhs[p], rhs[q], solid, np.setdiff1d(np.arange(len(p)), solid)


# --------------------------------------------------------------------------------------------
# Lagrange multipliers through the block solver
# --------------------------------------------------------------------------------------------
def rebar_prism(cells, solver, enforcement="lagrange"):
    """Five clamped steel rebars (beam elements as long as the solid's) in a concrete prism
    1 × 0.2 × 0.2, clamped at x = 0, a downward traction on x = 1; linear kinematics."""
    beams = [{"curve": {"line": [[0, y, z], [1, y, z]]}, "elements": cells[0], "section": {"E": 200e9, "radius": 0.01}}
             for y, z in ((0.05, 0.05), (0.15, 0.05), (0.05, 0.15), (0.15, 0.15), (0.1, 0.1))]
    return Scene.from_dict({
        "solid": {"mesh": {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": list(cells), "element": "hexahedron"},
                  "material": {"model": "saint_venant_kirchhoff", "E": 30e9, "nu": 0.2}},
        "beams": beams, "coupling": {"enforcement": enforcement},
        "dirichlet": [{"on": "solid:x_min"}] + [{"on": f"beam:{i}:start"} for i in range(5)],
        "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -2e6]}],
        "analysis": {"kinematics": "linear", "solver": solver}})


def test_lagrange_prism_above_the_direct_limit_converges_with_operator_gamma():
    """The issue's scene: 3.2k unknowns, solver "auto" picks the block solver. With the penalty
    default as γ MINRES stalled (residual 1.6e-3 after 1000 iterations); with γ from the
    operators and the auxiliary space on the augmented stiffness: 76 iterations (block-diagonal
    MINRES), 29 with the block-triangular GMRES."""
    block = m13.solve(rebar_prism((26, 4, 4), "auto"))
    info = block.model.last_linear_info
    assert len(block.model.free) > DIRECT_MAX_DOFS
    assert info["method"] == "block" and info["converged"] and info["residual"] <= 1e-8
    assert info["krylov"] == "gmres" and info["iterations"] <= 45    # measured 29 (MINRES: 76)
    # γ is of the stiffness scale of the operators (E h / h), far below the penalty default
    assert info["gamma"] < 1e-1 * block.model.penalty
    direct = m13.solve(rebar_prism((26, 4, 4), "direct"))
    assert direct.model.last_linear_info["method"] == "direct"
    assert _rel(block.z, direct.z) < 1e-7                           # measured 7e-10 (displacements and λ)
    assert block.steps[0].residuals[-1] <= 1e-8 * block.steps[0].residuals[0]


def test_direct_saddle_solve_matches_a_dense_solve():
    """SuperLU on the unscaled saddle point lost 1.5e-5 of the solution on this prism (2 % on the
    3k-unknown one): its blocks differ by the modulus. Reference: LAPACK on the same system with
    the constraint rows scaled to the stiffness."""
    model = Model(rebar_prism((12, 2, 2), "direct")).prepare()
    K, B, kappa, b, c, solid, beam = _reduced_saddle(model)
    s = abs(K).max() / abs(B).max()
    dense = np.block([[K.toarray(), s * B.T.toarray()], [s * B.toarray(), np.zeros((B.shape[0],) * 2)]])
    y = np.linalg.solve(dense, np.concatenate([b, s * c]))
    x_ref, lam_ref = y[:len(b)], s * y[len(b):]
    x, lam, info = solve_saddle(K, B, kappa, b, c, "direct", solid=solid, beam=beam)
    assert _rel(x, x_ref) < 1e-9 and _rel(lam, lam_ref) < 1e-7       # measured 2e-11, 1e-9
    assert info["residual"] <= info["rtol"]


# --------------------------------------------------------------------------------------------
# dependent multiplier rows
# --------------------------------------------------------------------------------------------
def coarse_bar(lm="line4", extra_dirichlet=({"on": "beam:0:start"},), cells=(2, 1, 1), elements=2):
    """A steel bar on the axis of a concrete hex8 bar one element thick: along the axis the solid
    moves linearly per element, which line4 multipliers over-resolve."""
    return Scene.from_dict({
        "solid": {"mesh": {"box": [[0, 0, 0], [1, 0.1, 0.1]], "cells": list(cells), "element": "hexahedron"},
                  "material": {"model": "saint_venant_kirchhoff", "E": 30e9, "nu": 0.2}},
        "beams": [{"curve": {"line": [[0, 0.05, 0.05], [1, 0.05, 0.05]]}, "elements": elements,
                   "section": {"E": 200e9, "radius": 0.01}}],
        "coupling": {"enforcement": "lagrange", "lm": lm},
        "dirichlet": [{"on": "solid:x_min"}, *extra_dirichlet],
        "load": [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e5]}],
        "analysis": {"kinematics": "linear"}})


def test_dependent_multiplier_rows_are_removed_with_a_warning_and_least_norm_lambda():
    """21 multiplier rows, rank 18: the old direct solve returned λ up to 9e20 from the singular
    factorisation. Now the three rows of LM node 1 are dropped with a warning naming them, and λ is
    the multiplier of least Σ κ λ² that transfers the same forces (a dense pseudo-inverse here)."""
    with pytest.warns(CouplingWarning, match=r"coupling.lm: the coupling rows of beams\[0\] LM nodes 1 \(x, y, z\) "
                                             r"are combinations.*lm = 'line4'.*left out.*line2"):
        result = m13.solve(coarse_bar())
    model = result.model
    info = model.last_linear_info
    assert info["dependent_rows"].tolist() == [3, 4, 5] and info["n_multipliers"] == 18
    assert info["constraint_residual"] < 1e-14                      # the dropped rows hold too
    K, B, kappa, b, c, _, _ = _reduced_saddle(model)
    x = result.z[model.free[model.free < model.n_displacement_dofs]]
    lam = result.z[model.n_displacement_dofs:]
    force = b - K @ x                                               # = Bᵀλ, unique
    assert np.abs(B.T @ lam - force).max() <= 1e-9 * np.abs(force).max()
    root = np.sqrt(kappa)
    reference = np.linalg.lstsq((B.T @ sp.diags(1 / root)).toarray(), force, rcond=None)[0] / root
    assert _rel(lam, reference) < 1e-8
    assert np.abs(lam).max() < 1e6                                  # measured 3.1e5 (the old code: 9e20)


def test_dependent_rows_contradicted_by_prescribed_values_stop_the_run():
    """Moving the beam's start while the solid it sits in is clamped there contradicts the
    dependent rows: no λ can hold it, and the run stops before solving."""
    scene = coarse_bar(extra_dirichlet=({"on": "beam:0:start", "value": [0, 0, 1e-3]},))
    with pytest.raises(SceneError, match=r"^dirichlet: the prescribed values contradict the coupling: the rows of "
                                         r"beams\[0\] LM nodes 1 \(x, y, z\)"):
        m13.solve(scene)


def test_dependent_rows_finds_rows_that_depend_across_beams():
    """Rows of different beams can only depend on each other through combinations whose beam part
    vanishes: a row with no beam columns (its beam fully held) that is a combination of another
    such row and of the left null vector of a third beam's block is found, and nothing else."""
    from mortar1d3d.solvers.dependent import dependent_rows
    rng = np.random.default_rng(1)
    M = rng.standard_normal((8, 20)) * (rng.random((8, 20)) < 0.4)     # 20 solid columns
    D = np.zeros((8, 6))
    D[0:2, 0:4] = rng.standard_normal((2, 4))                         # beam a: rows 0, 1
    D[5:8, 4:6] = rng.standard_normal((3, 2))                         # beam b: rows 5-7, rank 2
    B = np.hstack([M, D])
    null = np.linalg.svd(D[5:8, 4:6].T)[2][-1]                        # a combination of beam b's rows
    B[3] = 0.7 * B[2] + null @ B[5:8]                                 # rows 2-4 have no beam columns
    dep = dependent_rows(sp.csr_matrix(B), beam=np.arange(20, 26))
    assert dep.rows.tolist() == [3]
    assert np.abs(dep.combinations @ B).max() <= 1e-14 * np.abs(B).max()
    keep = np.setdiff1d(np.arange(8), dep.rows)
    assert np.linalg.matrix_rank(B[keep]) == 7 == np.linalg.matrix_rank(B)
    # the least-norm multiplier keeps the forces and does not depend on the row that was dropped
    lam, w = rng.standard_normal(8), rng.random(8) + 0.5
    least = dep.least_norm(lam, w)
    assert np.abs(B.T @ (least - lam)).max() <= 1e-13 * np.abs(B.T @ lam).max()
    reference = np.linalg.lstsq((B.T / np.sqrt(w)), B.T @ lam, rcond=None)[0] / np.sqrt(w)
    assert np.abs(least - reference).max() <= 1e-12 * np.abs(reference).max()


def test_singular_saddle_point_raises_instead_of_returning_multipliers():
    """Without the dependent rows removed the saddle point is singular; partial pivoting left no
    pivot below 3e-13 of the largest here and the old code returned λ up to 9e10 (true: 4.5e6).
    Now the condition estimate (about 1e23) reports it."""
    from mortar1d3d.solvers.dependent import DependentRows
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CouplingWarning)
        model = Model(coarse_bar(cells=(8, 2, 2), elements=8)).prepare()
    K, B, kappa, b, c, solid, beam = _reduced_saddle(model)
    none = DependentRows(np.zeros(0, np.int64), sp.csr_matrix((0, B.shape[0])), B.shape[0])
    with pytest.raises(LinearSolverError, match=r"singular to working precision.*dependent_rows"):
        solve_saddle(K, B, kappa, b, c, "direct", solid=solid, beam=beam, dependent=none)
    with pytest.warns(CouplingWarning, match=r"solve_saddle: rows .* of B are combinations"):
        x, lam, info = solve_saddle(K, B, kappa, b, c, "direct", solid=solid, beam=beam)
    assert len(info["dependent_rows"]) == 3 and np.abs(lam).max() < 1e7   # measured 4.5e6


def test_lagrange_scene_without_coupled_rows_solves_the_solid():
    """A beam outside the solid (held by its supports) leaves no multiplier: the saddle solve used
    to fail on its empty constraint block (ValueError from a max over no rows)."""
    scene = Scene.from_dict({
        "solid": {"mesh": {"box": [[0, 0, 0], [1, 0.1, 0.1]], "cells": [4, 1, 1], "element": "hexahedron"},
                  "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.0}},
        "beams": [{"curve": {"line": [[0, 2, 2], [1, 2, 2]]}, "elements": 4, "section": {"E": 2e11, "radius": 0.01}}],
        "coupling": {"enforcement": "lagrange"},
        "dirichlet": [{"on": "solid:x_min"}, {"on": "beam:0:start", "clamp": True}, {"on": "beam:0:end"}],
        "load": [{"type": "traction", "on": "solid:x_max", "value": [1e5, 0, 0]}],
        "analysis": {"kinematics": "linear"}})
    with pytest.warns(CouplingWarning, match=r"beams\[0\]: no part of this beam lies inside the solid"):
        result = m13.solve(scene)
    assert result.model.n_multipliers == 0
    # a bar in tension, ν = 0: the end moves by σ L / E
    X = result.model.solid_mesh.points
    assert np.allclose(result.solid_displacement[X[:, 0] == 1.0, 0], 1e5 / 1e9, rtol=1e-10)


# --------------------------------------------------------------------------------------------
# far from the origin
# --------------------------------------------------------------------------------------------
def test_beam_forces_do_not_see_the_distance_from_the_origin():
    """Forces at a rigidly translated state equal those at the original state: to 5e-14 at the
    origin and (formerly 7e-11, r'' from absolute positions) 1e5 away from it."""
    direction = np.array([1.0, 2.0, 2.0]) / 3
    diffs = []
    for shift in (0.0, 1e5):
        points = shift + np.outer(np.linspace(0, 1, 9), direction)
        mesh = BeamMesh.hermite(points, np.tile(direction, (9, 1)), np.column_stack([np.arange(8), np.arange(1, 9)]))
        beam = BeamModel(mesh, EA=1e8, EI=1e2)
        d = 1e-4 * np.random.default_rng(0).standard_normal(beam.n_dofs)
        moved = d.copy()
        moved.reshape(-1, 6)[:, :3] += [0.3, -0.2, 0.1]           # positions move, tangents do not
        f, _ = beam.evaluate(d)
        g, _ = beam.evaluate(moved)
        diffs.append(np.abs(g - f).max() / np.abs(f).max())
    assert diffs[1] <= 10 * diffs[0]


@pytest.mark.parametrize("enforcement", ["lagrange", "penalty"])
def test_nonlinear_cantilever_far_from_the_origin_converges_as_at_the_origin(enforcement):
    """examples/scenes/rebar_cantilever.toml moved by 1e5 m: Lagrange multipliers stalled at a
    residual of 8.5e-5 (target 1.2e-6) and gave up. Now every step converges as at the origin and
    the answers differ by what representing the coordinates costs (eps 1e5 / h = 2.2e-10)."""
    base = tomllib.loads((SCENES / "rebar_cantilever.toml").read_text())
    results = []
    for shift in (0.0, 1e5):
        data = tomllib.loads((SCENES / "rebar_cantilever.toml").read_text())
        data["solid"]["mesh"]["box"] = [[v + shift for v in p] for p in base["solid"]["mesh"]["box"]]
        data["beams"][0]["curve"]["line"] = [[v + shift for v in p] for p in base["beams"][0]["curve"]["line"]]
        data["coupling"]["enforcement"] = enforcement
        results.append(m13.solve(Scene.from_dict(data)))
    near, far = results
    h = 0.1
    scale = EPS * 1e5 / h
    assert len(far.steps) == len(near.steps) == 4 and all(s.cuts == 0 for s in far.steps)
    assert [s.iterations for s in far.steps] == [s.iterations for s in near.steps]
    assert _rel(far.solid_displacement, near.solid_displacement) < 10 * scale       # measured 0.4x
    assert _rel(far.beam_displacement, near.beam_displacement) < 10 * scale         # measured 0.3x
    assert _rel(far.line_load, near.line_load) < 100 * scale                        # measured 10x


class _AbsoluteSpring:
    """One spring k between a support and a point at coordinate X, its force formed from absolute
    positions, ``k ((X + z) - X)``: round-off eps |X| k that no relative target can get under."""

    def __init__(self, X, k=1e3, f=1e3, reference=True):
        self.X, self.k, self.f = X, k, f
        self.free, self.fixed = np.array([0]), np.zeros(0, np.int64)
        if reference:
            self.reference = lambda: np.array([X])

    def prescribed(self, t):
        return np.zeros(0)

    def residual(self, z, t, tangent=True):
        r = np.array([self.k * ((self.X + z[0]) - self.X) + 1e-6 * self.k * z[0] ** 2 - t * self.f])
        return r, sp.csr_matrix([[self.k * (1 + 2e-6 * z[0])]])

    def solve_linear(self, A, b, x0=None, rtol=None):
        return b / A.toarray()[0]


def test_newton_round_off_floor_sees_the_coordinates():
    """A residual formed from coordinates 1e9 away carries round-off 2e-7 of the load (target
    1e-8): Newton used to cut the step until it gave up; with the coordinates in its round-off
    floor it accepts once the increments stop contracting, and the answer is right to that floor."""
    from mortar1d3d.solvers.newton import ConvergenceError, solve_load_steps
    z, records, _ = solve_load_steps(_AbsoluteSpring(1e9), np.zeros(1), 1)
    assert records[0].cuts == 0 and records[0].iterations <= 10
    assert abs(z[0] - 1.0) <= 1e3 * EPS * 1e9                       # z = f/k = 1 up to the floor
    with pytest.raises(ConvergenceError):                           # a system that does not say where it lies
        solve_load_steps(_AbsoluteSpring(1e9, reference=False), np.zeros(1), 1, max_cuts=1)


# --------------------------------------------------------------------------------------------
# Krylov tolerances: from the analysis, and a stall at round-off is no failure
# --------------------------------------------------------------------------------------------
def fibre_cube_scene(n, fibres, elements, solver, enforcement="penalty"):
    """The benchmark scene (fibre_cube) in a clamped linear-elastic cube, end traction."""
    beams, solid = m13.generate.fibre_cube(n, fibres, elements)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.01}}],
                     coupling={"enforcement": enforcement},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                     analysis={"kinematics": "linear", "solver": solver})


def test_benchmark_scene_default_solver_does_not_fail_at_round_off():
    """fibre_cube(6, 300, 8) (the smallest tried that shows it; fibre_cube(20, 1000, 20) stalls
    the same way): auxiliary-space CG stalled at 1.1e-10 against the fixed 1e-10 and raised. The
    linear analysis now asks for analysis.rtol, and a stall at round-off is success."""
    result = m13.solve(fibre_cube_scene(6, 300, 8, "auto"))
    info = result.model.last_linear_info
    assert info["method"] == "aux" and info["converged"] and info["rtol"] == result.model.scene.analysis["rtol"]
    direct = m13.solve(fibre_cube_scene(6, 300, 8, "direct"))
    assert _rel(result.z, direct.z) < 1e-8                          # measured 1.7e-11
    # asked for less than round-off allows: stops at the round-off level, above 1e-12
    scene = fibre_cube_scene(6, 300, 8, "auto")
    scene.analysis["rtol"] = 1e-12
    tight = m13.solve(scene)
    info = tight.model.last_linear_info
    assert info["status"] == "roundoff" and 1e-12 < info["residual"] < 1e-9  # measured 1.5e-10
    assert _rel(tight.z, direct.z) < 1e-9


def test_cg_stall_at_round_off_is_convergence():
    """Asked for a residual below round-off, AMG-CG stalls; it used to raise LinearSolverError."""
    prob = coupled_problem((16, 8, 8))
    A = penalty_matrix(prob, 1e3)
    x_direct, _ = solve_linear(A, prob["b"], "direct")
    x, info = solve_linear(A, prob["b"], "amg", near_nullspace=prob["R"], rtol=1e-17)
    from mortar1d3d.solvers.krylov import roundoff_level
    assert info["status"] == "roundoff" and info["converged"]
    assert info["residual"] <= roundoff_level(A, x, prob["b"])
    assert _rel(x, x_direct) < 1e-10
    with pytest.raises(LinearSolverError, match="did not converge"):  # far from round-off it still fails
        solve_linear(A, prob["b"], "amg", near_nullspace=prob["R"], rtol=1e-17, maxiter=3)


@pytest.mark.parametrize("enforcement, solvers", [("penalty", ("auto", "direct", "amg")),
                                                  ("lagrange", ("auto", "direct", "block"))])
def test_benchmark_scene_every_solver_path_through_solve(enforcement, solvers):
    """fibre_cube(4, 60, 8), 3.6k (penalty) and 5.2k (Lagrange) unknowns. With Lagrange
    multipliers the old direct solve reached a residual of 2.7e-3 only (unchecked) and the block
    solver needed 1000 iterations; the fibres' elements are 0.15 of the solid's."""
    results = {s: m13.solve(fibre_cube_scene(4, 60, 8, s, enforcement)) for s in solvers}
    direct = results["direct"]
    assert direct.model.last_linear_info["residual"] <= direct.model.scene.analysis["rtol"]
    for solver, result in results.items():
        info = result.model.last_linear_info
        assert info["converged"], solver
        assert result.steps[0].residuals[-1] <= 1e-8 * result.steps[0].residuals[0], solver
        assert _rel(result.z, direct.z) < 1e-8, solver               # measured 1e-9
    for solver, result in results.items():                           # plan() said what would run
        assert set(result.counts) <= {e.name for e in m13.plan(fibre_cube_scene(4, 60, 8, solver, enforcement))}
    iterative = results["block" if enforcement == "lagrange" else "amg"].model.last_linear_info
    assert iterative["iterations"] <= 25                             # measured 17 (MINRES: 45), 10
    assert results["auto"].model.last_linear_info["method"] == iterative["method"]


def test_block_triangular_gmres_and_block_diagonal_minres_match_direct():
    """Both block methods on the same saddle point (fibre_cube(4, 60, 8), line2): the solution of
    the direct solve, and the block-triangular GMRES in well under half MINRES's iterations (the
    triangular preconditioner's spectrum is one cluster, the diagonal one's two of both signs)."""
    model = Model(fibre_cube_scene(4, 60, 8, "block", "lagrange")).prepare()
    K, B, kappa, b, c, solid, beam = _reduced_saddle(model)
    options = dict(solid=solid, beam=beam, near_nullspace=model.rigid_body_modes()[model.free[:K.shape[0]]],
                   prolongation=model._follow_split()["prolongation"], rtol=1e-8)
    x_dir, lam_dir, _ = solve_saddle(K, B, kappa, b, c, "direct", **options)
    iterations = {}
    for krylov in ("gmres", "minres"):
        x, lam, info = solve_saddle(K, B, kappa, b, c, "block", krylov=krylov, **options)
        assert info["krylov"] == krylov and info["status"] == "converged" and info["residual"] <= 1e-8
        assert _rel(x, x_dir) < 1e-8 and _rel(lam, lam_dir) < 1e-6, krylov    # measured <= 1e-9, 1e-8
        iterations[krylov] = info["iterations"]
    assert iterations["gmres"] <= 25 and iterations["minres"] <= 70           # measured 17, 45
    assert 2 * iterations["gmres"] < iterations["minres"]
    with pytest.raises(ValueError, match="krylov must be"):
        solve_saddle(K, B, kappa, b, c, "block", krylov="cg", **options)


def test_restarted_gmres_solves_a_nonsymmetric_system():
    """The GMRES loop on its own: a non-symmetric convection-diffusion-like matrix, restarted
    every 5 iterations, Jacobi-preconditioned; the true residual reaches the reduction asked."""
    from mortar1d3d.solvers.krylov import _gmres
    n = 200
    A = sp.diags([np.full(n - 1, -1.6), np.linspace(2.5, 4.0, n), np.full(n - 1, -0.4)], [-1, 0, 1], format="csr")
    x_true = np.sin(np.arange(n))
    b = A @ x_true
    diagonal = A.diagonal()
    x, iterations, status = _gmres(A, b, np.zeros(n), lambda r: r / diagonal, 1e-10, 500, restart=5)
    assert status == "tolerance" and iterations > 5                 # restarted at least once
    assert np.linalg.norm(b - A @ x) <= 1e-10 * np.linalg.norm(b)
    assert _rel(x, x_true) < 1e-8
    x, iterations, status = _gmres(A, b, np.zeros(n), lambda r: r / diagonal, 1e-10, 3, restart=5)
    assert status == "maxiter" and iterations == 3


# --------------------------------------------------------------------------------------------
# CG breakdown on an indefinite tangent
# --------------------------------------------------------------------------------------------
def triaxial_block(solver):
    """Nearly incompressible neo-Hooke cube (ν = 0.4999) under triaxial tension σ = 0.7 E: ln J
    exceeds μ/λ = 2e-4, the material tangent loses definiteness (μ - λ ln J < 0)."""
    return Scene.from_dict({
        "solid": {"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [5, 5, 5], "element": "hexahedron"},
                  "material": {"model": "neo_hooke", "E": 1e6, "nu": 0.4999}},
        "dirichlet": [{"on": "solid:x_min", "components": ["x"]}, {"on": "solid:y_min", "components": ["y"]},
                      {"on": "solid:z_min", "components": ["z"]}],
        "load": [{"type": "traction", "on": f"solid:{a}_max", "value": [7e5 * (a == b) for b in "xyz"]} for a in "xyz"],
        "analysis": {"kinematics": "nonlinear", "solver": solver, "steps": 2}})


def test_cg_breakdown_switches_to_minres_and_says_so(capsys):
    """AMG-CG stopped on pᵀKp <= 0, Newton cut the step and gave up at load factor 0.95. Now
    MINRES takes over and the run takes the 2 steps of the direct solver; the log says why."""
    result = m13.solve(triaxial_block("amg"), progress=True)
    direct = m13.solve(triaxial_block("direct"))
    assert [s.load_factor for s in result.steps] == [s.load_factor for s in direct.steps] == [0.5, 1.0]
    notes = [n for s in result.steps for n in s.notes]
    assert notes and all("AMG-preconditioned CG broke down" in n and "MINRES took over" in n for n in notes)
    log = capsys.readouterr().out
    assert "broke down" in log and "MINRES took over" in log
    assert _rel(result.solid_displacement, direct.solid_displacement) < 1e-8
    assert not any(s.notes for s in direct.steps)


def test_newton_asks_the_linear_solver_for_a_tenth_of_its_target():
    """The linear solves of a Newton iteration used a fixed rtol of 1e-10, whatever the analysis,
    then a tenth of the analysis's rtol relative to the current residual; now a tenth of what the
    step's residual target still needs."""
    scene = triaxial_block("amg")
    scene.analysis["rtol"] = 1e-7
    for load in scene.loads:                     # σ = 0.1 E: far from the indefinite range, CG alone
        load["value"] = load["value"] / 7
    result = m13.solve(scene)
    from mortar1d3d.solvers.newton import LINEAR_RTOL_FACTOR, LINEAR_RTOL_MAX
    # the last solve of the last step: a tenth of the step's target rtol ‖r_0‖ relative to its ‖r_k‖
    residuals = result.steps[-1].residuals
    assert len(residuals) >= 3                                      # so r_k < r_0: looser than rtol / 10
    expected = min(LINEAR_RTOL_MAX, LINEAR_RTOL_FACTOR * 1e-7 * residuals[0] / residuals[-2])
    assert math.isclose(result.model.last_linear_info["rtol"], expected)
    assert expected > 10 * LINEAR_RTOL_FACTOR * 1e-7
    assert "fallback" not in result.model.last_linear_info
    assert result.steps[-1].residuals[-1] <= 1e-7 * residuals[0]
