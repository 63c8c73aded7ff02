"""Smoothed-aggregation AMG (pyamg) for elasticity-like SPD matrices, with rigid-body modes
(:func:`~mortar1d3d.solvers.rigid.rigid_body_modes`) as near null space."""
import numpy as np
import pyamg
import scipy.sparse as sp

from ._common import check_square

__all__ = ["build_amg", "AMG_SEED", "VCycle"]

#: seed of the random start vectors of pyamg's spectral-radius estimates (repeatable set-up)
AMG_SEED = 20241125


def _block_size(n, block_size):
    if block_size is None:
        return 3 if n % 3 == 0 else 1
    if block_size not in (1, 3) or n % block_size:
        raise ValueError(f"block_size must be 1 or 3 and divide the size {n}, got {block_size}")
    return block_size


def build_amg(A, near_nullspace=None, *, block_size=None, weighting="diagonal", improve_candidates=True, theta=0.0,
              filter_entries=False):
    """Smoothed-aggregation AMG hierarchy for an SPD elasticity-like matrix.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, SPD
    near_nullspace : (n, k) array_like of float, optional
        Vectors ``A`` should map to (almost) zero, e.g. ``rigid_body_modes(...)[free]``.
        Default: the constant vector (pyamg's default; poor for elasticity).
    block_size : {None, 1, 3}
        Aggregate by DOF triplets (BSR with 3x3 blocks) when 3: right when DOFs ``3i..3i+2``
        belong to one node, i.e. Dirichlet conditions fix whole nodes. Default: 3 if ``n`` is a
        multiple of 3, else 1.
    weighting : {"diagonal", "local"}
        Damping of the Jacobi-smoothed prolongation (pyamg's ``weighting``): ``"diagonal"``
        estimates the spectral radius of ``D⁻¹A`` with a few Arnoldi/Lanczos steps, ``"local"``
        bounds it row by row (no eigenvalue estimate, a slightly more damped prolongation).
    improve_candidates : bool
        Relax the near null space before aggregating (pyamg's default, 4 symmetric block
        Gauss–Seidel sweeps per candidate vector). Rigid-body modes need no improving: without
        it the set-up of the auxiliary matrix of ``fibre_cube(n, 1000, 20)`` took 1.0 s of CPU
        instead of 1.4 s (n = 20) and 11.8 s instead of 16.8 s (n = 40), with the same CG
        iterations (20 and 33).
    theta : float
        Threshold of the symmetric strength of connection: entries below ``θ √(a_ii a_jj)`` (block
        norms for BSR) do not tie DOFs into one aggregate.
    filter_entries : bool
        Smooth the tentative prolongation with ``A`` restricted to its strong entries (pyamg's
        ``filter_entries``): sparser prolongations and coarse levels when ``θ > 0``.

    Returns
    -------
    pyamg.multilevel.MultilevelSolver
        Use ``VCycle(ml)`` (or ``ml.aspreconditioner()``) as a symmetric positive V-cycle preconditioner.

    Notes
    -----
    Settings: symmetric strength of connection (default ``θ = 0``), standard
    aggregation, Jacobi-smoothed prolongation (ω = 4/3), symmetric block Gauss–Seidel pre- and
    post-smoothing (so the V-cycle is symmetric and CG may use it), coarse levels down to
    500 unknowns solved directly. Energy-minimising prolongation was tried: fewer iterations,
    but a setup several times slower, which does not pay off in a Newton loop.
    """
    # a square BSR matrix with the blocks asked for is taken as it is (no round trip through CSR)
    ready = (sp.issparse(A) and A.format == "bsr" and A.shape[0] == A.shape[1]
             and A.blocksize == (_block_size(A.shape[0], block_size),) * 2)
    A = A if ready else check_square(A, "A")
    n = A.shape[0]
    bs = _block_size(n, block_size)
    B = None
    if near_nullspace is not None:
        B = np.ascontiguousarray(near_nullspace, dtype=np.float64)
        if B.ndim != 2 or B.shape[0] != n:
            raise ValueError(f"near_nullspace must have shape ({n}, k), got {B.shape}")
    matrix = A if ready else A.tobsr(blocksize=(bs, bs)) if bs > 1 else A
    # pyamg starts its spectral-radius estimate (weighting="diagonal") from numpy's global random
    # generator: the hierarchy, and the iteration counts, changed from one process to the next.
    # A fixed seed makes the set-up repeatable; the caller's random stream is put back afterwards.
    state = np.random.get_state()
    try:
        np.random.seed(AMG_SEED)
        return pyamg.smoothed_aggregation_solver(
            matrix, B=B, symmetry="hermitian", strength=("symmetric", {"theta": theta}),
            **({} if improve_candidates else dict(improve_candidates=None)),
            smooth=("jacobi", {"omega": 4.0 / 3.0, "weighting": weighting,
                                             "filter_entries": filter_entries}), max_coarse=500, coarse_solver="splu")
    finally:
        np.random.set_state(state)


class VCycle:
    """One V-cycle of a pyamg hierarchy from a zero start, as a preconditioner (``matvec``).

    The same cycle as ``ml.aspreconditioner(cycle="V")`` (pre-smoothing, residual, restriction, the
    coarser levels, correction, post-smoothing; the coarsest level by the hierarchy's coarse
    solver) and the same result bit for bit, without what pyamg's ``solve`` adds around the cycle:
    the norms of the right-hand side and of the residual before and after it, and the two products
    with the finest matrix those residuals need, whose values a single cycle discards. On
    ``fibre_cube(20, 1000, 20)`` the three norms were threaded BLAS ``ddot`` calls of about 7 ms each
    at a load of 4 (benchmarks/README.md, "The solve after the set-up").

    Parameters
    ----------
    ml : pyamg.multilevel.MultilevelSolver
    """

    def __init__(self, ml):
        self.ml = ml
        self.levels = ml.levels
        self.shape = ml.levels[0].A.shape
        self.dtype = ml.levels[0].A.dtype

    def matvec(self, b):
        """``V b``: one V-cycle for ``A x = b`` from ``x = 0``."""
        b = np.ravel(np.asarray(b, dtype=self.dtype))
        if len(self.levels) == 1:
            return np.ravel(self.ml.coarse_solver(self.levels[0].A, b))
        x = np.zeros_like(b)
        self._cycle(0, x, b)
        return x

    __call__ = matvec

    def _cycle(self, lvl, x, b):
        level = self.levels[lvl]
        level.presmoother(level.A, x, b)
        coarse_b = level.R @ (b - level.A @ x)
        if lvl == len(self.levels) - 2:
            coarse_x = np.ravel(self.ml.coarse_solver(self.levels[-1].A, coarse_b))
        else:
            coarse_x = np.zeros_like(coarse_b)
            self._cycle(lvl + 1, coarse_x, coarse_b)
        x += level.P @ coarse_x
        level.postsmoother(level.A, x, b)
