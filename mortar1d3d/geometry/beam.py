"""Evaluation of beam centrelines inside kernels.

Position coefficients are stored relative to the beam element's origin (its first node); the
caller adds ``shift`` (beam origin minus solid element origin) to land in the solid element's
local frame without cancellation (the position functions sum to one).
"""
from .._config import njit
from ..elements import beam as beam_functions


@njit
def beam_point(code, Q, length, s0, s1, s2, eta, H, dH):
    """(r0, r1, r2, dr0, dr1, dr2): r(η) + shift and dr/dη for coefficients ``Q`` (4, 3)."""
    beam_functions.shape(code, eta, length, H)
    beam_functions.deriv(code, eta, length, dH)
    r0, r1, r2 = s0, s1, s2
    d0 = d1 = d2 = 0.0
    for k in range(beam_functions.n_functions(code)):
        r0 += H[k] * Q[k, 0]
        r1 += H[k] * Q[k, 1]
        r2 += H[k] * Q[k, 2]
        d0 += dH[k] * Q[k, 0]
        d1 += dH[k] * Q[k, 1]
        d2 += dH[k] * Q[k, 2]
    return r0, r1, r2, d0, d1, d2
