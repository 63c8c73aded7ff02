"""Sparse direct factorisation (SuperLU) and the size up to which it beats AMG; a banded
Cholesky for SPD matrices of small bandwidth (the beam blocks of the auxiliary space).

scipy offers no sparse Cholesky; :func:`factorize` chooses SuperLU's ordering and pivoting for
SPD matrices, other matrices and saddle points (see its Notes). :func:`factorize_spd_block`
takes LAPACK's banded Cholesky where the bandwidth is small.
"""
import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["DIRECT_MAX_DOFS", "BANDED_MAX_BANDWIDTH", "BandedCholesky", "bandwidth", "factorize", "factorize_spd_block"]

#: ``method="auto"`` of :func:`~mortar1d3d.solvers.linear.solve_linear` (and ``solver = "auto"`` of a
#: scene) factorises systems up to this many unknowns and uses AMG + CG above. Measured on hex8
#: elasticity + a penalty-coupled chain (2 cores, loaded):
#: direct / AMG seconds 0.05 / 0.18 (1.4k DOF), 0.29 / 0.33 (2.7k), 0.56 / 0.47 (3.6k),
#: 2.1 / 0.74 (6.1k), 32 / 6.9 (26k), 151 / 11.5 (51k): SuperLU fill grows fast in 3D.
DIRECT_MAX_DOFS = 3_000


def factorize(A, symmetric_positive, saddle=False):
    """SuperLU factorisation of a sparse matrix.

    SPD matrices use a minimum-degree ordering of ``A + Aᵀ`` with diagonal pivots
    (``SymmetricMode``): the fill of a symmetric ordering, no row interchanges needed. Measured
    on 3D hex8 elasticity with a penalty-coupled chain (14k, 26k, 51k DOF) it factorises and
    solves 1.5x, 1.4x, 1.9x faster than scipy's default (``COLAMD`` with partial pivoting, what
    ``spsolve`` does), with the same accuracy (relative difference < 1e-12). Other matrices keep
    partial pivoting. Saddle points (``saddle=True``: a zero λ block, so most pivots leave the
    diagonal) use ``COLAMD``, the ordering made for partial pivoting: on 60 fibres in a 4³ cube
    (5.2k unknowns) it factorised in 0.4 s with 2.5M entries in L + U, the symmetric ordering in
    6.0 s with 8.2M.
    """
    A = sp.csc_matrix(A)
    if symmetric_positive:
        return spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options=dict(SymmetricMode=True))
    return spla.splu(A, permc_spec="COLAMD" if saddle else "MMD_AT_PLUS_A")


#: :func:`factorize_spd_block` uses a banded Cholesky factorisation up to this half-bandwidth:
#: the beam blocks of the auxiliary space (one Hermite fibre after another, DOFs in node order)
#: have 15, the banded factor then stores ``16 n`` numbers and a solve reads each once
BANDED_MAX_BANDWIDTH = 64


class BandedCholesky:
    """Cholesky factorisation of an SPD matrix of small bandwidth (LAPACK ``pbtrf``/``pbtrs``).

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, SPD, ``|i - j| <= bandwidth`` for every entry
    bandwidth : int
        Half-bandwidth ``k``.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``A`` is not positive definite (a non-positive pivot).

    Notes
    -----
    The factor is stored in LAPACK's lower band format, ``(k + 1, n)``. A block-diagonal matrix
    of many small banded blocks (the beams of a scene, one after the other) is one banded matrix:
    one LAPACK call factorises or solves all blocks, without a Python loop over the beams.
    """

    def __init__(self, A, bandwidth):
        A = sp.coo_matrix(A)
        n = A.shape[0]
        lower = A.row >= A.col
        # summed by np.bincount (np.add.at's unbuffered scatter took 0.1-0.2 s for the 126,000 beam DOFs
        # of fibre_cube(20, 1000, 20)); duplicates are summed in the same order
        flat = (A.row[lower] - A.col[lower]).astype(np.int64) * n + A.col[lower]
        band = np.bincount(flat, weights=A.data[lower], minlength=(bandwidth + 1) * n).reshape(bandwidth + 1, n)
        self.factor = scipy.linalg.cholesky_banded(band, lower=True, overwrite_ab=True, check_finite=False)
        self.shape = A.shape

    def solve(self, b):
        """``A⁻¹ b`` for ``b`` of shape (n,) or (n, k)."""
        return scipy.linalg.cho_solve_banded((self.factor, True), b, check_finite=False)


def bandwidth(A):
    """Half-bandwidth ``max |i - j|`` over the stored entries of a sparse matrix (0 if empty)."""
    A = sp.coo_matrix(A)
    return int(np.abs(A.row - A.col).max()) if A.nnz else 0


def factorize_spd_block(A):
    """Factorisation of an SPD matrix with a ``solve`` method: :class:`BandedCholesky` when the
    half-bandwidth is at most :data:`BANDED_MAX_BANDWIDTH`, else :func:`factorize` (SuperLU).

    On the 1000 fibres of ``fibre_cube(20, 1000, 20)`` (126,000 beam DOFs, half-bandwidth 15) the
    banded factor solved in a fraction of SuperLU's time (benchmarks/README.md, "Coupled solve
    against the solid alone"). A matrix that the banded Cholesky finds not positive definite goes
    to SuperLU as well (diagonal pivots: it fails there too if a pivot is exactly zero).
    """
    k = bandwidth(A)
    if k <= BANDED_MAX_BANDWIDTH:
        try:
            return BandedCholesky(A, k)
        except np.linalg.LinAlgError:
            pass
    return factorize(A, symmetric_positive=True)
