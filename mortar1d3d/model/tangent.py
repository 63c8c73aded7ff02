"""The model's tangent as one CSR pattern, built once and refilled on every Newton iteration.

The tangent of solid + beams + penalty coupling is a sum of blocks whose sparsity patterns do not
change between iterations: the solid's (a fixed assembly graph), each beam group's (a cached element
pattern, placed at the group's unknowns) and the constant penalty coupling stiffness. Summing them
with ``scipy.sparse`` on every call (``block_diag``, then matrix additions) builds and sorts a new
matrix each time: COO → CSR conversions, sorted merges and a fresh allocation of the whole tangent.
Here the union of the patterns is computed once, with, for every block, the position of each of its
entries in the union's ``data``; an iteration then allocates one ``data`` array and adds the
constant's and each block's values at their positions (a compiled loop: numpy's fancy indexing
took as long as the solid's element kernel at 3e5 unknowns).

The result has the same entries and the same values bit for bit as the scipy sum: every entry has
at most one block contribution besides the constant part (the blocks sit on disjoint unknowns), and
a sum of two floating-point numbers does not depend on their order. Entries that are exactly zero
are removed, as scipy's matrix addition removes them, so the pattern is the same too (a direct
solver's fill-reducing ordering depends on it).

A block or constant whose pattern differs from the one the positions were made for (compared by
value; read-only pattern arrays, like the solid's, by memory address) makes the union be rebuilt: correct for any input, fast when patterns are
fixed. The union and the positions are built with one byte per entry for the patterns and a
binary search per entry (:func:`~mortar1d3d.physics.assembly_graph.pattern_positions`), so the
build needs little more memory than the tangent itself.

The ``data`` array of a result is recycled by the next call once no one holds it any more (the
caller dropped the previous tangent, and with it every view of its values): it is set to zero and
filled again, instead of a new array being allocated. Above a few tens of MB (the tangent of 1e5
unknowns has 62 MB of values) every new array is fresh memory from the operating system, whose
pages are faulted in and zeroed one by one during the first writes: at 1e6 unknowns that cost
about a tenth of an iteration, and is what made the cost per unknown grow with the size. A
tangent that is still held (by the caller, a solver, a view of its data) is never touched: the
next result then gets a new array. :func:`~mortar1d3d.solvers.newton.solve_load_steps` drops
its tangent after each linear solve for this reason. The price: the pattern keeps the last
result's values alive after the caller has dropped them (625 MB at 1e6 unknowns), until the next
call or until the pattern itself goes.
"""
import sys

import numpy as np
import scipy.sparse as sp

from ..physics.assembly_graph import add_at_positions, has_zero, pattern_positions, subtract_at_positions


def _same_memory(a, b):
    """Whether two arrays are the same memory (scipy wraps a matrix's index arrays in new array
    objects on every construction, so identity of the objects says nothing). Trusted as "the same
    pattern" only for read-only arrays, which no one can have changed in place (the solid's)."""
    return a is b or (a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
                      and a.shape == b.shape and a.dtype == b.dtype and a.strides == b.strides)


def _placed(K, index, n):
    """The pattern of square CSR block ``K`` placed in an (n, n) matrix (one byte per entry), with the
    local → global map of its rows and columns; ``index``: an int offset or a local → global array."""
    m = K.shape[0]
    if isinstance(index, (int, np.integer)):
        local_to_global = np.arange(index, index + m, dtype=np.int64)
        # rows offset..offset+m-1 keep their structure: no COO, no sort
        small = np.int32 if max(n, K.nnz) < np.iinfo(np.int32).max else np.int64
        indptr = np.concatenate([np.zeros(index, dtype=small), K.indptr.astype(small),
                                 np.full(n - index - m, K.indptr[-1], dtype=small)])
        placed = sp.csr_matrix((np.ones(K.nnz, dtype=np.int8), K.indices.astype(small) + small(index), indptr),
                               shape=(n, n))
    else:
        local_to_global = np.asarray(index, dtype=np.int64)
        rows = np.repeat(np.arange(m), np.diff(K.indptr))
        placed = sp.csr_matrix((np.ones(K.nnz, dtype=np.int8),
                                (local_to_global[rows], local_to_global[K.indices])), shape=(n, n))
    return placed, local_to_global


def _canonical(K):
    """CSR without repeated entries (a load's values are subtracted entry by entry, so repeats must be
    summed first, as scipy's conversion to CSR sums them)."""
    K = K if sp.isspmatrix_csr(K) else K.tocsr()
    if not K.has_canonical_format:
        K = K.copy()
        K.sum_duplicates()
    return K


def _positions(union, K, local_to_global, index_type):
    positions = np.empty(K.nnz, dtype=index_type)
    missing = pattern_positions(union.indptr, union.indices, K.indptr, K.indices, local_to_global,
                                local_to_global, positions)
    if missing:
        raise AssertionError(f"TangentPattern: {missing} entries of a block are not in the union pattern")
    return positions


class FilledBlock:
    """A block whose pattern is known before its values, which it adds straight into the result.

    ``fill(data, positions)`` adds the block's value of entry k (of the CSR pattern ``indptr``,
    ``indices``) at ``data[positions[k]]``, starting from zero there. The solid is passed this way
    (:meth:`~mortar1d3d.physics.solid.SolidModel.add_tangent_into`): its element kernel writes
    into the tangent's data, so no separate solid matrix is allocated, filled and copied.
    """

    def __init__(self, shape, indptr, indices, fill):
        self.shape = tuple(shape)
        self.indptr = indptr
        self.indices = indices
        self.fill = fill

    @property
    def nnz(self):
        return len(self.indices)


class TangentPattern:
    """Sums of fixed-pattern sparse blocks into an (n, n) CSR matrix over one cached pattern.

    Parameters
    ----------
    n : int
        Size of the square result.

    Use :meth:`assemble` with the same list layout on every call: ``blocks`` is a list of
    ``(K, index)`` pairs (CSR blocks or :class:`FilledBlock`, and their offset or local → global
    index array) and ``constant`` a CSR matrix of the full size added to every result (or None).
    """

    def __init__(self, n):
        self.n = int(n)
        self._signature = None
        self.n_builds = 0
        self.n_recycled = 0
        self._spare = None              # the data array of the last result (module docstring)

    def _data(self):
        """A zeroed data array for the next result: the last result's, if no one else holds it."""
        spare, self._spare = self._spare, None
        # references to spare: this name and getrefcount's argument; one more is a holder
        if spare is not None and spare.shape == (self._nnz,) and sys.getrefcount(spare) == 2:
            spare.fill(0.0)
            self.n_recycled += 1
            return spare
        del spare
        return np.zeros(self._nnz)

    @staticmethod
    def _layout(blocks, constant, subtract):
        return [(K.shape, K.indptr, K.indices) for K, _ in blocks] + \
            ([(constant.shape, constant.indptr, constant.indices)] if constant is not None else []) + \
            [(K.shape, K.indptr, K.indices) for K, _, _ in subtract]

    def _matches(self, layout):
        if self._signature is None or len(layout) != len(self._signature):
            return False
        for (shape, indptr, indices), (shape0, indptr0, indices0) in zip(layout, self._signature):
            if shape != shape0:
                return False
            if _same_memory(indptr, indptr0) and _same_memory(indices, indices0) \
                    and not (indptr.flags.writeable or indices.flags.writeable):
                continue
            if not (np.array_equal(indptr, indptr0) and np.array_equal(indices, indices0)):
                return False
        return True

    def _build(self, blocks, constant, subtract, layout):
        n = self.n
        placed = [_placed(K, index, n) for K, index in blocks]
        placed_subtract = [_placed(K, index, n) for K, index, _ in subtract]
        union = sp.csr_matrix((n, n), dtype=np.int8)
        for pattern, _ in placed + placed_subtract:
            union = union + pattern
        identity = np.arange(n, dtype=np.int64)
        if constant is not None:
            union = union + sp.csr_matrix((np.ones(constant.nnz, dtype=np.int8), constant.indices, constant.indptr),
                                          shape=(n, n))
        union.sum_duplicates()                                   # canonical: sorted columns, no repeats
        index_type = np.int32 if max(union.nnz, n) < np.iinfo(np.int32).max else np.int64
        self._indptr = union.indptr.astype(index_type)
        self._indices = union.indices.astype(index_type)
        self._indptr.flags.writeable = False
        self._indices.flags.writeable = False
        self._positions = [_positions(union, K, rows, index_type) for (K, _), (_, rows) in zip(blocks, placed)]
        self._subtract_positions = [_positions(union, K, rows, index_type)
                                    for (K, _, _), (_, rows) in zip(subtract, placed_subtract)]
        self._constant_positions = None
        self._protected = None
        if constant is not None:
            self._constant_positions = _positions(union, constant, identity, index_type)
            self._protected = np.zeros(union.nnz, dtype=bool)
            self._protected[self._constant_positions] = True
        self._nnz = union.nnz
        # copies of the patterns the positions were made for (the caller's arrays may be reused)
        self._signature = [(shape, indptr.copy(), indices.copy()) for shape, indptr, indices in layout]
        self.n_builds += 1

    def assemble(self, blocks, constant=None, subtract=(), zeros="eliminate"):
        """``constant + Σ_k P_k K_k P_kᵀ − Σ_l s_l P_l L_l P_lᵀ`` as CSR (sorted indices).

        Parameters
        ----------
        blocks : list of (scipy.sparse.csr_matrix or FilledBlock, int or (m,) int array)
            Square blocks on disjoint sets of unknowns, with their global offset or index array.
            Filled blocks are filled first, then the constant and the matrices are added (the
            order of the two terms an entry may have does not change the sum's bits).
        constant : scipy.sparse.csr_matrix (n, n) or None
            Added to every result (a changed pattern rebuilds the union, like a block's).
        subtract : list of (scipy.sparse.csr_matrix, int or (m,) int array, float)
            Terms ``s_l L_l`` subtracted last, one after the other (loads' tangents: they may share
            entries with the blocks and with each other); each value is subtracted as
            ``a − (s·v)``, which is what ``K − s * L`` gives in scipy.
        zeros : {"eliminate", "keep", "keep_constant"}
            Which entries that come out exactly zero are removed: all (what scipy's sums do), none
            (the union pattern as it is, as ``scipy.sparse.bmat`` keeps stored zeros), or all but
            the constant's (a saddle point's constraint border keeps its stored zeros next to a
            stiffness without any).
        """
        if zeros not in ("eliminate", "keep", "keep_constant"):
            raise ValueError(f"TangentPattern.assemble: zeros must be eliminate, keep or keep_constant, got {zeros!r}")
        if zeros == "keep_constant" and constant is None:
            zeros = "eliminate"
        blocks = [(K if isinstance(K, FilledBlock) or sp.isspmatrix_csr(K) else K.tocsr(), index)
                  for K, index in blocks]
        subtract = [(_canonical(K), index, float(scale)) for K, index, scale in subtract]
        layout = self._layout(blocks, constant, subtract)
        if not self._matches(layout):
            self._build(blocks, constant, subtract, layout)
        else:
            # equal patterns: keep the caller's arrays, so the next call compares memory addresses
            self._signature = [(shape, indptr, indices) for shape, indptr, indices in layout]
        data = self._data()
        for (K, _), positions in zip(blocks, self._positions):
            if isinstance(K, FilledBlock):
                K.fill(data, positions)
        if constant is not None:
            add_at_positions(data, self._constant_positions, constant.data)
        for (K, _), positions in zip(blocks, self._positions):
            if not isinstance(K, FilledBlock):
                add_at_positions(data, positions, K.data)
        for (K, _, scale), positions in zip(subtract, self._subtract_positions):
            subtract_at_positions(data, positions, K.data, scale)
        self._spare = data
        if zeros == "keep_constant" and self._protected is not None and has_zero(data):
            keep = (data != 0.0) | self._protected
            counts = np.concatenate([[0], np.cumsum(keep)])
            K = sp.csr_matrix((data[keep], self._indices[keep], counts[self._indptr]), shape=(self.n, self.n))
            K.has_sorted_indices = True
            return K
        if zeros == "eliminate" and has_zero(data):
            K = sp.csr_matrix((data, self._indices.copy(), self._indptr.copy()), shape=(self.n, self.n), copy=False)
            K.has_sorted_indices = True
            K.eliminate_zeros()
            return K
        # the union pattern as it is: the result shares it, read-only so that no caller can change
        # it in place
        K = sp.csr_matrix((data, self._indices, self._indptr), shape=(self.n, self.n), copy=False)
        K.has_sorted_indices = True
        return K
