"""The torsion-free Kirchhoff beam as 4C's ``BEAM3EB`` element forms it (``model = "beam3eb"``).

Same centreline as the library's ``torsion_free`` beam (cubic Hermite, positions and nodal
tangent vectors, 6 DOFs per node; docs/conventions.md §2) and the same theory (Meier, Popp &
Wall, CMAME 2015/2016), but two terms are formed the way 4C forms them, so that 4C's results are
reproduced to its own tolerances:

* **Axial strain, assumed natural strain (ANS).** ``ε_c = |r_s| − 1`` is sampled at three points
  of each element, ``ξ = −1, 1, 0``, and interpolated between them with quadratic Lagrange
  polynomials, ``ε̄(ξ) = Σ_c L_c(ξ) ε_c``. The internal force is ``∫ EA ε̄ δε ds`` with the
  *exact* strain variation ``δε = δ|r_s|``: not the variation of an energy (a Petrov–Galerkin
  form), so the tangent (its exact derivative) is not symmetric.
* **Bending energy** ``½ EI |r_s × r_ss|² / |r_s|⁴`` per reference length, i.e. ``½ EI κ² |r_s|²``
  (κ: the geometric curvature), where the ``torsion_free`` beam has ``½ EI κ²``. The two agree
  to first order in the axial strain.

Both terms are integrated with 4 Gauss points per element. At a Gauss point with
``a = r'``, ``b = r''`` (derivatives with respect to ξ, reference ``J = |r0'|``) and Gauss weight w::

    f_axial = EA w ε̄ ∂|a|/∂q,        f_bending = ½ EI (w / J) ∂P/∂q,   P = |a × b|² / |a|⁴.

The library's default stays ``torsion_free`` (a variational element, exact strain): compare the
two in ``docs/fourc.md``.
"""
import numpy as np

from .._config import njit
from ..quadrature import gauss_legendre
from .beam import BeamModel, _tables, _current_derivatives, cross_square_gradient, cross_square_hessian

__all__ = ["Beam3ebModel", "GAUSS_POINTS", "COLLOCATION"]

#: Gauss points per element of both terms (4C's rule for BEAM3EB)
GAUSS_POINTS = 4
#: sampling points of the axial strain, in the order of the quadratic Lagrange functions below
COLLOCATION = (-1.0, 1.0, 0.0)


def _ans_functions(xi):
    """Quadratic Lagrange functions on the nodes −1, 1, 0 (in this order) at ``xi``: (len(xi), 3)."""
    xi = np.asarray(xi, dtype=float)
    return np.column_stack([0.5 * xi * (xi - 1.0), 0.5 * xi * (xi + 1.0), 1.0 - xi * xi])


@njit
def _bending(a, b, c, want, grad, hess):
    """``c P`` with ``P = |a × b|² / |a|⁴`` and its derivatives with respect to (a, b).

    With ``u = a·a`` and Lagrange's identity ``C = u (b·b) − (a·b)²``, ``P = C / u²``.
    """
    u = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    C = max(u * bb - ab * ab, 0.0)
    u2 = u * u
    u3 = u2 * u
    u4 = u3 * u
    W = c * C / u2
    if want == 0:
        return W
    Ca = np.empty(3)
    Cb = np.empty(3)
    for i in range(3):
        Ca[i], Cb[i] = cross_square_gradient(a, b, u, ab, bb, i)
        grad[i] = c * (Ca[i] / u2 - 4.0 * C * a[i] / u3)
        grad[3 + i] = c * Cb[i] / u2
    if want < 2:
        return W
    for i in range(3):
        for j in range(3):
            Caa, Cbb, Cab, delta = cross_square_hessian(a, b, u, ab, bb, i, j)
            hess[i, j] = c * (Caa / u2 - 4.0 * (Ca[i] * a[j] + a[i] * Ca[j]) / u3 - 4.0 * C * delta / u3
                              + 24.0 * C * a[i] * a[j] / u4)
            hess[i, 3 + j] = c * (Cab / u2 - 4.0 * a[i] * Cb[j] / u3)
            hess[3 + j, i] = hess[i, 3 + j]
            hess[3 + i, 3 + j] = c * Cbb / u2
    return W


@njit
def _elements(dH, ddH, A0, B0, dHc, A0c, Jc, Lg, wA, wB, Qd, want, energy, fe, ke):
    """Energy-like value, internal force and tangent of every element (4C's BEAM3EB).

    Parameters
    ----------
    dH, ddH : (n_el, n_g, 4) float64
        ``dH_k/dξ``, ``d²H_k/dξ²`` at the Gauss points.
    A0, B0 : (n_el, n_g, 3) float64
        Reference ``r0'`` and ``r0''`` there (element-local coordinates).
    dHc : (n_el, 3, 4) float64
        ``dH_k/dξ`` at the three sampling points of the axial strain.
    A0c : (n_el, 3, 3) float64
        Reference ``r0'`` at the sampling points; ``Jc`` (n_el, 3) its lengths.
    Lg : (n_g, 3) float64
        The quadratic interpolation functions of the sampled strains at the Gauss points.
    wA, wB : (n_el, n_g) float64
        ``EA w`` and ``EI w / J`` per Gauss point.
    Qd : (n_el, 4, 3) float64
        Displacement part of the current coefficients.
    want : int
        0 energy, 1 and forces, 2 and tangents.
    energy : (n_el,)
        ``Σ ½ EA ε̄² w J + ½ EI (w/J) P`` (4C's internal energy; not a potential of the forces).
    fe : (n_el, 12), ke : (n_el, 12, 12)
        Outputs, local DOF ``3k + i``; ``ke`` is not symmetric.
    """
    n_el, n_g, n_f = dH.shape[0], dH.shape[1], dH.shape[2]
    a = np.empty(3)
    b = np.empty(3)
    da = np.empty(3)
    grad = np.empty(6)
    hess = np.empty((6, 6))
    eps_c = np.empty(3)
    deps_c = np.empty((3, 3 * n_f))
    deps = np.empty(3 * n_f)
    dnorm = np.empty(3 * n_f)
    for e in range(n_el):
        total = 0.0
        if want >= 1:
            fe[e, :] = 0.0
        if want == 2:
            ke[e, :, :] = 0.0
        # the three sampled strains, free of cancellation against the coordinates:
        # |a| − J = (2 a0·da + da·da) / (|a| + J)
        for c in range(3):
            for i in range(3):
                da[i] = 0.0
                for k in range(n_f):
                    da[i] += dHc[e, c, k] * Qd[e, k, i]
                a[i] = A0c[e, c, i] + da[i]
            na = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            J = Jc[e, c]
            eps_c[c] = (2.0 * (A0c[e, c, 0] * da[0] + A0c[e, c, 1] * da[1] + A0c[e, c, 2] * da[2])
                        + da[0] * da[0] + da[1] * da[1] + da[2] * da[2]) / (J * (na + J))
            for k in range(n_f):
                for i in range(3):
                    deps_c[c, 3 * k + i] = dHc[e, c, k] * a[i] / (na * J)
        for g in range(n_g):
            _current_derivatives(dH, ddH, A0, B0, Qd, e, g, a, b, da)
            eps = Lg[g, 0] * eps_c[0] + Lg[g, 1] * eps_c[1] + Lg[g, 2] * eps_c[2]
            na = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            J0 = np.sqrt(A0[e, g, 0] ** 2 + A0[e, g, 1] ** 2 + A0[e, g, 2] ** 2)
            total += 0.5 * wA[e, g] * J0 * eps * eps
            total += _bending(a, b, 0.5 * wB[e, g], want, grad, hess)
            if want == 0:
                continue
            # axial: EA w ε̄ ∂|a|/∂q with ∂|a|/∂q_k = dH_k a / |a|
            for k in range(n_f):
                for i in range(3):
                    dnorm[3 * k + i] = dH[e, g, k] * a[i] / na
            for r in range(3 * n_f):
                fe[e, r] += wA[e, g] * eps * dnorm[r]
            # bending: chain rule through a = Σ dH_k q_k, b = Σ ddH_k q_k
            for k in range(n_f):
                for i in range(3):
                    fe[e, 3 * k + i] += dH[e, g, k] * grad[i] + ddH[e, g, k] * grad[3 + i]
            if want < 2:
                continue
            for r in range(3 * n_f):
                deps[r] = Lg[g, 0] * deps_c[0, r] + Lg[g, 1] * deps_c[1, r] + Lg[g, 2] * deps_c[2, r]
            cA = wA[e, g]
            for k in range(n_f):
                for l in range(n_f):
                    d1k, d2k, d1l, d2l = dH[e, g, k], ddH[e, g, k], dH[e, g, l], ddH[e, g, l]
                    for i in range(3):
                        for j in range(3):
                            r, s = 3 * k + i, 3 * l + j
                            # ∂/∂q_s of ε̄ ∂|a|/∂q_r: δε̄ term and ε̄ ∂²|a|
                            delta = 1.0 if i == j else 0.0
                            value = cA * (dnorm[r] * deps[s]
                                          + eps * d1k * d1l * (delta - a[i] * a[j] / (na * na)) / na)
                            value += (d1k * d1l * hess[i, j] + d1k * d2l * hess[i, 3 + j]
                                      + d2k * d1l * hess[3 + i, j] + d2k * d2l * hess[3 + i, 3 + j])
                            ke[e, r, s] += value
        energy[e] = total


class Beam3ebModel(BeamModel):
    """4C's ``BEAM3EB`` torsion-free beam on a ``hermite`` :class:`~mortar1d3d.mesh.BeamMesh`.

    Parameters
    ----------
    beams : BeamMesh
        Straight Hermite centrelines (a curved reference is a ValueError, as for ``torsion_free``).
    EA, EI : float or (n_elements,) array_like
        Axial and bending stiffness, > 0.
    model : str
        The beam type's name (``"beam3eb"``).

    Notes
    -----
    The formulation is the module docstring's. :meth:`evaluate` returns the internal force and its
    exact derivative, which is not symmetric (the ANS axial term is not variational);
    :meth:`energy` is 4C's stored energy ``Σ ½ EA ε̄² + ½ EI P`` (its gradient is not the internal
    force). :meth:`sample` reports the exact strain ``|r_s| − 1``, as for ``torsion_free``.
    """

    symmetric = False

    def __init__(self, beams, EA, EI=None, model="beam3eb"):
        # the parent builds the Hermite tables, reference derivatives and DOF maps of a 4-point rule
        super().__init__(beams, EA, EI, model="torsion_free", n_gauss=GAUSS_POINTS, axial_gauss=None)
        from .beam_types import beam_type
        self.model, self.type = model, beam_type(model)
        eta, w = gauss_legendre(GAUSS_POINTS)
        _, dHc, _ = _tables(beams.element_type, COLLOCATION, beams.lengths)
        self._dHc = np.ascontiguousarray(dHc)
        Q0 = self._local(self._coefficients(self._q0))
        A0c = np.einsum("egk,eki->egi", self._dHc, Q0)
        self._A0c = np.ascontiguousarray(A0c)
        self._Jc = np.ascontiguousarray(np.linalg.norm(A0c, axis=2))
        self._Lg = np.ascontiguousarray(_ans_functions(eta))
        self._wA = np.ascontiguousarray(self.EA[:, None] * w[None, :])
        self._wB = np.ascontiguousarray(self.EI[:, None] * w[None, :] / self._J)

    def _run(self, d, want):
        Qd = self._coefficients(self._displacement(d))
        n_el, nd = self._dofs.shape
        energy = np.empty(n_el)
        fe = np.empty((n_el, nd) if want >= 1 else (0, 0))
        ke = np.empty((n_el, nd, nd) if want == 2 else (0, 0, 0))
        _elements(self._dH, self._ddH, self._A0, self._B0, self._dHc, self._A0c, self._Jc, self._Lg, self._wA,
                  self._wB, Qd, want, energy, fe, ke)
        return energy, fe, ke

    def __repr__(self):
        return f"Beam3ebModel({self.beams.n_elements} elements, {self.n_dofs} DOFs)"
