"""Hyperelastic materials: 2nd Piola–Kirchhoff stress and material tangent from F.

A :class:`Material` is a frozen description (name, E, ν and the derived Lamé parameters);
:func:`stress_tangent` is the kernel the element loops call, dispatching on ``Material.code``.

Voigt convention (used for the tangent ``C`` and nowhere else): index order
``[11, 22, 33, 12, 23, 13]``, strains with engineering shear (γ_12 = 2 E_12), so that
``S_voigt = C @ E_voigt`` and ``C[p, q] = ∂S_p/∂E_q`` with ``C[p, q] = C_IJKL`` for
``p = (I, J)``, ``q = (K, L)``. ``C`` has both minor and (for these materials) major symmetry.
"""
import math
from dataclasses import dataclass

import numpy as np

from .._config import njit, njit_inline
from .kinematics import det3, green_lagrange

MATERIALS = ("linear_elastic", "saint_venant_kirchhoff", "neo_hooke")
LINEAR_ELASTIC, SAINT_VENANT_KIRCHHOFF, NEO_HOOKE = 0, 1, 2

#: Voigt position p -> tensor indices (I, J)
VOIGT = np.array([[0, 0], [1, 1], [2, 2], [0, 1], [1, 2], [0, 2]], dtype=np.int64)
#: tensor indices (I, J) -> Voigt position
VOIGT_INDEX = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2]], dtype=np.int64)


@dataclass(frozen=True)
class Material:
    """An isotropic elastic material; build it with :func:`material` (which validates).

    Attributes
    ----------
    name : str
        One of :data:`MATERIALS`.
    E : float
        Young's modulus.
    nu : float
        Poisson's ratio, -1 < ν < 0.5.
    code : int
        Index of ``name`` in :data:`MATERIALS` (dispatch inside kernels).
    """

    name: str
    E: float
    nu: float
    code: int

    @property
    def lam(self):
        """First Lamé parameter λ = E ν / ((1 + ν)(1 - 2ν))."""
        return self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))

    @property
    def mu(self):
        """Shear modulus μ = E / (2(1 + ν))."""
        return self.E / (2.0 * (1.0 + self.nu))


def material(name, E, nu):
    """Validated :class:`Material`.

    Parameters
    ----------
    name : str
        ``"linear_elastic"``, ``"saint_venant_kirchhoff"`` or ``"neo_hooke"``.
    E : float
        Young's modulus, finite and > 0.
    nu : float
        Poisson's ratio, finite, -1 < ν < 0.5.

    Raises
    ------
    ValueError
        Naming the offending value (and the known material names for an unknown ``name``).
    """
    if name not in MATERIALS:
        raise ValueError(f"unknown material {name!r}; known materials: {', '.join(MATERIALS)}")
    try:
        E = float(E)
        nu = float(nu)
    except (TypeError, ValueError):
        raise ValueError(f"material {name!r}: E and nu must be numbers, got E={E!r}, nu={nu!r}") from None
    if not (math.isfinite(E) and E > 0.0):
        raise ValueError(f"material {name!r}: Young's modulus E must be finite and > 0, got E={E!r}")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise ValueError(f"material {name!r}: Poisson's ratio nu must satisfy -1 < nu < 0.5, got nu={nu!r}")
    return Material(name, E, nu, MATERIALS.index(name))


@njit
def stress_tangent(code, lam, mu, H, S, C):
    """2nd Piola–Kirchhoff stress, material tangent and strain energy density at ``F``.

    Parameters
    ----------
    code : int
        Material code (:data:`MATERIALS` index).
    lam, mu : float
        Lamé parameters.
    H : (3, 3) float64
        Displacement gradient ``H = F - I`` (passed instead of F so that the strains of small
        deformations carry no cancellation error: ``E = (H + Hᵀ + HᵀH)/2``, not ``(FᵀF - I)/2``).
    S : (3, 3) float64, out
        2nd Piola–Kirchhoff stress.
    C : (6, 6) float64, out
        ``dS/dE`` in Voigt form (module docstring).

    Returns
    -------
    W : float
        Strain energy density per unit reference volume; NaN (with S and C NaN) for
        ``neo_hooke`` at ``det F <= 0``, where the energy is undefined. Never raises.

    Notes
    -----
    With ``E = (FᵀF - I)/2``, ``C_g = FᵀF``, ``J = det F``:

    - ``saint_venant_kirchhoff``: ``W = λ/2 (tr E)² + μ E:E``, ``S = λ tr E I + 2μ E``,
      ``C = λ I⊗I + 2μ 𝕀``.
    - ``linear_elastic``: Hooke's law between S and E, i.e. identical to
      ``saint_venant_kirchhoff`` when called with finite deformation; with linear kinematics
      the solid model feeds the small strain ε instead of E (then σ = λ tr ε I + 2μ ε).
    - ``neo_hooke`` (compressible): ``W = μ/2 (tr C_g - 3) - μ ln J + λ/2 (ln J)²``,
      ``S = μ (I - C_g⁻¹) + λ ln J C_g⁻¹``,
      ``C_IJKL = λ C⁻¹_IJ C⁻¹_KL + (μ - λ ln J)(C⁻¹_IK C⁻¹_JL + C⁻¹_IL C⁻¹_JK)``.
    """
    # Green–Lagrange strain from H (six scalars, no allocation in the hot loop), then C_g = I + 2E
    e00, e11, e22, e01, e12, e02 = green_lagrange(H)
    c00, c11, c22 = 1.0 + 2.0 * e00, 1.0 + 2.0 * e11, 1.0 + 2.0 * e22
    c01, c12, c02 = 2.0 * e01, 2.0 * e12, 2.0 * e02
    if code == NEO_HOOKE:
        # J - 1 = tr H + (principal 2×2 minors of H) + det H, exact without cancellation
        minors = (H[0, 0] * H[1, 1] - H[0, 1] * H[1, 0] + H[1, 1] * H[2, 2] - H[1, 2] * H[2, 1]
                  + H[0, 0] * H[2, 2] - H[0, 2] * H[2, 0])
        Jm1 = H[0, 0] + H[1, 1] + H[2, 2] + minors + det3(H)
        J = 1.0 + Jm1
        if not J > 0.0:
            S[:, :] = np.nan
            C[:, :] = np.nan
            return np.nan
        lnJ = math.log1p(Jm1)
        inv = 1.0 / (J * J)          # det C_g = J²
        # C_g⁻¹ stored in S first: C needs it, then S is built from it
        S[0, 0] = (c11 * c22 - c12 * c12) * inv
        S[1, 1] = (c00 * c22 - c02 * c02) * inv
        S[2, 2] = (c00 * c11 - c01 * c01) * inv
        S[0, 1] = S[1, 0] = (c02 * c12 - c01 * c22) * inv
        S[1, 2] = S[2, 1] = (c01 * c02 - c00 * c12) * inv
        S[0, 2] = S[2, 0] = (c01 * c12 - c02 * c11) * inv
        beta = mu - lam * lnJ
        for p in range(6):
            I = VOIGT[p, 0]
            J_ = VOIGT[p, 1]
            for q in range(p, 6):
                K = VOIGT[q, 0]
                L = VOIGT[q, 1]
                value = lam * S[I, J_] * S[K, L] + beta * (S[I, K] * S[J_, L] + S[I, L] * S[J_, K])
                C[p, q] = value
                C[q, p] = value
        # S = μ (I - C⁻¹) + λ ln J C⁻¹ = 2μ C⁻¹E + λ ln J C⁻¹ (no cancellation in I - C⁻¹)
        i00, i11, i22, i01, i12, i02 = S[0, 0], S[1, 1], S[2, 2], S[0, 1], S[1, 2], S[0, 2]
        CE00 = i00 * e00 + i01 * e01 + i02 * e02
        CE11 = i01 * e01 + i11 * e11 + i12 * e12
        CE22 = i02 * e02 + i12 * e12 + i22 * e22
        CE01 = i00 * e01 + i01 * e11 + i02 * e12
        CE12 = i01 * e02 + i11 * e12 + i12 * e22
        CE02 = i00 * e02 + i01 * e12 + i02 * e22
        S[0, 0] = 2.0 * mu * CE00 + lam * lnJ * i00
        S[1, 1] = 2.0 * mu * CE11 + lam * lnJ * i11
        S[2, 2] = 2.0 * mu * CE22 + lam * lnJ * i22
        S[0, 1] = S[1, 0] = 2.0 * mu * CE01 + lam * lnJ * i01
        S[1, 2] = S[2, 1] = 2.0 * mu * CE12 + lam * lnJ * i12
        S[0, 2] = S[2, 0] = 2.0 * mu * CE02 + lam * lnJ * i02
        return mu * (e00 + e11 + e22) - mu * lnJ + 0.5 * lam * lnJ * lnJ
    # saint_venant_kirchhoff and linear_elastic (Hooke's law between S and E)
    hooke_stress(lam, mu, e00, e11, e22, e01, e12, e02, S)
    hooke(lam, mu, C)
    trace = e00 + e11 + e22
    EE = e00 * e00 + e11 * e11 + e22 * e22 + 2.0 * (e01 * e01 + e12 * e12 + e02 * e02)
    return 0.5 * lam * trace * trace + mu * EE


@njit_inline
def hooke_stress(lam, mu, e00, e11, e22, e01, e12, e02, S):
    """Write Hooke's stress ``λ tr e I + 2μ e`` of a symmetric strain ``e`` (six components) into ``S``.

    The stress of ``saint_venant_kirchhoff`` and ``linear_elastic`` (``e = E``) and the small
    strain stress σ (``e = ε``) of the solid's cell fields.
    """
    trace = e00 + e11 + e22
    S[0, 0] = lam * trace + 2.0 * mu * e00
    S[1, 1] = lam * trace + 2.0 * mu * e11
    S[2, 2] = lam * trace + 2.0 * mu * e22
    S[0, 1] = S[1, 0] = 2.0 * mu * e01
    S[1, 2] = S[2, 1] = 2.0 * mu * e12
    S[0, 2] = S[2, 0] = 2.0 * mu * e02


@njit
def hooke(lam, mu, C):
    """Write Hooke's tensor ``λ I⊗I + 2μ 𝕀`` (6, 6) Voigt (engineering shear) into ``C``."""
    C[:, :] = 0.0
    for p in range(3):
        for q in range(3):
            C[p, q] = lam
        C[p, p] = lam + 2.0 * mu
        C[p + 3, p + 3] = mu
