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

import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["LinearSolverError", "rigid_body_modes", "build_amg", "AuxiliarySpacePreconditioner",
           "solve_linear", "solve_saddle",
           "DIRECT_MAX_DOFS", "SADDLE_DIRECT_MAX_DOFS", "AUGMENTATION_FACTOR"]

#: ``method="auto"`` of :func:`solve_linear` factorises systems up to this many unknowns and
#: uses AMG + CG above. Measured on hex8 elasticity + a penalty-coupled chain (2 cores, loaded):
#: direct / AMG seconds 0.05 / 0.18 (1.4k DOF), 0.29 / 0.33 (2.7k), 0.56 / 0.47 (3.6k),
#: 2.1 / 0.74 (6.1k), 32 / 6.9 (26k), 151 / 11.5 (51k): SuperLU fill grows fast in 3D.
DIRECT_MAX_DOFS = 3_000

#: ``method="auto"`` of :func:`solve_saddle`: direct up to this many unknowns (primal + λ).
#: The same crossover as above (λ adds few unknowns; MINRES needs 2-3x the CG iterations
#: but the indefinite factorisation pivots), not measured separately.
SADDLE_DIRECT_MAX_DOFS = 3_000

#: default ``γ = AUGMENTATION_FACTOR * (stiffness scale)`` of the block preconditioner
AUGMENTATION_FACTOR = 0.3

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


def _factorize(A, symmetric_positive):
    """SuperLU factorisation of a sparse matrix.

    SPD matrices use a minimum-degree ordering of ``A + Aᵀ`` with diagonal pivots
    (``SymmetricMode``): the fill of a symmetric ordering, no row interchanges needed. Measured
    on 3D hex8 elasticity with a penalty-coupled chain (14k, 26k, 51k DOF) it factorises and
    solves 1.5x, 1.4x, 1.9x faster than scipy's default (``COLAMD`` with partial pivoting, what
    ``spsolve`` does), with the same accuracy (relative difference < 1e-12). Indefinite
    saddle-point matrices keep partial pivoting (their λ block has a zero diagonal).
    """
    A = sp.csc_matrix(A)
    if symmetric_positive:
        return spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options=dict(SymmetricMode=True))
    return spla.splu(A, permc_spec="MMD_AT_PLUS_A")


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
    starting residual. Returns ``(x, iterations, stopped_by_tolerance)``.
    """
    r = b - A @ x
    target = reduction * np.linalg.norm(r)
    z = apply_preconditioner(r)
    p = z.copy()
    rz = r @ z
    for it in range(1, maxiter + 1):
        q = A @ p
        pq = p @ q
        if not pq > 0:   # A or the preconditioner is not positive definite: no progress possible
            return x, it, False
        alpha = rz / pq
        x += alpha * p
        r -= alpha * q
        if np.linalg.norm(r) <= target:
            return x, it, True
        z = apply_preconditioner(r)
        rz_new = r @ z
        p *= rz_new / rz
        p += z
        rz = rz_new
    return x, maxiter, False


def _minres(A, b, x, apply_preconditioner, reduction, maxiter):
    """Preconditioned MINRES (symmetric ``A``, SPD preconditioner ``P``) from ``x``.

    Stops when the preconditioned residual norm ``‖r‖_{P⁻¹}`` has dropped by ``reduction``.
    Returns ``(x, iterations, stopped_by_tolerance)``.

    Notes
    -----
    Lanczos in the ``P⁻¹`` inner product plus Givens QR of the tridiagonal matrix, after
    Elman, Silvester & Wathen, *Finite Elements and Fast Iterative Solvers* (2014), the
    preconditioned MINRES algorithm; ``|η|`` is ``‖r_j‖_{P⁻¹}``.
    """
    v = b - A @ x
    z = apply_preconditioner(v)
    gamma = np.sqrt(max(v @ z, 0.0))
    if gamma == 0.0:
        return x, 0, True
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
            return x, it, False
        gamma_new = np.sqrt(vz)
        a0 = c * delta - c_old * s * gamma
        a1 = np.hypot(a0, gamma_new)
        a2 = s * delta + c_old * c * gamma
        a3 = s_old * gamma
        if a1 == 0.0:
            return x, it, False
        c_old, s_old = c, s
        c, s = a0 / a1, gamma_new / a1
        w_new = (z - a3 * w_old - a2 * w) / a1
        x += (c * eta) * w_new
        eta = -s * eta
        if abs(eta) <= target or gamma_new == 0.0:
            return x, it, True
        v_old, v = v, v_new
        z = z_new
        w_old, w = w, w_new
        gamma_old, gamma = gamma, gamma_new
    return x, maxiter, False


def _krylov(kind, A, rhs, x, apply_preconditioner, rtol, maxiter, residual):
    """Run CG or MINRES until ``residual(x) <= rtol`` (the caller's true relative residual).

    The Krylov method's own stopping test uses a recursive or a preconditioned residual, which
    can differ from the true one; if it stops early, restart from ``x`` asking for the missing
    reduction (halved for safety), at most ``_MAX_RESTARTS`` times.
    Returns ``(x, iterations, residual, converged)``.
    """
    method = _cg if kind == "cg" else _minres
    total = 0
    res = residual(x)
    for _ in range(_MAX_RESTARTS + 1):
        if res <= rtol:
            return x, total, res, True
        reduction = rtol / res if total == 0 else 0.5 * rtol / res
        x, it, stopped_by_tolerance = method(A, rhs, x, apply_preconditioner, reduction, maxiter - total)
        total += it
        res = residual(x)
        if res > rtol and (not stopped_by_tolerance or total >= maxiter):
            return x, total, res, False
    return x, total, res, res <= rtol


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
        factorisation / AMG setup, then substitution / CG), ``converged``, ``rtol``, ``maxiter``.

    Raises
    ------
    LinearSolverError
        If CG does not reach ``rtol`` within ``maxiter`` iterations.

    Notes
    -----
    Direct: scipy offers no sparse Cholesky, so SuperLU it is; for SPD matrices the fill is
    that of a symmetric ordering when pivots stay on the diagonal, which is safe for SPD. CG
    stops on its recursive residual and then checks the true one (restarting if needed).
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
    x, info["iterations"], info["residual"], info["converged"] = _krylov(
        "cg", A, b, x, M.matvec, rtol, maxiter, residual)
    info["solve_time"] = time.perf_counter() - t
    if not info["converged"]:
        _raise_not_converged("auxiliary-space-preconditioned CG" if method == "aux" else "AMG-preconditioned CG", info,
                             "pass near_nullspace=rigid_body_modes(...)[free] if you did not, raise maxiter, "
                             "check that A is symmetric positive definite (enough Dirichlet conditions, every "
                             "beam held), or use method='direct'")
    return x, info


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
                 near_nullspace=None, rtol=1e-10, maxiter=1000, primal="monolithic"):
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
        ``"direct"``: SuperLU on the assembled saddle-point matrix. ``"block"``: MINRES with the
        block-diagonal preconditioner of the Notes. ``"auto"``: direct up to
        :data:`SADDLE_DIRECT_MAX_DOFS` unknowns (``n`` + multipliers), block above.
    solid, beam : (n_s,), (n_b,) array_like of int, optional
        Which free DOFs are solid and which are beam (together a partition of ``0..n-1``).
        Used for the default γ (solid DOFs) and by ``primal="split"``. Default: all solid.
    penalty_scale : float, optional
        The augmentation ``γ`` (force / length², like the penalty ε). Default:
        ``AUGMENTATION_FACTOR`` × ``Σ K_ii / Σ (BᵀWB)_ii`` over the coupled solid DOFs, i.e.
        about the coupling as stiff as the solid it sits in.
    near_nullspace : (n, k) array_like, optional
        Rigid-body modes of all free primal DOFs (solid and beam), for the AMG.
    rtol : float
        Relative residual to reach, measured on the scaled system (see Notes).
    maxiter : int
        Maximum MINRES iterations.
    primal : {"monolithic", "split"}
        Block method, primal block: one AMG V-cycle on all of ``K_γ`` (default), or AMG on
        the solid block and a sparse factorisation of the beam block, block-diagonally
        (slower to converge, see Notes; kept for comparison).

    Returns
    -------
    x : (n,) ndarray of float64
    lam : (m,) ndarray of float64
        Multipliers per row of ``B`` (0 on rows without a multiplier).
    info : dict
        ``method``, ``iterations``, ``residual``, ``setup_time``, ``solve_time``, ``converged``
        as in :func:`solve_linear`, plus ``gamma`` (block method), ``constraint_residual``
        ``‖B x - c‖ / max(‖c‖, ‖B‖_1 ‖x‖)`` and ``n_multipliers`` (rows kept).

    Raises
    ------
    LinearSolverError
        If MINRES does not converge, or the direct factorisation finds the matrix singular.

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

    **Preconditioner** (SPD, so MINRES applies): ``P = diag(P_γ, κ/γ)`` with ``P_γ`` one AMG
    V-cycle on ``K_γ`` (all primal DOFs, rigid-body modes of solid and beams as near null space:
    they lie in the null space of ``BᵀWB`` too, since ``B`` ties rigid motions exactly).

    **Choice of γ.** Larger γ improves ``S̃`` but makes ``K_γ`` harder for AMG (its near null
    space becomes "beam follows the solid", which piecewise-rigid aggregates represent only
    approximately). Measured on a clamped hex8 box with a coupled spring chain (beam elements
    ~1.6 solid elements long), MINRES iterations for γ/γ₀ = 0.3, 1, 3, 10, 30:
    3.9k DOF: 41, 46, 57, 85, 125; 27.8k DOF: 46, 53, 69, 94, 138. Hence
    ``AUGMENTATION_FACTOR = 0.3`` of the stiffness scale ``γ₀``. The split primal block
    (``primal="split"``) ignores the strong solid–beam coupling ``-γ MᵀWD`` inside ``K_γ``:
    for a vector satisfying the constraint it sees ``K + 2γ BᵀWB`` where the matrix has ``K``;
    it needed 2-3x more iterations in the same measurements, even with exact block solves.

    **Residual.** The rows of ``B`` have other units than those of ``K``; the residual reported
    and tested against ``rtol`` is that of the system with the constraint rows multiplied by γ,
    ``‖[r_x; γ r_λ]‖ / ‖[b; γ c]‖`` (γ is computed for the direct method too).
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
    Bc = B[rows]
    cc = c[rows]
    W = sp.diags(1.0 / kappa_rows[rows])
    BtWB = (Bc.T @ W @ Bc).tocsr()
    gamma = (AUGMENTATION_FACTOR * _stiffness_scale(K, BtWB, solid if len(solid) else np.arange(n))
             if penalty_scale is None else float(penalty_scale))
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
                converged=True, rtol=rtol, maxiter=maxiter, gamma=gamma, n_multipliers=n_lam)
    lam = np.zeros(m)
    if rhs_norm == 0.0:
        info["constraint_residual"] = 0.0
        return np.zeros(n), lam, info

    if method == "direct":
        t = time.perf_counter()
        try:
            lu = _factorize(Saddle, symmetric_positive=False)
        except RuntimeError as error:   # SuperLU: "Factor is exactly singular"
            raise LinearSolverError(
                f"the saddle-point matrix is singular ({error}): some DOF is held neither by K nor "
                "by the coupling B (a beam outside the solid? missing Dirichlet conditions?), or B "
                "has dependent rows") from error
        info["setup_time"] = time.perf_counter() - t
        t = time.perf_counter()
        y = lu.solve(rhs)
        info["solve_time"] = time.perf_counter() - t
        info["residual"] = residual(y)
    else:
        t = time.perf_counter()
        K_gamma = (K + gamma * BtWB).tocsr()
        null = None if near_nullspace is None else np.asarray(near_nullspace, dtype=np.float64)
        if null is not None and null.shape[0] != n:
            raise ValueError(f"near_nullspace must have shape ({n}, k), got {null.shape}")
        schur_inverse = gamma / kappa_rows[rows]         # S̃⁻¹ = γ W
        if primal == "monolithic":
            ml = build_amg(K_gamma, null)
            amg = ml.aspreconditioner(cycle="V")

            def apply_preconditioner(r):
                return np.concatenate([amg.matvec(r[:n]), schur_inverse * r[n:]])
        elif primal == "split":
            ml = build_amg(K_gamma[solid][:, solid], None if null is None else null[solid])
            amg = ml.aspreconditioner(cycle="V")
            lu_beam = _factorize(K_gamma[beam][:, beam], symmetric_positive=True) if len(beam) else None

            def apply_preconditioner(r):
                z = np.empty_like(r)
                z[solid] = amg.matvec(r[solid])
                if lu_beam is not None:
                    z[beam] = lu_beam.solve(r[beam])
                z[n:] = schur_inverse * r[n:]
                return z
        else:
            raise ValueError(f"primal must be 'monolithic' or 'split', got {primal!r}")
        info["setup_time"] = time.perf_counter() - t
        info["amg_levels"] = len(ml.levels)

        augmented = sp.bmat([[K_gamma, Bc.T], [Bc, None]], format="csr")
        rhs_aug = np.concatenate([b + gamma * (Bc.T @ (W @ cc)), cc])
        t = time.perf_counter()
        # the augmented system has the same solution; the residual is checked on the original
        y, info["iterations"], info["residual"], info["converged"] = _krylov(
            "minres", augmented, rhs_aug, np.zeros(size), apply_preconditioner, rtol, maxiter, residual)
        info["solve_time"] = time.perf_counter() - t
    x = y[:n]
    lam[rows] = y[n:]
    Bx = B[rows] @ x
    info["constraint_residual"] = float(np.linalg.norm(Bx - cc) / max(np.linalg.norm(cc),
                                        abs(Bc).sum(axis=1).max() * np.linalg.norm(x), 1e-300))
    if not info["converged"]:
        _raise_not_converged("block-preconditioned MINRES", info,
                             "pass near_nullspace=rigid_body_modes(...)[free] and the solid/beam split if "
                             "you did not, raise maxiter, try penalty_scale 0.3-3x the default "
                             f"({gamma:.3g}), or use method='direct'")
    return x, lam, info
