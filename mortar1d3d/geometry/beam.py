"""Evaluation of beam centrelines inside kernels.

Position coefficients are stored relative to the beam element's origin (its first node); the
caller adds ``shift`` (beam origin minus solid element origin) to land in the solid element's
local frame without cancellation (the position functions sum to one).
"""
import numpy as np

from .._config import njit, njit_inline
from ..elements import beam as beam_functions
from ..elements.beam import select as beam_kernel

#: a map counts as affine when its nonlinear part is below AFFINE_TOL times the element size
AFFINE_TOL = 1e-12


@njit_inline
def beam_point(code, Q, length, s0, s1, s2, eta, H, dH):
    """(r0, r1, r2, dr0, dr1, dr2): r(η) + shift and dr/dη for coefficients ``Q`` (4, 3)."""
    beam_functions.shape(code, eta, length, H)
    beam_functions.deriv(code, eta, length, dH)
    return _combine(beam_functions.n_functions(code), Q, s0, s1, s2, H, dH)


@njit_inline
def beam_point_of(k, Q, length, s0, s1, s2, eta, H, dH):
    """:func:`beam_point` of the centreline type ``k`` given as a literal (a function compiled per
    beam type, e.g. through ``unlinked(..., cases=beam_functions.CODES)``, or a ``literal_unroll``
    loop over the codes): its kernels are called directly, without the registry's dispatch per point."""
    beam_kernel(k, "shape")(eta, length, H)
    beam_kernel(k, "deriv")(eta, length, dH)
    return _combine(beam_functions.N_FUNCTIONS[k], Q, s0, s1, s2, H, dH)


@njit_inline
def _combine(n, Q, s0, s1, s2, H, dH):
    # r = shift + Σ H_k q_k and dr/dη = Σ dH_k q_k over the first n functions
    r0, r1, r2 = s0, s1, s2
    d0 = d1 = d2 = 0.0
    for k in range(n):
        r0 += H[k] * Q[k, 0]
        r1 += H[k] * Q[k, 1]
        r2 += H[k] * Q[k, 2]
        d0 += dH[k] * Q[k, 0]
        d1 += dH[k] * Q[k, 1]
        d2 += dH[k] * Q[k, 2]
    return r0, r1, r2, d0, d1, d2


@njit
def beam_is_affine(beam_code, Qe, length, ddH):
    """Whether the centreline r(η) of one beam element is affine in η (to ``AFFINE_TOL · L``).

    Every centreline type interpolates its end points and has r'' of degree <= 1 in η (cubic
    Hermite, Lagrange lines up to line3), so its nonlinear part p (p(±1) = 0) obeys
    |p(η)| <= (1 - η²)/2 · max|p''| <= max(|r''(-1)|, |r''(1)|) / 2 per component. Affine means
    |r'| is constant and every coupling integrand is a polynomial in an affine solid element; a
    face function n·(ξ(r(η)) - o) of such an element is then linear in η. ``ddH``: buffer of
    ``MAX_FUNCTIONS`` for the second derivatives of the shape functions.
    """
    dev = 0.0
    for eta in (-1.0, 1.0):
        beam_functions.deriv2(beam_code, eta, length, ddH)
        for i in range(3):
            c = 0.0
            for k in range(beam_functions.n_functions(beam_code)):
                c += ddH[k] * Qe[k, i]
            dev = max(dev, 0.5 * abs(c))
    return dev <= AFFINE_TOL * length


@njit
def beams_affine(beam_code, Q, lengths):
    """(n,) bool: :func:`beam_is_affine` of every beam element (coefficients ``Q`` (n, 4, 3))."""
    out = np.empty(Q.shape[0], dtype=np.bool_)
    ddH = np.empty(beam_functions.MAX_FUNCTIONS)
    for e in range(Q.shape[0]):
        out[e] = beam_is_affine(beam_code, Q[e], lengths[e], ddH)
    return out
