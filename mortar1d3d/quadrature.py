"""Quadrature rules, all in one place: lines, faces and volumes of the reference elements.

- :func:`gauss_legendre`: n-point Gauss–Legendre on [-1, 1] (beam integrals, coupling segments,
  arc lengths);
- :func:`hexahedron_rule`, :func:`tetrahedron_rule`, :func:`wedge_rule`: volume rules of the solid
  elements (each element descriptor names its own, see :mod:`mortar1d3d.elements.descriptor`);
- :func:`quadrilateral_rule`, :func:`triangle_rule`: face rules (surface loads).

Every rule returns read-only arrays, so that a cached rule cannot be changed by a caller.
"""
from functools import lru_cache

import numpy as np


def _frozen(*arrays):
    for a in arrays:
        a.flags.writeable = False
    return arrays


@lru_cache(maxsize=None)
def gauss_legendre(n):
    """Points and weights (each (n,) float64, read-only) of the n-point Gauss-Legendre rule."""
    n = int(n)
    if n < 1:
        raise ValueError(f"number of Gauss points must be >= 1, got {n}")
    x, w = np.polynomial.legendre.leggauss(n)
    return _frozen(x, w)


@lru_cache(maxsize=None)
def hexahedron_rule(n):
    """The n × n × n Gauss rule on [-1, 1]³: points (n³, 3) with ξ fastest, then η, then ζ; weights (n³,)."""
    x, w = gauss_legendre(n)
    points = np.array([[x[i], x[j], x[k]] for k in range(n) for j in range(n) for i in range(n)])
    weights = np.array([w[i] * w[j] * w[k] for k in range(n) for j in range(n) for i in range(n)])
    return _frozen(points, weights)


@lru_cache(maxsize=None)
def tetrahedron_rule(n):
    """The 1-point (degree 1) or 4-point (degree 2) rule on the unit simplex (weights sum to 1/6)."""
    if n == 1:
        return _frozen(np.full((1, 3), 0.25), np.array([1.0 / 6.0]))
    if n != 4:
        raise ValueError(f"tetrahedron rules have 1 or 4 points, got {n}")
    a = (5.0 - 5.0 ** 0.5) / 20.0
    b = (5.0 + 3.0 * 5.0 ** 0.5) / 20.0
    points = np.array([[a, a, a], [b, a, a], [a, b, a], [a, a, b]])
    return _frozen(points, np.full(4, 1.0 / 24.0))


# symmetric triangle rules (Strang & Fix 1973; Dunavant 1985) by degree: orbits (a, a, 1 - 2a) with
# weights per unit area
_TRIANGLE_ORBITS = {2: ((1.0 / 6.0, 1.0 / 3.0),),
                    4: ((0.44594849091596488632, 0.22338158967801146570),
                        (0.09157621350977074346, 0.10995174365532186764))}


@lru_cache(maxsize=None)
def triangle_rule(degree=4):
    """A symmetric rule on the triangle ``u, v >= 0, u + v <= 1``, exact for polynomials of ``degree``.

    Parameters
    ----------
    degree : {2, 4}
        2: three points (the wedges' volume rule); 4: six points (face loads).

    Returns
    -------
    points : (3, 2) or (6, 2) float64
    weights : (3,) or (6,) float64, summing to the area 1/2
    """
    if degree not in _TRIANGLE_ORBITS:
        raise ValueError(f"triangle rules have degree 2 or 4, got {degree}")
    points, weights = [], []
    for a, w in _TRIANGLE_ORBITS[degree]:
        b = 1.0 - 2.0 * a
        points += [(a, a), (a, b), (b, a)]
        weights += [0.5 * w] * 3
    return _frozen(np.array(points), np.array(weights))


@lru_cache(maxsize=None)
def wedge_rule(triangle_degree, n):
    """The product of a triangle rule and the n-point Gauss–Legendre rule on the prism
    ``ξ1, ξ2 >= 0, ξ1 + ξ2 <= 1, ζ ∈ [-1, 1]``.

    Parameters
    ----------
    triangle_degree : {2, 4}
        Degree of the rule in (ξ1, ξ2) (:func:`triangle_rule`).
    n : int
        Gauss points in ζ (exact to degree 2n - 1).

    Returns
    -------
    points : (q, 3) float64
        The triangle's points fastest, then ζ.
    weights : (q,) float64, summing to the volume 1
    """
    tri, tri_w = triangle_rule(triangle_degree)
    x, w = gauss_legendre(n)
    points = np.array([[t[0], t[1], z] for z in x for t in tri])
    weights = np.array([wz * wt for wz in w for wt in tri_w])
    return _frozen(points, weights)


@lru_cache(maxsize=None)
def quadrilateral_rule():
    """The 3 × 3 Gauss–Legendre rule on ``[-1, 1]^2``: points (9, 2), weights (9,) summing to 4."""
    x, w = gauss_legendre(3)
    u, v = np.meshgrid(x, x, indexing="ij")
    return _frozen(np.column_stack([u.ravel(), v.ravel()]), np.outer(w, w).ravel())


@lru_cache(maxsize=None)
def gauss_tables(n_max):
    """Gauss-Legendre rules 1..n_max as padded tables (n_max + 1, n_max): row n holds the n-point rule
    (for kernels that give each coupling segment its own number of points)."""
    gx = np.zeros((n_max + 1, n_max))
    gw = np.zeros((n_max + 1, n_max))
    for n in range(1, n_max + 1):
        gx[n, :n], gw[n, :n] = gauss_legendre(n)
    return _frozen(gx, gw)
