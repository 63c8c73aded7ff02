"""4C's coupling forces of the rotational beam-to-solid coupling (``coupling.rotational.forces =
"fourc"``), an alternative to the variational forces of :mod:`.rotational_coupling`.

4C's mortar rotation pair (``BeamToSolidVolumeMeshtyingPairMortarRotation::
evaluate_rotational_coupling_terms``) uses the same constraint and penalty as the library,
``g_j = Σ_p Φ_j w_p ψ_p``, ``λ_j = ε κ_j⁻¹ g_j`` (its relative rotation is the rotation vector
of the quaternion product ``q_B⁻¹ q_S``, i.e. ``log(Λ_S Λ_Bᵀ) = -ψ``: the same spatial frame,
the opposite sign, which changes neither the energy nor the forces), but it does not take the
forces as the derivative of the constraint:

- the solid's share is ``Σ_p w_p (∂θ_S/∂u)ᵀ T(ψ_S)⁻ᵀ ...``, which is the exact gradient
  (``(∂ψ_p/∂u)ᵀ λ_p``, as here);
- the beam's share on the spins of rotation node k is ``Σ_p w_p L_k(η_p) T⁻¹(ψ_p) λ_p`` (in the
  library's sign; ``L_k`` the line3 Lagrange functions, ``T⁻¹`` Jelenić's T, 4C's ``Tmatrix``),
  where the exact gradient is ``Σ_p w_p Ĩ_kᵀ T⁻ᵀ(ψ_p) λ_p`` with the element's generalised spin
  interpolation ``Ĩ_k`` (δψ_p = T⁻¹(ψ_p) Σ_k Ĩ_k δθ_k). The two differ where ψ_p ≠ 0 (the skew
  part of T⁻¹ changes sign under the transpose) and where the triads turn along the element
  (``Ĩ_k ≠ L_k I``), at the order of ψ times the line moment.

The forces are therefore the point Jacobians' transposes applied to λ_p with the beam columns of
each point Jacobian replaced by ``L_k T⁻ᵀ(ψ_p)`` (:func:`beam_columns`). Their exact derivative,
the tangent this option uses, needs the directional derivative of ``T⁻¹(ψ) λ`` in ψ
(:func:`inverse_jacobian_derivative`).
"""
import numpy as np

__all__ = ["inverse_jacobian", "inverse_jacobian_derivative", "beam_columns", "FORCES"]

#: ``coupling.rotational.forces``: the library's exact gradient, or 4C's force form
FORCES = ("variational", "fourc")
#: below this a² the coefficient D of T⁻¹ and its derivative use their Taylor series
_SERIES = 0.05


def _coefficient(a2):
    """``D(a²) = (1 - (a/2) cot(a/2))/a²`` and ``dD/d(a²)`` (arrays)."""
    a2 = np.asarray(a2, dtype=float)
    small = a2 < _SERIES
    D = np.empty_like(a2)
    dD = np.empty_like(a2)
    s = a2[small]
    D[small] = 1 / 12 + s / 720 + s ** 2 / 30240 + s ** 3 / 1209600 + s ** 4 / 47900160
    dD[small] = 1 / 720 + 2 * s / 30240 + 3 * s ** 2 / 1209600 + 4 * s ** 3 / 47900160
    b = a2[~small]
    a = np.sqrt(b)
    c = 0.5 * a / np.tan(0.5 * a)
    dc = 0.5 / np.tan(0.5 * a) - 0.25 * a / np.sin(0.5 * a) ** 2          # dc/da
    D[~small] = (1.0 - c) / b
    dD[~small] = (-0.5 * a * dc - (1.0 - c)) / b ** 2
    return D, dD


def inverse_jacobian(psi):
    """``T⁻¹(ψ) = I - ½ [ψ]× + D [ψ]×²`` (n, 3, 3) for rotation vectors ψ (n, 3); 4C's ``Tmatrix``."""
    psi = np.asarray(psi, dtype=float).reshape(-1, 3)
    D, _ = _coefficient(np.einsum("ni,ni->n", psi, psi))
    S = _skew(psi)
    return np.eye(3)[None] - 0.5 * S + D[:, None, None] * S @ S


def inverse_jacobian_derivative(psi, lam):
    """``∂(T⁻¹(ψ) λ)/∂ψ`` (n, 3, 3) at rotation vectors ψ (n, 3) for fixed vectors λ (n, 3).

    Along v: ``-½ v × λ + D (v × (ψ × λ) + ψ × (v × λ)) + 2 (ψ·v) D' ψ × (ψ × λ)``.
    """
    psi = np.asarray(psi, dtype=float).reshape(-1, 3)
    lam = np.asarray(lam, dtype=float).reshape(-1, 3)
    D, dD = _coefficient(np.einsum("ni,ni->n", psi, psi))
    Sp, Sl = _skew(psi), _skew(lam)
    pl = np.cross(psi, lam)
    ppl = np.cross(psi, pl)
    # v × (ψ × λ) = -[ψ×λ]× v;  ψ × (v × λ) = -[ψ]× [λ]× v
    return (0.5 * Sl - D[:, None, None] * (_skew(pl) + Sp @ Sl)
            + 2.0 * dD[:, None, None] * ppl[:, :, None] * psi[:, None, :])


def beam_columns(psi, lag):
    """4C's beam columns of the point Jacobians: ``L_k(η_p) T⁻ᵀ(ψ_p)`` (n, 3, 9), node k's spins
    in columns 3k..3k+2 (``lag``: (n, 3) line3 Lagrange functions at the points)."""
    Tt = np.transpose(inverse_jacobian(psi), (0, 2, 1))
    return (lag[:, None, :, None] * Tt[:, :, None, :]).reshape(-1, 3, 9)


def _skew(v):
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2], S[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    S[..., 1, 0], S[..., 2, 0], S[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return S
