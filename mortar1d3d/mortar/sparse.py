"""COO → CSR in Numba, deterministic, with 3×3 identity blocks expanded.

Entries are ordered by a stable counting sort on rows and a stable merge sort on columns, and
duplicates are summed in their COO order; since the COO order does not depend on the number
of threads, neither do the resulting bits.
"""
import numpy as np
import scipy.sparse as sp
from numba import prange

from .._config import njit, njit_parallel


@njit
def _row_order(rows, n_rows):
    counts = np.zeros(n_rows + 1, dtype=np.int64)
    for q in range(rows.shape[0]):
        counts[rows[q] + 1] += 1
    start = np.cumsum(counts)
    fill = start[:-1].copy()
    order = np.empty(rows.shape[0], dtype=np.int64)
    for q in range(rows.shape[0]):
        order[fill[rows[q]]] = q
        fill[rows[q]] += 1
    return start, order


@njit_parallel
def _sum_duplicates(start, order, cols, vals, ucols, uvals, unique):
    for r in prange(start.shape[0] - 1):
        a = start[r]
        b = start[r + 1]
        idx = order[a:b]
        c = cols[idx]
        perm = np.argsort(c, kind="mergesort")
        m = 0
        for t in range(b - a):
            col = c[perm[t]]
            v = vals[idx[perm[t]]]
            if m > 0 and ucols[a + m - 1] == col:
                uvals[a + m - 1] += v
            else:
                ucols[a + m] = col
                uvals[a + m] = v
                m += 1
        unique[r] = m


@njit_parallel
def _expand(start, ucols, uvals, unique, block, indptr, indices, data):
    n_rows = unique.shape[0]
    prefix = np.zeros(n_rows + 1, dtype=np.int64)
    for r in range(n_rows):
        prefix[r + 1] = prefix[r] + unique[r]
    for r in range(n_rows):
        for i in range(block):
            indptr[block * r + i + 1] = block * prefix[r] + (i + 1) * unique[r]
    for r in prange(n_rows):
        u = unique[r]
        for i in range(block):
            out = block * prefix[r] + i * u
            for t in range(u):
                indices[out + t] = block * ucols[start[r] + t] + i
                data[out + t] = uvals[start[r] + t]


def block_csr(rows, cols, vals, shape, block=3):
    """CSR matrix of ``kron(coo(vals, (rows, cols), shape), I_block)`` with duplicates summed."""
    n_rows, n_cols = shape
    start, order = _row_order(rows, n_rows)
    ucols = np.empty(len(rows), dtype=np.int64)
    uvals = np.empty(len(rows))
    unique = np.zeros(n_rows, dtype=np.int64)
    _sum_duplicates(start, order, cols, vals, ucols, uvals, unique)
    nnz = int(unique.sum()) * block
    indptr = np.zeros(block * n_rows + 1, dtype=np.int64)
    indices = np.empty(nnz, dtype=np.int64)
    data = np.empty(nnz)
    _expand(start, ucols, uvals, unique, block, indptr, indices, data)
    return sp.csr_matrix((data, indices, indptr), shape=(block * n_rows, block * n_cols))
