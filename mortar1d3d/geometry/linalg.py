"""Tiny dense kernels used in the hot loops (3×3 solves without allocation)."""
from .._config import njit


@njit
def solve3(A, b, x):
    """Solve the 3×3 system A x = b by Cramer's rule. Returns det(A); x is untouched if det == 0."""
    c00 = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    c01 = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    c02 = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    det = A[0, 0] * c00 + A[0, 1] * c01 + A[0, 2] * c02
    if det == 0.0:
        return det
    inv = 1.0 / det
    b0, b1, b2 = b[0], b[1], b[2]
    x[0] = inv * (c00 * b0 + (A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]) * b1 + (A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]) * b2)
    x[1] = inv * (c01 * b0 + (A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]) * b1 + (A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]) * b2)
    x[2] = inv * (c02 * b0 + (A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]) * b1 + (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]) * b2)
    return det


@njit
def norm3(v):
    return (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) ** 0.5
