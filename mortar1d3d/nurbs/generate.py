"""Exact NURBS geometry: hollow cylinders (pipe sections of any angle up to a closed pipe) and bricks.

Both start from the coarsest exact patch (linear in the straight directions, rational quadratic
around the circumference) and reach the requested degree and element counts by degree elevation
and knot insertion, which leave the geometry unchanged (:mod:`mortar1d3d.nurbs.knots`).
"""
from math import ceil, cos, radians

import numpy as np

from .patch import NurbsPatch, NurbsSolid

#: the largest arc one rational quadratic segment spans here (degrees): its middle weight
#: cos(θ/2) >= 1/2 keeps the parametrisation mild
MAX_SEGMENT_ANGLE = 120.0


def _elevate_to(patch, degree):
    """``patch`` degree-elevated (exactly) to ``degree``: one int for every direction or three."""
    degrees = _degrees(degree)
    for d in range(3):
        if degrees[d] < patch.degrees[d]:
            raise ValueError(f"degree: must be >= {patch.degrees[d]} in direction {d} (the exact geometry's "
                             f"degree there), got {degrees[d]}")
        patch = patch.elevate(d, degrees[d] - patch.degrees[d])
    return patch


def _degrees(degree):
    """Three ints from one degree (every direction) or three."""
    given = np.asarray(degree)
    if given.ndim > 1 or given.size not in (1, 3):
        raise ValueError(f"degree: expected an integer or three, got {degree}")
    degrees = np.broadcast_to(given.ravel() if given.size == 3 else given.reshape(()), (3,))
    if not all(float(q) == int(q) for q in degrees):
        raise ValueError(f"degree: expected an integer or three, got {degree}")
    return tuple(int(q) for q in degrees)


def _counts(elements):
    counts = tuple(int(n) for n in np.broadcast_to(np.asarray(elements), (3,)))
    if min(counts) < 1:
        raise ValueError(f"elements: expected three counts >= 1, got {elements}")
    return counts


def arc_segments(angle, n_elements):
    """Number of rational quadratic segments of an arc of ``angle`` degrees cut into ``n_elements``
    elements: the fewest that divide ``n_elements`` with each segment at most
    ``MAX_SEGMENT_ANGLE``; ValueError if none does."""
    for d in range(1, n_elements + 1):
        if n_elements % d == 0 and angle / d <= MAX_SEGMENT_ANGLE + 1e-12:
            return d
    raise ValueError(f"elements around the circumference: {n_elements} element(s) cannot cover {angle}° with "
                     f"arcs of at most {MAX_SEGMENT_ANGLE}° each; use at least {ceil(angle / MAX_SEGMENT_ANGLE)}")


def hollow_cylinder(r_inner, r_outer, height, angle=360.0, elements=(1, 4, 1), degree=2, start=0.0):
    """A hollow cylinder about the z axis (a closed pipe for ``angle = 360``) as one exact NURBS patch.

    Parameters
    ----------
    r_inner, r_outer : float
        Radii (m), 0 < r_inner < r_outer.
    height : float
        Length along z (m), from z = 0.
    angle : float
        Opening angle in degrees, 0 < angle <= 360, starting at ``start`` degrees from the x axis.
    elements : (3,) int
        Elements (knot spans) radially, around the circumference, along the axis.
    degree : int or (3,) ints
        Degree in every direction, or per direction (radial, circumferential, axial): at least
        (1, 2, 1), the exact geometry's degrees (the circle needs 2); higher ones are reached by
        degree elevation, which leaves the geometry unchanged.

    Returns
    -------
    NurbsSolid
        Parameter directions: 0 radial (inner → outer), 1 circumferential (counter-clockwise), 2 axial,
        so det J > 0. A closed pipe's first and last circumferential control planes coincide and are
        identified (one set of global control points on the seam).
    """
    r_inner, r_outer, height, angle = float(r_inner), float(r_outer), float(height), float(angle)
    if not 0.0 < r_inner < r_outer:
        raise ValueError(f"radii: expected 0 < r_inner < r_outer, got {r_inner}, {r_outer}")
    if not height > 0.0:
        raise ValueError(f"height: expected > 0, got {height}")
    if not 0.0 < angle <= 360.0:
        raise ValueError(f"angle: expected 0 < angle <= 360 degrees, got {angle}")
    nr, nc, nz = _counts(elements)
    segments = arc_segments(angle, nc)
    step = radians(angle) / segments
    # unit arc: 2 segments + 1 points, middle ones at the tangents' intersection with weight cos(step/2)
    theta = radians(float(start)) + 0.5 * step * np.arange(2 * segments + 1)
    radius = np.where(np.arange(2 * segments + 1) % 2 == 1, 1.0 / cos(0.5 * step), 1.0)
    arc_w = np.where(np.arange(2 * segments + 1) % 2 == 1, cos(0.5 * step), 1.0)
    if abs(angle - 360.0) < 1e-12:
        theta[-1] = theta[0]          # the seam: the very same point, so the two control planes coincide
    arc = np.column_stack([radius * np.cos(theta), radius * np.sin(theta)])
    r = np.array([r_inner, r_outer])
    z = np.array([0.0, height])
    control = np.empty((2, len(theta), 2, 3))
    control[..., 0] = r[:, None, None] * arc[None, :, 0, None]
    control[..., 1] = r[:, None, None] * arc[None, :, 1, None]
    control[..., 2] = z[None, None, :]
    weights = np.broadcast_to(arc_w[None, :, None], control.shape[:3])
    arc_knots = np.concatenate([[0.0] * 3, np.repeat(np.arange(1, segments), 2), [float(segments)] * 3])
    linear = np.array([0.0, 0.0, 1.0, 1.0])
    patch = NurbsPatch(control, weights, (linear, arc_knots, linear), (1, 2, 1))
    patch = _elevate_to(patch, degree).refine((nr, nc // segments, nz))
    return NurbsSolid([patch])


def brick(lower, upper, elements=(1, 1, 1), degree=2):
    """The box ``lower <= x <= upper`` as one NURBS patch (all weights 1) of ``degree`` (>= 1, one for every
    direction or three) with ``elements`` equal spans per direction; parameter direction d runs along x_d."""
    lower = np.asarray(lower, dtype=np.float64)
    upper = np.asarray(upper, dtype=np.float64)
    if lower.shape != (3,) or upper.shape != (3,) or not (upper > lower).all():
        raise ValueError(f"brick: expected lower < upper (three coordinates each), got {lower}, {upper}")
    corners = np.stack(np.meshgrid(*[np.array([lo, hi]) for lo, hi in zip(lower, upper)], indexing="ij"), axis=-1)
    linear = np.array([0.0, 0.0, 1.0, 1.0])
    patch = NurbsPatch(corners, np.ones((2, 2, 2)), (linear, linear, linear), (1, 1, 1))
    return NurbsSolid([_elevate_to(patch, degree).refine(_counts(elements))])


__all__ = ["hollow_cylinder", "brick", "arc_segments", "MAX_SEGMENT_ANGLE"]
