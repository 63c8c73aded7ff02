"""Block CSR of the mortar operators in Numba, deterministic, 3×3 identity blocks expanded.

Each LM row gathers its entries from the local matrices of the (beam element, solid element)
groups that touch it, in a fixed order (beam elements ascending, groups, columns), sums the entries
of each column in that order and sorts the distinct columns. Rows are independent (parallel) and the summation order does not
depend on the number of threads, so neither do the resulting bits. A first pass counts each
row's distinct columns; the second writes the expanded CSR arrays directly (no intermediate
copy of the gathered entries: less memory to fault in).
"""
import numpy as np
import scipy.sparse as sp

from .._config import CHUNK, njit, njit_inline
from .._parallel import in_parallel
from .._memory import carve
from .._schedule import claim, n_chunks, new_claims, workers


#: rows with up to this many distinct columns are ordered by counting (m² comparisons without branches),
#: longer ones by an insertion sort
_RANK_MAX = 64


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


@njit
def _count_unique(src_offsets, src, n_phi, beam_groups, width, col_table, col_row, n_cols, unique, workers):
    """Distinct columns (``unique``) of every row.

    Each worker keeps a marker array over the columns (the last row that saw a column):
    counting costs one visit per entry, no sort, in any order of the rows.
    """
    claims = new_claims(src_offsets.shape[0] - 1, workers)
    _count_unique_workers(workers, claims, src_offsets, src, n_phi, beam_groups, width, col_table, col_row, n_cols,
                          unique)


@njit
def _count_unique_worker(worker, claims, src_offsets, src, n_phi, beam_groups, width, col_table, col_row, n_cols,
                         unique):
    n_rows = src_offsets.shape[0] - 1
    marker = np.full(n_cols, -1, dtype=np.int64)
    begin, stop = claim(claims, n_rows, worker)
    while begin < stop:
        for r in range(begin, stop):
            u = 0
            for t in range(src_offsets[r], src_offsets[r + 1]):
                e = src[t] // n_phi
                for g in range(beam_groups[e], beam_groups[e + 1]):
                    row = col_row[g]
                    for q in range(width[g]):
                        c = col_table[row, q]
                        if marker[c] != r:
                            marker[c] = r
                            u += 1
            unique[r] = u
        begin, stop = claim(claims, n_rows, worker)


#: the kernels' workers run on the package's one parallel loop (see mortar1d3d._parallel)
_count_unique_workers = in_parallel(_count_unique_worker)


@njit
def _fill_rows(src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row, vals, first,
               max_unique, n_cols, block, indices, data, workers):
    """Gather and sum each row's entries per column, sort the columns, and write the row's ``block``
    expanded copies.

    Each column's sum runs over its entries in the gather order (beam elements ascending, groups,
    columns: deterministic), as a stable sort of the gathered entries followed by the sums of equal
    columns would; a marker over the columns (the column's slot in the row) merges them as they come,
    so only the distinct columns are sorted: a row of a 27-node element type gathers several times
    as many entries as it has columns (its beam elements' groups share nodes).
    """
    claims = new_claims(src_offsets.shape[0] - 1, workers)
    _fill_rows_workers(workers, claims, src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row,
                       vals, first, max_unique, n_cols, block, indices, data)


@njit
def _fill_rows_worker(worker, claims, src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row,
                      vals, first, max_unique, n_cols, block, indices, data):
    n_rows = src_offsets.shape[0] - 1
    cols = np.empty(max_unique, dtype=np.int64)
    vs = np.empty(max_unique)
    slot = np.full(n_cols, -1, dtype=np.int64)
    rank = np.empty(max_unique, dtype=np.int64)
    begin, stop = claim(claims, n_rows, worker)
    while begin < stop:
        _fill_rows_chunk(begin, stop, src_offsets, src, n_phi, beam_groups, entry_start, width, col_table,
                         col_row, vals, first, block, indices, data, cols, vs, slot, rank)
        begin, stop = claim(claims, n_rows, worker)


@njit_inline
def _fill_rows_chunk(begin, stop, src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row, vals,
                     first, block, indices, data, cols, vs, slot, rank):
    """The rows ``begin:stop`` of :func:`_fill_rows` (its loop body per claimed chunk; ``cols``, ``vs``,
    ``slot`` and ``rank`` the worker's buffers, ``slot`` all -1 on entry and on return)."""
    for r in range(begin, stop):
        m = 0
        for t in range(src_offsets[r], src_offsets[r + 1]):
            e = src[t] // n_phi
            j = src[t] % n_phi
            for g in range(beam_groups[e], beam_groups[e + 1]):
                base = entry_start[g] + j * width[g]
                row = col_row[g]
                for q in range(width[g]):
                    c = col_table[row, q]
                    k = slot[c]
                    if k < 0:
                        slot[c] = m
                        cols[m] = c
                        vs[m] = vals[base + q]
                        m += 1
                    else:
                        vs[k] += vals[base + q]
        for t in range(m):
            slot[cols[t]] = -1
        if m <= _RANK_MAX:
            # each distinct column's place in the sorted row: the number of smaller ones (no branch per
            # comparison, unlike a sort: the row's columns come in no order the branches could learn)
            for t in range(m):
                c = cols[t]
                k = 0
                for u in range(m):
                    k += cols[u] < c
                rank[t] = k
        else:
            for i in range(1, m):            # insertion sort of the distinct columns (long rows)
                c = cols[i]
                v = vs[i]
                k = i - 1
                while k >= 0 and cols[k] > c:
                    cols[k + 1] = cols[k]
                    vs[k + 1] = vs[k]
                    k -= 1
                cols[k + 1] = c
                vs[k + 1] = v
            for t in range(m):
                rank[t] = t
        for i in range(block):
            out = block * first[r] + i * m
            for t in range(m):
                indices[out + rank[t]] = block * cols[t] + i
                data[out + rank[t]] = vs[t]


#: the worker (compiled on its own, called through a symbol by the package's one parallel loop) inlines its
#: loop body (``njit_inline``), which is thus optimised once
_fill_rows_workers = in_parallel(_fill_rows_worker)


@njit
def _block_indptr(first, unique, block, indptr):
    """Row pointers of the expanded matrix: block row r has ``block`` rows of ``unique[r]`` entries."""
    indptr[0] = 0
    _block_indptr_parts(n_chunks(unique.shape[0], CHUNK), first, unique, block, indptr)


@njit
def _block_indptr_part(c, first, unique, block, indptr):
    # the block rows of chunk c (a parallel loop over the rows in chunks: one call per chunk)
    for r in range(c * CHUNK, min(unique.shape[0], (c + 1) * CHUNK)):
        for i in range(block):
            indptr[block * r + i + 1] = block * first[r] + (i + 1) * unique[r]


_block_indptr_parts = in_parallel(_block_indptr_part)


def gathered_block_csr(src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row, vals, shape,
                       block=3):
    """Block CSR of per-group local matrices, gathered row by row (parallel, deterministic).

    Group g of beam element e (groups of e are ``beam_groups[e]:beam_groups[e+1]``) holds, for
    each local multiplier function j, ``width[g]`` values at ``entry_start[g] + j*width[g]`` of
    ``vals``, in the columns ``col_table[col_row[g], :width[g]]``; row ``r`` receives the entries
    of the (e, j) listed in ``src[src_offsets[r]:src_offsets[r+1]]`` (as ``e*n_phi + j``).
    Every entry stands for a ``block`` x ``block`` identity block.
    """
    n_rows, n_cols = shape
    unique = np.empty(n_rows, dtype=np.int64)
    _count_unique(src_offsets, src, n_phi, beam_groups, width, col_table, col_row, n_cols, unique, workers())
    first = np.zeros(n_rows + 1, dtype=np.int64)
    np.cumsum(unique, out=first[1:])
    nnz = int(first[-1]) * block
    big = max(nnz, block * max(n_rows, n_cols)) >= np.iinfo(np.int32).max
    index_type = np.int64 if big else np.int32   # what scipy would convert to anyway
    indptr, indices, data = carve((block * n_rows + 1, index_type), (nnz, index_type), (nnz, np.float64))
    _block_indptr(first, unique, block, indptr)
    _fill_rows(src_offsets, src, n_phi, beam_groups, entry_start, width, col_table, col_row, vals, first,
               max(1, int(unique.max())) if n_rows else 1, n_cols, block, indices, data, workers())
    return _attach_csr(data, indices, indptr, (block * n_rows, block * n_cols))


def _attach_csr(data, indices, indptr, shape):
    """A CSR matrix that uses the given (valid, sorted, duplicate-free) arrays as they are.

    SciPy's constructor copies arrays that are views of a block more than twice their size
    (``_prune_array``), which the carved arrays are: about 1.8 ms of serial copying per call on
    the benchmark scene. The arrays are built here and are final, so they are attached directly.
    """
    matrix = sp.csr_matrix(shape, dtype=data.dtype)
    matrix.data, matrix.indices, matrix.indptr = data, indices, indptr
    matrix.has_sorted_indices = True
    matrix.has_canonical_format = True
    return matrix


@njit
def _residual_squares(d_ptr, d_idx, d_val, q, m_ptr, m_idx, m_val, x, partial, workers):
    # per chunk of rows: Σ (D q - M x)_r² and Σ (D q)_r², rows in order;
    # chunks summed in order by the caller, so the result does not depend on the number of threads
    claims = new_claims(d_ptr.shape[0] - 1, workers)
    _residual_squares_workers(workers, claims, d_ptr, d_idx, d_val, q, m_ptr, m_idx, m_val, x, partial)


@njit
def _residual_squares_worker(worker, claims, d_ptr, d_idx, d_val, q, m_ptr, m_idx, m_val, x, partial):
    n_rows = d_ptr.shape[0] - 1
    begin, stop = claim(claims, n_rows, worker)
    while begin < stop:
        diff = 0.0
        ref = 0.0
        for r in range(begin, stop):
            a = 0.0
            for t in range(d_ptr[r], d_ptr[r + 1]):
                a += d_val[t] * q[d_idx[t]]
            b = 0.0
            for t in range(m_ptr[r], m_ptr[r + 1]):
                b += m_val[t] * x[m_idx[t]]
            diff += (a - b) ** 2
            ref += a * a
        partial[begin // CHUNK, 0] = diff
        partial[begin // CHUNK, 1] = ref
        begin, stop = claim(claims, n_rows, worker)


_residual_squares_workers = in_parallel(_residual_squares_worker)


def relative_residual(D, q, M, x):
    """‖D q − M x‖ / ‖D q‖ (0 if D q = 0), in one parallel pass over the rows.

    Not ``np.linalg.norm`` of scipy products: its BLAS call wakes OpenBLAS's thread pool, which
    then competes with Numba's threads for the cores (two threads ran slower than one).
    """
    # the Python function: calling the kernel from here would compile it for (int64, int64) besides the
    # kernels' (int64, literal CHUNK)
    partial = np.empty((n_chunks.py_func(D.shape[0], CHUNK), 2))
    _residual_squares(D.indptr, D.indices, D.data, np.ascontiguousarray(q, dtype=np.float64), M.indptr, M.indices,
                      M.data, np.ascontiguousarray(x, dtype=np.float64), partial, workers())
    diff, ref = partial.sum(axis=0) if len(partial) else (0.0, 0.0)
    return float(np.sqrt(diff / ref)) if ref > 0 else 0.0
