"""Sparse kernels of the auxiliary space's set-up: its products, each in one pass, and the weak node
blocks of the auxiliary matrix dropped in one pass (Numba).

Every product here has the form ``f ⊙ (L₁ [I; R₁]) + L₂ R₂`` (``f`` a factor per row, ``I`` the
identity on the first columns of ``L₁``): the smoothing step of the follow operator
(``P − J (A_BS + A_BB P)``), the beam rows of ``A E`` and the auxiliary matrix ``Eᵀ A E`` are all
of it. SciPy forms such a product from stacked copies of its operands (``hstack``, ``vstack``)
and then multiplies them in two passes (one that counts the entries of each row, one that fills
them); here each output row is accumulated once, from the operands as they are, and entries below
a fraction of their row's largest can be left out as the row is written.
"""
import numpy as np
import scipy.sparse as sp

from .._config import njit, njit_inline


@njit_inline
def _add_row(indptr, indices, data, k, a, where, touched, acc, count):
    """``acc += a · row k`` of a CSR matrix, the columns first touched appended to ``touched``
    (``where[j] ≥ 0`` marks them); returns the new count of touched columns."""
    for q in range(indptr[k], indptr[k + 1]):
        j = indices[q]
        if where[j] < 0:
            where[j] = count
            touched[count] = j
            count += 1
        acc[j] += a * data[q]
    return count


@njit
def _extend_and_add(first, l1_indptr, l1_indices, l1_data, factor, r1_indptr, r1_indices, r1_data,
                    l2_indptr, l2_indices, l2_data, r2_indptr, r2_indices, r2_data, n_cols, drop):
    """Rows of ``factor ⊙ (L₁ [I; R₁]) + L₂ R₂`` (CSR arrays; ``I`` the ``first`` x ``first``
    identity, so a column ``c < first`` of ``L₁`` is output column ``c`` and a column ``c ≥ first``
    stands for row ``c − first`` of ``R₁``; ``L₂`` may have no entries). Exact zeros are left out, and
    with ``drop > 0`` every entry below ``drop`` times the largest magnitude of its row.
    Returns ``(indptr, indices, data)``; the columns of a row are in the order they were first
    touched."""
    n_rows = len(l1_indptr) - 1
    where = np.full(n_cols, -1, np.int64)      # position of each column in the current row, or -1
    acc = np.zeros(n_cols)
    touched = np.empty(n_cols, np.int64)
    indptr = np.zeros(n_rows + 1, np.int64)
    capacity = max(16, 2 * (len(l1_data) + len(r1_data)))
    indices = np.empty(capacity, np.int32)
    data = np.empty(capacity)
    nnz = 0
    for i in range(n_rows):
        count = 0
        f = factor[i]
        for e in range(l1_indptr[i], l1_indptr[i + 1]):
            c = l1_indices[e]
            a = f * l1_data[e]
            if c < first:
                if where[c] < 0:
                    where[c] = count
                    touched[count] = c
                    count += 1
                acc[c] += a
            else:
                count = _add_row(r1_indptr, r1_indices, r1_data, c - first, a, where, touched, acc, count)
        for e in range(l2_indptr[i], l2_indptr[i + 1]):
            count = _add_row(r2_indptr, r2_indices, r2_data, l2_indices[e], l2_data[e], where, touched, acc, count)
        threshold = 0.0
        if drop > 0.0:
            largest = 0.0
            for t in range(count):
                largest = max(largest, abs(acc[touched[t]]))
            threshold = drop * largest
        if nnz + count > capacity:
            capacity = max(2 * capacity, nnz + count)
            grown = np.empty(capacity, np.int32)
            grown[:nnz] = indices[:nnz]
            indices = grown
            grown_data = np.empty(capacity)
            grown_data[:nnz] = data[:nnz]
            data = grown_data
        for t in range(count):
            j = touched[t]
            v = acc[j]
            if v != 0.0 and abs(v) >= threshold:
                indices[nnz] = j
                data[nnz] = v
                nnz += 1
            acc[j] = 0.0
            where[j] = -1
        indptr[i + 1] = nnz
    return indptr, indices[:nnz], data[:nnz]


def _csr_arrays(A):
    return A.indptr, A.indices, A.data


def extend_and_add(L1, R1, factor=None, L2=None, R2=None, drop=0.0):
    """``factor ⊙ (L₁ [I; R₁]) + L₂ R₂`` as a CSR matrix (``_extend_and_add``), ``I`` the identity of
    ``R₁``'s column count ``m``: ``L₁`` has ``m + R₁.shape[0]`` columns, the result ``m``; ``factor``
    (one number per row, default 1) scales the first term only; ``L₂ R₂`` is left out when ``L2`` is
    None; ``drop`` as in :func:`~mortar1d3d.solvers.preconditioners.drop_weak_entries`. Exact zeros
    are left out (as SciPy's products do)."""
    n_rows, n_cols = L1.shape[0], R1.shape[1]
    first = n_cols
    if n_cols > np.iinfo(np.int32).max:
        raise ValueError(f"at most 2**31 - 1 columns, got {n_cols}")
    if L1.shape[1] != first + R1.shape[0]:
        raise ValueError(f"L1 must have {first} + {R1.shape[0]} columns, got {L1.shape[1]}")
    factor = np.ones(n_rows) if factor is None else np.ascontiguousarray(factor, dtype=np.float64)
    if L2 is None:
        L2 = sp.csr_matrix((n_rows, 0))
        R2 = sp.csr_matrix((0, n_cols))
    if L2.shape[0] != n_rows or L2.shape[1] != R2.shape[0] or R2.shape[1] != n_cols:
        raise ValueError("L2 R2 must have the shape of the first term")
    indptr, indices, data = _extend_and_add(
        first, *_csr_arrays(L1.tocsr()), factor, *_csr_arrays(R1.tocsr()), *_csr_arrays(L2.tocsr()),
        *_csr_arrays(R2.tocsr()), n_cols, float(drop))
    if indptr[-1] <= np.iinfo(np.int32).max:
        indptr = indptr.astype(np.int32)
    else:
        indices = indices.astype(np.int64)
    return sp.csr_matrix((data, indices, indptr), shape=(n_rows, n_cols))


@njit
def _drop_weak_blocks(indptr, indices, data, k, delta, compensation):
    """The kernel of :func:`~mortar1d3d.solvers.preconditioners.drop_weak_blocks` on a CSR matrix of
    ``k x k`` node blocks (columns of a row in any order): ``(indptr, indices, blocks)`` of the BSR
    result, block columns sorted. ``compensation``: 0 none, 1 the dropped blocks' absolute row sums
    on the diagonal, 2 the symmetric part of their sum on the diagonal block."""
    n = len(indptr) - 1
    nodes = n // k
    own = np.zeros(nodes)                    # Frobenius norms of the diagonal blocks
    for r in range(n):
        node = r // k
        for e in range(indptr[r], indptr[r + 1]):
            if indices[e] // k == node:
                own[node] += data[e] * data[e]
    own = np.sqrt(own)
    slot = np.full(nodes, -1, np.int64)      # the block of each column node in the current block row
    columns = np.empty(nodes, np.int64)
    buffer = np.zeros((nodes, k, k))
    out_indptr = np.zeros(nodes + 1, np.int64)
    capacity = max(16, nodes + len(data) // (2 * k * k))
    out_indices = np.empty(capacity, np.int32)
    out_blocks = np.empty((capacity, k, k))
    dropped = np.zeros((k, k))
    kept = 0
    for node in range(nodes):
        count = 0
        for a in range(k):
            r = node * k + a
            for e in range(indptr[r], indptr[r + 1]):
                c = indices[e]
                other = c // k
                if slot[other] < 0:
                    slot[other] = count
                    columns[count] = other
                    count += 1
                buffer[slot[other], a, c - other * k] += data[e]
        order = np.sort(columns[:count])
        if kept + count > capacity:
            capacity = max(2 * capacity, kept + count)
            grown = np.empty(capacity, np.int32)
            grown[:kept] = out_indices[:kept]
            out_indices = grown
            grown_blocks = np.empty((capacity, k, k))
            grown_blocks[:kept] = out_blocks[:kept]
            out_blocks = grown_blocks
        dropped[:, :] = 0.0
        diagonal = -1
        for t in range(count):
            other = order[t]
            s = slot[other]
            norm = 0.0
            for a in range(k):
                for b in range(k):
                    norm += buffer[s, a, b] * buffer[s, a, b]
            norm = np.sqrt(norm)
            if other == node or norm >= delta * np.sqrt(own[node] * own[other]):
                if other == node:
                    diagonal = kept
                out_indices[kept] = other
                out_blocks[kept] = buffer[s]
                kept += 1
            elif compensation == 1:
                for a in range(k):
                    for b in range(k):
                        dropped[a, a] += abs(buffer[s, a, b])
            elif compensation == 2:
                for a in range(k):
                    for b in range(k):
                        dropped[a, b] += buffer[s, a, b]
            buffer[s] = 0.0
            slot[other] = -1
        if diagonal >= 0 and compensation > 0:
            for a in range(k):
                for b in range(k):
                    out_blocks[diagonal, a, b] += 0.5 * (dropped[a, b] + dropped[b, a])
        out_indptr[node + 1] = kept
    return out_indptr, out_indices[:kept], out_blocks[:kept]


#: ``compensation`` of :func:`drop_weak_node_blocks` as the kernel's code
COMPENSATIONS = {"none": 0, "abs": 1, "signed": 2}


def drop_weak_node_blocks(A, delta, compensation, block_size):
    """:func:`~mortar1d3d.solvers.preconditioners.drop_weak_blocks` of a CSR matrix in one pass over
    its entries (``_drop_weak_blocks``), without converting it to BSR first: a BSR matrix with sorted
    block columns."""
    A = A.tocsr()
    k = block_size
    indptr, indices, blocks = _drop_weak_blocks(A.indptr, A.indices, A.data, k, float(delta),
                                                COMPENSATIONS[compensation])
    return sp.bsr_matrix((blocks, indices, indptr.astype(np.int32) if indptr[-1] < 2**31 else indptr),
                         shape=A.shape)
