"""The model's tangent as one CSR pattern, built once and refilled on every Newton iteration.

The tangent of solid + beams + penalty coupling is a sum of blocks whose sparsity patterns do not
change between iterations: the solid's (a fixed assembly graph), each beam group's (a cached element
pattern, placed at the group's unknowns) and the constant penalty coupling stiffness. Summing them
with ``scipy.sparse`` on every call (``block_diag``, then matrix additions) builds and sorts a new
matrix each time: COO → CSR conversions, sorted merges and a fresh allocation of the whole tangent.
Here the union of the patterns is computed once, with, for every block, the position of each of its
entries in the union's ``data``; an iteration then allocates one ``data`` array, copies the constant
part in and adds each block's values at their positions.

The result has the same entries and the same values bit for bit as the scipy sum: every entry has
at most one block contribution besides the constant part (the blocks sit on disjoint unknowns), and
a sum of two floating-point numbers does not depend on their order. Entries that are exactly zero
are removed, as scipy's matrix addition removes them, so the pattern is the same too (a direct
solver's fill-reducing ordering depends on it).

A block whose pattern differs from the one the positions were made for (compared by identity, then
by value), or another constant matrix object, makes the union be rebuilt: correct for any input,
fast when patterns are fixed. The constant matrix's values are read when the union is built: change
it by passing a new matrix, not in place.
"""
import numpy as np
import scipy.sparse as sp


def _global_keys(K, index, n):
    """Row-major keys ``i * n + j`` of the entries of CSR block ``K`` (in its ``data`` order), rows
    and columns mapped to the global unknowns by ``index`` (an int offset or a local → global array)."""
    rows = np.repeat(np.arange(K.shape[0], dtype=np.int64), np.diff(K.indptr))
    cols = K.indices.astype(np.int64)
    if isinstance(index, (int, np.integer)):
        rows += index
        cols += index
    else:
        rows, cols = index[rows], index[cols]
    return rows * n + cols


class TangentPattern:
    """Sums of fixed-pattern sparse blocks into an (n, n) CSR matrix over one cached pattern.

    Parameters
    ----------
    n : int
        Size of the square result.

    Use :meth:`assemble` with the same list layout on every call: ``blocks`` is a list of
    ``(K, index)`` pairs (CSR blocks and their offset or local → global index array) and
    ``constant`` a CSR matrix of the full size added to every result (or None).
    """

    def __init__(self, n):
        self.n = int(n)
        self._signature = None
        self._constant = None
        self.n_builds = 0

    @staticmethod
    def _layout(blocks, constant):
        return [(K.shape, K.indptr, K.indices) for K, _ in blocks] + \
            ([(constant.shape, constant.indptr, constant.indices)] if constant is not None else [])

    def _matches(self, layout):
        if self._signature is None or len(layout) != len(self._signature):
            return False
        for (shape, indptr, indices), (shape0, indptr0, indices0) in zip(layout, self._signature):
            if shape != shape0:
                return False
            if indptr is indptr0 and indices is indices0:
                continue
            if not (np.array_equal(indptr, indptr0) and np.array_equal(indices, indices0)):
                return False
        return True

    def _build(self, blocks, constant, layout):
        n = self.n
        keys = [_global_keys(K, index, n) for K, index in blocks]
        if constant is not None:
            keys.append(_global_keys(constant, 0, n))
        union = np.unique(np.concatenate(keys)) if keys else np.zeros(0, dtype=np.int64)
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(union // n, minlength=n), out=indptr[1:])
        index_type = np.int32 if max(len(union), n) < np.iinfo(np.int32).max else np.int64
        self._indptr = indptr.astype(index_type)
        self._indices = (union % n).astype(index_type)
        self._indptr.flags.writeable = False
        self._indices.flags.writeable = False
        self._positions = [np.searchsorted(union, k).astype(index_type) for k in keys[:len(blocks)]]
        # a block with repeated entries (not canonical CSR) is summed entry by entry
        self._unique = [len(np.unique(k)) == len(k) for k in keys[:len(blocks)]]
        self._base = np.zeros(len(union))
        if constant is not None:
            np.add.at(self._base, np.searchsorted(union, keys[-1]), constant.data)
        # copies of the patterns the positions were made for (the caller's arrays may be reused)
        self._signature = [(shape, indptr.copy(), indices.copy()) for shape, indptr, indices in layout]
        self._constant = constant
        self.n_builds += 1

    def assemble(self, blocks, constant=None):
        """``constant + Σ_k P_k K_k P_kᵀ`` as CSR (sorted indices, no stored zeros).

        Parameters
        ----------
        blocks : list of (scipy.sparse.csr_matrix, int or (m,) int array)
            Square blocks on disjoint sets of unknowns, with their global offset or index array.
        constant : scipy.sparse.csr_matrix (n, n) or None
            The same matrix object on every call (a new object rebuilds the union).
        """
        blocks = [(K if sp.isspmatrix_csr(K) else K.tocsr(), index) for K, index in blocks]
        layout = self._layout(blocks, constant)
        if constant is not self._constant or not self._matches(layout):
            self._build(blocks, constant, layout)
        else:
            # identical patterns by value: keep their arrays, so the next call compares by identity
            self._signature = [(shape, indptr, indices) for shape, indptr, indices in layout]
        data = self._base.copy()
        for (K, _), positions, unique in zip(blocks, self._positions, self._unique):
            if unique:
                data[positions] += K.data
            else:
                np.add.at(data, positions, K.data)
        if np.any(data == 0.0):
            K = sp.csr_matrix((data, self._indices.copy(), self._indptr.copy()), shape=(self.n, self.n), copy=False)
            K.has_sorted_indices = True
            K.eliminate_zeros()
            return K
        # no zeros: the result shares the cached pattern, which is read-only so that no caller can
        # change it in place
        K = sp.csr_matrix((data, self._indices, self._indptr), shape=(self.n, self.n), copy=False)
        K.has_sorted_indices = True
        return K
