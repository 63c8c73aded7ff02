"""The Krylov driver of the linear solvers: CG, MINRES and GMRES to a relative residual chosen by
the caller, checked on the true residual, a stall at the round-off level counted as convergence, and
a breakdown of CG on an indefinite matrix handed on to MINRES and then to a sparse LU.

:func:`run_krylov` restarts the method while its own residual claims more than the true one
shows; :func:`cg_with_fallback` is what :func:`~mortar1d3d.solvers.linear.solve_linear` runs
on an SPD system, :func:`run_krylov` with ``"gmres"`` (or ``"minres"``) what
:func:`~mortar1d3d.solvers.saddle.solve_saddle` runs on a saddle point.

**Whose CG and MINRES** (measured with ``benchmarks/krylov_paths.py``, scipy 1.17, see
benchmarks/README.md, "Krylov methods: scipy's or our own"):

- CG is :func:`scipy.sparse.linalg.cg`, with the curvature checks (``pᵀAp``, ``rᵀz``) in the
  operator and preconditioner handed to it (:func:`_cg`). Its iterations are those of the
  hand-written loop it replaced, on every CG path of the tests and benchmarks (23, 18, 18, 103 on
  the test box, 15 and 20 in penalty_solve n = 10, 20, 23/38/65/129 in scene_solve n = 20, 1447
  CG + MINRES in the ν = 0.4999 breakdown case), with residuals equal to round-off; solve time
  equal within noise (medians of 6 runs alternating with the old loop: ratio 0.99).
- MINRES stays our own (:func:`_minres`): scipy's stops on tests that cannot be switched off
  (``‖r‖ <= eps ‖A‖ ‖x‖`` and ``‖A‖ ‖x‖ eps >= ‖b‖``, in the norms of the preconditioned
  system), which fire on the saddle point of ``scene_solve`` (λ dominates ``‖x‖``): Lagrange,
  traction, n = 20 raised LinearSolverError (residual 1.1e-7 after 90 iterations, restarts
  included) where ours converges in 99. Its preconditioned residual, the quantity our
  stopping test and round-off stall detection need, is not exposed: a callback has to compute the
  true residual (one more product with the saddle matrix per iteration). With both (the system
  also scaled by ``diag(1, γ)``) it converged everywhere, but took 5 % longer on that scene
  (54.0 against 51.4 s, medians of 4 alternating runs) and 1403 against 1333 iterations on the
  four Lagrange scene_solve runs (214 against 144 to recognise the round-off stall at rtol 1e-12).
- GMRES is our own too (:func:`_gmres`, flexible, restarted): the saddle point's block-triangular
  preconditioner is not symmetric, so MINRES cannot take it; scipy's ``gmres`` would again hide
  the residual our stopping test needs. With it the Lagrange solves of
  ``benchmarks/lagrange_solve.py`` need 26 and 40 iterations where block-diagonal MINRES needs 88
  and 125.
"""
import numpy as np
import scipy.sparse.linalg as spla

from ._common import LinearSolverError
from .direct import factorize

__all__ = ["run_krylov", "cg_with_fallback", "roundoff_level", "raise_not_converged"]

#: restarts of the Krylov method when its own (recursive or preconditioned) residual claims
#: convergence but the true residual does not meet ``rtol`` yet
_MAX_RESTARTS = 4

#: Krylov vectors GMRES keeps before it restarts (two per iteration: the Arnoldi basis and its
#: preconditioned images); the block-triangular saddle solves of the benchmarks converge within it
GMRES_RESTART = 60


class _Breakdown(Exception):
    """Raised from inside scipy's CG: the operator or the preconditioner is not positive definite."""


def _cg(A, b, x, apply_preconditioner, reduction, maxiter):
    """Preconditioned conjugate gradients from ``x``: :func:`scipy.sparse.linalg.cg`.

    Stops when the recursive residual norm has dropped by ``reduction`` relative to the
    starting residual. Returns ``(x, iterations, status)``, status ``"tolerance"``,
    ``"maxiter"`` or ``"breakdown"`` (``pᵀAp <= 0`` or ``rᵀz <= 0``: ``A`` or the
    preconditioner is not positive definite, CG cannot go on).

    Notes
    -----
    scipy's CG neither checks nor exposes the curvature ``pᵀAp`` and ``rᵀz``; the operator and
    the preconditioner handed to it check them and end the run (:class:`_Breakdown`) before
    scipy divides by them. The first preconditioner call comes before any search direction
    (scipy's first operator call, if ``x`` is not zero, is the initial residual). The two checks
    sum with numpy (pairwise) rather than a BLAS dot: on the shared 2-core machine a threaded
    BLAS dot of 152k entries took 16 ms against 0.07 ms, and with BLAS dots the wrapper made CG
    11 % slower on ``scene_solve`` (penalty, weight, n = 20, 8 alternating pairs at load 5-6).
    """
    n = len(b)
    state = dict(x=x, iterations=0, started=False)

    def operator(p):
        q = A @ p
        if state["started"] and not (p * q).sum() > 0:
            state["iterations"] += 1             # counted as the iteration it broke down in
            raise _Breakdown
        return q

    def preconditioner(r):
        state["started"] = True
        z = apply_preconditioner(r)
        if not (r * z).sum() > 0:
            raise _Breakdown
        return z

    def count(xk):                               # scipy updates x in place and calls this once per iteration
        state["x"] = xk
        state["iterations"] += 1

    start = b - A @ x if x.any() else b
    try:
        _, info = spla.cg(spla.LinearOperator((n, n), matvec=operator, dtype=float), b, x, rtol=0.0,
                          atol=reduction * np.linalg.norm(start), maxiter=maxiter,
                          M=spla.LinearOperator((n, n), matvec=preconditioner, dtype=float), callback=count)
    except _Breakdown:
        return state["x"], state["iterations"], "breakdown"
    return state["x"], state["iterations"], "maxiter" if info else "tolerance"


def _minres(A, b, x, apply_preconditioner, reduction, maxiter):
    """Preconditioned MINRES (symmetric ``A``, SPD preconditioner ``P``) from ``x``.

    Stops when the preconditioned residual norm ``‖r‖_{P⁻¹}`` has dropped by ``reduction``.
    Returns ``(x, iterations, status)`` as :func:`_cg` (breakdown: the preconditioner is not
    positive definite, or the Lanczos process cannot continue).

    Notes
    -----
    Lanczos in the ``P⁻¹`` inner product plus Givens QR of the tridiagonal matrix, after
    Elman, Silvester & Wathen, *Finite Elements and Fast Iterative Solvers* (2014), the
    preconditioned MINRES algorithm; ``|η|`` is ``‖r_j‖_{P⁻¹}``. Our own rather than
    :func:`scipy.sparse.linalg.minres`, which does not expose ``|η|`` and stops early on the
    saddle points here (see the module's docstring).
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


def _gmres(A, b, x, apply_preconditioner, reduction, maxiter, restart=None):
    """Right-preconditioned GMRES from ``x``, restarted every ``restart`` iterations.

    Stops when the residual norm ``‖b − A x‖`` (of the system given, not a preconditioned one)
    has dropped by ``reduction``. Returns ``(x, iterations, status)`` as :func:`_cg`
    (breakdown: the Arnoldi process met a zero column, ``A`` times a preconditioned vector
    vanished).

    Notes
    -----
    The flexible form (Saad, *Iterative Methods for Sparse Linear Systems*, 2003, §9.4.1): the
    preconditioned basis vectors are kept, so the update needs no further preconditioner
    application and the preconditioner may be any operator, symmetric or not. Orthogonalisation
    by classical Gram–Schmidt applied twice (two matrix–vector products with the basis instead of
    ``j`` dot products per step); the Hessenberg matrix is reduced by Givens rotations as it
    grows, so ``|g_{j+1}|`` is the residual norm at every step without forming ``x``.
    """
    restart = GMRES_RESTART if restart is None else restart
    n = len(b)
    r = b - A @ x
    beta = float(np.linalg.norm(r))
    if beta == 0.0:
        return x, 0, "tolerance"
    target = reduction * beta
    total = 0
    while total < maxiter:
        m = min(restart, maxiter - total)
        V = np.empty((m + 1, n))
        Z = np.empty((m, n))
        H = np.zeros((m + 1, m))
        cs, sn = np.zeros(m), np.zeros(m)
        g = np.zeros(m + 1)
        g[0] = beta
        V[0] = r / beta
        k = 0
        breakdown = False
        while k < m:
            Z[k] = apply_preconditioner(V[k])
            w = A @ Z[k]
            h = V[:k + 1] @ w
            w -= h @ V[:k + 1]
            again = V[:k + 1] @ w
            w -= again @ V[:k + 1]
            H[:k + 1, k] = h + again
            H[k + 1, k] = float(np.linalg.norm(w))
            for i in range(k):
                H[i, k], H[i + 1, k] = cs[i] * H[i, k] + sn[i] * H[i + 1, k], cs[i] * H[i + 1, k] - sn[i] * H[i, k]
            norm = float(np.hypot(H[k, k], H[k + 1, k]))
            if norm == 0.0:
                breakdown = True
                break
            cs[k], sn[k] = H[k, k] / norm, H[k + 1, k] / norm
            next_norm = H[k + 1, k]
            H[k, k], H[k + 1, k] = norm, 0.0
            g[k + 1] = -sn[k] * g[k]
            g[k] = cs[k] * g[k]
            k += 1
            total += 1
            if abs(g[k]) <= target or next_norm == 0.0:
                break
            V[k] = w / next_norm
        if k:
            y = _upper_solve(H[:k, :k], g[:k])
            x = x + y @ Z[:k]
        if breakdown:
            return x, total, "breakdown"
        r = b - A @ x
        beta = float(np.linalg.norm(r))
        if beta <= target or abs(g[k]) <= target:
            return x, total, "tolerance"
    return x, total, "maxiter"


def _upper_solve(R, g):
    """``R⁻¹ g`` for a small upper-triangular ``R`` (back substitution)."""
    y = np.zeros(len(g))
    for i in range(len(g) - 1, -1, -1):
        y[i] = (g[i] - R[i, i + 1:] @ y[i + 1:]) / R[i, i]
    return y


def roundoff_level(A, y, rhs, scale=None):
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


def run_krylov(kind, A, rhs, x, apply_preconditioner, rtol, maxiter, residual, floor):
    """Run CG, MINRES or GMRES until ``residual(x) <= rtol`` (the caller's true relative residual).

    The Krylov method's own stopping test uses a recursive or a preconditioned residual, which
    can differ from the true one; if it stops early, restart from ``x`` asking for the missing
    reduction (halved for safety), at most ``_MAX_RESTARTS`` times. A run that no longer
    halves the true residual while that is at or below ``floor(x)`` (its round-off level,
    :func:`roundoff_level`) has stalled at round-off: the residual cannot fall further, which is
    success too, even when ``rtol`` asked for less.
    Returns ``(x, iterations, residual, status)``, status ``"converged"``, ``"roundoff"``
    (stalled at the round-off level above ``rtol``), ``"breakdown"`` (see :func:`_cg`) or
    ``"maxiter"``.
    """
    method = {"cg": _cg, "minres": _minres, "gmres": _gmres}[kind]
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


def cg_with_fallback(A, b, x, apply_preconditioner, rtol, maxiter, residual, floor, name):
    """Preconditioned CG from ``x`` (:func:`run_krylov`); after a breakdown MINRES from zero with
    the same preconditioner, and a sparse LU with partial pivoting if that fails too.

    ``name`` names the CG in the note. Returns ``(x, info)``, ``info`` with ``iterations`` (CG
    and MINRES together), ``residual``, ``status`` (see :func:`run_krylov`; ``"converged"``
    after a successful LU) and after a breakdown ``breakdown_iteration``, ``fallback``
    (``"minres"`` or ``"direct"``) and ``note`` (one line saying what happened, for logs).
    """
    info = {}
    x, info["iterations"], info["residual"], status = run_krylov("cg", A, b, x, apply_preconditioner, rtol, maxiter,
                                                                 residual, floor)
    if status == "breakdown":
        # CG needs A and its preconditioner positive definite; a tangent past a limit point or of a
        # material outside its convex range (neo-Hooke with λ ln J > μ) is not. MINRES takes
        # symmetric indefinite matrices (with the same preconditioner while that stays positive),
        # a factorisation with partial pivoting anything nonsingular.
        cg_iterations = info["iterations"]
        y, it, res, status = run_krylov("minres", A, b, np.zeros(len(b)), apply_preconditioner, rtol, maxiter,
                                        residual, floor)
        info["iterations"] += it
        info["breakdown_iteration"] = cg_iterations
        note = f"{name} broke down (matrix or preconditioner not positive definite), "
        if status in ("converged", "roundoff"):
            x, info["residual"], info["fallback"] = y, res, "minres"
            note += "MINRES took over"
        else:
            lu = factorize(A, symmetric_positive=False)
            x = lu.solve(b)
            info["residual"], info["fallback"] = residual(x), "direct"
            status = "converged" if info["residual"] <= max(rtol, floor(x)) else "breakdown"
            note += "MINRES failed too, sparse LU took over"
        info["note"] = note
    info["status"] = status
    return x, info


def raise_not_converged(what, info, hints):
    raise LinearSolverError(
        f"{what} did not converge: relative residual {info['residual']:.3e} after "
        f"{info['iterations']} iterations (rtol {info['rtol']:.1e}, maxiter {info['maxiter']}). "
        f"Try: {hints}")
