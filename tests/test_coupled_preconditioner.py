"""The parts of the auxiliary-space preconditioner that make the coupled solve cheaper: the banded
Cholesky of the beam blocks, on its own and inside the preconditioner on a fibre scene."""
import numpy as np
import pytest
import scipy.sparse as sp

from mortar1d3d.solvers.direct import (BANDED_MAX_BANDWIDTH, BandedCholesky, bandwidth, factorize,
                                       factorize_spd_block)


def banded_blocks(sizes, k, rng, shift=1.0):
    """Block-diagonal symmetric matrix of banded blocks (half-bandwidth k), like the beams of a
    scene one after the other; ``shift`` < 0 makes it indefinite."""
    blocks = []
    for m in sizes:
        B = np.zeros((m, m))
        for d in range(1, k + 1):
            v = rng.standard_normal(m - d)
            B += np.diag(v, d) + np.diag(v, -d)
        B += np.diag(shift * (2 * k + 1 + rng.random(m)))   # diagonally dominant when shift = 1
        blocks.append(sp.csr_matrix(B))
    return sp.block_diag(blocks, format="csr")


def test_banded_cholesky_solves_like_superlu():
    rng = np.random.default_rng(5)
    A = banded_blocks([30, 45, 21, 60], 5, rng)
    assert bandwidth(A) == 5
    b = rng.standard_normal((A.shape[0], 2))
    factor = factorize_spd_block(A)
    assert isinstance(factor, BandedCholesky) and factor.factor.shape == (6, A.shape[0])
    x = factor.solve(b)
    x_lu = factorize(A, symmetric_positive=True).solve(b)
    assert np.abs(A @ x - b).max() <= 1e-12 * np.abs(b).max()
    assert np.abs(x - x_lu).max() <= 1e-12 * np.abs(x_lu).max()
    assert np.array_equal(factor.solve(b[:, 0]), x[:, 0])


def test_wide_or_indefinite_blocks_go_to_superlu():
    rng = np.random.default_rng(6)
    A = banded_blocks([40, 40, 40], 3, rng)
    # the same matrix with its DOFs shuffled: a bandwidth far beyond the banded limit
    perm = rng.permutation(A.shape[0])
    wide = A[perm][:, perm].tocsr()
    assert bandwidth(wide) > BANDED_MAX_BANDWIDTH
    b = rng.standard_normal(A.shape[0])
    factor = factorize_spd_block(wide)
    assert not isinstance(factor, BandedCholesky)
    assert np.abs(wide @ factor.solve(b) - b).max() <= 1e-12 * np.abs(b).max()
    # indefinite (negative diagonal block): the banded Cholesky meets a negative pivot, SuperLU solves it
    mixed = sp.block_diag([A, banded_blocks([20], 3, rng, shift=-1.0)], format="csr")
    with pytest.raises(np.linalg.LinAlgError):
        BandedCholesky(mixed, bandwidth(mixed))
    b = rng.standard_normal(mixed.shape[0])
    factor = factorize_spd_block(mixed)
    assert not isinstance(factor, BandedCholesky)
    assert np.abs(mixed @ factor.solve(b) - b).max() <= 1e-10 * np.abs(b).max()


@pytest.fixture(scope="module")
def fibre_system():
    """fibre_cube(8, 150, 10) in a clamped linear-elastic cube at the default penalty: (A, b, R, split)
    of the reduced system (11,844 unknowns, 1,944 of them solid)."""
    import mortar1d3d as m13
    from mortar1d3d.model import Model
    beams, solid = m13.generate.fibre_cube(8, 150, 10)
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                      dirichlet=[{"on": "solid:x_min"}],
                      load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                      analysis={"kinematics": "linear", "solver": "amg"})
    model = Model(scene).prepare()
    r, K = model.residual(np.zeros(model.n_unknowns), 1.0)
    free = model.free
    return K[free][:, free].tocsr(), -r[free], model.rigid_body_modes()[free], model._follow_split()


def test_auxiliary_space_on_fibres_uses_the_banded_beam_factor_and_agrees_with_direct(fibre_system):
    """Hermite fibres, DOFs numbered along each: the beam block is factorised banded; the
    preconditioner (no candidate improvement of the rigid-body modes) keeps its iterations."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    A, b, R, split = fibre_system
    solid = split["solid"]
    pre = AuxiliarySpacePreconditioner(A, solid, split["beam"], split["prolongation"], R[solid], block_size=3)
    assert isinstance(pre._beam_factor, BandedCholesky) and pre.levels == 2
    assert pre._s == slice(0, len(solid))                        # solid first, beams after: no gathers
    x, info = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
    assert info["method"] == "aux" and info["converged"] and info["residual"] <= 1e-8
    assert info["iterations"] <= 20                             # measured 16
    x_direct, _ = solve_linear(A, b, "direct")
    assert np.linalg.norm(x - x_direct) <= 1e-7 * np.linalg.norm(x_direct)
    assert set(pre.timings) == {"auxiliary matrix", "amg set-up", "beam factorisation", "applications",
                                "amg cycles", "beam solves"}
    # the parts of an application are timed inside it (a bookkeeping check, not a speed claim)
    t = pre.timings
    assert t["applications"] > 0 and t["amg cycles"] + t["beam solves"] <= t["applications"]
