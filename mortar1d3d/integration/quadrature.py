"""Gauss-Legendre rules on [-1, 1]."""
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=None)
def gauss_legendre(n):
    """Points and weights (each (n,) float64, read-only) of the n-point Gauss-Legendre rule."""
    n = int(n)
    if n < 1:
        raise ValueError(f"number of Gauss points must be >= 1, got {n}")
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w
