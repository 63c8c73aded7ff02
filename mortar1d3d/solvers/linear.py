"""Linear solvers for the systems of one Newton iteration (docs/conventions.md §1, "Enforcement"): the
entry points, and the names of the modules they are built from.

Two kinds of systems arise, both on the free DOFs only (Dirichlet DOFs are eliminated by the
caller), ordered ``[d_S; d_B]`` (solid first):

- **penalty**: ``A x = b`` with ``A = K + ε Bᵀ diag(κ⁻¹) B`` symmetric positive definite:
  :func:`solve_linear` (sparse direct, or conjugate gradients with smoothed-aggregation AMG, or
  with the auxiliary-space preconditioner :class:`AuxiliarySpacePreconditioner` that stays
  robust at large penalties).
- **Lagrange multipliers**: the saddle point ``[[K, Bᵀ], [B, 0]] [x; λ] = [b; c]``:
  :func:`solve_saddle` (sparse direct, or GMRES with an augmented-Lagrangian block-triangular
  preconditioner: the auxiliary space or AMG on the augmented stiffness, ``κ/γ`` for ``λ``).

:func:`rigid_body_modes` gives the near null space that AMG needs for elasticity, and
:func:`build_amg` the AMG hierarchy, which a Newton loop may build once and pass to
:func:`solve_linear` as ``preconditioner`` while the stiffness changes little.

One idea per module, all importable from here as before:

- :mod:`~mortar1d3d.solvers.rigid`: rigid-body modes of DOF triplets;
- :mod:`~mortar1d3d.solvers.direct`: SuperLU factorisation, :data:`DIRECT_MAX_DOFS`, the banded
  Cholesky of the beam blocks;
- :mod:`~mortar1d3d.solvers.amg`: smoothed-aggregation AMG set-up;
- :mod:`~mortar1d3d.solvers.preconditioners`: the auxiliary-space preconditioner;
- :mod:`~mortar1d3d.solvers._products`: the two Numba kernels of its set-up (its sparse products
  row by row, the weak node blocks dropped);
- :mod:`~mortar1d3d.solvers.krylov`: CG/MINRES/GMRES to the caller's tolerance, breakdown fallback,
  round-off floor;
- :mod:`~mortar1d3d.solvers.dependent`: dependent constraint rows;
- :mod:`~mortar1d3d.solvers.saddle`: the saddle-point solver;
- :mod:`~mortar1d3d.solvers._common`: :class:`LinearSolverError` and argument checks.

Everything here works on ``scipy.sparse`` matrices; the heavy lifting is in SuperLU (scipy) and
pyamg, and the only Numba kernels are those of ``_products``.
"""
import time

import numpy as np

from ._common import LinearSolverError, check_square, check_vector, split_dofs
from .amg import AMG_SEED, VCycle, build_amg
from .dependent import DEPENDENT_ROW_TOLERANCE, DependentRows, dependent_rows
from .direct import (BANDED_MAX_BANDWIDTH, DIRECT_MAX_DOFS, BandedCholesky, bandwidth, factorize,  # noqa: F401
                     factorize_spd_block)
from .krylov import cg_with_fallback, raise_not_converged, roundoff_level
from .preconditioners import AuxiliarySpacePreconditioner, drop_weak_blocks, harmonic_prolongation, smooth_prolongation
from .rigid import rigid_body_modes
from .schur import schur_cg
from .saddle import (AUGMENTATION_FACTOR, AUXILIARY_AUGMENTATION_FACTOR, SADDLE_DIRECT_MAX_DOFS,
                     SaddlePreconditioner, solve_saddle)

__all__ = ["LinearSolverError", "rigid_body_modes", "build_amg", "AMG_SEED", "AuxiliarySpacePreconditioner",
           "smooth_prolongation", "harmonic_prolongation", "drop_weak_blocks",
           "solve_linear", "solve_saddle", "dependent_rows", "DependentRows", "DEPENDENT_ROW_TOLERANCE",
           "DIRECT_MAX_DOFS", "SADDLE_DIRECT_MAX_DOFS", "AUGMENTATION_FACTOR", "AUXILIARY_AUGMENTATION_FACTOR",
           "SaddlePreconditioner"]

#: the factorisation under its former private name (``mortar1d3d.study`` imports it from here)
_factorize = factorize


def solve_linear(A, b, method="auto", *, near_nullspace=None, rtol=1e-10, maxiter=500, x0=None,
                 preconditioner=None, block_size=None, solid=None, beam=None, prolongation=None):
    """Solve the SPD system ``A x = b`` (penalty coupling, linear elasticity).

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, symmetric positive definite
    b : (n,) array_like of float
    method : {"auto", "direct", "amg", "aux", "schur"}
        ``"direct"``: SuperLU (:func:`scipy.sparse.linalg.splu`) with a symmetric minimum-degree
        ordering and diagonal pivoting (see Notes). ``"amg"``: conjugate gradients
        preconditioned by one V-cycle of smoothed-aggregation AMG (:func:`build_amg`).
        ``"aux"``: conjugate gradients preconditioned by :class:`AuxiliarySpacePreconditioner`
        (needs ``solid``, ``beam``, ``prolongation``): for beams penalty-coupled to a solid,
        where plain AMG degrades as ε grows. ``"schur"``: the beam DOFs eliminated exactly
        (banded factor) and CG on the solid's Schur complement with the auxiliary space's V-cycle
        (:func:`~mortar1d3d.solvers.schur.schur_cg`; same needs as ``"aux"``, the same iterations
        on the fibre cube, cheaper ones). ``"auto"``: direct up to :data:`DIRECT_MAX_DOFS`
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
        preconditioner (implies ``method="aux"`` unless ``method="schur"``) to reuse; it may
        have been built for an earlier, similar ``A``.
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
        ``method`` ("direct", "amg", "aux" or "schur"), ``iterations`` (0 for direct), ``residual`` (true
        relative residual ``‖b - A x‖/‖b‖``), ``setup_time`` and ``solve_time`` (seconds:
        factorisation / AMG setup, then substitution / CG), ``converged``, ``rtol``, ``maxiter``;
        iterative methods add ``status`` (``"converged"``, or ``"roundoff"``: the residual
        stalled at its round-off level above ``rtol``, which counts as converged), and after a
        breakdown of CG ``breakdown_iteration``, ``fallback`` (``"minres"`` or ``"direct"``)
        and ``note`` (one line saying what happened, for logs); ``"amg"`` and ``"aux"`` add
        ``preconditioner`` (the hierarchy or auxiliary-space preconditioner used, for
        ``preconditioner`` of a later call).

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
    with ``k`` entries per row, see :func:`~mortar1d3d.solvers.krylov.roundoff_level`) cannot fall further: CG stopping there has
    converged, whatever ``rtol`` asked for. If CG breaks down (``pᵀAp <= 0``: ``A`` is not
    positive definite, e.g. the tangent of a nearly incompressible solid in tension), MINRES
    with the same preconditioner takes over, and a sparse LU with partial pivoting if that
    fails too.
    """
    A = check_square(A, "A")
    n = A.shape[0]
    b = check_vector(b, n, "b")
    if preconditioner is not None:
        aux = isinstance(preconditioner, AuxiliarySpacePreconditioner)
        method = ("schur" if method == "schur" else "aux") if aux else "amg"
    if method == "auto":
        method = "direct" if n <= DIRECT_MAX_DOFS else ("amg" if prolongation is None else "aux")
    if method not in ("direct", "amg", "aux", "schur"):
        raise ValueError(f"method must be 'auto', 'direct', 'amg', 'aux' or 'schur', got {method!r}")
    missing = prolongation is None or solid is None or beam is None
    if method in ("aux", "schur") and preconditioner is None and missing:
        raise ValueError(f"method {method!r} needs solid, beam and prolongation (see AuxiliarySpacePreconditioner)")
    bnorm = np.linalg.norm(b)
    info = dict(method=method, iterations=0, residual=0.0, setup_time=0.0, solve_time=0.0,
                converged=True, rtol=rtol, maxiter=maxiter)
    if bnorm == 0.0:
        return np.zeros(n), info

    def residual(x):
        return np.linalg.norm(b - A @ x) / bnorm

    if method == "direct":
        t = time.perf_counter()
        lu = factorize(A, symmetric_positive=True)
        info["setup_time"] = time.perf_counter() - t
        t = time.perf_counter()
        x = lu.solve(b)
        info["solve_time"] = time.perf_counter() - t
        info["residual"] = residual(x)
        return x, info

    t = time.perf_counter()
    if method in ("aux", "schur"):
        if preconditioner is None:
            solid, beam = split_dofs(n, solid, beam)
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
        info["preconditioner"] = preconditioner
    else:
        ml = preconditioner if preconditioner is not None else build_amg(A, near_nullspace, block_size=block_size)
        M = VCycle(ml)
        info["amg_levels"] = len(ml.levels)
        info["preconditioner"] = ml
    info["setup_time"] = time.perf_counter() - t
    t = time.perf_counter()
    x = np.zeros(n) if x0 is None else check_vector(x0, n, "x0").copy()

    def floor(y):
        return roundoff_level(A, y, b)

    name = {"aux": "auxiliary-space-preconditioned CG", "schur": "Schur-complement CG"}.get(method,
                                                                                          "AMG-preconditioned CG")
    if method == "schur" and M.A is not A:
        # a preconditioner kept from another matrix (Newton with reuse): its beam factor is of that
        # matrix's beam block, and the Schur complement eliminates the beams exactly, so it would
        # solve the other system; the auxiliary-space sweep takes the kept preconditioner as it is
        aux_name = "auxiliary-space-preconditioned CG"
        x, outcome = cg_with_fallback(A, b, x, M.matvec, rtol, maxiter, residual, floor, aux_name)
        outcome["note"] = ("Schur-complement CG needs the beam factor of this matrix; with the preconditioner "
                           f"kept from an earlier one the {aux_name} ran instead. " + outcome.get("note", "")).strip()
    elif method == "schur":
        x, outcome = schur_cg(A, b, M, x, rtol, maxiter)
        if outcome["status"] not in ("converged", "roundoff"):
            # CG on S broke down or stalled: the auxiliary-space sweep on the whole system (with
            # its MINRES and LU fallbacks) from zero, with the iterations left
            before, status = outcome["iterations"], outcome["status"]
            aux_name = "auxiliary-space-preconditioned CG"
            x, outcome = cg_with_fallback(A, b, np.zeros(n), M.matvec, rtol, max(1, maxiter - before), residual,
                                          floor, aux_name)
            outcome["iterations"] += before
            outcome["fallback"] = outcome.get("fallback", "aux")
            outcome["note"] = (f"Schur-complement CG ended '{status}' after {before} iterations; the {aux_name} "
                               "took over from zero. " + outcome.get("note", "")).strip()
    else:
        x, outcome = cg_with_fallback(A, b, x, M.matvec, rtol, maxiter, residual, floor, name)
    info.update(outcome)
    info["solve_time"] = time.perf_counter() - t
    info["converged"] = info["status"] in ("converged", "roundoff")
    if not info["converged"]:
        raise_not_converged(name, info,
                            "pass near_nullspace=rigid_body_modes(...)[free] if you did not, raise maxiter, "
                            "check that A is symmetric positive definite (enough Dirichlet conditions, every "
                            "beam held), or use method='direct'")
    return x, info
