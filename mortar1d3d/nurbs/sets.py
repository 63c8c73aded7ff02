"""Sets by position on rational (NURBS) elements: the nodes of the parts of the body in a region.

The nodes of a rational Bézier element are control points. Only its corners lie on the body in
general; an arc's middle control point lies off the circle, and no control point's displacement is
the body's displacement at that point. A set by position (a box ``inside``, a plane such as
``x_min``) therefore selects here what holds the body there: the control points of every corner,
edge, face or whole element whose body points all lie in the region (sampled on a lattice of the
entity). Fixing an entity's control points fixes the entity, and fixing less would not.
"""
from itertools import combinations, product

import numpy as np

from ..elements.solid.bezier_hex import lattice_indices
from .mesh import _single_block as _block, element_values

#: sample points per parameter direction of an entity (its corners included)
SAMPLES = 5


def _entities(p):
    """Every corner, edge, face and the volume of a hexahedron of degree ``p``: (fixed axes, their sides
    ±1) pairs, with the sampled parameters ``xi`` (k, 3) and the lattice condition of its nodes."""
    s = np.linspace(-1.0, 1.0, SAMPLES)
    for n_fixed in (3, 2, 1, 0):
        for axes in combinations(range(3), n_fixed):
            for sides in product((-1.0, 1.0), repeat=n_fixed):
                grids = [np.array([sides[axes.index(a)]]) if a in axes else s for a in range(3)]
                xi = np.stack(np.meshgrid(*grids, indexing="ij"), axis=-1).reshape(-1, 3)
                yield axes, [0 if side < 0 else p for side in sides], xi


def body_nodes(solid, inside):
    """Nodes of the rational hexahedra of ``solid`` that hold the body where ``inside`` holds.

    Parameters
    ----------
    solid : SolidMesh
    inside : callable
        ``inside(x)`` of points ``x`` (..., 3) → bool (...): the region.

    Returns
    -------
    (k,) int64, sorted: the control points of every entity (corner, edge, face, element) of a rational
    element whose sampled body points all lie in the region.
    """
    out = [np.zeros(0, dtype=np.int64)]
    for d, conn in solid.blocks:
        if not d.rational:
            continue
        lattice = lattice_indices(np.asarray(d.reference_nodes, dtype=np.float64), d.degree)
        sub = _block(solid, d, conn[:, : d.n_nodes])
        for axes, ends, xi in _entities(d.degree):
            hit = inside(element_values(sub, xi, solid.points)).all(axis=1)
            if hit.any():
                local = np.flatnonzero((lattice[:, list(axes)] == ends).all(axis=1)) if axes else np.arange(d.n_nodes)
                out.append(conn[np.flatnonzero(hit)[:, None], local[None, :]].ravel())
    return np.unique(np.concatenate(out))


def body_extent(solid, axis):
    """Smallest and largest coordinate ``axis`` of the body of the rational elements of ``solid`` (sampled on
    the elements' faces; a rational element's control points may lie beyond its body)."""
    lo, hi = np.inf, -np.inf
    for d, conn in solid.blocks:
        if d.rational:
            for axes, _, xi in _entities(d.degree):
                if len(axes) == 1:
                    x = element_values(_block(solid, d, conn[:, : d.n_nodes]), xi, solid.points)[..., axis]
                    lo, hi = min(lo, float(x.min())), max(hi, float(x.max()))
    return lo, hi


def element_centres(solid):
    """A point of the body per element (n_elements, 3): for a rational element its point at the parameter
    centre ξ = 0 (its control points' centroid may lie off the body: an arc's middle control point bulges
    out), for a polynomial element the centroid of its nodes (its point at ξ = 0 where it is affine)."""
    out = []
    for d, conn in solid.blocks:
        conn = conn[:, : d.n_nodes]
        if d.rational:
            # rational types are Bézier hexahedra on [-1, 1]³: the centre is ξ = 0
            out.append(element_values(_block(solid, d, conn), np.zeros((1, 3)), solid.points)[:, 0])
        else:
            out.append(solid.points[conn].mean(axis=1))
    return np.concatenate(out)


__all__ = ["body_nodes", "body_extent", "element_centres", "SAMPLES"]
