"""COO → CSR in Numba, deterministic, with 3×3 identity blocks expanded.

Entries are ordered by two stable counting sorts (by column, then by row), and duplicates are
summed in their COO order. The COO order does not depend on the number of threads, so neither
do the resulting bits. Cost O(nnz + n_rows + n_cols), no per-row sorting.
"""
import numpy as np
import scipy.sparse as sp
from numba import prange

from .._config import njit, njit_parallel


@njit
def _stable_counting_order(keys, n_keys, order_in):
    """Permutation that sorts ``keys[order_in]`` stably; returns (order, offsets per key)."""
    counts = np.zeros(n_keys + 1, dtype=np.int64)
    for q in range(order_in.shape[0]):
        counts[keys[order_in[q]] + 1] += 1
    start = np.cumsum(counts)
    fill = start[:-1].copy()
    order = np.empty(order_in.shape[0], dtype=np.int64)
    for q in range(order_in.shape[0]):
        t = order_in[q]
        k = keys[t]
        order[fill[k]] = t
        fill[k] += 1
    return order, start


@njit
def _sorted_unique(rows, cols, vals, n_rows, n_cols):
    by_col, _ = _stable_counting_order(cols, n_cols, np.arange(rows.shape[0]))
    order, start = _stable_counting_order(rows, n_rows, by_col)
    ucols = np.empty(rows.shape[0], dtype=np.int64)
    uvals = np.empty(rows.shape[0])
    unique = np.zeros(n_rows, dtype=np.int64)
    for r in range(n_rows):
        a = start[r]
        m = 0
        for t in range(a, start[r + 1]):
            q = order[t]
            if m > 0 and ucols[a + m - 1] == cols[q]:
                uvals[a + m - 1] += vals[q]
            else:
                ucols[a + m] = cols[q]
                uvals[a + m] = vals[q]
                m += 1
        unique[r] = m
    return start, ucols, uvals, unique


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
    """CSR matrix of ``kron(coo(vals, (rows, cols), shape), I_block)`` with duplicates summed.

    Column indices are sorted within rows; explicit zeros are kept (the sparsity pattern is
    that of the coupled pairs).
    """
    n_rows, n_cols = shape
    start, ucols, uvals, unique = _sorted_unique(rows, cols, vals, n_rows, n_cols)
    nnz = int(unique.sum()) * block
    big = max(nnz, block * max(n_rows, n_cols)) >= np.iinfo(np.int32).max
    index_type = np.int64 if big else np.int32   # what scipy would convert to anyway
    indptr = np.zeros(block * n_rows + 1, dtype=index_type)
    indices = np.empty(nnz, dtype=index_type)
    data = np.empty(nnz)
    _expand(start, ucols, uvals, unique, block, indptr, indices, data)
    matrix = sp.csr_matrix((data, indices, indptr), shape=(block * n_rows, block * n_cols))
    matrix.has_sorted_indices = True
    return matrix
