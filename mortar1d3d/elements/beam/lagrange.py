"""Lagrange centrelines on η ∈ [-1, 1]: ``line`` (nodes -1, +1), ``line3`` (nodes -1, +1, 0)."""
from ..._config import njit


@njit
def line2_shape(eta, H):
    H[0] = 0.5 * (1.0 - eta)
    H[1] = 0.5 * (1.0 + eta)


@njit
def line2_deriv(eta, dH):
    dH[0] = -0.5
    dH[1] = 0.5


@njit
def line3_shape(eta, H):
    H[0] = 0.5 * eta * (eta - 1.0)
    H[1] = 0.5 * eta * (eta + 1.0)
    H[2] = 1.0 - eta * eta


@njit
def line3_deriv(eta, dH):
    dH[0] = eta - 0.5
    dH[1] = eta + 0.5
    dH[2] = -2.0 * eta
