"""The mortar saddle point ``[[K, Bᵀ], [B, 0]] [x; λ] = [b; c]`` of Lagrange multipliers: a
sparse direct solve of the scaled system, or GMRES (MINRES) with an augmented-Lagrangian
block-triangular (block-diagonal) preconditioner (AMG or the auxiliary space on the primal block,
``κ/γ`` for ``λ``), dependent constraint rows left out (:mod:`~mortar1d3d.solvers.dependent`).
"""
import time
import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CouplingWarning, format_ids
from ._common import LinearSolverError, check_square, check_vector, split_dofs
from .amg import VCycle, build_amg
from .dependent import DependentRows, dependent_rows
from .direct import DIRECT_MAX_DOFS, factorize
from .krylov import raise_not_converged, roundoff_level, run_krylov
from .preconditioners import AuxiliarySpacePreconditioner

__all__ = ["solve_saddle", "SaddlePreconditioner", "SADDLE_DIRECT_MAX_DOFS", "AUGMENTATION_FACTOR",
           "AUXILIARY_AUGMENTATION_FACTOR"]

#: ``method="auto"`` of :func:`solve_saddle`: direct up to this many unknowns (primal + λ).
#: The same crossover as :data:`~mortar1d3d.solvers.direct.DIRECT_MAX_DOFS` (λ adds few unknowns;
#: MINRES needs 2-3x the CG iterations but the indefinite factorisation pivots), not measured
#: separately.
SADDLE_DIRECT_MAX_DOFS = DIRECT_MAX_DOFS

#: default ``γ = AUGMENTATION_FACTOR * (stiffness scale of the solid)`` of the block preconditioner
#: with an AMG V-cycle on the augmented stiffness (see :func:`solve_saddle`)
AUGMENTATION_FACTOR = 0.3

#: default ``γ = AUXILIARY_AUGMENTATION_FACTOR * (stiffness scale of all coupled DOFs)`` of the
#: block preconditioner with the auxiliary-space preconditioner on the augmented stiffness
AUXILIARY_AUGMENTATION_FACTOR = 10.0


class SaddlePreconditioner:
    """The primal block of :func:`solve_saddle`'s block preconditioner with the γ it was built
    for, so that later solves with a similar stiffness can reuse it.

    Attributes
    ----------
    gamma : float
        The augmentation ``K_γ = K + γ BᵀWB`` the primal block approximates.
    primal : str
        ``"aux"``, ``"monolithic"`` or ``"split"`` (see :func:`solve_saddle`).
    apply : callable
        ``(n,) -> (n,)``: one application of the primal preconditioner.
    levels : int
        AMG levels.
    """

    def __init__(self, gamma, primal, apply, levels):
        self.gamma, self.primal, self.apply, self.levels = gamma, primal, apply, levels


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
                 block_size=None, krylov="gmres", preconditioner=None):
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
        multiplier columns scaled by γ (see Notes). ``"block"``: the Krylov method
        ``krylov`` with the block preconditioner of the Notes. ``"auto"``: direct up to
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
        not depend on it, only how fast the Krylov method gets there (and how well the direct matrix is
        scaled); a coupling penalty of 1e3 E as γ costs the block methods their convergence (see Notes).
    near_nullspace : (n, k) array_like, optional
        Rigid-body modes of all free primal DOFs (solid and beam), for the AMG.
    rtol : float
        Relative residual to reach, measured on the scaled system (see Notes).
    maxiter : int
        Maximum Krylov iterations.
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
    krylov : {"gmres", "minres"}
        Block method: right-preconditioned GMRES with the block upper-triangular preconditioner
        (default), or MINRES with the block-diagonal one (kept for comparison: 3-4x the
        iterations, see Notes).
    preconditioner : SaddlePreconditioner, optional
        ``info["preconditioner"]`` of an earlier block solve with the same ``B`` and a similar
        ``K`` (a later Newton iteration), reused instead of building the primal block anew: its
        γ replaces ``penalty_scale``, its primal preconditioner stands for ``K_γ``.

    Returns
    -------
    x : (n,) ndarray of float64
    lam : (m,) ndarray of float64
        Multipliers per row of ``B`` (0 on rows without a multiplier). With dependent rows:
        of all multipliers that transfer the computed forces ``Bᵀλ``, the one of least
        ``Σ κ λ²`` (the line load of least L2 norm), whichever rows were dropped.
    info : dict
        ``method``, ``iterations``, ``residual``, ``setup_time``, ``solve_time``, ``converged``
        as in :func:`~mortar1d3d.solvers.linear.solve_linear`, plus ``gamma``,
        ``constraint_residual`` ``‖B x - c‖ / max(‖c‖, ‖B‖_1 ‖x‖)`` (all constraint rows, the
        dependent ones too), ``n_multipliers`` (independent rows solved for), ``dependent_rows``
        (ids), ``status`` (``"converged"`` or ``"roundoff"``, see
        :func:`~mortar1d3d.solvers.linear.solve_linear`), and after a breakdown of the Krylov method
        ``fallback`` (``"direct"``) and ``note``; the block method adds ``preconditioner`` (a
        :class:`SaddlePreconditioner`, for ``preconditioner`` of a later call).

    Raises
    ------
    LinearSolverError
        If the Krylov method does not converge, or the direct factorisation finds the matrix singular
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

    **Preconditioner.** ``krylov="gmres"`` (default): the block upper-triangular
    ``P = [[P_γ, Bᵀ], [0, −κ/γ]]``, applied as ``z_λ = −γW r_λ``, ``z_x = P_γ⁻¹ (r_x − Bᵀ z_λ)``
    (one primal application and one product with ``Bᵀ``), right-preconditioned (flexible)
    GMRES on the system with the constraint rows times γ, so that GMRES minimises the norm tested
    against ``rtol``. With exact blocks ``𝒜 P⁻¹ = [[I, 0], [B K_γ⁻¹, S S̃⁻¹]]``: its eigenvalues
    are 1 and those of ``S S̃⁻¹``, in ``[1/(1 + μ/γ), 1]`` (above), each counted once, where the
    block-diagonal preconditioner's symmetric spectrum has them in two intervals of both signs
    and MINRES needs about twice the iterations for the same bound. Measured (rtol 1e-8,
    benchmarks/lagrange_solve.py, line2, ``fibre_cube(n, fibres, 10)``, E_f = 2e11, r = 1 cm):
    GMRES 17 / 19 / 26 / 40 iterations against MINRES 45 / 68 / 88 / 125 for (n, fibres) = (4,
    60), (8, 150), (15, 155), (20, 1000), where penalty CG with the auxiliary space on the same
    scene needs 10 / 15 / 21 / 31. With an exact ``K_γ`` solve instead of ``P_γ`` GMRES needs
    17 on (8, 150): the Schur approximation, not the AMG, sets the count; adding
    ``(B diag(K)⁻¹ Bᵀ)⁻¹`` to ``S̃⁻¹`` (a sparse factorisation of the multipliers' coupling) cut
    that to 15 only; γ = 0.3x, 3x and 9x the default needed 35, 37 and 60 on (15, 155) against
    26 (a larger γ sharpens ``S̃`` but costs the primal preconditioner more than that saves).

    ``krylov="minres"``: ``P = diag(P_γ, κ/γ)`` (SPD, so MINRES applies). With ``primal="aux"``
    ``P_γ`` is one sweep of :class:`AuxiliarySpacePreconditioner` on ``K_γ`` (the penalty
    system with ε = γ, for which it was made: robust in γ, so γ may be large and ``S̃`` good).
    With ``"monolithic"`` it is one AMG V-cycle on ``K_γ`` (all primal DOFs, rigid-body modes of
    solid and beams as near null space: they lie in the null space of ``BᵀWB`` too, since ``B``
    ties rigid motions exactly).

    **Choice of γ, auxiliary space.** Measured MINRES iterations (block-diagonal, rtol 1e-8) for
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
    K = check_square(K, "K")
    n = K.shape[0]
    if not sp.issparse(B) or B.shape[1] != n:
        raise ValueError(f"B must be a scipy.sparse matrix with {n} columns, got {getattr(B, 'shape', None)}")
    B = B.tocsr()
    m = B.shape[0]
    b = check_vector(b, n, "b")
    c = check_vector(c, m, "c")
    rows, kappa_rows = _constraint_rows(B, kappa)
    solid, beam = split_dofs(n, solid, beam)
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
    if preconditioner is not None:
        gamma = preconditioner.gamma
    elif penalty_scale is not None:
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
    if krylov not in ("gmres", "minres"):
        raise ValueError(f"krylov must be 'gmres' or 'minres', got {krylov!r}")

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
        return roundoff_level(Saddle, y, rhs, scale)

    def direct():
        hint = ("some DOF is held neither by K nor by the coupling B (a beam outside the solid? missing "
                "Dirichlet conditions?), or rows of B depend on each other that `dependent` does not list "
                "(pass dependent=dependent_rows(B, beam)); the multipliers of such a matrix would be noise")
        start = time.perf_counter()
        scaled = sp.bmat([[K, gamma * Bc.T], [gamma * Bc, None]], format="csc")
        try:
            lu = factorize(scaled, symmetric_positive=False, saddle=True)
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
        if preconditioner is not None:
            primal, apply_primal, levels = preconditioner.primal, preconditioner.apply, preconditioner.levels
        elif primal == "aux":
            # the lumped follow operator as before (the smoothed one was measured on penalty systems
            # only), with the hierarchy built from the sparsified auxiliary matrix as for penalty: on
            # the 15³ cube with 155 fibres 24 instead of 26 GMRES iterations and 0.65 of the CPU
            # (benchmarks/README.md, "Lagrange multipliers against penalty")
            aux = AuxiliarySpacePreconditioner(K_gamma, solid, beam, prolongation,
                                               None if null is None else null[solid], block_size=block_size,
                                               **dict(AuxiliarySpacePreconditioner.LUMPED,
                                                      sparsify=AuxiliarySpacePreconditioner.SPARSIFY))
            levels = aux.levels
            apply_primal = aux.matvec
        elif primal == "monolithic":
            ml = build_amg(K_gamma, null, block_size=block_size)
            apply_primal = VCycle(ml).matvec
            levels = len(ml.levels)
        else:
            ml = build_amg(K_gamma[solid][:, solid], None if null is None else null[solid])
            levels = len(ml.levels)
            amg = VCycle(ml)
            lu_beam = factorize(K_gamma[beam][:, beam], symmetric_positive=True) if len(beam) else None

            def apply_primal(r):
                z = np.empty_like(r)
                z[solid] = amg.matvec(r[solid])
                if lu_beam is not None:
                    z[beam] = lu_beam.solve(r[beam])
                return z
        info["setup_time"] = time.perf_counter() - t
        info["amg_levels"] = levels
        info["primal"] = primal
        info["krylov"] = krylov
        info["preconditioner"] = SaddlePreconditioner(gamma, primal, apply_primal, levels)

        augmented = sp.bmat([[K_gamma, Bc.T], [Bc, None]], format="csr")
        rhs_aug = np.concatenate([b + gamma * (Bc.T @ (W @ cc)), cc])
        t = time.perf_counter()
        # the augmented system has the same solution; the residual is checked on the original
        if krylov == "minres":
            def apply_preconditioner(r):          # block-diagonal, SPD
                return np.concatenate([apply_primal(r[:n]), schur_inverse * r[n:]])
            operator, rhs_krylov = augmented, rhs_aug
        else:
            # GMRES minimises the residual of the system it is given: the one with the constraint
            # rows times γ, whose norm is the one tested against rtol
            Bt = Bc.T.tocsr()

            def apply_preconditioner(r):          # block upper-triangular, applied to the scaled residual
                z_lam = -schur_inverse * (r[n:] / gamma)
                return np.concatenate([apply_primal(r[:n] - Bt @ z_lam), z_lam])
            operator, rhs_krylov = (sp.diags(scale) @ augmented).tocsr(), scale * rhs_aug
        y, info["iterations"], info["residual"], info["status"] = run_krylov(
            krylov, operator, rhs_krylov, np.zeros(size), apply_preconditioner, rtol, maxiter, residual, floor)
        info["solve_time"] = time.perf_counter() - t
        if info["status"] == "breakdown":
            # the preconditioner is not positive definite: K_γ is not (an indefinite tangent), so
            # its AMG V-cycle need not be either
            y, info["residual"] = direct()
            info["status"], info["fallback"] = "converged", "direct"
            info["note"] = (f"block-preconditioned {krylov.upper()} broke down (stiffness not positive definite), "
                            "sparse LU took over")
    info["converged"] = info["status"] in ("converged", "roundoff")
    x = y[:n]
    lam[rows] = y[n:]
    lam = dependent.least_norm(lam, kappa_rows)
    B_all, c_all = B[all_rows], c[all_rows]
    row_sum = float(abs(B_all).sum(axis=1).max()) if len(all_rows) else 0.0
    info["constraint_residual"] = float(np.linalg.norm(B_all @ x - c_all) / max(
        np.linalg.norm(c_all), row_sum * np.linalg.norm(x), 1e-300))
    if not info["converged"]:
        raise_not_converged(f"block-preconditioned {krylov.upper()}", info,
                             "pass near_nullspace=rigid_body_modes(...)[free] and the solid/beam split if "
                             "you did not, raise maxiter, try penalty_scale 0.3-3x the default "
                             f"({gamma:.3g}), or use method='direct'")
    return x, lam, info
