"""Block CSR of the mortar operators in Numba, deterministic, 3×3 identity blocks expanded.

Each LM row gathers its entries from the local matrices of the (beam element, solid element)
groups that touch it, in a fixed order (beam elements ascending, groups, columns), sorts them by
column and sums duplicates. Rows are independent (parallel) and the summation order does not
depend on the number of threads, so neither do the resulting bits.
"""
import numpy as np
import scipy.sparse as sp
from numba import prange

from .._config import CHUNK, njit, njit_parallel
from ..geometry.linalg import n_chunks


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


@njit
def row_sources(lm_index, n_phi, n_rows):
    """CSR over LM rows of the (beam element, local function) pairs that feed each row."""
    n_beam = lm_index.shape[0]
    counts = np.zeros(n_rows + 1, dtype=np.int64)
    for e in range(n_beam):
        for j in range(n_phi):
            counts[lm_index[e, j] + 1] += 1
    offsets = np.cumsum(counts)
    fill = offsets[:-1].copy()
    src = np.empty(offsets[-1], dtype=np.int64)   # e * n_phi + j, ascending per row
    for e in range(n_beam):
        for j in range(n_phi):
            r = lm_index[e, j]
            src[fill[r]] = e * n_phi + j
            fill[r] += 1
    return offsets, src


@njit_parallel
def _gather_bounds(src_offsets, src, n_phi, beam_groups, width, bound):
    for r in prange(src_offsets.shape[0] - 1):
        total = 0
        for t in range(src_offsets[r], src_offsets[r + 1]):
            e = src[t] // n_phi
            for g in range(beam_groups[e], beam_groups[e + 1]):
                total += width[g]
        bound[r] = total


@njit_parallel
def _gather_rows(src_offsets, src, n_phi, beam_groups, entry_start, width, cols, vals, start, ucols, uvals,
                 unique):
    for r in prange(src_offsets.shape[0] - 1):
        a = start[r]
        n = 0
        # gather in a fixed order (beam elements ascending, groups, columns): deterministic sums
        for t in range(src_offsets[r], src_offsets[r + 1]):
            e = src[t] // n_phi
            j = src[t] % n_phi
            for g in range(beam_groups[e], beam_groups[e + 1]):
                base = entry_start[g] + j * width[g]
                for q in range(width[g]):
                    ucols[a + n] = cols[base + q]
                    uvals[a + n] = vals[base + q]
                    n += 1
        for i in range(a + 1, a + n):       # stable insertion sort by column (short rows)
            c = ucols[i]
            v = uvals[i]
            k = i - 1
            while k >= a and ucols[k] > c:
                ucols[k + 1] = ucols[k]
                uvals[k + 1] = uvals[k]
                k -= 1
            ucols[k + 1] = c
            uvals[k + 1] = v
        m = 0
        for t in range(a, a + n):
            if m > 0 and ucols[a + m - 1] == ucols[t]:
                uvals[a + m - 1] += uvals[t]
            else:
                ucols[a + m] = ucols[t]
                uvals[a + m] = uvals[t]
                m += 1
        unique[r] = m


def gathered_block_csr(src_offsets, src, n_phi, beam_groups, entry_start, width, cols, vals, shape, block=3):
    """Block CSR of per-group local matrices, gathered row by row (parallel, deterministic).

    Group g of beam element e (groups of e are ``beam_groups[e]:beam_groups[e+1]``) holds, for
    each local multiplier function j, ``width[g]`` entries at ``entry_start[g] + j*width[g]``
    with global columns ``cols`` and values ``vals``; row ``r`` receives the entries of the
    (e, j) listed in ``src[src_offsets[r]:src_offsets[r+1]]`` (as ``e*n_phi + j``).
    """
    n_rows, n_cols = shape
    bound = np.empty(n_rows, dtype=np.int64)
    _gather_bounds(src_offsets, src, n_phi, beam_groups, width, bound)
    start = np.concatenate([np.zeros(1, np.int64), np.cumsum(bound)])
    ucols = np.empty(start[-1], dtype=np.int64)
    uvals = np.empty(start[-1])
    unique = np.empty(n_rows, dtype=np.int64)
    _gather_rows(src_offsets, src, n_phi, beam_groups, entry_start, width, cols, vals, start, ucols, uvals, unique)
    return _finish(start, ucols, uvals, unique, n_rows, n_cols, block)


def _finish(start, ucols, uvals, unique, n_rows, n_cols, block):
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


@njit_parallel
def _residual_squares(d_ptr, d_idx, d_val, q, m_ptr, m_idx, m_val, x, partial):
    # per chunk of rows: Σ (D q - M x)_r² and Σ (D q)_r²; chunks summed in order by the caller,
    # so the result does not depend on the number of threads
    n_rows = d_ptr.shape[0] - 1
    for c in prange(n_chunks(n_rows, CHUNK)):
        diff = 0.0
        ref = 0.0
        for r in range(c * CHUNK, min(n_rows, (c + 1) * CHUNK)):
            a = 0.0
            for t in range(d_ptr[r], d_ptr[r + 1]):
                a += d_val[t] * q[d_idx[t]]
            b = 0.0
            for t in range(m_ptr[r], m_ptr[r + 1]):
                b += m_val[t] * x[m_idx[t]]
            diff += (a - b) ** 2
            ref += a * a
        partial[c, 0] = diff
        partial[c, 1] = ref


def relative_residual(D, q, M, x):
    """‖D q − M x‖ / ‖D q‖ (0 if D q = 0), in one parallel pass over the rows.

    Not ``np.linalg.norm`` of scipy products: its BLAS call wakes OpenBLAS's thread pool, which
    then competes with Numba's threads for the cores (two threads ran slower than one).
    """
    partial = np.empty((n_chunks(D.shape[0], CHUNK), 2))
    _residual_squares(D.indptr, D.indices, D.data, np.ascontiguousarray(q, dtype=np.float64), M.indptr, M.indices,
                      M.data, np.ascontiguousarray(x, dtype=np.float64), partial)
    diff, ref = partial.sum(axis=0) if len(partial) else (0.0, 0.0)
    return float(np.sqrt(diff / ref)) if ref > 0 else 0.0
