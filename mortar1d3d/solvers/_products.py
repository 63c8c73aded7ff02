"""Sparse products of the auxiliary space's set-up, each in one pass (Numba kernels).

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

from .._config import njit


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
                k = c - first
                for q in range(r1_indptr[k], r1_indptr[k + 1]):
                    j = r1_indices[q]
                    if where[j] < 0:
                        where[j] = count
                        touched[count] = j
                        count += 1
                    acc[j] += a * r1_data[q]
        for e in range(l2_indptr[i], l2_indptr[i + 1]):
            k = l2_indices[e]
            a = l2_data[e]
            for q in range(r2_indptr[k], r2_indptr[k + 1]):
                j = r2_indices[q]
                if where[j] < 0:
                    where[j] = count
                    touched[count] = j
                    count += 1
                acc[j] += a * r2_data[q]
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
