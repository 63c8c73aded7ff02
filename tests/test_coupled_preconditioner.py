"""The parts of the auxiliary-space preconditioner that make the coupled solve cheap: the banded
Cholesky of the beam blocks and the strength threshold of the AMG on the auxiliary matrix."""
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
