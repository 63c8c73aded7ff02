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
    claims = new_claims(n, workers)
    for worker in prange(workers):
        begin, stop = claim(claims, n, worker)
        while begin < stop:
            for item in range(begin, stop):
                visits[item] += 1
                chunk_of[item] = begin // CHUNK
            begin, stop = claim(claims, n, worker)


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


def test_workers_claim_their_own_part_first_then_steal():
    n = 10 * CHUNK + 3                       # 11 chunks: worker 0 owns 0-4, worker 1 owns 5-10
    claims = new_claims(n, 2)
    assert claim(claims, n, 1) == (5 * CHUNK, 6 * CHUNK)
    assert claim(claims, n, 0) == (0, CHUNK)
    for chunk in range(6, 11):               # worker 1 finishes its part (the last chunk is short) ...
        assert claim(claims, n, 1) == (chunk * CHUNK, min(n, (chunk + 1) * CHUNK))
    for chunk in range(1, 5):                # ... then takes worker 0's chunks in order
        assert claim(claims, n, 1) == (chunk * CHUNK, (chunk + 1) * CHUNK)
    assert claim(claims, n, 0) == (n, n) and claim(claims, n, 1) == (n, n)


def test_more_workers_than_chunks():
    claims = new_claims(CHUNK + 1, 5)        # 2 chunks: workers 0, 1, 3 own none
    assert claim(claims, CHUNK + 1, 0) == (0, CHUNK)          # stolen from worker 2's part
    assert claim(claims, CHUNK + 1, 3) == (CHUNK, CHUNK + 1)  # from worker 4's
    assert claim(claims, CHUNK + 1, 4) == (CHUNK + 1, CHUNK + 1)
