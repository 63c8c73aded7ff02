"""Tiny dense kernels for the hot loops: 3-vectors and 3×3 matrices as scalars (no allocation)."""
from .._config import njit


@njit
def solve3(a00, a01, a02, a10, a11, a12, a20, a21, a22, b0, b1, b2):
    """Solve the 3×3 system A x = b by Cramer's rule. Returns (det, x0, x1, x2); x = 0 if det == 0."""
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if det == 0.0:
        return det, 0.0, 0.0, 0.0
    inv = 1.0 / det
    x0 = inv * (c00 * b0 + (a02 * a21 - a01 * a22) * b1 + (a01 * a12 - a02 * a11) * b2)
    x1 = inv * (c01 * b0 + (a00 * a22 - a02 * a20) * b1 + (a02 * a10 - a00 * a12) * b2)
    x2 = inv * (c02 * b0 + (a01 * a20 - a00 * a21) * b1 + (a00 * a11 - a01 * a10) * b2)
    return det, x0, x1, x2


@njit
def inverse3(a00, a01, a02, a10, a11, a12, a20, a21, a22, out):
    """Write the inverse of A into ``out`` (3, 3) by cofactors; return det A (``out`` untouched unless > 0)."""
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if not det > 0.0:
        return det
    inv = 1.0 / det
    out[0, 0], out[0, 1], out[0, 2] = inv * c00, inv * (a02 * a21 - a01 * a22), inv * (a01 * a12 - a02 * a11)
    out[1, 0], out[1, 1], out[1, 2] = inv * c01, inv * (a00 * a22 - a02 * a20), inv * (a02 * a10 - a00 * a12)
    out[2, 0], out[2, 1], out[2, 2] = inv * c02, inv * (a01 * a20 - a00 * a21), inv * (a00 * a11 - a01 * a10)
    return det


@njit
def norm3(a, b, c):
    return (a * a + b * b + c * c) ** 0.5
