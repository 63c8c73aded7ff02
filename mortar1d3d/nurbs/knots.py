"""Open knot vectors of one parameter direction: validation, spans, B-spline values, and the linear
maps between nested spline spaces (knot insertion, degree elevation, Bézier extraction).

Everything here is numpy and one-dimensional; a trivariate patch applies it direction by direction
(:mod:`mortar1d3d.nurbs.patch`). Conventions: a degree-p knot vector ``U`` of n functions has
n + p + 1 non-decreasing entries, the first and the last repeated p + 1 times (open), no interior
knot repeated more than p times. A span is a non-empty interval ``[U[k], U[k+1])``; its p + 1
non-zero functions are ``k - p … k``.

The maps are matrices ``T`` (n_new, n_old) with ``N_old_i = Σ_j T[j, i] N_new_j``: homogeneous
control points (w P, w) transform as ``P^w_new = T P^w_old``, which leaves the curve unchanged and
says that the old space lies in the new one (nested spaces).
"""
from math import comb

import numpy as np


def check_knots(knots, degree, what="knots"):
    """Validated open knot vector (float64 array) of a degree-``degree`` spline; ValueError otherwise."""
    U = np.asarray(knots, dtype=np.float64)
    p = int(degree)
    if p < 1:
        raise ValueError(f"{what}: degree must be >= 1, got {degree}")
    if U.ndim != 1 or len(U) < 2 * (p + 1):
        raise ValueError(f"{what}: expected at least {2 * (p + 1)} knots for degree {p}, got {U.shape}")
    if not np.isfinite(U).all() or (np.diff(U) < 0).any():
        raise ValueError(f"{what}: knots must be finite and non-decreasing")
    if not (U[: p + 1] == U[0]).all() or not (U[-p - 1:] == U[-1]).all() or U[-1] <= U[0]:
        raise ValueError(f"{what}: the knot vector must be open (first and last knot repeated {p + 1} times)")
    _, counts = np.unique(U[p + 1: -p - 1], return_counts=True)
    if (counts > p).any():
        raise ValueError(f"{what}: an interior knot is repeated more than {p} times (discontinuous basis)")
    return U


def n_functions(knots, degree):
    return len(knots) - degree - 1


def spans(knots, degree):
    """Indices k of the non-empty spans ``[U[k], U[k+1])`` in increasing order (int64)."""
    U = np.asarray(knots)
    k = np.arange(degree, len(U) - degree - 1)
    return k[U[k + 1] > U[k]]


def find_span(knots, degree, u):
    """Span index k with ``U[k] <= u < U[k+1]`` for each u (the last span for u at the end)."""
    U = np.asarray(knots)
    u = np.asarray(u, dtype=np.float64)
    n = n_functions(U, degree)
    k = np.searchsorted(U, u, side="right") - 1
    return np.clip(k, degree, n - 1)


def bspline_values(knots, degree, u, derivative=False):
    """Values (or first derivatives) of all B-splines at the points ``u``: (len(u), n_functions).

    Cox–de Boor recursion over the whole knot vector (plain numpy; for tests and for building the
    refinement maps, not for kernels). Right-continuous, with the last span closed at its end.
    """
    U = np.asarray(knots, dtype=np.float64)
    u = np.atleast_1d(np.asarray(u, dtype=np.float64))
    p = int(degree)
    k = find_span(U, p, u)
    # degree 0: the indicator of the span holding u
    B = np.zeros((len(u), len(U) - 1))
    B[np.arange(len(u)), k] = 1.0
    for q in range(1, p + 1):
        if derivative and q == p:
            D = np.zeros((len(u), len(U) - q - 1))
            for i in range(len(U) - q - 1):
                a = U[i + q] - U[i]
                b = U[i + q + 1] - U[i + 1]
                left = q * B[:, i] / a if a > 0 else 0.0
                right = q * B[:, i + 1] / b if b > 0 else 0.0
                D[:, i] = left - right
            return D
        nxt = np.zeros((len(u), len(U) - q - 1))
        for i in range(len(U) - q - 1):
            a = U[i + q] - U[i]
            b = U[i + q + 1] - U[i + 1]
            if a > 0:
                nxt[:, i] += (u - U[i]) / a * B[:, i]
            if b > 0:
                nxt[:, i] += (U[i + q + 1] - u) / b * B[:, i + 1]
        B = nxt
    return B


def insertion_matrix(knots, degree, new_knots):
    """Knot insertion (Boehm's rule, one knot at a time): the new knot vector and ``T`` (n_new, n_old).

    Inserting ū into span k replaces the control points k-p+1 … k by convex combinations
    α_i P_i + (1 - α_i) P_{i-1}, α_i = (ū - U_i) / (U_{i+p} - U_i), and shifts the ones after it.
    """
    U = check_knots(knots, degree)
    p = int(degree)
    T = np.eye(n_functions(U, p))
    for ubar in np.sort(np.atleast_1d(np.asarray(new_knots, dtype=np.float64))):
        if not U[0] < ubar < U[-1]:
            raise ValueError(f"insert knot {ubar}: must lie strictly inside ({U[0]}, {U[-1]})")
        n = n_functions(U, p)
        k = int(find_span(U, p, ubar))
        A = np.zeros((n + 1, n))
        for i in range(n + 1):
            if i <= k - p:
                A[i, i] = 1.0
            elif i >= k + 1:
                A[i, i - 1] = 1.0
            else:
                alpha = (ubar - U[i]) / (U[i + p] - U[i])
                A[i, i] = alpha
                A[i, i - 1] = 1.0 - alpha
        T = A @ T
        U = np.insert(U, k + 1, ubar)
    return check_knots(U, p), T


def elevation_matrix(knots, degree):
    """Degree elevation by one: the new knot vector (every distinct knot once more) and ``T`` (n_new, n_old).

    The old B-splines lie in the new space, so T is the exact solution of the collocation system
    ``N_new(u) T = N_old(u)`` at p + 2 points per span (least squares over all spans: square and
    regular on each span's p + 2 local functions, exact to round-off).
    """
    U = check_knots(knots, degree)
    p = int(degree)
    values, counts = np.unique(U, return_counts=True)
    V = np.repeat(values, counts + 1)
    V = check_knots(V, p + 1)
    u = []
    for k in spans(U, p):
        u.append(U[k] + (U[k + 1] - U[k]) * (np.arange(1, p + 3) / (p + 3)))
    u = np.concatenate(u)
    old = bspline_values(U, p, u)
    new = bspline_values(V, p + 1, u)
    T, *_ = np.linalg.lstsq(new, old, rcond=None)
    T[np.abs(T) < 1e-14] = 0.0
    return V, T


def extraction_operators(knots, degree):
    """Bézier extraction: per non-empty span e, ``C[e]`` (p+1, p+1) with ``N_{first[e] + i} = Σ_a C[e][i, a] B_a``.

    B_a are the degree-p Bernstein polynomials on the span mapped to [-1, 1]. Computed by inserting
    every interior knot up to multiplicity p (the spline becomes one Bézier segment per span, whose
    control points are the rows ``e p … e p + p`` of the insertion matrix).

    Returns
    -------
    C : (n_spans, p+1, p+1) float64
    first : (n_spans,) int64
        Index of the first function that is non-zero on the span (``k - p`` for span k).
    """
    U = check_knots(knots, degree)
    p = int(degree)
    values, counts = np.unique(U[p + 1: -p - 1], return_counts=True)
    extra = np.repeat(values, p - counts)
    _, T = insertion_matrix(U, p, extra) if len(extra) else (U, np.eye(n_functions(U, p)))
    ks = spans(U, p)
    C = np.empty((len(ks), p + 1, p + 1))
    first = ks - p
    for e, k in enumerate(ks):
        C[e] = T[e * p: e * p + p + 1, k - p: k + 1].T
    return C, first.astype(np.int64)


def bernstein_values(degree, x):
    """Bernstein polynomials of degree p on [-1, 1] at the points x: (len(x), p+1) (numpy)."""
    x = np.atleast_1d(np.asarray(x, dtype=np.float64))
    t = 0.5 * (1.0 + x)
    return np.stack([comb(degree, a) * (1.0 - t) ** (degree - a) * t ** a for a in range(degree + 1)], axis=1)


def bernstein_elevation(degree, target):
    """Degree elevation of the Bernstein basis: ``M`` (p+1, q+1) with ``B^p_i = Σ_j M[i, j] B^q_j`` for the
    target degree q >= p, ``M[i, j] = C(p, i) C(q − p, j − i) / C(q, j)`` for 0 <= j − i <= q − p (the
    product of B^p_i with the partition of unity of degree q − p, term by term). Exact; a Bézier
    segment's control points (homogeneous, for rational ones) elevate as ``Mᵀ P``."""
    p, q = int(degree), int(target)
    if q < p:
        raise ValueError(f"Bernstein elevation from degree {p} to {q}: the target must not be lower")
    M = np.zeros((p + 1, q + 1))
    for i in range(p + 1):
        for j in range(i, i + q - p + 1):
            M[i, j] = comb(p, i) * comb(q - p, j - i) / comb(q, j)
    return M


__all__ = ["check_knots", "n_functions", "spans", "find_span", "bspline_values", "insertion_matrix",
           "elevation_matrix", "extraction_operators", "bernstein_values", "bernstein_elevation"]
