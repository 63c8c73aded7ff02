"""Thin helpers around petsc4py: initialisation, matrices and vectors from per-rank triplets, gathering.

Every rank passes the entries it computed with global (rank-major) indices, whichever rank owns
the row; PETSc's COO assembly sends off-rank entries to their owner and adds repeated entries.
"""
import numpy as np
import scipy.sparse as sp

from ._require import require

_PETSC = None


def petsc():
    """The ``petsc4py.PETSc`` module, initialised once (mpi4py first, so both share MPI)."""
    global _PETSC
    # asked every time, so that a missing package is named even after a successful first use
    require("mpi4py")
    petsc4py = require("petsc4py")
    if _PETSC is None:
        petsc4py.init()
        from petsc4py import PETSc
        _PETSC = PETSc
    return _PETSC


def coo_matrix(comm, rows, cols, values, row_sizes, col_sizes, block_size=None):
    """An assembled ``MPIAIJ`` matrix of the sum of the entries given on all ranks.

    Parameters
    ----------
    comm : PETSc.Comm
    rows, cols : (k,) int
        Global indices (any rank's rows).
    values : (k,) float64
    row_sizes, col_sizes : (local, global)
        This rank's owned rows (columns: its part of the input vector) and the totals.
    block_size : int, optional
        Rows per node (3 for displacements: GAMG aggregates nodes and reads the block size).

    Notes
    -----
    Repeated entries are summed here (scipy) and then across ranks by PETSc: entries of rows another
    rank owns are stashed by ``MatSetValues`` and sent at ``MatAssemblyBegin/End``. Preallocation
    counts the rank's own entries of its rows; entries another rank adds to them may allocate more.
    """
    PETSc = petsc()
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    (n_local, n), (m_local, m) = (tuple(int(s) for s in row_sizes), tuple(int(s) for s in col_sizes))
    A = PETSc.Mat().create(comm=comm)
    A.setSizes(((n_local, n), (m_local, m)), bsize=block_size)
    A.setType(PETSc.Mat.Type.MPIAIJ)
    first_row = _exclusive_sum(comm, n_local)
    first_col = _exclusive_sum(comm, m_local)
    unique_rows, inverse = np.unique(rows, return_inverse=True)
    C = sp.csr_matrix((np.asarray(values, dtype=np.float64), (inverse.ravel(), cols)), shape=(len(unique_rows), max(m, 1)))
    C.sum_duplicates()
    # preallocation of the owned rows from this rank's entries (diagonal block: owned columns)
    own = (unique_rows >= first_row) & (unique_rows < first_row + n_local)
    d_nnz, o_nnz = np.zeros(n_local, np.int64), np.zeros(n_local, np.int64)
    if own.any():
        Co = C[np.flatnonzero(own)]
        in_diag = (Co.indices >= first_col) & (Co.indices < first_col + m_local)
        per_row = np.repeat(np.arange(Co.shape[0]), np.diff(Co.indptr))
        local = unique_rows[own] - first_row
        d_nnz[local] = np.bincount(per_row, weights=in_diag, minlength=Co.shape[0]).astype(np.int64)
        o_nnz[local] = np.bincount(per_row, weights=~in_diag, minlength=Co.shape[0]).astype(np.int64)
    A.setPreallocationNNZ((np.minimum(d_nnz, m_local).astype(PETSc.IntType), o_nnz.astype(PETSc.IntType)))
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    if len(unique_rows):
        A.setValuesIJV(C.indptr.astype(PETSc.IntType), C.indices.astype(PETSc.IntType), C.data,
                       addv=PETSc.InsertMode.ADD_VALUES, rowmap=unique_rows.astype(PETSc.IntType))
    A.assemble()
    return A


def _exclusive_sum(comm, value):
    """Sum of ``value`` over the ranks before this one."""
    return int(comm.tompi4py().exscan(int(value)) or 0)


def summed_vector(comm, index, values, sizes):
    """An assembled ``MPI`` vector of the sum of the entries given on all ranks (global indices)."""
    PETSc = petsc()
    v = PETSc.Vec().createMPI(tuple(int(s) for s in sizes), comm=comm)
    v.set(0.0)
    if len(index):
        v.setValues(np.asarray(index, dtype=PETSc.IntType), np.asarray(values, dtype=PETSc.ScalarType),
                    addv=PETSc.InsertMode.ADD_VALUES)
    v.assemblyBegin()
    v.assemblyEnd()
    return v


def _allgather(comm, obj):
    return comm.tompi4py().allgather(obj)


def gather_matrix(A):
    """The distributed matrix ``A`` as a scipy CSR matrix on every rank."""
    indptr, indices, data = A.getValuesCSR()
    first, _ = A.getOwnershipRange()
    parts = _allgather(A.getComm(), (first, np.asarray(indptr), np.asarray(indices), np.asarray(data)))
    rows = [np.repeat(np.arange(f, f + len(p) - 1), np.diff(p)) for f, p, _, _ in parts]
    n, m = A.getSize()
    return sp.csr_matrix((np.concatenate([d for *_, d in parts]),
                          (np.concatenate(rows), np.concatenate([i for _, _, i, _ in parts]))), shape=(n, m))


def gather_vector(v):
    """The distributed vector ``v`` as an array on every rank."""
    return np.concatenate(_allgather(v.getComm(), np.asarray(v.getArray()).copy()))


class Entries:
    """Given global entries of distributed vectors of one layout, received on this rank: one
    ``VecScatter`` into a sequential vector, made once and used for every vector of that layout.

    Parameters
    ----------
    layout : PETSc.Vec
        Any vector of the layout (only its layout is used).
    indices : (k,) int array_like
        Global indices, in the order the entries are wanted.
    """

    def __init__(self, layout, indices):
        PETSc = petsc()
        self.values = PETSc.Vec().createSeq(len(indices), comm=PETSc.COMM_SELF)
        index = PETSc.IS().createGeneral(np.asarray(indices).astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = PETSc.Scatter().create(layout, index, self.values, None)
        index.destroy()

    def __call__(self, x):
        """The entries of ``x`` (collective); a view of this object's buffer, valid until the next call."""
        PETSc = petsc()
        self.scatter.scatter(x, self.values, addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        return self.values.getArray()
