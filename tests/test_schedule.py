"""Dynamic scheduling of the kernels' loops (mortar1d3d._schedule) and the CSR hand-over."""
import numba
import numpy as np
import pytest
import scipy.sparse as sp
from numba import prange

import mortar1d3d as m13
from mortar1d3d._config import CHUNK, njit_parallel
from mortar1d3d._schedule import claim, n_chunks, new_claims, workers


@njit_parallel
def _visit(n, visits, chunk_of, workers):
    claims = new_claims()
    for worker in prange(workers):
        begin, stop = claim(claims, n)
        while begin < stop:
            for item in range(begin, stop):
                visits[item] += 1
                chunk_of[item] = begin // CHUNK
            begin, stop = claim(claims, n)


@pytest.mark.parametrize("n", [0, 1, CHUNK - 1, CHUNK, CHUNK + 1, 5 * CHUNK + 7])
@pytest.mark.parametrize("n_workers", [1, 2, 7])
def test_every_item_claimed_once(n, n_workers):
    visits = np.zeros(n, dtype=np.int64)
    chunk_of = np.full(n, -1, dtype=np.int64)
    _visit(n, visits, chunk_of, n_workers)
    assert np.array_equal(visits, np.ones(n, dtype=np.int64))
    assert np.array_equal(chunk_of, np.arange(n) // CHUNK)
    assert chunk_of.max(initial=-1) + 1 == n_chunks(n, CHUNK)


def test_workers_follow_numba_threads():
    default = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert workers() == 1
    finally:
        numba.set_num_threads(default)
    assert workers() == default


def test_operators_are_attached_not_copied_and_valid():
    """D and M hold the arrays the engine wrote (SciPy's constructor would copy carved views)."""
    beams, solid = m13.generate.fibre_cube(3, 6, 3)
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=3)
    for matrix in (ops.D, ops.M):
        assert matrix.data.base is not None and matrix.indices.base is not None    # views of one block
        assert matrix.has_canonical_format
        rebuilt = sp.csr_matrix((matrix.data.copy(), matrix.indices.copy(), matrix.indptr.copy()), shape=matrix.shape)
        rebuilt.check_format(full_check=True)
        rebuilt.sum_duplicates()
        assert rebuilt.nnz == matrix.nnz
        assert np.array_equal(rebuilt.indices, matrix.indices) and np.array_equal(rebuilt.data, matrix.data)
        assert matrix.shape[0] == 3 * ops.n_lm and len(matrix.data) == len(matrix.indices) == matrix.nnz
