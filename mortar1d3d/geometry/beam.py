"""Evaluation of beam centrelines inside kernels.

Position coefficients are stored relative to the beam element's origin (its first node), and
``shift`` = beam origin - solid origin is added after the sum, so that the point comes out in
the solid element's local frame without cancellation (position functions sum to one).
"""
from .._config import njit
from ..elements import beam as beam_functions


@njit
def beam_point(code, Q, length, shift, eta, H, dH, r, dr):
    """r(η) (shifted) and dr/dη of the centreline with coefficients ``Q`` (4, 3)."""
    beam_functions.shape(code, eta, length, H)
    beam_functions.deriv(code, eta, length, dH)
    n = beam_functions.n_functions(code)
    for i in range(3):
        s = shift[i]
        ds = 0.0
        for k in range(n):
            s += H[k] * Q[k, i]
            ds += dH[k] * Q[k, i]
        r[i] = s
        dr[i] = ds
