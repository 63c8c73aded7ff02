"""Strain measures of a material point from its displacement gradient ``H = ∇u = F - I``.

Every kernel that needs a strain (the materials, the fibres, the solid's cell fields) takes it
from here, so that each measure has one formula and one floating point evaluation order.

The measures take ``H`` rather than ``F``: ``E = (H + Hᵀ + HᵀH)/2`` carries no cancellation
error for small deformations, where ``(FᵀF - I)/2`` would lose the digits of ``H`` in ``1 + H``.
Symmetric tensors come back as six scalars in the Voigt order of
:mod:`~mortar1d3d.physics.materials` (``11, 22, 33, 12, 23, 13``, tensor components, not
engineering shears): no allocation in the Gauss point loops.
"""
from .._config import njit_inline


@njit_inline
def green_lagrange(H):
    """Green–Lagrange strain ``E = (H + Hᵀ + HᵀH) / 2`` of a displacement gradient.

    Parameters
    ----------
    H : (3, 3) float64
        ``H = F - I``.

    Returns
    -------
    e00, e11, e22, e01, e12, e02 : float
        The six independent components of ``E`` (``E_ij``, not engineering shears).
    """
    # diagonal: H_ii plus half the (small) quadratic term, summed first, so that no digit of
    # H_ii is lost to the rounding of a sum with larger terms
    e00 = H[0, 0] + 0.5 * (H[0, 0] * H[0, 0] + H[1, 0] * H[1, 0] + H[2, 0] * H[2, 0])
    e11 = H[1, 1] + 0.5 * (H[0, 1] * H[0, 1] + H[1, 1] * H[1, 1] + H[2, 1] * H[2, 1])
    e22 = H[2, 2] + 0.5 * (H[0, 2] * H[0, 2] + H[1, 2] * H[1, 2] + H[2, 2] * H[2, 2])
    e01 = 0.5 * (H[0, 1] + H[1, 0] + H[0, 0] * H[0, 1] + H[1, 0] * H[1, 1] + H[2, 0] * H[2, 1])
    e12 = 0.5 * (H[1, 2] + H[2, 1] + H[0, 1] * H[0, 2] + H[1, 1] * H[1, 2] + H[2, 1] * H[2, 2])
    e02 = 0.5 * (H[0, 2] + H[2, 0] + H[0, 0] * H[0, 2] + H[1, 0] * H[1, 2] + H[2, 0] * H[2, 2])
    return e00, e11, e22, e01, e12, e02


@njit_inline
def small_strain(H):
    """Small (linearised) strain ``ε = (H + Hᵀ) / 2``: six scalars as :func:`green_lagrange`."""
    return H[0, 0], H[1, 1], H[2, 2], 0.5 * (H[0, 1] + H[1, 0]), 0.5 * (H[1, 2] + H[2, 1]), 0.5 * (H[0, 2] + H[2, 0])


@njit_inline
def det3(A):
    """Determinant of a (3, 3) array by cofactors of the first row."""
    return (A[0, 0] * (A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1])
            - A[0, 1] * (A[1, 0] * A[2, 2] - A[1, 2] * A[2, 0])
            + A[0, 2] * (A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]))
