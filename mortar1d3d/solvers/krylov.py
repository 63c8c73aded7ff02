"""The Krylov driver of the linear solvers: CG and MINRES to a relative residual chosen by the
caller, checked on the true residual, a stall at the round-off level counted as convergence, and
a breakdown of CG on an indefinite matrix handed on to MINRES and then to a sparse LU.

:func:`run_krylov` restarts the method while its own residual claims more than the true one
shows; :func:`cg_with_fallback` is what :func:`~mortar1d3d.solvers.linear.solve_linear` runs
on an SPD system, :func:`run_krylov` with ``"minres"`` what
:func:`~mortar1d3d.solvers.saddle.solve_saddle` runs on a saddle point.
"""
import numpy as np

from ._common import LinearSolverError
from .direct import factorize

__all__ = ["run_krylov", "cg_with_fallback", "roundoff_level", "raise_not_converged"]

#: restarts of the Krylov method when its own (recursive or preconditioned) residual claims
#: convergence but the true residual does not meet ``rtol`` yet
_MAX_RESTARTS = 4


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


# ---- experiment: scipy's CG and MINRES behind the same interface (MORTAR1D3D_KRYLOV=scipy)
import os  # noqa: E402

import scipy.sparse.linalg as spla  # noqa: E402

_BACKEND = os.environ.get("MORTAR1D3D_KRYLOV", "own")


class _Stop(Exception):
    def __init__(self, status):
        self.status = status


def _cg_scipy(A, b, x, apply_preconditioner, reduction, maxiter, residual=None):
    """scipy's CG; the operator and the preconditioner check the curvature CG needs."""
    n = len(b)
    r0 = b - A @ x if x.any() else b
    state = dict(x=x, it=0, started=False)

    def matvec(p):
        q = A @ p
        if state["started"] and not (p @ q if _BACKEND == "scipy" else (p * q).sum()) > 0:
            state["it"] += 1
            raise _Stop("breakdown")
        return q

    def psolve(r):
        state["started"] = True
        z = apply_preconditioner(r)
        if not (r @ z if _BACKEND == "scipy" else (r * z).sum()) > 0:
            raise _Stop("breakdown")
        return z

    def callback(xk):
        state["x"] = xk
        state["it"] += 1

    try:
        _, info = spla.cg(spla.LinearOperator((n, n), matvec=matvec, dtype=float), b, x, rtol=0.0,
                          atol=reduction * np.linalg.norm(r0), maxiter=maxiter,
                          M=spla.LinearOperator((n, n), matvec=psolve, dtype=float), callback=callback)
        status = "maxiter" if info else "tolerance"
    except _Stop as stop:
        status = stop.status
    return state["x"], state["it"], status


def _minres_scipy(A, b, x, apply_preconditioner, reduction, maxiter, residual=None):
    goal = reduction * residual(x)
    state = dict(x=x, it=0)

    def callback(xk):
        state["x"] = xk
        state["it"] += 1
        if residual(xk) <= goal:
            raise _Stop("tolerance")

    n = len(b)
    try:
        y, info = spla.minres(A, b, x if x.any() else None, rtol=0.0, maxiter=maxiter,
                              M=spla.LinearOperator((n, n), matvec=apply_preconditioner, dtype=float),
                              callback=callback)
        status = "maxiter" if info else "tolerance"
        state["x"] = y
    except _Stop as stop:
        status = stop.status
    except ValueError as error:          # "indefinite preconditioner", "non-symmetric matrix"
        if "indefinite" not in str(error) and "non-symmetric" not in str(error):
            raise
        status = "breakdown"
    return state["x"], state["it"], status


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
    """Run CG or MINRES until ``residual(x) <= rtol`` (the caller's true relative residual).

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
    if _BACKEND.startswith("scipy"):
        method = _cg_scipy if kind == "cg" else _minres_scipy
        extra = dict(residual=residual)
    else:
        method = _cg if kind == "cg" else _minres
        extra = {}
    total = 0
    res = residual(x)
    for _ in range(_MAX_RESTARTS + 1):
        if res <= rtol:
            return x, total, res, "converged"
        reduction = rtol / res if total == 0 else 0.5 * rtol / res
        previous = res
        x, it, status = method(A, rhs, x, apply_preconditioner, reduction, maxiter - total, **extra)
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
