"""Linear solvers for the systems of one Newton iteration (design.md §1, "Enforcement").

Two kinds of systems arise, both on the free DOFs only (Dirichlet DOFs are eliminated by the
caller), ordered ``[d_S; d_B]`` (solid first):

- **penalty**: ``A x = b`` with ``A = K + ε Bᵀ diag(κ⁻¹) B`` symmetric positive definite:
  :func:`solve_linear` (sparse direct, or conjugate gradients with smoothed-aggregation AMG, or
  with the auxiliary-space preconditioner :class:`AuxiliarySpacePreconditioner` that stays
  robust at large penalties).
- **Lagrange multipliers**: the saddle point ``[[K, Bᵀ], [B, 0]] [x; λ] = [b; c]``:
  :func:`solve_saddle` (sparse direct, or MINRES with an augmented-Lagrangian block
  preconditioner: AMG on the solid, a sparse factorisation on the beams, ``κ/γ`` for ``λ``).

:func:`rigid_body_modes` gives the near null space that AMG needs for elasticity, and
:func:`build_amg` the AMG hierarchy, which a Newton loop may build once and pass to
:func:`solve_linear` as ``preconditioner`` while the stiffness changes little.

Everything here works on ``scipy.sparse`` matrices; the heavy lifting is in SuperLU (scipy) and
pyamg, so there is no Numba kernel in this module.
"""
import time
import warnings
from dataclasses import dataclass

import numpy as np
import pyamg
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from ..errors import CouplingWarning, format_ids

__all__ = ["LinearSolverError", "rigid_body_modes", "build_amg", "AuxiliarySpacePreconditioner",
           "solve_linear", "solve_saddle", "dependent_rows", "DependentRows",
           "DIRECT_MAX_DOFS", "SADDLE_DIRECT_MAX_DOFS", "AUGMENTATION_FACTOR", "AUXILIARY_AUGMENTATION_FACTOR"]

#: ``method="auto"`` of :func:`solve_linear` factorises systems up to this many unknowns and
#: uses AMG + CG above. Measured on hex8 elasticity + a penalty-coupled chain (2 cores, loaded):
#: direct / AMG seconds 0.05 / 0.18 (1.4k DOF), 0.29 / 0.33 (2.7k), 0.56 / 0.47 (3.6k),
#: 2.1 / 0.74 (6.1k), 32 / 6.9 (26k), 151 / 11.5 (51k): SuperLU fill grows fast in 3D.
DIRECT_MAX_DOFS = 3_000

#: ``method="auto"`` of :func:`solve_saddle`: direct up to this many unknowns (primal + λ).
#: The same crossover as above (λ adds few unknowns; MINRES needs 2-3x the CG iterations
#: but the indefinite factorisation pivots), not measured separately.
SADDLE_DIRECT_MAX_DOFS = 3_000

#: default ``γ = AUGMENTATION_FACTOR * (stiffness scale of the solid)`` of the block preconditioner
#: with an AMG V-cycle on the augmented stiffness (see :func:`solve_saddle`)
AUGMENTATION_FACTOR = 0.3

#: default ``γ = AUXILIARY_AUGMENTATION_FACTOR * (stiffness scale of all coupled DOFs)`` of the
#: block preconditioner with the auxiliary-space preconditioner on the augmented stiffness
AUXILIARY_AUGMENTATION_FACTOR = 10.0

#: restarts of the Krylov method when its own (recursive or preconditioned) residual claims
#: convergence but the true residual does not meet ``rtol`` yet
_MAX_RESTARTS = 4


class LinearSolverError(RuntimeError):
    """A linear solve failed: the message says what was reached and what to try."""


# --------------------------------------------------------------------------- near null space

def rigid_body_modes(points, tangent_mask=None):
    """The six rigid-body modes of a set of DOF triplets (three translations, three rotations).

    Parameters
    ----------
    points : (n_triplets, 3) array_like of float
        For each DOF triplet ``3*i .. 3*i+2``: the coordinates of the point it moves (a solid
        node, a beam node's position) or, where ``tangent_mask`` is True, the tangent vector
        itself (a Hermite beam node's tangent triplet).
    tangent_mask : (n_triplets,) array_like of bool, optional
        True for tangent triplets. Default: all triplets are positions.

    Returns
    -------
    R : (3*n_triplets, 6) ndarray of float64
        Columns: translations along x, y, z, then rotations about x, y, z.

    Notes
    -----
    A rigid motion ``u(x) = a + ω × x`` moves a position triplet by ``a + ω × x`` and turns a
    tangent by ``ω × t`` (a translation does not change a tangent). The rotations are taken
    about the centroid of the position triplets: the span is the same as about the origin, but
    the columns are better scaled for far-away models (AMG orthonormalises them per aggregate).
    Select the rows of the free DOFs, ``R[free]``, after eliminating Dirichlet DOFs.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n_triplets, 3), got {points.shape}")
    n = len(points)
    if tangent_mask is None:
        tangent = np.zeros(n, dtype=bool)
    else:
        tangent = np.asarray(tangent_mask, dtype=bool)
        if tangent.shape != (n,):
            raise ValueError(f"tangent_mask must have shape ({n},), got {tangent.shape}")
    position = ~tangent
    arm = points.copy()
    if position.any():
        arm[position] -= points[position].mean(axis=0)
    R = np.zeros((n, 3, 6))
    for i in range(3):
        R[position, i, i] = 1.0
    x, y, z = arm.T
    # ω × x for ω = e_x, e_y, e_z
    R[:, 1, 3], R[:, 2, 3] = -z, y
    R[:, 0, 4], R[:, 2, 4] = z, -x
    R[:, 0, 5], R[:, 1, 5] = -y, x
    return R.reshape(3 * n, 6)


# --------------------------------------------------------------------------- building blocks

def _check_square(A, name):
    if not sp.issparse(A):
        raise TypeError(f"{name} must be a scipy.sparse matrix, got {type(A).__name__}")
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be square, got shape {A.shape}")
    return A.tocsr()


def _check_vector(v, n, name):
    v = np.asarray(v, dtype=np.float64)
    if v.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {v.shape}")
    return v


def _factorize(A, symmetric_positive, saddle=False):
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


def _block_size(n, block_size):
    if block_size is None:
        return 3 if n % 3 == 0 else 1
    if block_size not in (1, 3) or n % block_size:
        raise ValueError(f"block_size must be 1 or 3 and divide the size {n}, got {block_size}")
    return block_size


def build_amg(A, near_nullspace=None, *, block_size=None, weighting="diagonal"):
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

    Returns
    -------
    pyamg.multilevel.MultilevelSolver
        Use ``ml.aspreconditioner()`` as a symmetric positive V-cycle preconditioner.

    Notes
    -----
    Settings: symmetric strength of connection with ``θ = 0`` (block norms for BSR), standard
    aggregation, Jacobi-smoothed prolongation (ω = 4/3), symmetric block Gauss–Seidel pre- and
    post-smoothing (so the V-cycle is symmetric and CG may use it), coarse levels down to
    500 unknowns solved directly. Energy-minimising prolongation was tried: fewer iterations,
    but a setup several times slower, which does not pay off in a Newton loop.
    """
    A = _check_square(A, "A")
    n = A.shape[0]
    bs = _block_size(n, block_size)
    B = None
    if near_nullspace is not None:
        B = np.ascontiguousarray(near_nullspace, dtype=np.float64)
        if B.ndim != 2 or B.shape[0] != n:
            raise ValueError(f"near_nullspace must have shape ({n}, k), got {B.shape}")
    matrix = A.tobsr(blocksize=(bs, bs)) if bs > 1 else A
    return pyamg.smoothed_aggregation_solver(
        matrix, B=B, symmetry="hermitian", strength=("symmetric", {"theta": 0.0}),
        smooth=("jacobi", {"omega": 4.0 / 3.0, "weighting": weighting}), max_coarse=500, coarse_solver="splu")


class AuxiliarySpacePreconditioner:
    """Preconditioner for the penalty system of beams coupled to a solid, robust in ε.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, SPD
        ``K + ε Bᵀ κ⁻¹ B`` on the free DOFs.
    solid, beam : (n_s,), (n_b,) array_like of int
        Which free DOFs are solid and which are beam (a partition of ``0..n-1``).
    prolongation : (n_b, n_s) scipy.sparse matrix
        ``P``: beam DOFs that follow a solid displacement, ``D P ≈ M`` (e.g.
        :func:`mortar1d3d.physics.coupling.follow_operator` restricted to the free DOFs).
    near_nullspace : (n_s, k) array_like, optional
        Rigid-body modes of the solid DOFs, for the AMG of the auxiliary matrix.
    block_size : {None, 1, 3}
        AMG aggregation of the auxiliary (solid) matrix, see :func:`build_amg`.

    Attributes
    ----------
    auxiliary : scipy.sparse.csr_matrix, (n_s, n_s)
        ``A_aux = Eᵀ A E`` with ``E = [I; P]`` (solid rows, then beam rows).
    amg : pyamg.multilevel.MultilevelSolver
        Hierarchy of ``A_aux``.
    setup_time : float
        Seconds to build all of the above and factorise the beam block.

    Notes
    -----
    With a large penalty ε the low-energy motions of ``A`` are those where the beams follow the
    solid, ``D d_B ≈ M d_S``: a coupled mode of solid and beam DOFs that smoothed aggregation
    on ``A`` (aggregates of nearby DOFs, rigid-body modes as near null space) cannot represent,
    so CG needed 600-800 iterations at ε = 1e3 E. Here the space is split as
    ``[d_S; d_B] = E d_S + [0; d_B − P d_S]``:

    - the *auxiliary space* ``range(E)``: solid motions with the beams following. Its matrix
      ``A_aux = K_SS + Pᵀ K_BB P + ε (M − D P)ᵀ κ⁻¹ (M − D P)`` is the solid stiffened by the
      beams it carries, an elasticity-like matrix with the solid's rigid-body modes, solved by
      one AMG V-cycle;
    - the *beam space* ``[0; y]``: ``A_BB = K_BB + ε Dᵀκ⁻¹D``, block-diagonal per beam, factorised
      exactly.

    Because ``P`` keeps the gap of ``E d_S`` small, the coupling between the two spaces is of
    the order of the beam stiffness, not of ε. One application is the symmetric multiplicative
    Schwarz sweep beam → auxiliary → beam (symmetric and positive definite, so CG applies).
    Measured on ``fibre_cube(n, 1000, 20)`` at ε = 1e3 E, rtol 1e-8 (benchmarks/penalty_solve.py):
    14, 20, 33 CG iterations for n = 10, 20, 40, against 608-783 for AMG on ``A`` (n = 10, 20).
    The additive variant (both corrections from the same residual) saves one product with ``A``
    per application but needed 16/24 iterations against 14/19 (n = 10/20). At a small penalty
    (ε ~ 10 E) plain AMG is the better choice (medium test problem: 19 against 28 iterations),
    but the auxiliary space stays bounded as ε grows (18 iterations at ε = 1e3 and 1e4 E where
    plain AMG needs 103 and 319).
    """

    def __init__(self, A, solid, beam, prolongation, near_nullspace=None, *, block_size=None):
        start = time.perf_counter()
        A = _check_square(A, "A")
        n = A.shape[0]
        self.solid, self.beam = _split(n, solid, beam)
        n_s, n_b = len(self.solid), len(self.beam)
        if n_s == 0 or n_b == 0:
            raise ValueError("the auxiliary-space preconditioner needs both solid and beam DOFs; "
                             "use build_amg for a system of one kind")
        if not sp.issparse(prolongation) or prolongation.shape != (n_b, n_s):
            raise ValueError(f"prolongation must be a scipy.sparse matrix of shape ({n_b}, {n_s}) "
                             f"(beam DOFs x solid DOFs), got {getattr(prolongation, 'shape', None)}")
        P = prolongation.tocsr()
        self.A = A
        self.shape = A.shape
        self.A_beam_rows = A[self.beam].tocsr()                 # rows of the beam DOFs
        self.A_beam_cols = self.A_beam_rows.T.tocsr()            # A is symmetric
        A_solid_rows = A[self.solid].tocsr()
        A_sb = A_solid_rows[:, self.beam]
        A_bb = self.A_beam_rows[:, self.beam].tocsc()
        # Eᵀ A E with E = [I; P], without forming E
        cross = (A_sb @ P).tocsr()
        self.auxiliary = (A_solid_rows[:, self.solid] + cross + cross.T + P.T @ (A_bb @ P)).tocsr()
        self.prolongation = P
        self._restriction = P.T.tocsr()
        null = None if near_nullspace is None else np.asarray(near_nullspace, dtype=np.float64)
        if null is not None and null.shape[0] != n_s:
            raise ValueError(f"near_nullspace must have one row per solid DOF ({n_s}), got {null.shape}")
        # "local" weighting: the spectral-radius estimate of the default took up to a third of the AMG
        # setup of fibre_cube(40) (CPU 14-18 s against 12.4 s, loaded machine), same 33 CG iterations
        self.amg = build_amg(self.auxiliary, null, block_size=block_size, weighting="local")
        self._cycle = self.amg.aspreconditioner(cycle="V")
        self._beam_lu = _factorize(A_bb, symmetric_positive=True)
        self.setup_time = time.perf_counter() - start

    @property
    def levels(self):
        """AMG levels of the auxiliary matrix."""
        return len(self.amg.levels)

    def matvec(self, r):
        """One symmetric sweep: beam block, auxiliary space, beam block."""
        x = np.zeros_like(r)
        x_b = self._beam_lu.solve(r[self.beam])
        x[self.beam] = x_b
        residual = r - self.A_beam_cols @ x_b
        z = self._cycle.matvec(residual[self.solid] + self._restriction @ residual[self.beam])
        x[self.solid] += z
        x[self.beam] += self.prolongation @ z
        x[self.beam] += self._beam_lu.solve(r[self.beam] - self.A_beam_rows @ x)
        return x


# --------------------------------------------------------------------------- Krylov methods

def _cg(A, b, x, apply_preconditioner, reduction, maxiter):
    """Preconditioned conjugate gradients from ``x``.

    Stops when the recursive residual norm has dropped by ``reduction`` relative to the
    starting residual. Returns ``(x, iterations, status)``, status ``"tolerance"``,
    ``"maxiter"`` or ``"breakdown"`` (``pᵀAp <= 0`` or ``rᵀz <= 0``: ``A`` or the
    preconditioner is not positive definite, CG cannot go on).
    """
    r = b - A @ x
    target = reduction * np.linalg.norm(r)
    z = apply_preconditioner(r)
    p = z.copy()
    rz = r @ z
    if not rz > 0:
        return x, 0, "breakdown"
    for it in range(1, maxiter + 1):
        q = A @ p
        pq = p @ q
        if not pq > 0:
            return x, it, "breakdown"
        alpha = rz / pq
        x += alpha * p
        r -= alpha * q
        if np.linalg.norm(r) <= target:
            return x, it, "tolerance"
        z = apply_preconditioner(r)
        rz_new = r @ z
        if not rz_new > 0:
            return x, it, "breakdown"
        p *= rz_new / rz
        p += z
        rz = rz_new
    return x, maxiter, "maxiter"


def _minres(A, b, x, apply_preconditioner, reduction, maxiter):
    """Preconditioned MINRES (symmetric ``A``, SPD preconditioner ``P``) from ``x``.

    Stops when the preconditioned residual norm ``‖r‖_{P⁻¹}`` has dropped by ``reduction``.
    Returns ``(x, iterations, status)`` as :func:`_cg` (breakdown: the preconditioner is not
    positive definite, or the Lanczos process cannot continue).

    Notes
    -----
    Lanczos in the ``P⁻¹`` inner product plus Givens QR of the tridiagonal matrix, after
    Elman, Silvester & Wathen, *Finite Elements and Fast Iterative Solvers* (2014), the
    preconditioned MINRES algorithm; ``|η|`` is ``‖r_j‖_{P⁻¹}``.
    """
    v = b - A @ x
    z = apply_preconditioner(v)
    vz = v @ z
    if vz < 0:
        return x, 0, "breakdown"
    gamma = np.sqrt(vz)
    if gamma == 0.0:
        return x, 0, "tolerance"
    target = reduction * gamma
    eta = gamma
    v_old = np.zeros_like(v)
    w = np.zeros_like(v)
    w_old = np.zeros_like(v)
    gamma_old = 1.0
    c_old = c = 1.0
    s_old = s = 0.0
    for it in range(1, maxiter + 1):
        z /= gamma
        Az = A @ z
        delta = Az @ z
        v_new = Az - (delta / gamma) * v - (gamma / gamma_old) * v_old
        z_new = apply_preconditioner(v_new)
        vz = v_new @ z_new
        if vz < 0:       # preconditioner not positive definite
            return x, it, "breakdown"
        gamma_new = np.sqrt(vz)
        a0 = c * delta - c_old * s * gamma
        a1 = np.hypot(a0, gamma_new)
        a2 = s * delta + c_old * c * gamma
        a3 = s_old * gamma
        if a1 == 0.0:
            return x, it, "breakdown"
        c_old, s_old = c, s
        c, s = a0 / a1, gamma_new / a1
        w_new = (z - a3 * w_old - a2 * w) / a1
        x += (c * eta) * w_new
        eta = -s * eta
        if abs(eta) <= target or gamma_new == 0.0:
            return x, it, "tolerance"
        v_old, v = v, v_new
        z = z_new
        w_old, w = w, w_new
        gamma_old, gamma = gamma, gamma_new
    return x, maxiter, "maxiter"


def _roundoff(A, y, rhs, scale=None):
    """Relative round-off level of the residual ``‖scale (rhs − A y)‖ / ‖scale rhs‖``.

    Entry i of ``A y`` sums ``k_i`` products (the stored entries of row i); their rounding
    errors accumulate like ``sqrt(k_i) eps (|A| |y|)_i`` (the statistical estimate; ``k_i eps``
    is the worst case), and subtracting from ``rhs`` adds ``eps |rhs_i|``. Measured on
    penalty-coupled fibre cubes (15k-130k unknowns): this level is 6-26x
    ``eps ‖|A||y|‖ / ‖rhs‖``, SuperLU's own residual 0.4-1.9x and stalled CG 0.5-2.7x that.
    """
    eps = np.finfo(float).eps
    A = A.tocsr()
    level = eps * (np.sqrt(np.diff(A.indptr)) * (abs(A) @ np.abs(y)) + np.abs(rhs))
    if scale is not None:
        level, rhs = scale * level, scale * rhs
    norm = np.linalg.norm(rhs)
    return float(np.linalg.norm(level) / norm) if norm > 0 else 0.0


def _krylov(kind, A, rhs, x, apply_preconditioner, rtol, maxiter, residual, floor):
    """Run CG or MINRES until ``residual(x) <= rtol`` (the caller's true relative residual).

    The Krylov method's own stopping test uses a recursive or a preconditioned residual, which
    can differ from the true one; if it stops early, restart from ``x`` asking for the missing
    reduction (halved for safety), at most ``_MAX_RESTARTS`` times. A run that no longer
    halves the true residual while that is at or below ``floor(x)`` (its round-off level,
    :func:`_roundoff`) has stalled at round-off: the residual cannot fall further, which is
    success too, even when ``rtol`` asked for less.
    Returns ``(x, iterations, residual, status)``, status ``"converged"``, ``"roundoff"``
    (stalled at the round-off level above ``rtol``), ``"breakdown"`` (see :func:`_cg`) or
    ``"maxiter"``.
    """
    method = _cg if kind == "cg" else _minres
    total = 0
    res = residual(x)
    for _ in range(_MAX_RESTARTS + 1):
        if res <= rtol:
            return x, total, res, "converged"
        reduction = rtol / res if total == 0 else 0.5 * rtol / res
        previous = res
        x, it, status = method(A, rhs, x, apply_preconditioner, reduction, maxiter - total)
        total += it
        res = residual(x)
        if rtol < res <= floor(x) and (res > 0.5 * previous or status != "tolerance" or total >= maxiter):
            return x, total, res, "roundoff"
        if res > rtol and (status != "tolerance" or total >= maxiter):
            return x, total, res, "breakdown" if status == "breakdown" else "maxiter"
    if res <= rtol:
        return x, total, res, "converged"
    return x, total, res, "roundoff" if res <= floor(x) else "maxiter"


def _raise_not_converged(what, info, hints):
    raise LinearSolverError(
        f"{what} did not converge: relative residual {info['residual']:.3e} after "
        f"{info['iterations']} iterations (rtol {info['rtol']:.1e}, maxiter {info['maxiter']}). "
        f"Try: {hints}")


# --------------------------------------------------------------------------- SPD systems

def solve_linear(A, b, method="auto", *, near_nullspace=None, rtol=1e-10, maxiter=500, x0=None,
                 preconditioner=None, block_size=None, solid=None, beam=None, prolongation=None):
    """Solve the SPD system ``A x = b`` (penalty coupling, linear elasticity).

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, symmetric positive definite
    b : (n,) array_like of float
    method : {"auto", "direct", "amg", "aux"}
        ``"direct"``: SuperLU (:func:`scipy.sparse.linalg.splu`) with a symmetric minimum-degree
        ordering and diagonal pivoting (see Notes). ``"amg"``: conjugate gradients
        preconditioned by one V-cycle of smoothed-aggregation AMG (:func:`build_amg`).
        ``"aux"``: conjugate gradients preconditioned by :class:`AuxiliarySpacePreconditioner`
        (needs ``solid``, ``beam``, ``prolongation``): for beams penalty-coupled to a solid,
        where plain AMG degrades as ε grows. ``"auto"``: direct up to :data:`DIRECT_MAX_DOFS`
        unknowns, above it ``"aux"`` when ``prolongation`` is given, else ``"amg"``.
    near_nullspace : (n, k) array_like, optional
        For AMG: rigid-body modes of the free DOFs (:func:`rigid_body_modes`). Without them AMG
        on elasticity needs several times more iterations. For ``"aux"``: the rows of all free
        DOFs (the solid rows are used).
    rtol : float
        Relative residual ``‖b - A x‖ / ‖b‖`` to reach (iterative methods).
    maxiter : int
        Maximum CG iterations.
    x0 : (n,) array_like, optional
        Start vector of CG (e.g. the previous Newton correction). Ignored by ``"direct"``.
    preconditioner : pyamg MultilevelSolver or AuxiliarySpacePreconditioner, optional
        A hierarchy from :func:`build_amg` (implies ``method="amg"``) or an auxiliary-space
        preconditioner (implies ``method="aux"``) to reuse; it may have been built for an
        earlier, similar ``A``.
    block_size : {None, 1, 3}
        AMG aggregation by DOF triplets, see :func:`build_amg`.
    solid, beam : (n_s,), (n_b,) array_like of int, optional
        ``"aux"``: which free DOFs are solid and which are beam (a partition of ``0..n-1``).
    prolongation : (n_b, n_s) scipy.sparse matrix, optional
        ``"aux"``: beam DOFs following the solid, see :class:`AuxiliarySpacePreconditioner`.

    Returns
    -------
    x : (n,) ndarray of float64
    info : dict
        ``method`` ("direct", "amg" or "aux"), ``iterations`` (0 for direct), ``residual`` (true
        relative residual ``‖b - A x‖/‖b‖``), ``setup_time`` and ``solve_time`` (seconds:
        factorisation / AMG setup, then substitution / CG), ``converged``, ``rtol``, ``maxiter``;
        iterative methods add ``status`` (``"converged"``, or ``"roundoff"``: the residual
        stalled at its round-off level above ``rtol``, which counts as converged), and after a
        breakdown of CG ``breakdown_iteration``, ``fallback`` (``"minres"`` or ``"direct"``)
        and ``note`` (one line saying what happened, for logs).

    Raises
    ------
    LinearSolverError
        If CG does not reach ``rtol`` (or stall at the round-off level) within ``maxiter``
        iterations.

    Notes
    -----
    Direct: scipy offers no sparse Cholesky, so SuperLU it is; for SPD matrices the fill is
    that of a symmetric ordering when pivots stay on the diagonal, which is safe for SPD. CG
    stops on its recursive residual and then checks the true one (restarting if needed). A
    true residual that stalls at its round-off level (about ``sqrt(k) eps ‖|A||x|‖ / ‖b‖``
    with ``k`` entries per row, see ``_roundoff``) cannot fall further: CG stopping there has
    converged, whatever ``rtol`` asked for. If CG breaks down (``pᵀAp <= 0``: ``A`` is not
    positive definite, e.g. the tangent of a nearly incompressible solid in tension), MINRES
    with the same preconditioner takes over, and a sparse LU with partial pivoting if that
    fails too.
    """
    A = _check_square(A, "A")
    n = A.shape[0]
    b = _check_vector(b, n, "b")
    if preconditioner is not None:
        method = "aux" if isinstance(preconditioner, AuxiliarySpacePreconditioner) else "amg"
    if method == "auto":
        method = "direct" if n <= DIRECT_MAX_DOFS else ("amg" if prolongation is None else "aux")
    if method not in ("direct", "amg", "aux"):
        raise ValueError(f"method must be 'auto', 'direct', 'amg' or 'aux', got {method!r}")
    if method == "aux" and preconditioner is None and (prolongation is None or solid is None or beam is None):
        raise ValueError("method 'aux' needs solid, beam and prolongation (see AuxiliarySpacePreconditioner)")
    bnorm = np.linalg.norm(b)
    info = dict(method=method, iterations=0, residual=0.0, setup_time=0.0, solve_time=0.0,
                converged=True, rtol=rtol, maxiter=maxiter)
    if bnorm == 0.0:
        return np.zeros(n), info

    def residual(x):
        return np.linalg.norm(b - A @ x) / bnorm

    if method == "direct":
        t = time.perf_counter()
        lu = _factorize(A, symmetric_positive=True)
        info["setup_time"] = time.perf_counter() - t
        t = time.perf_counter()
        x = lu.solve(b)
        info["solve_time"] = time.perf_counter() - t
        info["residual"] = residual(x)
        return x, info

    t = time.perf_counter()
    if method == "aux":
        if preconditioner is None:
            solid, beam = _split(n, solid, beam)
            null = None
            if near_nullspace is not None:
                null = np.asarray(near_nullspace, dtype=np.float64)
                if null.ndim != 2 or null.shape[0] != n:
                    raise ValueError(f"near_nullspace must have shape ({n}, k), got {null.shape}")
                null = null[solid]
            preconditioner = AuxiliarySpacePreconditioner(A, solid, beam, prolongation, null,
                                                          block_size=block_size)
        M = preconditioner
        info["amg_levels"] = preconditioner.levels
    else:
        ml = preconditioner if preconditioner is not None else build_amg(A, near_nullspace, block_size=block_size)
        M = ml.aspreconditioner(cycle="V")
        info["amg_levels"] = len(ml.levels)
    info["setup_time"] = time.perf_counter() - t
    t = time.perf_counter()
    x = np.zeros(n) if x0 is None else _check_vector(x0, n, "x0").copy()

    def floor(y):
        return _roundoff(A, y, b)

    x, info["iterations"], info["residual"], status = _krylov("cg", A, b, x, M.matvec, rtol, maxiter, residual, floor)
    name = "auxiliary-space-preconditioned CG" if method == "aux" else "AMG-preconditioned CG"
    if status == "breakdown":
        # CG needs A and its preconditioner positive definite; a tangent past a limit point or of a
        # material outside its convex range (neo-Hooke with λ ln J > μ) is not. MINRES takes
        # symmetric indefinite matrices (with the same preconditioner while that stays positive),
        # a factorisation with partial pivoting anything nonsingular.
        cg_iterations = info["iterations"]
        y, it, res, status = _krylov("minres", A, b, np.zeros(n), M.matvec, rtol, maxiter, residual, floor)
        info["iterations"] += it
        info["breakdown_iteration"] = cg_iterations
        note = f"{name} broke down (matrix or preconditioner not positive definite), "
        if status in ("converged", "roundoff"):
            x, info["residual"], info["fallback"] = y, res, "minres"
            note += "MINRES took over"
        else:
            lu = _factorize(A, symmetric_positive=False)
            x = lu.solve(b)
            info["residual"], info["fallback"] = residual(x), "direct"
            status = "converged" if info["residual"] <= max(rtol, floor(x)) else "breakdown"
            note += "MINRES failed too, sparse LU took over"
        info["note"] = note
    info["solve_time"] = time.perf_counter() - t
    info["status"] = status
    info["converged"] = status in ("converged", "roundoff")
    if not info["converged"]:
        _raise_not_converged(name, info,
                             "pass near_nullspace=rigid_body_modes(...)[free] if you did not, raise maxiter, "
                             "check that A is symmetric positive definite (enough Dirichlet conditions, every "
                             "beam held), or use method='direct'")
    return x, info


# --------------------------------------------------------------------------- dependent constraint rows

#: rows of ``B`` count as dependent when a combination of them with unit coefficient norm (rows
#: and columns first scaled to unit size) is shorter than this: the multipliers of such rows
#: would carry less than half of the working digits (their error grows like eps / length),
#: while dropping one leaves a constraint violation of at most this relative size
DEPENDENT_ROW_TOLERANCE = float(np.sqrt(np.finfo(float).eps))


@dataclass
class DependentRows:
    """Rows of a constraint matrix ``B`` that depend on the others (see :func:`dependent_rows`).

    Attributes
    ----------
    rows : (d,) ndarray of int64
        The dependent rows (ids of rows of ``B``, sorted); the other rows are independent.
    combinations : (d, m) scipy.sparse.csr_matrix
        A basis of the left null space of ``B`` (``combinations @ B ≈ 0``); row k has
        coefficient 1 at ``rows[k]`` and 0 at the other dependent rows.
    n_rows : int
        ``m``, the number of rows of ``B``.
    """

    rows: np.ndarray
    combinations: object
    n_rows: int

    def __len__(self):
        return len(self.rows)

    def least_norm(self, lam, weight):
        """``lam`` plus the null-space combination that minimises ``Σ weight λ²``.

        ``Bᵀλ``, the forces the multipliers transfer, is unchanged; of all multipliers that
        transfer them this is the one of least weighted norm, so the answer does not depend on
        which of the dependent rows were dropped.
        """
        if not len(self):
            return lam
        C = self.combinations
        Cw = (C @ sp.diags(weight)).tocsr()
        y = spla.spsolve((Cw @ C.T).tocsc(), Cw @ lam)
        return lam - C.T @ np.atleast_1d(y)


def _components(A):
    """Connected-component label of every row of ``A`` (rows are connected by shared columns)."""
    pattern = A.tocsr(copy=True)
    pattern.data = np.ones_like(pattern.data)
    return connected_components(pattern @ pattern.T, directed=False)[1]


def _groups(label):
    order = np.argsort(label, kind="stable")
    return np.split(order, np.flatnonzero(np.diff(label[order])) + 1)


def _row_rank(A, tolerance):
    """Rank of the rows of the dense ``A``, pivot order and ``R`` of a column-pivoted QR of ``Aᵀ``."""
    R, piv = sla.qr(A.T, mode="r", pivoting=True)
    diag = np.abs(np.diag(R))
    return int(np.count_nonzero(diag > tolerance)), piv, R


def dependent_rows(B, beam=None, *, tolerance=DEPENDENT_ROW_TOLERANCE):
    """Rows of a mortar constraint matrix that are (numerically) combinations of the others.

    Parameters
    ----------
    B : (m, n) scipy.sparse matrix
        Constraint rows ``[-M, D]`` on the free DOF columns. Empty rows (all their columns
        eliminated) constrain nothing and are left out.
    beam : (n_b,) array_like of int, optional
        The beam DOF columns (the ``D`` part); default none (every column a solid DOF).
    tolerance : float
        See :data:`DEPENDENT_ROW_TOLERANCE`.

    Returns
    -------
    DependentRows

    Notes
    -----
    A dense rank decision on all of ``B`` would cost ``O(m² n)``; the structure makes it local.
    Columns are scaled to unit largest entry and then rows to unit length, so that neither the
    units of tangent DOFs nor short LM supports sway the decision. Rows are grouped by the beam
    columns they share (one group per beam and component: x, y and z rows never share a
    column) and a column-pivoted QR of each group's rows finds the dependent ones. Rows of
    different groups can only depend on each other through combinations whose beam part
    vanishes, i.e. through the left null space ``Z`` of each group's beam block (usually empty:
    ``D`` has full row rank unless the multiplier space is richer than the centreline or
    Dirichlet conditions removed beam columns). The rows ``Zᵀ M`` of all groups, grouped again
    by the solid columns they share, are tested the same way; a pivoted QR of the dependent
    combinations then chooses the rows to drop so that the remaining ones are independent.
    """
    B = B.tocsr()
    m, n = B.shape
    if B.nnz == 0:
        return DependentRows(np.zeros(0, np.int64), sp.csr_matrix((0, m)), m)
    is_beam = np.zeros(n, dtype=bool)
    if beam is not None:
        is_beam[np.asarray(beam, dtype=np.int64)] = True
    column = np.asarray(abs(B).max(axis=0).todense()).ravel()
    column[column == 0] = 1.0
    Bn = (B @ sp.diags(1.0 / column)).tocsr()
    length = np.sqrt(np.asarray(Bn.multiply(Bn).sum(axis=1)).ravel())
    # empty rows constrain nothing (no multiplier): they are neither dependent nor independent
    scale = np.divide(1.0, length, out=np.zeros(m), where=length > 0)
    Bn = (sp.diags(scale) @ Bn).tocsr()
    Bn.eliminate_zeros()
    dropped, combos = [], []        # combos: (rows, coefficients) of scaled rows
    stage2 = []                     # per group: kept rows, Z, Zᵀ M (dense), its solid columns
    label = _components(Bn[:, is_beam])
    label[length == 0] = -1
    for rows in _groups(label):
        if length[rows[0]] == 0:
            continue
        block = Bn[rows]
        cols = np.unique(block.indices)
        dense = block[:, cols].toarray()
        rank, piv, R = _row_rank(dense, tolerance)
        if rank < len(rows):
            # each dependent pivot row in terms of the first `rank` ones: [-R11⁻¹ R12; I]
            top = -sla.solve_triangular(R[:rank, :rank], R[:rank, rank:len(rows)]) if rank else \
                np.zeros((0, len(rows)))
            for k in range(len(rows) - rank):
                dropped.append(rows[piv[rank + k]])
                combos.append((rows[np.append(piv[:rank], piv[rank + k])], np.append(top[:, k], 1.0)))
        kept = dense[piv[:rank]]
        on_beam = is_beam[cols]
        if on_beam.any():
            U, s, _ = np.linalg.svd(kept[:, on_beam], full_matrices=True)
            Z = U[:, int(np.count_nonzero(s > tolerance)):]
        else:
            Z = np.eye(rank)
        if Z.shape[1]:
            stage2.append((rows[piv[:rank]], Z, Z.T @ kept[:, ~on_beam], cols[~on_beam]))
    if stage2:
        parts = []
        for _, Z, solid, cols in stage2:
            k, c = solid.shape
            parts.append(sp.csr_matrix((solid.ravel(), (np.repeat(np.arange(k), c), np.tile(cols, k))), shape=(k, n)))
        T = sp.vstack(parts, format="csr")
        owner = np.concatenate([np.full(Z.shape[1], i) for i, (_, Z, _, _) in enumerate(stage2)])
        betas = []                  # dependent combinations of rows of T
        for t_rows in _groups(_components(T)):
            block = T[t_rows]
            cols = np.unique(block.indices)
            if len(cols) == 0:
                beta = np.eye(len(t_rows))
            else:
                rank, piv, R = _row_rank(block[:, cols].toarray(), tolerance)
                if rank == len(t_rows):
                    continue
                beta = np.zeros((len(t_rows), len(t_rows) - rank))
                if rank:
                    beta[piv[:rank]] = -sla.solve_triangular(R[:rank, :rank], R[:rank, rank:len(t_rows)])
                beta[piv[rank:]] = np.eye(len(t_rows) - rank)
            full = np.zeros((len(T.indptr) - 1, beta.shape[1]))
            full[t_rows] = beta
            betas.append(full)
        if betas:
            beta = np.hstack(betas)
            # the combinations over the kept rows of the groups involved: α = Z β, group by group
            involved = np.unique(owner[np.any(beta != 0, axis=1)])
            rows = np.concatenate([stage2[i][0] for i in involved])
            alpha = np.vstack([stage2[i][1] @ beta[owner == i] for i in involved])
            d = alpha.shape[1]
            _, _, piv = sla.qr(alpha.T, mode="economic", pivoting=True)
            # a basis with coefficient 1 at its own dropped row and 0 at the others
            alpha = alpha @ np.linalg.inv(alpha[piv[:d]])
            for k in range(d):
                dropped.append(rows[piv[k]])
                use = alpha[:, k] != 0
                combos.append((rows[use], alpha[use, k]))
    if not dropped:
        return DependentRows(np.zeros(0, np.int64), sp.csr_matrix((0, m)), m)
    r = np.concatenate([rows for rows, _ in combos])
    k = np.concatenate([np.full(len(rows), i) for i, (rows, _) in enumerate(combos)])
    v = np.concatenate([coef for _, coef in combos]) * scale[r]       # back to the rows of B
    C = sp.csr_matrix((v, (k, r)), shape=(len(combos), m))
    order = np.argsort(dropped)
    return DependentRows(np.asarray(dropped, dtype=np.int64)[order], C[order], m)


# --------------------------------------------------------------------------- saddle points

def _constraint_rows(B, kappa):
    """Rows of ``B`` that carry a multiplier: κ > 0 and the row not empty after elimination."""
    m = B.shape[0]
    kappa = np.asarray(kappa, dtype=np.float64)
    if kappa.shape == (m // 3,) and m % 3 == 0:
        kappa = np.repeat(kappa, 3)
    if kappa.shape != (m,):
        raise ValueError(f"kappa must have shape ({m // 3},) (per LM node) or ({m},) (per row), "
                         f"got {kappa.shape}")
    if np.any(kappa < 0) or not np.all(np.isfinite(kappa)):
        raise ValueError("kappa must be finite and >= 0")
    row_nnz = np.diff(B.indptr)
    return np.flatnonzero((kappa > 0) & (row_nnz > 0)), kappa


def _split(n, solid, beam):
    if solid is None and beam is None:
        return np.arange(n), np.zeros(0, dtype=np.int64)
    solid = np.arange(n) if solid is None else np.asarray(solid, dtype=np.int64)
    if beam is None:
        beam = np.setdiff1d(np.arange(n), solid)
    beam = np.asarray(beam, dtype=np.int64)
    cover = np.zeros(n, dtype=np.int64)
    np.add.at(cover, solid, 1)
    np.add.at(cover, beam, 1)
    if np.any(cover != 1):
        raise ValueError("solid and beam must partition the free DOFs 0..n-1 (each exactly once)")
    return solid, beam


def _stiffness_scale(K, BtWB, dofs):
    """``Σ K_ii / Σ (BᵀWB)_ii`` over the coupled DOFs among ``dofs`` (force / length²).

    A ratio of sums, not a median of ratios: solid nodes the beam barely touches have tiny
    ``(BᵀWB)_ii`` and would dominate a median (it changed by 10x between two meshes of the
    same problem, the ratio of sums by 1.4x).
    """
    coupling = BtWB.diagonal()[dofs]
    stiffness = K.diagonal()[dofs]
    used = (coupling > 0) & (stiffness > 0)
    if not used.any():
        return 1.0
    return float(stiffness[used].sum() / coupling[used].sum())


def solve_saddle(K, B, kappa, b, c, method="auto", *, solid=None, beam=None, penalty_scale=None,
                 near_nullspace=None, rtol=1e-10, maxiter=1000, primal=None, dependent=None, prolongation=None,
                 block_size=None):
    """Solve the mortar saddle point ``[[K, Bᵀ], [B, 0]] [x; λ] = [b; c]``.

    Parameters
    ----------
    K : (n, n) scipy.sparse matrix
        Symmetric stiffness of the free DOFs ``[d_S; d_B]``, positive semi-definite; it may be
        singular on beam DOFs that only the coupling holds (``ker K ∩ ker B = {0}`` is needed).
    B : (m, n) scipy.sparse matrix
        Coupling ``[-M, D]`` restricted to the free DOF columns, ``m = 3 n_lm``.
    kappa : (n_lm,) or (m,) array_like of float
        κ per LM node (expanded to its three rows) or per row. Rows with κ = 0 (LM nodes no pair
        touched) and rows left empty by the elimination carry no multiplier: ``λ = 0`` there and
        their ``c`` is ignored.
    b : (n,) array_like of float
    c : (m,) array_like of float
    method : {"auto", "direct", "block"}
        ``"direct"``: SuperLU on the saddle-point matrix with the constraint rows and the
        multiplier columns scaled by γ (see Notes). ``"block"``: MINRES with the
        block-diagonal preconditioner of the Notes. ``"auto"``: direct up to
        :data:`SADDLE_DIRECT_MAX_DOFS` unknowns (``n`` + multipliers), block above.
    solid, beam : (n_s,), (n_b,) array_like of int, optional
        Which free DOFs are solid and which are beam (together a partition of ``0..n-1``).
        Used for the default γ and by ``primal="split"`` and ``"aux"``. Default: all solid.
    penalty_scale : float, optional
        The augmentation and scaling ``γ`` (force / length², like the penalty ε). Default (and
        what :class:`~mortar1d3d.model.Model` uses) from the operators, ``Σ K_ii / Σ (BᵀWB)_ii``
        (the stiffness that ties a DOF to the coupling's weight on it): over all coupled DOFs
        times ``AUXILIARY_AUGMENTATION_FACTOR`` with ``primal="aux"``, over the coupled solid
        DOFs times ``AUGMENTATION_FACTOR`` otherwise. Not a penalty parameter: the solution does
        not depend on it, only how fast MINRES gets there (and how well the direct matrix is
        scaled); a coupling penalty of 1e3 E as γ costs MINRES its convergence (see Notes).
    near_nullspace : (n, k) array_like, optional
        Rigid-body modes of all free primal DOFs (solid and beam), for the AMG.
    rtol : float
        Relative residual to reach, measured on the scaled system (see Notes).
    maxiter : int
        Maximum MINRES iterations.
    primal : {None, "aux", "monolithic", "split"}
        Block method, primal block: one application of :class:`AuxiliarySpacePreconditioner`
        to ``K_γ`` (``"aux"``, needs ``prolongation``), one AMG V-cycle on all of ``K_γ``
        (``"monolithic"``), or AMG on the solid block and a sparse factorisation of the beam
        block, block-diagonally (``"split"``: slower to converge, see Notes; kept for
        comparison). Default: ``"aux"`` when ``prolongation`` is given, else ``"monolithic"``.
    dependent : DependentRows, optional
        The rows of ``B`` that depend on the others, from :func:`dependent_rows` (a caller
        that solves with the same ``B`` many times finds them once and reports them in its
        own terms). Default: found here, with a :class:`~mortar1d3d.errors.CouplingWarning`
        naming them if there are any.
    prolongation : (n_b, n_s) scipy.sparse matrix, optional
        Beam DOFs following the solid (see :class:`AuxiliarySpacePreconditioner`), for
        ``primal="aux"``.
    block_size : {None, 1, 3}
        AMG aggregation (see :func:`build_amg`).

    Returns
    -------
    x : (n,) ndarray of float64
    lam : (m,) ndarray of float64
        Multipliers per row of ``B`` (0 on rows without a multiplier). With dependent rows:
        of all multipliers that transfer the computed forces ``Bᵀλ``, the one of least
        ``Σ κ λ²`` (the line load of least L2 norm), whichever rows were dropped.
    info : dict
        ``method``, ``iterations``, ``residual``, ``setup_time``, ``solve_time``, ``converged``
        as in :func:`solve_linear`, plus ``gamma``, ``constraint_residual``
        ``‖B x - c‖ / max(‖c‖, ‖B‖_1 ‖x‖)`` (all constraint rows, the dependent ones too),
        ``n_multipliers`` (independent rows solved for), ``dependent_rows`` (ids), ``status``
        (``"converged"`` or ``"roundoff"``, see :func:`solve_linear`), and after a breakdown of
        MINRES ``fallback`` (``"direct"``) and ``note``.

    Raises
    ------
    LinearSolverError
        If MINRES does not converge, or the direct factorisation finds the matrix singular
        (a zero pivot, or a condition estimate of 1/eps or more) or cannot reach ``rtol``.

    Notes
    -----
    **Augmented Lagrangian.** With ``W = diag(κ⁻¹)`` and any ``γ > 0`` the system is equivalent
    (because ``B x = c``) to

        [[K_γ, Bᵀ], [B, 0]] [x; λ] = [b + γ BᵀW c; c],   K_γ = K + γ BᵀWB,

    whose primal block is SPD even where ``K`` alone is singular (beams held only by the
    coupling: ``D`` controls the beam positions, ``K_BB`` the rest). By the Sherman–Morrison–
    Woodbury identity the Schur complement ``S = B K_γ⁻¹ Bᵀ`` satisfies
    ``S⁻¹ = (B K⁻¹ Bᵀ)⁻¹ + γ W``, so ``S̃ = κ/γ`` (i.e. ``S̃⁻¹ = γW``) is exact up to
    ``(B K⁻¹ Bᵀ)⁻¹``: the eigenvalues of ``S̃⁻¹ S`` lie in ``[1/(1 + μ/γ), 1]`` with
    ``μ = λ_max(κ (B K⁻¹ Bᵀ)⁻¹)``, which does not grow with mesh refinement (κ ~ h and
    ``B K⁻¹ Bᵀ ~ κ²/(E h)`` for the stiffest multiplier modes).

    ``μ`` stays bounded only while the multiplier space is not richer than the solid space
    along the beam (beam elements not much shorter than solid elements, the usual mortar
    inf-sup condition); otherwise the beam's own stiffness ``EA/l²`` enters ``μ``.

    **Preconditioner** (SPD, so MINRES applies): ``P = diag(P_γ, κ/γ)``. With ``primal="aux"``
    ``P_γ`` is one sweep of :class:`AuxiliarySpacePreconditioner` on ``K_γ`` (the penalty
    system with ε = γ, for which it was made: robust in γ, so γ may be large and ``S̃`` good).
    With ``"monolithic"`` it is one AMG V-cycle on ``K_γ`` (all primal DOFs, rigid-body modes of
    solid and beams as near null space: they lie in the null space of ``BᵀWB`` too, since ``B``
    ties rigid motions exactly).

    **Choice of γ, auxiliary space.** Measured MINRES iterations (rtol 1e-8) for
    γ = 3, 10, 30 × ``Σ K_ii / Σ (BᵀWB)_ii`` over all coupled DOFs: five clamped rebars in a
    hex8 prism, beam elements as long as the solid's, 3.2k unknowns: 85, 76, 83; 0.9k: 37, 37,
    46; straight fibres (fibre_cube, beam elements 0.08-0.23 of the solid's) (4, 60, 8): 60, 45,
    43; (6, 300, 8), 25k unknowns: 72, 60, 63; (5, 200, 20): 53, 45, 48. Hence
    ``AUXILIARY_AUGMENTATION_FACTOR = 10``. The scale over all coupled DOFs matters: on the
    fibres the beams' scale is 20-580x the solid's, and γ = 10x the solid's scale needed 99,
    171 and 394 iterations there (75 and 47 on the prisms). The AMG V-cycle instead (γ = 0.3x
    the solid's scale) needs 128 and 40 on the prisms but stalls on the fibres (residual 2e-5
    after 600 iterations on (4, 60, 8), 1.5e-4 after 1000 on (6, 300, 8)): fine beams make the
    multiplier space richer than the solid's along them, ``μ`` grows, and only a large γ keeps
    ``S̃`` good, which AMG on ``K_γ`` cannot follow.

    **Choice of γ, AMG.** Larger γ improves ``S̃`` but makes ``K_γ`` harder for AMG (its near null
    space becomes "beam follows the solid", which piecewise-rigid aggregates represent only
    approximately). Measured on a clamped hex8 box with a coupled spring chain (beam elements
    ~1.6 solid elements long), MINRES iterations for γ/γ₀ = 0.3, 1, 3, 10, 30:
    3.9k DOF: 41, 46, 57, 85, 125; 27.8k DOF: 46, 53, 69, 94, 138. Hence
    ``AUGMENTATION_FACTOR = 0.3`` of the stiffness scale ``γ₀``. The split primal block
    (``primal="split"``) ignores the strong solid–beam coupling ``-γ MᵀWD`` inside ``K_γ``:
    for a vector satisfying the constraint it sees ``K + 2γ BᵀWB`` where the matrix has ``K``;
    it needed 2-3x more iterations in the same measurements, even with exact block solves.

    **Residual and scaling.** The rows of ``B`` have other units than those of ``K``; the
    residual reported and tested against ``rtol`` is that of the system with the constraint
    rows multiplied by γ, ``‖[r_x; γ r_λ]‖ / ‖[b; γ c]‖``. The direct method factorises that
    scaled system, ``[[K, γBᵀ], [γB, 0]] [x; λ/γ] = [b; γc]``, whose blocks are of one size:
    unscaled, ``K`` (~E h) and ``B`` (~h) differ by the modulus, and SuperLU's threshold
    pivoting then lost 2 % of the solution on five rebars in a prism (2.9k unknowns). A
    singular matrix is reported, never solved: an estimated condition number (1-norm, from
    the factors) of 1/eps or more raises LinearSolverError; up to two steps of iterative
    refinement then reach ``rtol``.

    **Dependent rows.** A multiplier space richer than what the solid resolves along a beam
    (``line4`` on a coarse mesh; element-based integration with fewer points than LM nodes)
    makes rows of ``B`` dependent, the saddle point singular and λ undetermined. Those rows
    (:func:`dependent_rows`) are left out of the solve; the forces ``Bᵀλ`` and ``x`` are
    unique, and λ is the least-norm multiplier that transfers them.
    """
    K = _check_square(K, "K")
    n = K.shape[0]
    if not sp.issparse(B) or B.shape[1] != n:
        raise ValueError(f"B must be a scipy.sparse matrix with {n} columns, got {getattr(B, 'shape', None)}")
    B = B.tocsr()
    m = B.shape[0]
    b = _check_vector(b, n, "b")
    c = _check_vector(c, m, "c")
    rows, kappa_rows = _constraint_rows(B, kappa)
    solid, beam = _split(n, solid, beam)
    if primal is None:
        primal = "monolithic" if prolongation is None else "aux"
    if primal not in ("aux", "monolithic", "split"):
        raise ValueError(f"primal must be 'aux', 'monolithic' or 'split', got {primal!r}")
    if primal == "aux" and prolongation is None:
        raise ValueError("primal='aux' needs the prolongation (see AuxiliarySpacePreconditioner)")
    if dependent is None:
        # only the rows that carry a multiplier: the others are zeroed, and empty rows are left out
        carries = np.zeros(m)
        carries[rows] = 1.0
        dependent = dependent_rows(sp.diags(carries) @ B, beam)
        if len(dependent):
            warnings.warn(f"solve_saddle: rows {format_ids(dependent.rows)} of B are combinations of the other rows "
                          "(B has no full row rank); they are left out, and λ is the least-norm multiplier "
                          "transferring the same forces", CouplingWarning, stacklevel=2)
    elif not isinstance(dependent, DependentRows) or dependent.n_rows != m:
        raise ValueError(f"dependent must be the DependentRows of this B ({m} rows), got {dependent!r}")
    all_rows = rows
    rows = np.setdiff1d(rows, dependent.rows)
    Bc = B[rows]
    cc = c[rows]
    W = sp.diags(1.0 / kappa_rows[rows])
    BtWB = (Bc.T @ W @ Bc).tocsr()
    if penalty_scale is not None:
        gamma = float(penalty_scale)
    elif primal == "aux":
        gamma = AUXILIARY_AUGMENTATION_FACTOR * _stiffness_scale(K, BtWB, np.arange(n))
    else:
        gamma = AUGMENTATION_FACTOR * _stiffness_scale(K, BtWB, solid if len(solid) else np.arange(n))
    if not gamma > 0:
        raise ValueError(f"penalty_scale must be > 0, got {penalty_scale}")
    n_lam = len(rows)
    size = n + n_lam
    if method == "auto":
        method = "direct" if size <= SADDLE_DIRECT_MAX_DOFS else "block"
    if method not in ("direct", "block"):
        raise ValueError(f"method must be 'auto', 'direct' or 'block', got {method!r}")

    Saddle = sp.bmat([[K, Bc.T], [Bc, None]], format="csr")
    rhs = np.concatenate([b, cc])
    scale = np.concatenate([np.ones(n), np.full(n_lam, gamma)])
    rhs_norm = np.linalg.norm(scale * rhs)

    def residual(y):
        return np.linalg.norm(scale * (rhs - Saddle @ y)) / rhs_norm if rhs_norm > 0 else 0.0

    info = dict(method=method, iterations=0, residual=0.0, setup_time=0.0, solve_time=0.0,
                converged=True, rtol=rtol, maxiter=maxiter, gamma=gamma, n_multipliers=n_lam,
                dependent_rows=dependent.rows)
    lam = np.zeros(m)
    if rhs_norm == 0.0:
        info["constraint_residual"] = 0.0
        return np.zeros(n), lam, info

    def floor(y):
        return _roundoff(Saddle, y, rhs, scale)

    def direct():
        hint = ("some DOF is held neither by K nor by the coupling B (a beam outside the solid? missing "
                "Dirichlet conditions?), or rows of B depend on each other that `dependent` does not list "
                "(pass dependent=dependent_rows(B, beam)); the multipliers of such a matrix would be noise")
        start = time.perf_counter()
        scaled = sp.bmat([[K, gamma * Bc.T], [gamma * Bc, None]], format="csc")
        try:
            lu = _factorize(scaled, symmetric_positive=False, saddle=True)
        except RuntimeError as error:   # SuperLU: "Factor is exactly singular"
            raise LinearSolverError(f"the saddle-point matrix is singular ({error}): {hint}") from error
        # a singular matrix is reported, never solved: partial pivoting need not leave a tiny pivot
        # (line4 multipliers on a coarse solid: none below 3e-13 of the largest, λ 2e4 times too
        # large), and a consistent right-hand side hides it from the residual; the condition
        # estimate does not (Hager–Higham, a few solves): 1e22-1e33 there, 3e5-2e6 on
        # well-posed prisms, bars and fibre cubes
        inverse = spla.LinearOperator((size, size), matvec=lu.solve, rmatvec=lambda v: lu.solve(v, trans="T"),
                                      dtype=float)
        condition = float(abs(scaled).sum(axis=0).max()) * spla.onenormest(inverse)
        info["condition_estimate"] = condition
        if not condition * np.finfo(float).eps < 1.0:
            raise LinearSolverError(f"the saddle-point matrix is singular to working precision (condition number "
                                    f"about {condition:.1e}): {hint}")
        info["setup_time"] += time.perf_counter() - start
        start = time.perf_counter()
        # [x; λ/γ] from [b; γc]: `scale` turns one into the other's units both ways
        y = scale * lu.solve(scale * rhs)
        for _ in range(2):      # iterative refinement: round-off of an ill-conditioned K
            if residual(y) <= max(rtol, floor(y)):
                break
            y += scale * lu.solve(scale * (rhs - Saddle @ y))
        res = residual(y)
        info["solve_time"] += time.perf_counter() - start
        if res > max(rtol, floor(y)):
            raise LinearSolverError(f"the direct saddle-point solve reached a relative residual of {res:.3e} only "
                                    f"(rtol {rtol:.1e}, round-off level {floor(y):.1e}, after iterative refinement): "
                                    f"the matrix is nearly singular; {hint}")
        return y, res

    if method == "direct":
        y, info["residual"] = direct()
        info["status"] = "converged"
    else:
        t = time.perf_counter()
        K_gamma = (K + gamma * BtWB).tocsr()
        null = None if near_nullspace is None else np.asarray(near_nullspace, dtype=np.float64)
        if null is not None and null.shape[0] != n:
            raise ValueError(f"near_nullspace must have shape ({n}, k), got {null.shape}")
        schur_inverse = gamma / kappa_rows[rows]         # S̃⁻¹ = γ W
        if primal == "aux":
            aux = AuxiliarySpacePreconditioner(K_gamma, solid, beam, prolongation,
                                               None if null is None else null[solid], block_size=block_size)
            levels = aux.levels

            def apply_preconditioner(r):
                return np.concatenate([aux.matvec(r[:n]), schur_inverse * r[n:]])
        elif primal == "monolithic":
            ml = build_amg(K_gamma, null, block_size=block_size)
            amg = ml.aspreconditioner(cycle="V")
            levels = len(ml.levels)

            def apply_preconditioner(r):
                return np.concatenate([amg.matvec(r[:n]), schur_inverse * r[n:]])
        else:
            ml = build_amg(K_gamma[solid][:, solid], None if null is None else null[solid])
            levels = len(ml.levels)
            amg = ml.aspreconditioner(cycle="V")
            lu_beam = _factorize(K_gamma[beam][:, beam], symmetric_positive=True) if len(beam) else None

            def apply_preconditioner(r):
                z = np.empty_like(r)
                z[solid] = amg.matvec(r[solid])
                if lu_beam is not None:
                    z[beam] = lu_beam.solve(r[beam])
                z[n:] = schur_inverse * r[n:]
                return z
        info["setup_time"] = time.perf_counter() - t
        info["amg_levels"] = levels
        info["primal"] = primal

        augmented = sp.bmat([[K_gamma, Bc.T], [Bc, None]], format="csr")
        rhs_aug = np.concatenate([b + gamma * (Bc.T @ (W @ cc)), cc])
        t = time.perf_counter()
        # the augmented system has the same solution; the residual is checked on the original
        y, info["iterations"], info["residual"], info["status"] = _krylov(
            "minres", augmented, rhs_aug, np.zeros(size), apply_preconditioner, rtol, maxiter, residual, floor)
        info["solve_time"] = time.perf_counter() - t
        if info["status"] == "breakdown":
            # the preconditioner is not positive definite: K_γ is not (an indefinite tangent), so
            # its AMG V-cycle need not be either
            y, info["residual"] = direct()
            info["status"], info["fallback"] = "converged", "direct"
            info["note"] = ("block-preconditioned MINRES broke down (stiffness not positive definite), sparse LU "
                            "took over")
    info["converged"] = info["status"] in ("converged", "roundoff")
    x = y[:n]
    lam[rows] = y[n:]
    lam = dependent.least_norm(lam, kappa_rows)
    B_all, c_all = B[all_rows], c[all_rows]
    row_sum = float(abs(B_all).sum(axis=1).max()) if len(all_rows) else 0.0
    info["constraint_residual"] = float(np.linalg.norm(B_all @ x - c_all) / max(
        np.linalg.norm(c_all), row_sum * np.linalg.norm(x), 1e-300))
    if not info["converged"]:
        _raise_not_converged("block-preconditioned MINRES", info,
                             "pass near_nullspace=rigid_body_modes(...)[free] and the solid/beam split if "
                             "you did not, raise maxiter, try penalty_scale 0.3-3x the default "
                             f"({gamma:.3g}), or use method='direct'")
    return x, lam, info
