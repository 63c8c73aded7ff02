"""Finite rotations: rotation matrices, rotation vectors and their Jacobians (Numba kernels).

Conventions (used by :mod:`.simo_reissner_kernel` and :mod:`.simo_reissner`):

=====================  ==========================================================================
``skew(v)``            ``[v]×``, the matrix with ``[v]× w = v × w``; ``axial`` is its inverse
``exp(ψ)``             Rodrigues: ``I + A [ψ]× + B [ψ]×²``, ``A = sin a / a``, ``B = (1 - cos a)/a²``,
                       ``a² = ψ·ψ``
``log(R)``             the rotation vector of R with ``|ψ| ≤ π`` (through the unit quaternion of R)
``T(ψ)``               left Jacobian: for ``R = exp(ψ)``, ``δR Rᵀ = [T(ψ) δψ]×`` (spatial spin);
                       ``T = I + B [ψ]× + C [ψ]×²``, ``C = (a - sin a)/a³``; ``Rᵀ δR = [Tᵀ δψ]×``
``T(ψ)⁻¹``             ``I - ½ [ψ]× + D [ψ]×²``, ``D = (1 - (a/2) cot(a/2))/a²``
``dT[v]``              directional derivative of ``T`` at ψ along ``v``
``compose(ψ, Δθ)``     ``log(exp(Δθ) exp(ψ))``: the multiplicative update ``Λ ← exp(Δθ) Λ``
=====================  ==========================================================================

*Complex-analytic by construction.* Every function here is an analytic function of its inputs,
so that the element kernels can be differentiated by the complex step (perturb an input by
``i h``, read the derivative from the imaginary part): the coefficients A, B, C, D and the
derivatives of B and C are functions of ``a² = ψ·ψ`` (never of ``|ψ|``, which would take a
conjugate), evaluated by their Taylor series below ``a² = 0.5`` (where the closed forms lose
digits to cancellation) and by the closed forms above it, whose square root is taken of a number
with a positive real part; :func:`log` chooses its branches (Spurrier's largest quaternion
component, the sign of the scalar part, the arctangent form) on real parts only. No ``abs`` and
no conjugate touches a value that may carry a perturbation. The kernels take float64 or complex128
arrays (one compiled version each) and write into output arrays of the same type.
"""
import math

import numpy as np

from .._config import njit

__all__ = ["skew", "axial", "exp", "log", "jacobian", "jacobian_inverse", "jacobian_derivative_transpose",
           "compose", "coefficients", "exp_rows", "log_rows", "compose_rows", "SERIES_LIMIT"]

#: below this a² (real part) the coefficient functions use their Taylor series
SERIES_LIMIT = 0.5
_TERMS = 12


def _series_tables():
    """Taylor coefficients in powers of a² of A, B, C, dB/d(a²), dC/d(a²) and D (12 terms each)."""
    f = [float(math.factorial(k)) for k in range(2 * _TERMS + 8)]
    A = [(-1) ** n / f[2 * n + 1] for n in range(_TERMS)]
    B = [(-1) ** n / f[2 * n + 2] for n in range(_TERMS)]
    C = [(-1) ** n / f[2 * n + 3] for n in range(_TERMS)]
    dB = [(n + 1) * (-1) ** (n + 1) / f[2 * n + 4] for n in range(_TERMS)]
    dC = [(n + 1) * (-1) ** (n + 1) / f[2 * n + 5] for n in range(_TERMS)]
    # (1 - x cot x) with x = a/2 is -Σ_{n≥1} (-1)^n B_2n a^2n / (2n)! (Bernoulli numbers B_2n)
    bernoulli = [1 / 6, -1 / 30, 1 / 42, -1 / 30, 5 / 66, -691 / 2730, 7 / 6, -3617 / 510, 43867 / 798,
                 -174611 / 330, 854513 / 138, -236364091 / 2730]
    D = [-(-1) ** n * bernoulli[n - 1] / f[2 * n] for n in range(1, _TERMS + 1)]
    return tuple(np.array(c) for c in (A, B, C, dB, dC, D))


_SA, _SB, _SC, _SDB, _SDC, _SD = _series_tables()
#: arctan(z)/z in powers of z² (below z² = 0.01: 9 terms reach round-off)
_SATAN = np.array([(-1) ** n / (2 * n + 1) for n in range(9)])
_ATAN_SERIES_LIMIT = 0.01


@njit
def _horner(c, x):
    s = c[c.shape[0] - 1] + 0.0 * x
    for k in range(c.shape[0] - 2, -1, -1):
        s = s * x + c[k]
    return s


@njit
def coefficients(a2):
    """``A, B, C, dB, dC`` at ``a² = ψ·ψ``: ``sin a/a``, ``(1 - cos a)/a²``, ``(a - sin a)/a³``,
    and the derivatives of B and C with respect to a² (float or complex)."""
    if a2.real < SERIES_LIMIT:
        return _horner(_SA, a2), _horner(_SB, a2), _horner(_SC, a2), _horner(_SDB, a2), _horner(_SDC, a2)
    a = np.sqrt(a2)
    s = np.sin(a)
    c1 = 1.0 - np.cos(a)
    A = s / a
    B = c1 / a2
    C = (a - s) / (a2 * a)
    dB = (a * s - 2.0 * c1) / (2.0 * a2 * a2)
    dC = (a * c1 - 3.0 * (a - s)) / (2.0 * a2 * a2 * a)
    return A, B, C, dB, dC


@njit
def _inverse_coefficient(a2):
    """``D = (1 - (a/2) cot(a/2)) / a²`` (singular at a = 2π only)."""
    if a2.real < SERIES_LIMIT:
        return _horner(_SD, a2)
    a = np.sqrt(a2)
    h = 0.5 * a
    return (1.0 - h * np.cos(h) / np.sin(h)) / a2


@njit
def skew(v, S):
    """``S = [v]×`` (3, 3)."""
    S[0, 0] = 0.0 * v[0]
    S[1, 1] = 0.0 * v[0]
    S[2, 2] = 0.0 * v[0]
    S[0, 1] = -v[2]
    S[0, 2] = v[1]
    S[1, 0] = v[2]
    S[1, 2] = -v[0]
    S[2, 0] = -v[1]
    S[2, 1] = v[0]


@njit
def axial(S, v):
    """``v`` with ``[v]× = skw(S)``: the axial vector of the skew part of S."""
    v[0] = 0.5 * (S[2, 1] - S[1, 2])
    v[1] = 0.5 * (S[0, 2] - S[2, 0])
    v[2] = 0.5 * (S[1, 0] - S[0, 1])


@njit
def _fill(psi, c0, c1, c2, M):
    """``M = c0 I + c1 [ψ]× + c2 [ψ]×²`` with ``[ψ]×² = ψ ψᵀ - a² I``."""
    a2 = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2]
    for i in range(3):
        for j in range(3):
            M[i, j] = c2 * psi[i] * psi[j]
        M[i, i] += c0 - c2 * a2
    M[0, 1] -= c1 * psi[2]
    M[0, 2] += c1 * psi[1]
    M[1, 0] += c1 * psi[2]
    M[1, 2] -= c1 * psi[0]
    M[2, 0] -= c1 * psi[1]
    M[2, 1] += c1 * psi[0]


@njit
def exp(psi, R):
    """``R = exp([ψ]×)`` (Rodrigues' formula)."""
    a2 = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2]
    A, B, _, _, _ = coefficients(a2)
    _fill(psi, 1.0, A, B, R)


@njit
def jacobian(psi, T):
    """Left Jacobian ``T(ψ)``: ``δR Rᵀ = [T(ψ) δψ]×`` for ``R = exp(ψ)``."""
    a2 = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2]
    _, B, C, _, _ = coefficients(a2)
    _fill(psi, 1.0, B, C, T)


@njit
def jacobian_inverse(psi, Ti):
    """``T(ψ)⁻¹ = I - ½ [ψ]× + D [ψ]×²`` (``|ψ| < 2π``)."""
    a2 = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2]
    _fill(psi, 1.0, -0.5, _inverse_coefficient(a2), Ti)


@njit
def _cross(a, b, c):
    c0 = a[1] * b[2] - a[2] * b[1]
    c1 = a[2] * b[0] - a[0] * b[2]
    c2 = a[0] * b[1] - a[1] * b[0]
    c[0] = c0
    c[1] = c1
    c[2] = c2


@njit
def jacobian_derivative_transpose(psi, v, u, out, work):
    """``out = (dT[v])ᵀ u``: the transpose of the derivative of ``T`` at ψ along ``v``, applied to u.

    With ``T = I + B [ψ]× + C [ψ]×²`` and ``a² = ψ·ψ``,
    ``dT[v] = B [v]× + C ([v]×[ψ]× + [ψ]×[v]×) + 2 (ψ·v) (B' [ψ]× + C' [ψ]×²)``, so
    ``dT[v]ᵀ u = -B v×u + C (ψ×(v×u) + v×(ψ×u)) + 2 (ψ·v) (-B' ψ×u + C' ψ×(ψ×u))``.
    ``work``: (9,) scratch of the same type.
    """
    a2 = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2]
    _, B, C, dB, dC = coefficients(a2)
    pv = 2.0 * (psi[0] * v[0] + psi[1] * v[1] + psi[2] * v[2])
    vu = work[0:3]
    pu = work[3:6]
    t = work[6:9]
    _cross(v, u, vu)
    _cross(psi, u, pu)
    for i in range(3):
        out[i] = -B * vu[i] - pv * dB * pu[i]
    _cross(psi, vu, t)
    for i in range(3):
        out[i] += C * t[i]
    _cross(v, pu, t)
    for i in range(3):
        out[i] += C * t[i]
    _cross(psi, pu, t)
    for i in range(3):
        out[i] += pv * dC * t[i]


@njit
def log(R, psi):
    """Rotation vector ``ψ`` (``|ψ| ≤ π``) of the rotation matrix R, through its unit quaternion.

    The quaternion's largest component (by real part) is taken first and the others follow from
    the off-diagonal entries (Spurrier 1978), so no square root is taken of a small number. The
    sign is chosen so that the scalar part w ≥ 0; then ``ψ = 2 atan2(s, w) v / s`` with the
    vector part v and ``s = √(v·v)``: for ``w ≥ s`` (angle ≤ π/2) as ``(2/w) v · atan(z)/z``,
    ``z² = v·v / w²`` (a series for small z²), otherwise as ``2 (π/2 - atan(w/s)) v / s``.
    """
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    d0 = R[0, 0].real
    d1 = R[1, 1].real
    d2 = R[2, 2].real
    trr = tr.real
    if trr >= d0 and trr >= d1 and trr >= d2:
        w = 0.5 * np.sqrt(1.0 + tr)
        f = 0.25 / w
        x = (R[2, 1] - R[1, 2]) * f
        y = (R[0, 2] - R[2, 0]) * f
        z = (R[1, 0] - R[0, 1]) * f
    elif d0 >= d1 and d0 >= d2:
        x = 0.5 * np.sqrt(1.0 + 2.0 * R[0, 0] - tr)
        f = 0.25 / x
        w = (R[2, 1] - R[1, 2]) * f
        y = (R[0, 1] + R[1, 0]) * f
        z = (R[0, 2] + R[2, 0]) * f
    elif d1 >= d2:
        y = 0.5 * np.sqrt(1.0 + 2.0 * R[1, 1] - tr)
        f = 0.25 / y
        w = (R[0, 2] - R[2, 0]) * f
        x = (R[0, 1] + R[1, 0]) * f
        z = (R[1, 2] + R[2, 1]) * f
    else:
        z = 0.5 * np.sqrt(1.0 + 2.0 * R[2, 2] - tr)
        f = 0.25 / z
        w = (R[1, 0] - R[0, 1]) * f
        x = (R[0, 2] + R[2, 0]) * f
        y = (R[1, 2] + R[2, 1]) * f
    if w.real < 0.0:
        w, x, y, z = -w, -x, -y, -z
    vv = x * x + y * y + z * z
    if vv.real <= (w * w).real:
        z2 = vv / (w * w)
        if z2.real < _ATAN_SERIES_LIMIT:
            g = _horner(_SATAN, z2)
        else:
            zz = np.sqrt(z2)
            g = np.arctan(zz) / zz
        c = 2.0 * g / w
    else:
        s = np.sqrt(vv)
        c = 2.0 * (0.5 * math.pi - np.arctan(w / s)) / s
    psi[0] = c * x
    psi[1] = c * y
    psi[2] = c * z


@njit
def compose(psi, dtheta, out, work):
    """``out = log(exp(Δθ) exp(ψ))``; ``work``: (3, 3, 3) scratch of the same type."""
    exp(dtheta, work[0])
    exp(psi, work[1])
    P = work[2]
    for i in range(3):
        for j in range(3):
            P[i, j] = work[0, i, 0] * work[1, 0, j] + work[0, i, 1] * work[1, 1, j] + work[0, i, 2] * work[1, 2, j]
    log(P, out)


# -- row-wise versions for numpy callers (the physics class, tests) ---------------------------------

@njit
def exp_rows(psi, R):
    """``R[k] = exp(ψ[k])`` for stacks ψ (n, 3), R (n, 3, 3)."""
    for k in range(psi.shape[0]):
        exp(psi[k], R[k])


@njit
def log_rows(R, psi):
    """``ψ[k] = log(R[k])`` for stacks R (n, 3, 3), ψ (n, 3)."""
    for k in range(R.shape[0]):
        log(R[k], psi[k])


@njit
def compose_rows(psi, dtheta, out):
    """``out[k] = compose(ψ[k], Δθ[k])`` for stacks (n, 3)."""
    work = np.empty((3, 3, 3), dtype=psi.dtype)
    for k in range(psi.shape[0]):
        compose(psi[k], dtheta[k], out[k], work)
