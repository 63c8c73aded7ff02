"""Rigid-body modes of DOF triplets: the near null space that AMG needs for elasticity, and the
motions a body must be held against (:meth:`mortar1d3d.model.Model.rigid_body_modes`)."""
import numpy as np

__all__ = ["rigid_body_modes"]


def rigid_body_modes(points, tangent_mask=None, *, centre=None, scale=1.0, rotation_mask=None):
    """The six rigid-body modes of a set of DOF triplets (three translations, three rotations).

    Parameters
    ----------
    points : (n_triplets, 3) array_like of float
        For each DOF triplet ``3*i .. 3*i+2``: the coordinates of the point it moves (a solid
        node, a beam node's position) or, where ``tangent_mask`` is True, the tangent vector
        itself (a Hermite beam node's tangent triplet).
    tangent_mask : (n_triplets,) array_like of bool, optional
        True for tangent triplets. Default: all triplets are positions.
    centre : (3,) array_like of float, optional
        The point the rotations are taken about. Default: the centroid of the position triplets.
    scale : float
        A length the rotation columns are divided by (e.g. the body's size: the columns are then
        of the order of the translations whatever the units). Default 1.
    rotation_mask : (n_triplets,) array_like of bool, optional
        True for rotation triplets (spatial spins of a beam's material frame): a rigid rotation
        ω turns them by ω itself, a translation not at all (their ``points`` are ignored).

    Returns
    -------
    R : (3*n_triplets, 6) ndarray of float64
        Columns: translations along x, y, z, then rotations about x, y, z.

    Notes
    -----
    A rigid motion ``u(x) = a + ω × x`` moves a position triplet by ``a + ω × x`` and turns a
    tangent by ``ω × t`` (a translation does not change a tangent). The rotations are taken
    about the centroid of the position triplets (or ``centre``): the span is the same as about
    the origin, but the columns are better scaled for far-away models (AMG orthonormalises them
    per aggregate). Select the rows of the free DOFs, ``R[free]``, after eliminating Dirichlet
    DOFs.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n_triplets, 3), got {points.shape}")
    n = len(points)
    if tangent_mask is None:
        tangent = np.zeros(n, dtype=bool)
    else:
        tangent = np.asarray(tangent_mask, dtype=bool)
        if tangent.shape != (n,):
            raise ValueError(f"tangent_mask must have shape ({n},), got {tangent.shape}")
    position = ~tangent
    arm = points.copy()
    if centre is not None:
        arm[position] -= np.asarray(centre, dtype=np.float64)
    elif position.any():
        arm[position] -= points[position].mean(axis=0)
    if scale != 1.0:
        arm /= scale
    R = np.zeros((n, 3, 6))
    for i in range(3):
        R[position, i, i] = 1.0
    x, y, z = arm.T
    # ω × x for ω = e_x, e_y, e_z
    R[:, 1, 3], R[:, 2, 3] = -z, y
    R[:, 0, 4], R[:, 2, 4] = z, -x
    R[:, 0, 5], R[:, 1, 5] = -y, x
    if rotation_mask is not None:
        spin = np.asarray(rotation_mask, dtype=bool)
        R[spin] = 0.0
        for i in range(3):
            R[spin, i, 3 + i] = 1.0 / scale
    return R.reshape(3 * n, 6)
